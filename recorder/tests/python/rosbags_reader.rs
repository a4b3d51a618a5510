//! The `rosbags` Python package reads the log as a rosbag2 file, every field as the Rust reader.

use std::process::Command;

use recorder::LogReader;
use serde_json::Value;

use crate::{check_message, expected_records, f, write_log, EPOCH_OFFSET_NS};

/// The same with `rosbags` (the pure-Python rosbag2 reader): `AnyReader` on the
/// file, every message deserialized with the types the file declares.
const ROSBAGS_SCRIPT: &str = r#"
import dataclasses, json, struct, sys
from pathlib import Path
from rosbags.highlevel import AnyReader

def plain(v):
    if dataclasses.is_dataclass(v):
        # the fields (rosbags adds the type name and the .msg constants, FLAG_...)
        return {f.name: plain(getattr(v, f.name)) for f in dataclasses.fields(v)
                if not f.name.startswith("__") and not f.name.isupper()}
    if hasattr(v, "tolist"):
        return plain(v.tolist())
    if isinstance(v, float):
        return {"f64": struct.unpack("<Q", struct.pack("<d", v))[0]}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    return v

with AnyReader([Path(sys.argv[1])]) as reader:
    print(json.dumps({"profile_ok": True, "message_count": reader.message_count,
                      "start_time": reader.start_time, "end_time": reader.end_time}))
    for c in reader.connections:
        print(json.dumps({"connection": c.topic, "msgtype": c.msgtype, "msgcount": c.msgcount}))
    for connection, timestamp, rawdata in reader.messages():
        msg = reader.deserialize(rawdata, connection.msgtype)
        print(json.dumps({"topic": connection.topic, "timestamp": timestamp, "msg": plain(msg)}))
"#;

/// True if python3 with `rosbags` runs; false (the test skips) only where
/// Python is not required.
fn python_rosbags() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import rosbags.highlevel"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_PYTHON").is_err(),
            "python3 with rosbags is required (.ci/setup installs it)"
        );
        eprintln!("SKIPPED: python3 with the rosbags package is not installed");
    }
    ok
}

/// `rosbags`' `AnyReader` opens the log as a rosbag2 file (profile `ros2`,
/// `offered_qos_profiles` on every channel) and deserializes every message to
/// the values the Rust reader gives, bit for bit, at the log's Unix times.
#[test]
fn rosbags_reads_the_log_as_a_rosbag2_file() {
    if !python_rosbags() {
        return;
    }
    let d = scratch::ScratchDir::new("recorder-rosbags");
    let path = d.join("log.mcap");
    write_log(&path);
    let log = LogReader::open(&path).unwrap().read().unwrap();
    let o = Command::new("python3")
        .args(["-c", ROSBAGS_SCRIPT])
        .arg(&path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lines: Vec<Value> = String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let total: u64 = log.channels.values().map(|c| c.messages).sum();
    assert_eq!(lines[0]["message_count"], total, "{}", lines[0]);
    // the first message is the first frame, at its acquisition as Unix time
    assert_eq!(
        lines[0]["start_time"], 1_764_000_001_000_000_000u64,
        "{}",
        lines[0]
    );
    let mut connections: Vec<(&str, &str, u64)> = lines
        .iter()
        .filter(|l| l.get("connection").is_some())
        .map(|l| {
            (
                l["connection"].as_str().unwrap(),
                l["msgtype"].as_str().unwrap(),
                l["msgcount"].as_u64().unwrap(),
            )
        })
        .collect();
    connections.sort();
    assert_eq!(
        connections,
        [
            (
                "/leakwatch/press-3/estimates",
                "leakwatch_msgs/msg/EstimateFrame",
                50
            ),
            (
                "/leakwatch/press-3/events",
                "leakwatch_msgs/msg/LeakEventFrame",
                2
            ),
            (
                "/leakwatch/press-3/frame_batches",
                "leakwatch_msgs/msg/SensorFrameBatch",
                17
            ),
            ("/leakwatch/press-3/frames", "leakwatch_msgs/msg/SensorFrame", 34),
            ("/leakwatch/press-3/gaps", "leakwatch_msgs/msg/Gap", 1),
            ("/leakwatch/press-3/health", "leakwatch_msgs/msg/HealthFrame", 1),
            ("/leakwatch/press-3/stats", "leakwatch_msgs/msg/StatsFrame", 1),
        ]
    );
    let expected = expected_records(&log);
    let mut seen: std::collections::BTreeMap<String, usize> = Default::default();
    for line in lines.iter().filter(|l| l.get("timestamp").is_some()) {
        let topic = line["topic"]
            .as_str()
            .unwrap()
            .strip_prefix("/leakwatch/press-3/")
            .unwrap();
        check_message(topic, &line["msg"], &expected, &mut seen);
    }
    for (topic, want) in &expected {
        assert_eq!(seen.get(*topic).copied().unwrap_or(0), want.len(), "{topic}");
    }
    let est = lines
        .iter()
        .filter(|l| l["topic"] == "/leakwatch/press-3/estimates")
        .nth(7)
        .unwrap();
    assert_eq!(est["msg"]["state"]["q_e1_m3_s"], f(707.0));
    assert_eq!(
        est["timestamp"],
        EPOCH_OFFSET_NS as u64 + log.estimates[7].acq_mono_ns
    );
}
