//! The Foxglove live view of a running rig: every channel read by a client; a stalled client.

use std::process::{Command, Stdio};

use crate::common::*;
use serde_json::Value;

use crate::{example, free_port, BIN, SERIAL};

/// `leakwatch run --live-view PORT` of a leak, read by the Foxglove client of
/// examples/liveview: serverInfo, four advertised channels (JSON, JSON Schema),
/// and at least one decoded message per channel with values in their physical
/// ranges, frames and estimates at 50 Hz of rig time, health at 10 Hz, every
/// raised leak event of the run's events.json, and the live view's CPU small.
#[test]
fn the_live_view_serves_a_running_rig_to_a_foxglove_client() {
    if !python_with("websockets") {
        return;
    }
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let view = run_a_leak_with_the_live_view();
    let c = &view.client;
    assert_eq!(c["subprotocol"], "foxglove.websocket.v1");
    the_live_view_and_the_log_share_one_time_base(&view);
    assert_eq!(c["server_info"]["metadata"]["rig"], "lv1");
    assert_eq!(c["bad"], 0);
    every_channel_is_advertised_in_range_and_at_its_rate(&view);
    the_leak_is_in_the_estimates_the_health_and_the_events(&view);
    the_live_views_log_counts_the_frames_and_its_cpu(&view.out);
}

/// A run of `leakwatch run --live-view` read by the Foxglove client.
struct LiveViewRun {
    /// The scratch folder that holds the run's config and output (removed
    /// when the run is dropped).
    _dir: scratch::ScratchDir,
    /// The run's output folder.
    out: std::path::PathBuf,
    /// The run's summary (stdout).
    summary: String,
    /// The client's report (examples/liveview/foxglove_client.py's JSON).
    client: Value,
    /// The wall clock before the run started and after it ended, ns.
    wall_ns: (u64, u64),
}

