//! The Foxglove layout of the live view, `docs/foxglove/leakwatch-layout.json`
//! (Foxglove: Layouts → Import from file): rod position and chamber pressures,
//! the three leak flows above the healthy state with the detector's
//! thresholds, the health status and the
//! events. The file names rig [`LAYOUT_RIG`]'s topics; [`for_rig`] gives it
//! for another rig, as `leakwatch run --live-view` writes it beside the run's
//! outputs.

use crate::LiveTopic;

/// The shipped layout, JSON text.
pub const LAYOUT_JSON: &str = include_str!("../../docs/foxglove/leakwatch-layout.json");

/// The rig whose topics the shipped layout names.
pub const LAYOUT_RIG: &str = "rig1";

/// The layout's path in the repository.
pub const LAYOUT_REPO_PATH: &str = "docs/foxglove/leakwatch-layout.json";

/// The file name `run --live-view` writes the layout to in its output folder.
pub const LAYOUT_FILE_NAME: &str = "foxglove-layout.json";

/// The Foxglove topic of `topic` for rig `rig`: `/leakwatch/<rig>/<name>`.
pub fn topic_name(rig: &str, topic: LiveTopic) -> String {
    format!("/leakwatch/{rig}/{}", topic.name())
}

/// The shipped layout with rig `rig`'s topics in place of [`LAYOUT_RIG`]'s.
pub fn for_rig(rig: &str) -> String {
    let mut text = LAYOUT_JSON.to_string();
    for topic in LiveTopic::ALL {
        text = text.replace(
            &format!("\"{}", topic_name(LAYOUT_RIG, topic)),
            &format!("\"{}", topic_name(rig, topic)),
        );
    }
    text
}

/// Every message path of a layout (a panel's `topicPath`, or a `value` of
/// its `paths`) that starts with `/`, as (topic, field) pairs: the topic up
/// to the first `.`, the field after it (empty for a whole topic).
pub fn message_paths(layout: &serde_json::Value) -> Vec<(String, String)> {
    let mut out = Vec::new();
    collect(layout, &mut out);
    out
}

fn collect(v: &serde_json::Value, out: &mut Vec<(String, String)>) {
    match v {
        serde_json::Value::Object(map) => {
            for (key, value) in map {
                match (key.as_str(), value.as_str()) {
                    ("topicPath" | "value", Some(path)) if path.starts_with('/') => {
                        let (topic, field) = path.split_once('.').unwrap_or((path, ""));
                        out.push((topic.to_string(), field.to_string()));
                    }
                    _ => collect(value, out),
                }
            }
        }
        serde_json::Value::Array(items) => items.iter().for_each(|i| collect(i, out)),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layout_is_json_and_names_only_topics_and_fields_the_live_view_publishes() {
        let layout: serde_json::Value = serde_json::from_str(LAYOUT_JSON).expect("the layout is JSON");
        for key in ["configById", "layout"] {
            assert!(layout.get(key).is_some(), "a Foxglove layout has {key}");
        }
        let paths = message_paths(&layout);
        assert!(paths.len() >= 8, "{paths:?}");
        let mut seen = std::collections::BTreeSet::new();
        for (topic, field) in &paths {
            let live = LiveTopic::ALL
                .into_iter()
                .find(|t| &topic_name(LAYOUT_RIG, *t) == topic)
                .unwrap_or_else(|| panic!("{topic} is not a topic the live view publishes"));
            seen.insert(live.name());
            if !field.is_empty() {
                let schema = crate::json::schema_of(live);
                assert!(
                    schema["properties"].get(field.as_str()).is_some(),
                    "{topic}.{field}: the live view's {} messages have no field {field}",
                    live.name()
                );
            }
        }
        assert_eq!(
            seen.len(),
            LiveTopic::ALL.len(),
            "every live topic is shown: {seen:?}"
        );
        // every panel the layout places is configured, and every configured one placed
        let text = layout["layout"].to_string();
        for id in layout["configById"].as_object().unwrap().keys() {
            assert!(text.contains(&format!("\"{id}\"")), "{id} is placed");
        }
    }

    #[test]
    fn the_layout_for_another_rig_names_its_topics() {
        let text = for_rig("press-3");
        assert!(!text.contains(&format!("/leakwatch/{LAYOUT_RIG}/")));
        let layout: serde_json::Value = serde_json::from_str(&text).unwrap();
        let paths = message_paths(&layout);
        assert!(
            paths.iter().all(|(t, _)| t.starts_with("/leakwatch/press-3/")),
            "{paths:?}"
        );
        assert_eq!(
            paths.len(),
            message_paths(&serde_json::from_str(LAYOUT_JSON).unwrap()).len()
        );
    }
}
