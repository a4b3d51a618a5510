//! The live outputs, end to end with real processes: the Foxglove live view of
//! a running pipeline read by a WebSocket client (Python's `websockets`), and
//! the Zenoh fleet: two rigs' gateways (a whole `leakwatch run --zenoh-connect`
//! and a gateway stage fed over the bus by the test) reaching one `leakwatch
//! watch`, and Python's `eclipse-zenoh` subscribing to a gateway.
//!
//! The Python clients need `websockets` and `eclipse-zenoh` (.ci/setup
//! installs them); CI sets LEAKWATCH_REQUIRE_PYTHON=1, so they must run there.

use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig};
use frames::{event_kind, event_phase, health_status, HealthFrame, LeakEventFrame};
use serde_json::Value;

mod common;
use common::*;

const BIN: &str = env!("CARGO_BIN_EXE_leakwatch");

/// The tests that run a pipeline share two cores: one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn example(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(path)
}

/// A TCP port free on the loopback interface now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn sigterm(child: &Child) {
    // SAFETY: kill(2) on our own child's pid.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
}

/// A child whose stdout lines are gathered as they come.
struct Lines {
    child: Child,
    lines: Arc<Mutex<Vec<String>>>,
}

impl Lines {
    fn spawn(cmd: &mut Command) -> Lines {
        let mut child = cmd.stdout(Stdio::piped()).spawn().expect("the process starts");
        let out = child.stdout.take().unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let l = lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                l.lock().unwrap().push(line);
            }
        });
        Lines { child, lines }
    }

    fn text(&self) -> String {
        self.lines.lock().unwrap().join("\n")
    }

    fn has(&self, pred: impl Fn(&str) -> bool) -> bool {
        self.lines.lock().unwrap().iter().any(|l| pred(l))
    }

    /// Waits up to `secs` for a line matching `pred`, calling `tick` every 50 ms meanwhile.
    fn wait_for(&self, secs: f64, what: &str, pred: impl Fn(&str) -> bool, mut tick: impl FnMut()) {
        let t0 = Instant::now();
        while !self.has(&pred) {
            assert!(
                t0.elapsed().as_secs_f64() < secs,
                "no {what} within {secs} s; output:\n{}",
                self.text()
            );
            tick();
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

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
    let c: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(c["subprotocol"], "foxglove.websocket.v1");
    // one time base: the live view's time of a frame is the log's, to the ns,
    // and the log's times are the wall clock of the run
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
    assert_eq!(c["server_info"]["metadata"]["rig"], "lv1");
    assert_eq!(c["bad"], 0);
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
    let range = |t: &str, f: &str| {
        let r = &c["ranges"][format!("/leakwatch/lv1/{t}")][f];
        (r[0].as_f64().unwrap(), r[1].as_f64().unwrap())
    };
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
    // the leak: in the estimates, in the health, and every raised leak event of the run
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
    // the live view's own account: what it sent, and its CPU
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

fn publish_health(h: &mut bus::Publisher<HealthFrame>, seq: &mut u64, status: u32, leak: [f64; 3]) {
    *seq += 1;
    h.send(&HealthFrame {
        seq: *seq,
        t_s: *seq as f64 * 0.1,
        status,
        active_events: u32::from(status == health_status::LEAK),
        leak_flow_lpm: leak,
        leak_flow_sigma_lpm: [0.01; 3],
        ..HealthFrame::default()
    })
    .unwrap();
}

fn leak_event(kind: u32, t_s: f64, size_lpm: f64) -> LeakEventFrame {
    LeakEventFrame {
        event_id: 7,
        kind,
        phase: event_phase::RAISED,
        t_detect_s: t_s,
        t_onset_s: t_s - 1.0,
        size_lpm,
        size_lpm_sigma: 0.01,
        confidence: 0.97,
        detector: frames::detector_bytes("leak-size"),
        ..LeakEventFrame::default()
    }
}

/// Two rigs on Zenoh, one `watch`: rig zA is a whole `leakwatch run
/// --zenoh-connect` with a leak, rig zB a gateway stage fed over the bus by
/// the test. The watch names both rigs, prints zB's event field for field and
/// zA's raised ext1 event at the time of the run's events.json.
#[test]
fn two_rigs_gateways_reach_one_watch() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tmpdir("fleet");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let watch = Lines::spawn(
        Command::new(BIN)
            .args(["watch", "--listen", &endpoint, "--seconds", "90"])
            .stderr(Stdio::inherit()),
    );
    watch.wait_for(
        20.0,
        "watch start",
        |l| l.contains("subscribed to leakwatch/**"),
        || {},
    );
    // rig zB: a gateway over a bus the test publishes on
    let prefix = format!("lwz{}", std::process::id());
    let gw_log = std::fs::File::create(dir.join("gateway-zB.log")).unwrap();
    let mut gw = Command::new(BIN)
        .args(["stage", "gateway", "--rig", "zB", "--connect", &endpoint])
        .env(bus::PREFIX_ENV, &prefix)
        .stderr(gw_log)
        .spawn()
        .unwrap();
    let bus = Bus::open(
        "zB",
        BusConfig {
            iox_prefix: Some(prefix),
            ..BusConfig::default()
        },
    )
    .unwrap();
    let mut health = bus.publisher::<HealthFrame>().unwrap();
    let mut events = bus.publisher::<LeakEventFrame>().unwrap();
    let mut seq = 0;
    watch.wait_for(
        30.0,
        "rig zB",
        |l| l.starts_with("zB ") && l.contains("status healthy"),
        || publish_health(&mut health, &mut seq, health_status::HEALTHY, [0.0; 3]),
    );
    // rig zA: a whole run with its gateway
    let cfg = short_warmup_config_with(&dir, "");
    let out = dir.join("run-zA");
    let run = Command::new(BIN)
        .args([
            "run",
            "--rig",
            "zA",
            "--seconds",
            "16",
            "--fault",
            "ext1:1lpm@10s",
        ])
        .args(["--zenoh-connect", &endpoint, "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    events
        .send(&leak_event(event_kind::INTERNAL, 42.5, 0.8125))
        .unwrap();
    publish_health(&mut health, &mut seq, health_status::LEAK, [0.0, 0.0, 0.8125]);
    watch.wait_for(
        20.0,
        "zB's event",
        |l| l.starts_with("zB ") && l.contains(" int "),
        || {},
    );
    sigterm(&watch.child);
    let mut child = watch.child;
    let _ = child.wait();
    sigterm(&gw);
    let _ = gw.wait();
    let text = watch.lines.lock().unwrap().join("\n");
    // zB: exactly what the test published
    assert!(
        text.contains(
            "zB           t =   42.500 s  raised   int               size 0.812 ± 0.010 L/min  onset 41.50 s  \
             confidence 0.97  (leak-size, event 7)"
        ),
        "{text}"
    );
    assert!(text.contains("status leak"), "{text}");
    // zA: the run's raised ext1 event, at its time
    let run_events = json(&out.join("events.json"));
    let ext1 = run_events
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "ext1" && e["phase"] == "raised")
        .unwrap_or_else(|| panic!("no raised ext1 in {run_events}"));
    let t = ext1["t_detect_s"].as_f64().unwrap();
    let line = format!("zA           t = {t:8.3} s  raised   ext1");
    assert!(text.contains(&line), "{line:?} not in:\n{text}");
    // the summary names both rigs with their estimates (zA at 10 Hz of its 16 s)
    assert!(text.contains("2 rig(s) seen"), "{text}");
    let za = text
        .lines()
        .find(|l| l.trim_start().starts_with("zA ") && l.contains("estimates "))
        .unwrap_or_else(|| panic!("{text}"));
    let n: u64 = za
        .split("estimates ")
        .nth(1)
        .and_then(|s| s.split([',', ';']).next())
        .and_then(|s| s.trim().parse().ok())
        .unwrap();
    assert!((140..=161).contains(&n), "{n} estimates of zA: {za}");
}

/// Python's eclipse-zenoh subscribes to a gateway that listens and decodes its
/// JSON messages: the health and the event the test published on the bus.
#[test]
fn python_zenoh_subscriber_decodes_a_gateways_messages() {
    if !python_with("zenoh") {
        return;
    }
    let dir = tmpdir("pyzenoh");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let prefix = format!("lwp{}", std::process::id());
    let gw_log = std::fs::File::create(dir.join("gateway.log")).unwrap();
    // listen only: without it the gateway also connects to this machine's default
    // endpoint, where a user's `leakwatch watch` would print the test's leak
    let cfg = dir.join("listen_only.toml");
    std::fs::write(&cfg, "[zenoh]\nconnect = []\n").unwrap();
    let mut gw = Command::new(BIN)
        .args([
            "stage", "gateway", "--rig", "py1", "--listen", &endpoint, "--config",
        ])
        .arg(&cfg)
        .env(bus::PREFIX_ENV, &prefix)
        .stderr(gw_log)
        .spawn()
        .unwrap();
    let py = Lines::spawn(
        Command::new("python3")
            .arg(example("zenoh/subscribe.py"))
            .args(["--connect", &endpoint, "--seconds", "60", "--until-event"])
            .stderr(Stdio::inherit()),
    );
    let bus = Bus::open(
        "py1",
        BusConfig {
            iox_prefix: Some(prefix),
            ..BusConfig::default()
        },
    )
    .unwrap();
    let mut health = bus.publisher::<HealthFrame>().unwrap();
    let mut events = bus.publisher::<LeakEventFrame>().unwrap();
    let mut seq = 0;
    py.wait_for(
        40.0,
        "health in Python",
        |l| l.contains("py1/health"),
        || publish_health(&mut health, &mut seq, health_status::LEAK, [0.5, f64::NAN, 0.0]),
    );
    py.wait_for(
        20.0,
        "the event in Python",
        |l| l.contains("py1/events"),
        || {
            events.send(&leak_event(event_kind::EXT2, 12.25, 0.375)).unwrap();
            std::thread::sleep(Duration::from_millis(200));
        },
    );
    sigterm(&gw);
    let _ = gw.wait();
    let mut child = py.child;
    let _ = child.wait();
    let lines = py.lines.lock().unwrap();
    let msgs: Vec<Value> = lines.iter().map(|l| serde_json::from_str(l).unwrap()).collect();
    let h = msgs.iter().find(|m| m["key"] == "leakwatch/py1/health").unwrap();
    assert_eq!(h["encoding"], "application/json");
    assert_eq!(h["msg"]["status"], "leak");
    assert_eq!(h["msg"]["leak_ext1_lpm"], 0.5);
    assert_eq!(h["msg"]["leak_ext2_lpm"], Value::Null);
    let e = msgs.iter().find(|m| m["key"] == "leakwatch/py1/events").unwrap();
    assert_eq!(e["msg"]["kind"], "ext2");
    assert_eq!(e["msg"]["phase"], "raised");
    assert_eq!(e["msg"]["t_detect_s"], 12.25);
    assert_eq!(e["msg"]["size_lpm"], 0.375);
    assert_eq!(e["msg"]["event_id"], 7);
}

/// The status line of a WebSocket handshake for `path` on `port` (offering `foxglove.sdk.v1`).
fn handshake_status(port: u16, path: &str) -> String {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(("127.0.0.1", port)).expect("the live view listens");
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\
         Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n"
    )
    .unwrap();
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n") && s.read(&mut b).unwrap_or(0) == 1 {
        head.push(b[0]);
    }
    String::from_utf8_lossy(&head).trim().to_string()
}