/// Runs 16 s of rig `lv1` with a 1 L/min ext1 leak from 10 s and its live
/// view, read for up to 40 s by the Foxglove client on the v1 protocol's
/// earlier name; checks both succeeded and the summary names every file
/// the run left beside its log.
fn run_a_leak_with_the_live_view() -> LiveViewRun {
    let dir = tmpdir("view");
    let cfg = short_warmup_config_with(&dir, "");
    let out = dir.join("run");
    let port = free_port().to_string();
    let wall_before = bus::wall_clock_ns();
    let run = Command::new(BIN)
        .args([
            "run",
            "--rig",
            "lv1",
            "--seconds",
            "16",
            "--fault",
            "ext1:1lpm@10s",
        ])
        .args(["--live-view", &port, "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // the v1 protocol's earlier name only, as @foxglove/ws-protocol offers it
    let client = Command::new("python3")
        .arg(example("liveview/foxglove_client.py"))
        .arg(format!("ws://127.0.0.1:{port}"))
        .args(["--seconds", "40", "--subprotocol", "foxglove.websocket.v1"])
        .output()
        .unwrap();
    let run = run.wait_with_output().unwrap();
    let wall_after = bus::wall_clock_ns();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    // the summary names every file the run left beside its log, the live view's own log too
    let summary = String::from_utf8_lossy(&run.stdout);
    let beside = summary
        .lines()
        .find_map(|l| l.strip_prefix("beside them: "))
        .unwrap_or_else(|| panic!("{summary}"));
    for f in [
        "acquisition.log",
        "estimator.log",
        "classifier.log",
        "recorder.log",
        "liveview.log",
        "config.toml",
    ] {
        assert!(beside.contains(f), "{f} missing: {beside}");
        assert!(out.join(f).is_file(), "{f}");
    }
    let stdout = String::from_utf8_lossy(&client.stdout);
    assert!(
        client.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&client.stderr)
    );
    let client: Value = serde_json::from_str(&stdout).unwrap();
    LiveViewRun {
        _dir: dir,
        out,
        summary: summary.into_owned(),
        client,
        wall_ns: (wall_before, wall_after),
    }
}

/// The live view's time of a frame is the log's, to the ns, and the log's
/// times are the wall clock of the run.
fn the_live_view_and_the_log_share_one_time_base(view: &LiveViewRun) {
    let (c, out) = (&view.client, &view.out);
    let (wall_before, wall_after) = view.wall_ns;
    let log = recorder::LogReader::open(&out.join("run.mcap"))
        .unwrap()
        .read()
        .unwrap();
    let offset: i64 = log.metadata["leakwatch"]["epoch_offset_ns"].parse().unwrap();
    let stamps = c["stamps"]["/leakwatch/lv1/frames"].as_object().unwrap();
    assert!(stamps.len() > 300, "{} frames with a time", stamps.len());
    let mut matched = 0;
    for f in &log.frames {
        if let Some(t) = stamps.get(&f.seq.to_string()) {
            assert_eq!(
                t.as_u64().unwrap(),
                bus::epoch_ns_with(f.acq_mono_ns, offset),
                "frame {}",
                f.seq
            );
            matched += 1;
        }
    }
    assert_eq!(
        matched,
        stamps.len(),
        "every frame the live view sent is in the log"
    );
    let (first, last) = (
        log.channels["frames"].first_log_time,
        log.channels["frames"].last_log_time,
    );
    assert!(
        wall_before < first && last < wall_after,
        "{wall_before} < {first}..{last} < {wall_after}"
    );
}

/// The layout's channels are advertised; each channel is JSON with a JSON
/// Schema and carried a message; pressures and position in their physical
/// ranges; frames and estimates at 50 Hz of rig time, health at 10 Hz.
fn every_channel_is_advertised_in_range_and_at_its_rate(view: &LiveViewRun) {
    let (c, out, summary) = (&view.client, &view.out, &view.summary);
    // the Foxglove layout, named at start, shows only channels the live view advertised
    let layout_path = out.join(live::layout::LAYOUT_FILE_NAME);
    assert!(
        summary.contains(&format!("live view layout: {}", layout_path.display())),
        "{summary}"
    );
    let layout: Value = serde_json::from_str(&std::fs::read_to_string(&layout_path).unwrap()).unwrap();
    let paths = live::layout::message_paths(&layout);
    assert!(!paths.is_empty());
    for (topic, _) in &paths {
        assert!(c["channels"].get(topic).is_some(), "{topic}: {}", c["channels"]);
    }
    let p_s = 13.8e6;
    let topics = ["frames", "estimates", "events", "health"].map(|t| format!("/leakwatch/lv1/{t}"));
    for t in &topics {
        let ch = &c["channels"][t];
        assert_eq!(ch["encoding"], "json", "{t}");
        assert_eq!(ch["schemaEncoding"], "jsonschema", "{t}");
        assert!(ch["schema"]["properties"].is_object(), "{t}");
        assert!(
            c["counts"][t].as_u64().unwrap_or(0) >= 1,
            "no message on {t}: {}",
            c["counts"]
        );
    }
    let range = |t: &str, f: &str| range_of(c, t, f);
    for (t, f) in [
        ("frames", "p1_pa"),
        ("frames", "p2_pa"),
        ("estimates", "p1_pa"),
        ("estimates", "p2_pa"),
    ] {
        let (lo, hi) = range(t, f);
        assert!(
            lo >= -0.02 * p_s && hi <= 1.02 * p_s && hi > 1e6,
            "{t}.{f} in [{lo}, {hi}] Pa"
        );
    }
    let (lo, hi) = range("frames", "x_m");
    assert!(lo >= 0.0 && hi <= 0.6 && hi > lo, "x in [{lo}, {hi}] m");
    // 50 Hz of rig time: 20 samples of 1 ms between two messages
    for t in ["frames", "estimates"] {
        let (s0, s1) = range(t, "seq");
        let n = c["counts"][format!("/leakwatch/lv1/{t}")].as_f64().unwrap();
        let per = (s1 - s0) / (n - 1.0);
        assert!(
            (per - 20.0).abs() < 0.5,
            "{t}: {n} messages over seq {s0}..{s1}: every {per} samples"
        );
        assert!(n > 300.0, "{t}: {n} messages");
    }
    let (h0, h1) = range("health", "seq");
    let nh = c["counts"]["/leakwatch/lv1/health"].as_f64().unwrap();
    assert!(
        (h1 - h0 + 1.0 - nh).abs() < 2.0 && nh > 100.0,
        "health: {nh} of seq {h0}..{h1}"
    );
}

/// The leak in the estimates, in the health (above its threshold), and every
/// raised leak event of the run's events.json among the live view's events.
fn the_leak_is_in_the_estimates_the_health_and_the_events(view: &LiveViewRun) {
    let (c, out) = (&view.client, &view.out);
    let range = |t: &str, f: &str| range_of(c, t, f);
    let last = &c["last"]["/leakwatch/lv1/estimates"];
    let ext1 = last["leak_ext1_lpm"].as_f64().unwrap();
    assert!(ext1 > 0.5 && ext1 < 3.0, "last ext1 estimate {ext1} L/min");
    assert!(
        range("health", "active_events").1 >= 1.0,
        "no active event in the health"
    );
    // the health carries the detector's thresholds once it armed, and the
    // ext1 flow rose above its own (the layout plots both)
    let (th_lo, th_hi) = range("health", "leak_ext1_threshold_lpm");
    let (_, flow_hi) = range("health", "leak_ext1_lpm");
    assert!(
        th_lo > 0.0 && flow_hi > th_hi,
        "ext1 threshold {th_lo}..{th_hi}, flow up to {flow_hi} L/min"
    );
    let live: Vec<(String, String, f64)> = c["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["kind"].as_str().unwrap().to_string(),
                e["phase"].as_str().unwrap().to_string(),
                e["t_detect_s"].as_f64().unwrap(),
            )
        })
        .collect();
    let run_events = json(&out.join("events.json"));
    let raised: Vec<(String, String, f64)> = run_events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["detector"] == "leak-size" && e["phase"] == "raised")
        .map(|e| {
            (
                e["kind"].as_str().unwrap().to_string(),
                "raised".to_string(),
                e["t_detect_s"].as_f64().unwrap(),
            )
        })
        .collect();
    assert!(
        raised
            .iter()
            .any(|(k, _, t)| k == "ext1" && *t > 10.0 && *t < 16.0),
        "{raised:?}"
    );
    for r in &raised {
        assert!(live.contains(r), "{r:?} not in the live view's events {live:?}");
    }
}

