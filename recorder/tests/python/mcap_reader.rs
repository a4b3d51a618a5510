//! The `mcap` Python package decodes every field of the log as the Rust reader does.

use std::process::Command;

use recorder::LogReader;
use serde_json::{json, Value};

use crate::{check_message, expected_records, f, write_log, EPOCH_OFFSET_NS};

/// Prints one JSON object per message, file order: topic, schema, times and the
/// decoded message, floats as their IEEE-754 bits (exact, NaN included).
const SCRIPT: &str = r#"
import json, struct, sys
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

def plain(v):
    if hasattr(v, "__slots__"):
        return {k: plain(getattr(v, k)) for k in v.__slots__}
    if isinstance(v, (bytes, bytearray)):
        return list(v)
    if isinstance(v, float):
        return {"f64": struct.unpack("<Q", struct.pack("<d", v))[0]}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    return v

with open(sys.argv[1], "rb") as f:
    reader = make_reader(f, decoder_factories=[DecoderFactory()])
    for schema, channel, message, decoded in reader.iter_decoded_messages(log_time_order=False):
        print(json.dumps({
            "topic": channel.topic,
            "encoding": channel.message_encoding,
            "schema": schema.name,
            "schema_encoding": schema.encoding,
            "log_time": message.log_time,
            "publish_time": message.publish_time,
            "msg": plain(decoded),
        }))
"#;

/// True if python3 with `mcap` and `mcap_ros2` runs; false (the test skips)
/// only where Python is not required.
fn python_mcap() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import mcap.reader, mcap_ros2.decoder"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_PYTHON").is_err(),
            "python3 with mcap and mcap-ros2-support is required (.ci/setup installs them)"
        );
        eprintln!("SKIPPED: python3 with the mcap and mcap-ros2-support packages is not installed");
    }
    ok
}

#[test]
fn python_decodes_every_field_as_the_rust_reader_does() {
    if !python_mcap() {
        return;
    }
    let d = scratch::ScratchDir::new("recorder-python");
    let path = d.join("log.mcap");
    write_log(&path);
    let log = LogReader::open(&path).unwrap().read().unwrap();
    let o = Command::new("python3")
        .args(["-c", SCRIPT])
        .arg(&path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines: Vec<Value> = String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // Rust's records per topic, in file order, as Python must name them
    let expected = expected_records(&log);
    let mut seen: std::collections::BTreeMap<String, usize> = Default::default();
    for line in &lines {
        // rosbag2 topics: /leakwatch/<rig>/<topic>
        let topic = line["topic"]
            .as_str()
            .unwrap()
            .strip_prefix("/leakwatch/press-3/")
            .unwrap_or_else(|| panic!("a topic of the rig: {line}"));
        assert_eq!(line["encoding"], "cdr", "{line}");
        assert_eq!(line["schema_encoding"], "ros2msg", "{line}");
        assert!(
            line["schema"]
                .as_str()
                .unwrap()
                .starts_with("leakwatch_msgs/msg/"),
            "{line}"
        );
        // one clock: log time and publish time are the record's monotonic stamp as Unix time
        assert_eq!(line["log_time"], line["publish_time"], "{line}");
        assert!(
            line["log_time"].as_u64().unwrap() >= EPOCH_OFFSET_NS as u64,
            "{line}"
        );
        check_message(topic, &line["msg"], &expected, &mut seen);
    }
    for (topic, want) in &expected {
        assert_eq!(seen.get(*topic).copied().unwrap_or(0), want.len(), "{topic}");
    }
    assert_eq!(
        (log.frames.len(), log.estimates.len(), log.events.len()),
        (50, 50, 2)
    );
    // the values a user looks for, by name
    let frame = lines
        .iter()
        .find(|l| l["topic"] == "/leakwatch/press-3/frames")
        .unwrap();
    // acq_mono_ns 1 s: 2025-11-24 16:00:01 UTC
    assert_eq!(frame["log_time"], 1_764_000_001_000_000_000u64);
    assert_eq!(frame["msg"]["acq_mono_ns"], 1_000_000_000u64);
    let est = lines
        .iter()
        .filter(|l| l["topic"] == "/leakwatch/press-3/estimates")
        .nth(7)
        .unwrap();
    assert_eq!(est["msg"]["state"]["q_e1_m3_s"], f(707.0));
    assert_eq!(est["msg"]["th_state"]["f_e_n"], f(-607.0));
    let events: Vec<&Value> = lines
        .iter()
        .filter(|l| l["topic"] == "/leakwatch/press-3/events")
        .collect();
    assert_eq!(
        (&events[0]["msg"]["kind"], &events[0]["msg"]["phase"]),
        (&json!("ext1"), &json!("raised"))
    );
    assert_eq!(events[1]["msg"]["kind"], "99");
    assert_eq!(log.events[1].kind, 99);
}