/// The live view stage with `[live_view] token_file` (mode 0600) in its
/// config: a client without the token, or with a wrong one, is answered 401;
/// one with `?token=` is switched to the WebSocket protocol.
#[test]
fn a_live_view_with_a_token_file_refuses_a_client_without_the_token() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmpdir("token");
    let token = "tok-0123456789abcdefghij";
    let token_file = dir.join("token");
    std::fs::write(&token_file, format!("{token}\n")).unwrap();
    std::fs::set_permissions(&token_file, std::fs::Permissions::from_mode(0o600)).unwrap();
    let cfg = dir.join("cfg.toml");
    std::fs::write(
        &cfg,
        format!(
            "[live_view]\ntoken_file = {:?}\n",
            token_file.display().to_string()
        ),
    )
    .unwrap();
    let prefix = format!("lwtk{}", std::process::id());
    let port = free_port();
    let log = std::fs::File::create(dir.join("liveview.log")).unwrap();
    let mut view = Command::new(BIN)
        .args([
            "stage",
            "liveview",
            "--rig",
            "tk",
            "--port",
            &port.to_string(),
            "--config",
        ])
        .arg(&cfg)
        .env(bus::PREFIX_ENV, &prefix)
        .stderr(log)
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "the live view never listened"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let none = handshake_status(port, "/");
    let wrong = handshake_status(port, "/?token=tok-0123456789abcdefghiX");
    let right = handshake_status(port, &format!("/?token={token}"));
    sigterm(&view);
    let _ = view.wait();
    BusConfig {
        iox_prefix: Some(prefix),
        ..BusConfig::default()
    }
    .remove_isolated_files()
    .unwrap();
    let log = std::fs::read_to_string(dir.join("liveview.log")).unwrap();
    assert_eq!(none, "HTTP/1.1 401 Unauthorized", "{log}");
    assert_eq!(wrong, "HTTP/1.1 401 Unauthorized", "{log}");
    assert!(right.starts_with("HTTP/1.1 101"), "{right}\n{log}");
    assert!(
        log.contains("refused (HTTP 401): no token") && log.contains("refused (HTTP 401): a wrong token"),
        "{log}"
    );
}

