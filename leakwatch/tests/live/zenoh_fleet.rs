//! The Zenoh fleet: two rigs' gateways reach one `watch`; Python's eclipse-zenoh decodes them.

use std::process::{Command, Stdio};
use std::time::Duration;

use crate::common::*;
use bus::{Bus, BusConfig};
use frames::{event_kind, event_phase, health_status, HealthFrame, LeakEventFrame};
use serde_json::Value;

use crate::{example, free_port, sigterm, Lines, BIN, SERIAL};

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
