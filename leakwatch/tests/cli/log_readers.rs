//! A run's log in other readers: rosbags (Python) and Foxglove's MCAP stack (Node.js).

use std::process::Command;

use crate::common::*;

/// Prints, for a log, what `rosbags` (the pure-Python rosbag2 reader) reads:
/// the message count, each connection's topic, type and count, the first log
/// time, and every frame's seq, p1 (IEEE-754 bits), log time and acquisition
/// stamp as JSON: from the frame batches (every frame in columns; a batch's
/// log time is its first frame's), the frames topic the plotting copy.
const ROSBAGS_SCRIPT: &str = r#"
import json, struct, sys
from pathlib import Path
from rosbags.highlevel import AnyReader

with AnyReader([Path(sys.argv[1])]) as reader:
    out = {"message_count": reader.message_count, "start_time": reader.start_time,
           "connections": {c.topic: [c.msgtype, c.msgcount] for c in reader.connections},
           "frames": []}
    batches = [c for c in reader.connections if c.topic.endswith("/frame_batches")]
    for connection, timestamp, rawdata in reader.messages(connections=batches):
        m = reader.deserialize(rawdata, connection.msgtype)
        n = len(m.p1_pa)
        acq = bytes(m.acq_mono_ns_shuffled.tolist())  # byte j of stamp i at j*n + i
        for i in range(n):
            p1 = struct.unpack("<Q", struct.pack("<d", float(m.p1_pa[i])))[0]
            stamp = int.from_bytes(bytes(acq[j * n + i] for j in range(8)), "little")
            out["frames"].append([m.first_seq + i, p1, timestamp, stamp])
    print(json.dumps(out))
"#;

