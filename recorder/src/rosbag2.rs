//! The rosbag2 `metadata.yaml` beside a run's log, so that a rosbag2 reader
//! (`ros2 bag info DIR`, Python's `rosbags`) opens the run's folder as a bag.

use crate::info::Info;
use crate::writer::OFFERED_QOS_PROFILES;

/// The rosbag2 metadata version written for a log of one file (ROS 2 Iron and
/// later: per-file entries, `custom_data`, `ros_distro`).
pub const METADATA_VERSION: u32 = 8;
/// The version written for a log in parts (a restarted recorder's): version 4
/// has no per-file entries, whose spans and counts the summary does not split.
pub const METADATA_VERSION_PARTS: u32 = 4;

/// A YAML string: double-quoted, with `\`, `"` and line breaks escaped (a
/// multi-line value keeps its lines).
fn quoted(s: &str) -> String {
    let escaped = s.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n");
    format!("\"{escaped}\"")
}

/// The `metadata.yaml` text for the log summarised by `info` (its first file
/// and later parts, named relative to the folder that holds them): storage
/// `mcap`, every channel with its message type, `cdr` and the QoS the file's
/// channels carry, the message counts, the start and duration in Unix ns.
pub fn metadata_yaml(info: &Info) -> String {
    let name = |p: &std::path::Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let mut files = vec![name(&info.path)];
    files.extend(info.later_parts.iter().map(|p| name(p)));
    let (start, end) = info.span_ns.unwrap_or((0, 0));
    let offset = info.wall_offset_ns.unwrap_or(0);
    let start_ns = (i128::from(start) + offset).max(0);
    let duration_ns = end.saturating_sub(start);
    let messages: u64 = info.channels.iter().map(|c| c.messages).sum();
    let mut y = String::from("rosbag2_bagfile_information:\n");
    let one_file = files.len() == 1;
    let version = if one_file {
        METADATA_VERSION
    } else {
        METADATA_VERSION_PARTS
    };
    y.push_str(&format!("  version: {version}\n"));
    y.push_str("  storage_identifier: mcap\n");
    y.push_str("  relative_file_paths:\n");
    for f in &files {
        y.push_str(&format!("    - {}\n", quoted(f)));
    }
    y.push_str(&format!("  duration:\n    nanoseconds: {duration_ns}\n"));
    y.push_str(&format!(
        "  starting_time:\n    nanoseconds_since_epoch: {start_ns}\n"
    ));
    y.push_str(&format!("  message_count: {messages}\n"));
    y.push_str("  topics_with_message_count:\n");
    for c in &info.channels {
        // "leakwatch_msgs/msg/SensorFrame (ros2msg)" -> "leakwatch_msgs/msg/SensorFrame"
        let msgtype = c.schema.split(" (").next().unwrap_or_default();
        y.push_str("    - topic_metadata:\n");
        y.push_str(&format!("        name: {}\n", quoted(&c.mcap_topic)));
        y.push_str(&format!("        type: {}\n", quoted(msgtype)));
        y.push_str(&format!(
            "        serialization_format: {}\n",
            quoted(&c.message_encoding)
        ));
        y.push_str(&format!(
            "        offered_qos_profiles: {}\n",
            quoted(OFFERED_QOS_PROFILES)
        ));
        y.push_str(&format!("      message_count: {}\n", c.messages));
    }
    y.push_str("  compression_format: \"\"\n  compression_mode: \"\"\n");
    if one_file {
        y.push_str(&format!(
            "  files:\n    - path: {}\n      starting_time:\n        nanoseconds_since_epoch: {start_ns}\n      duration:\n        nanoseconds: {duration_ns}\n      message_count: {messages}\n",
            quoted(&files[0])
        ));
        y.push_str("  custom_data: {}\n  ros_distro: ''\n");
    }
    y
}