/// Foxglove's own client library, `@foxglove/ws-protocol` (node), on a running
/// `leakwatch run --live-view` of a leak: with its default subprotocol it
/// receives frames, estimates, health and the leak's event (ext1). It runs
/// where `LEAKWATCH_NODE_MODULES` holds the package (.ci/setup installs it;
/// required with LEAKWATCH_REQUIRE_NODE=1, skipped elsewhere).
#[test]
fn foxglove_ws_protocol_receives_every_topic_of_a_running_rig() {
    let required = std::env::var("LEAKWATCH_REQUIRE_NODE").is_ok_and(|v| v == "1");
    let modules = std::env::var("LEAKWATCH_NODE_MODULES").ok().filter(|m| {
        Path::new(m)
            .join("node_modules/@foxglove/ws-protocol/package.json")
            .is_file()
    });
    let Some(modules) = modules else {
        assert!(
            !required,
            "LEAKWATCH_NODE_MODULES must hold @foxglove/ws-protocol"
        );
        eprintln!("SKIPPED: LEAKWATCH_NODE_MODULES names no @foxglove/ws-protocol (optional check)");
        return;
    };
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tmpdir("wsprotocol");
    let cfg = short_warmup_config_with(&dir, "");
    let port = free_port().to_string();
    let run = Command::new(BIN)
        .args([
            "run",
            "--rig",
            "lv3",
            "--seconds",
            "16",
            "--fault",
            "ext1:1lpm@10s",
        ])
        .args(["--live-view", &port, "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(dir.join("run"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // the live view starts with the run: retry the connection until it answers
    let start = Instant::now();
    let client = loop {
        let o = Command::new("node")
            .arg(example("liveview/ws_protocol_client.js"))
            .arg(format!("ws://127.0.0.1:{port}"))
            .args(["--seconds", "40"])
            .env("NODE_PATH", Path::new(&modules).join("node_modules"))
            .output()
            .unwrap();
        if o.status.success() || start.elapsed() > Duration::from_secs(20) {
            break o;
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    let run = run.wait_with_output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let stdout = String::from_utf8_lossy(&client.stdout);
    assert!(
        client.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&client.stderr)
    );
    let c: Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(c["subprotocol"], "foxglove.websocket.v1");
    for t in ["frames", "estimates", "health", "events"] {
        let topic = format!("/leakwatch/lv3/{t}");
        assert!(c["counts"][&topic].as_u64().unwrap_or(0) >= 1, "no {topic}: {c}");
    }
    assert!(
        c["counts"]["/leakwatch/lv3/frames"].as_u64().unwrap() > 100,
        "{c}"
    );
    let event = &c["first"]["/leakwatch/lv3/events"];
    assert!(
        event["kind"] == "ext1" || event["kind"] == "leak",
        "the first event is the leak: {event}"
    );
}