/// The least and the largest value of field `f` the client read on rig
/// lv1's topic `t`.
fn range_of(c: &Value, t: &str, f: &str) -> (f64, f64) {
    let r = &c["ranges"][format!("/leakwatch/lv1/{t}")][f];
    (r[0].as_f64().unwrap(), r[1].as_f64().unwrap())
}

/// The live view's own account in liveview.log: the frames it received, and
/// its CPU under 10 % of a core.
fn the_live_views_log_counts_the_frames_and_its_cpu(out: &std::path::Path) {
    let log = std::fs::read_to_string(out.join("liveview.log")).unwrap();
    let cpu_pct: f64 = log
        .split(" % of one core")
        .next()
        .and_then(|s| s.rsplit('(').next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or_else(|| panic!("no CPU figure in {log}"));
    assert!(cpu_pct < 10.0, "the live view used {cpu_pct} % of a core: {log}");
    let frames_in: u64 = log
        .split("received frames ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no count in {log}"));
    assert!((15_000..=16_000).contains(&frames_in), "{log}");
}

/// A client that subscribes to everything at 1 kHz and then reads nothing
/// does not slow the pipeline: the live view drops what the client cannot
/// take, the estimator and classifier miss no frame, and the live view keeps
/// up with the bus (no frame missing from its own subscriptions).
#[test]
fn a_stalled_live_view_client_costs_the_pipeline_nothing() {
    if !python_with("websockets") {
        return;
    }
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tmpdir("stall");
    let cfg = short_warmup_config_with(&dir, "[live_view]\nframes_hz = 1000.0\nestimates_hz = 1000.0\n");
    let out = dir.join("run");
    let port = free_port().to_string();
    let run = Command::new(BIN)
        .args(["run", "--rig", "lv2", "--seconds", "12", "--fault", "none"])
        .args(["--live-view", &port, "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = Command::new("python3")
        .arg(example("liveview/foxglove_client.py"))
        .arg(format!("ws://127.0.0.1:{port}"))
        .args(["--seconds", "16", "--stall"])
        .output()
        .unwrap();
    let run = run.wait_with_output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(
        client.status.success(),
        "{}",
        String::from_utf8_lossy(&client.stderr)
    );
    let lat = json(&out.join("latency.json"));
    for stage in ["estimator", "classifier"] {
        let s = &lat["stages"][stage];
        assert_eq!(s["frames_in"], 12_000, "{stage}: {s}");
        assert_eq!(s["seq_gaps"], 0, "{stage}: {s}");
    }
    let log = std::fs::read_to_string(out.join("liveview.log")).unwrap();
    assert!(log.contains("missing frames 0, estimates 0"), "{log}");
    // it did send (to the client's socket and backlog) at 1 kHz while subscribed
    let sent: u64 = log
        .split("sent frames ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no count in {log}"));
    assert!(sent > 5_000, "{log}");
}