/// A real run's log opens in `rosbags` as a rosbag2 file, and its folder as a
/// rosbag2 bag: every channel's message count and every frame's p1 equal
/// `leakwatch export`'s CSV, bit for bit, and its times are the wall clock of
/// the run (Unix time, ns).
#[test]
fn a_runs_log_opens_in_rosbags_and_equals_the_export() {
    let has = Command::new("python3")
        .args(["-c", "import rosbags.highlevel"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !has {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_PYTHON").is_err(),
            "python3 with rosbags is required (.ci/setup installs it)"
        );
        eprintln!("SKIPPED: python3 with the rosbags package is not installed");
        return;
    }
    let d = tmpdir("rosbags");
    let run = d.join("run");
    let wall_before = bus::wall_clock_ns();
    let o = leakwatch(&[
        "run",
        "--rig",
        "press-3",
        "--seconds",
        "3",
        "--fault",
        "none",
        "--out",
        run.to_str().unwrap(),
    ]);
    // exit 3: the detector never armed in 3 s (not watched); the log is whole
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    let wall_after = bus::wall_clock_ns();
    let log = run.join("run.mcap");
    let csv = d.join("csv");
    let o = leakwatch(&["export", log.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = Command::new("python3")
        .args(["-c", ROSBAGS_SCRIPT])
        .arg(&log)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let rows = |name: &str| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(csv.join(format!("{name}.csv"))).expect("the export's CSV");
        text.lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    };
    let mut total = 0;
    // the frames topic, for plotting: every 40th frame and every flagged one
    let n = plotted_frames(&rows("frames"));
    let topic = "/leakwatch/press-3/frames";
    assert_eq!(
        r["connections"][topic],
        serde_json::json!(["leakwatch_msgs/msg/SensorFrame", n]),
        "{}",
        r["connections"]
    );
    total += n;
    // every frame in the batches, 100 a message but where a chunk closes and at the end
    let batches = &r["connections"]["/leakwatch/press-3/frame_batches"];
    assert_eq!(batches[0], "leakwatch_msgs/msg/SensorFrameBatch", "{batches}");
    let n = batches[1].as_u64().expect("a count");
    assert!((30..=40).contains(&n), "{batches}");
    total += n;
    for (name, msg) in [
        ("estimates", "EstimateFrame"),
        ("events", "LeakEventFrame"),
        ("health", "HealthFrame"),
        ("stats", "StatsFrame"),
        ("gaps", "Gap"),
    ] {
        let n = rows(name).len() as u64 - 1;
        let topic = format!("/leakwatch/press-3/{name}");
        assert_eq!(
            r["connections"][&topic],
            serde_json::json!([format!("leakwatch_msgs/msg/{msg}"), n]),
            "{topic}: {}",
            r["connections"]
        );
        total += n;
    }
    assert_eq!(r["message_count"], total);
    // a 3 s run at 1 kHz
    let frames = rows("frames");
    assert!(frames.len() > 2900, "{} frames", frames.len());
    let col = |name: &str| frames[0].iter().position(|c| c == name).expect("a column");
    let (seq, p1, acq) = (col("seq"), col("p1_pa"), col("acq_mono_ns"));
    let got = r["frames"].as_array().expect("frames");
    assert_eq!(got.len(), frames.len() - 1);
    for (g, row) in got.iter().zip(&frames[1..]) {
        let want_p1: f64 = row[p1].parse().expect("a number");
        assert_eq!(g[0].as_u64(), row[seq].parse().ok(), "{g}");
        assert_eq!(
            g[1].as_u64(),
            Some(want_p1.to_bits()),
            "frame {}: p1 {want_p1}",
            row[seq]
        );
        assert_eq!(g[3].as_u64(), row[acq].parse().ok(), "{g}");
    }
    // Unix time of the run: the first message after the run started, the last before it ended
    let first = r["start_time"].as_u64().expect("a start time");
    assert!(
        wall_before < first && first < wall_after,
        "{wall_before} < {first} < {wall_after}"
    );
    let last_frame = got.last().and_then(|g| g[2].as_u64()).expect("a time");
    assert!(last_frame < wall_after, "{last_frame} < {wall_after}");
    // the run's folder opens as a rosbag2 bag too (its metadata.yaml), with the same content
    let o = Command::new("python3")
        .args(["-c", ROSBAGS_SCRIPT])
        .arg(&run)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let folder: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(folder, r, "the folder reads as the file");
}

/// The folder of Foxglove's npm clients (`LEAKWATCH_NODE_MODULES`, whose
/// `node_modules` .ci/setup fills from .ci/node/package.json) when node runs;
/// `None`, the test skipped, elsewhere; a failure where LEAKWATCH_REQUIRE_NODE
/// is set (CI).
fn node_clients(package: &str) -> Option<std::path::PathBuf> {
    let required = std::env::var("LEAKWATCH_REQUIRE_NODE").is_ok_and(|v| v == "1");
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let dir = std::env::var_os("LEAKWATCH_NODE_MODULES").map(std::path::PathBuf::from);
    let has = dir.as_ref().is_some_and(|d| {
        d.join("node_modules")
            .join(package)
            .join("package.json")
            .is_file()
    });
    if node && has {
        return dir;
    }
    let why = if !node {
        "node is not installed".to_string()
    } else {
        format!("LEAKWATCH_NODE_MODULES has no node_modules/{package}")
    };
    assert!(
        !required,
        "{why} (.ci/setup installs it; LEAKWATCH_REQUIRE_NODE=1)"
    );
    eprintln!("SKIPPED: {why}");
    None
}

/// Foxglove's MCAP stack in Node.js (examples/mcap/decode_log.js: @mcap/core's
/// indexed reader, @foxglove/rosmsg, @foxglove/rosmsg2-serialization) decodes
/// every message of a run's log: per topic the count of `leakwatch export`
/// (the frames topic: the frames plotted), no decode error, and every frame's
/// seq and p1 (from the batches) bit for bit.
#[test]
fn a_runs_log_decodes_with_foxglove_mcap_stack_in_node() {
    let Some(modules) = node_clients("@mcap/core") else {
        return;
    };
    let d = tmpdir("node-mcap");
    let run = d.join("run");
    let o = leakwatch(&[
        "run",
        "--rig",
        "press-4",
        "--seconds",
        "3",
        "--fault",
        "none",
        "--out",
        run.to_str().unwrap(),
    ]);
    // exit 3: the detector never armed in 3 s (not watched); the log is whole
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let log = run.join("run.mcap");
    let csv = d.join("csv");
    let o = leakwatch(&["export", log.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mcap/decode_log.js");
    let o = Command::new("node")
        .arg(&script)
        .arg(&log)
        .env("NODE_PATH", modules.join("node_modules"))
        .output()
        .expect("node runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(r["profile"], "ros2");
    let rows = |name: &str| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(csv.join(format!("{name}.csv"))).expect("the export's CSV");
        text.lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    };
    let mut total = 0;
    // the frames topic, for plotting: every 40th frame and every flagged one
    let t = &r["topics"]["/leakwatch/press-4/frames"];
    assert_eq!(t["schema"], "leakwatch_msgs/msg/SensorFrame", "{t}");
    let n = plotted_frames(&rows("frames"));
    assert_eq!(
        (t["errors"].as_u64(), t["count"].as_u64()),
        (Some(0), Some(n)),
        "{t}"
    );
    total += n;
    // every frame in the batches, 100 a message but where a chunk closes and at the end
    let t = &r["topics"]["/leakwatch/press-4/frame_batches"];
    assert_eq!(t["schema"], "leakwatch_msgs/msg/SensorFrameBatch", "{t}");
    assert_eq!(t["errors"], 0, "{t}");
    let n = t["count"].as_u64().expect("a count");
    assert!((30..=40).contains(&n), "{t}");
    total += n;
    for (name, msg) in [
        ("estimates", "EstimateFrame"),
        ("events", "LeakEventFrame"),
        ("health", "HealthFrame"),
        ("stats", "StatsFrame"),
        ("gaps", "Gap"),
    ] {
        let n = rows(name).len() as u64 - 1;
        let t = &r["topics"][format!("/leakwatch/press-4/{name}")];
        assert_eq!(t["schema"], format!("leakwatch_msgs/msg/{msg}"), "{t}");
        assert_eq!(t["errors"], 0, "{name}: {t}");
        assert_eq!(t["count"].as_u64(), Some(n), "{name}: {t}");
        total += n;
    }
    assert_eq!(r["statistics_messages"], total.to_string());
    // nested messages and codes by name
    let first = |name: &str| r["topics"][format!("/leakwatch/press-4/{name}")]["first"].clone();
    assert!(
        first("estimates")["state"]["p1_pa"].is_f64(),
        "{}",
        first("estimates")
    );
    assert_eq!(first("events")["kind"], "not-armed");
    assert!(
        first("health")["leak_flow_sigma_lpm"]["ext1"].is_f64(),
        "{}",
        first("health")
    );
    // every frame, bit for bit
    let frames = rows("frames");
    assert!(frames.len() > 2900, "{} frames", frames.len());
    let col = |name: &str| frames[0].iter().position(|c| c == name).expect("a column");
    let (seq, p1) = (col("seq"), col("p1_pa"));
    let got = r["frames"].as_array().expect("frames");
    assert_eq!(got.len(), frames.len() - 1);
    for (g, row) in got.iter().zip(&frames[1..]) {
        let want: f64 = row[p1].parse().expect("a number");
        assert_eq!(g[0].as_str(), Some(row[seq].as_str()), "{g}");
        assert_eq!(
            g[1].as_str(),
            Some(hex_le(want).as_str()),
            "frame {}: p1 {want}",
            row[seq]
        );
    }
}

/// How many of the exported frames (`frames.csv` rows, header first) the
/// recorder also puts on the frames topic for plotting: every 40th by sequence
/// number and every flagged one (`recorder::WriterOptions::frames_every`).
fn plotted_frames(rows: &[Vec<String>]) -> u64 {
    let col = |name: &str| rows[0].iter().position(|c| c == name).expect("a column");
    let (seq, flags) = (col("seq"), col("flags"));
    rows[1..]
        .iter()
        .filter(|r| r[seq].parse::<u64>().expect("a seq") % 40 == 0 || r[flags] != "0")
        .count() as u64
}

/// The little-endian bytes of `x` in hex, as node's `Buffer.writeDoubleLE` gives them.
fn hex_le(x: f64) -> String {
    x.to_le_bytes().iter().map(|b| format!("{b:02x}")).collect()
}
