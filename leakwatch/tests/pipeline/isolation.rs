//! Runs kept apart: two rigs side by side, a forged event, a second run on the same prefix.

use std::process::{Command, Stdio};
use std::time::Duration;

use crate::common::*;

use crate::{finish, raised_leaks, start_run, SERIAL};

#[test]
fn two_rigs_side_by_side_do_not_see_each_other() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("two");
    let cfg = short_warmup_config(&d);
    let (out_a, out_b) = (d.join("a"), d.join("b"));
    let a = start_run("rigA", "16", Some("ext2:0.5lpm@10s"), &out_a, &cfg);
    let b = start_run("rigB", "16", None, &out_b, &cfg);
    finish(a);
    finish(b);
    let ra = raised_leaks(&json(&out_a.join("events.json")));
    let rb = raised_leaks(&json(&out_b.join("events.json")));
    assert_eq!(ra.len(), 1, "{ra:?}");
    assert_eq!(ra[0]["kind"], "ext2");
    assert!(rb.is_empty(), "rig B is healthy: {rb:?}");
    for out in [&out_a, &out_b] {
        let log = recorder::LogReader::open(&out.join("run.mcap"))
            .unwrap()
            .read()
            .unwrap();
        assert_eq!(log.frames.len(), 16_000, "{}", out.display());
    }
}

/// A leak event published on the run's service by another process (here the
/// test itself) is told from the classifier's by the publishing process that
/// iceoryx2 writes into each sample's header: it is left out of the output and
/// warned about, never printed or recorded as a leak.
#[test]
fn a_forged_event_from_another_process_is_left_out() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("forge");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let prefix = format!("forge{}", std::process::id());
    let child = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args([
            "run",
            "--rig",
            &rig_id("e2e-forge"),
            "--scenario",
            "loaded-sine",
            "--seconds",
            "12",
        ])
        .args(["--fault", "none", "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .env("LEAKWATCH_IOX_PREFIX", &prefix)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("leakwatch runs");
    wait_for_stage("classifier", "e2e-forge");
    std::thread::sleep(Duration::from_secs(4));
    let bus = bus::Bus::open(
        &rig_id("e2e-forge"),
        bus::BusConfig {
            iox_prefix: Some(prefix.clone()),
            ..bus::BusConfig::default()
        },
    )
    .expect("the run's bus opens");
    let mut forger = bus
        .publisher::<frames::LeakEventFrame>()
        .expect("a second publisher");
    let fake = frames::LeakEventFrame {
        kind: frames::event_kind::EXT1,
        phase: frames::event_phase::RAISED,
        event_id: 99,
        t_detect_s: 5.0,
        size_lpm: 111.0,
        detector: frames::detector_bytes("leak-size"),
        ..frames::LeakEventFrame::default()
    };
    for _ in 0..3 {
        forger.send(&fake).expect("sent");
        std::thread::sleep(Duration::from_millis(200));
    }
    let o = finish(child);
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("not this run's classifier"), "{stderr}");
    assert!(!stdout.contains("111.000"), "{stdout}");
    let events = json(&out.join("events.json"));
    assert!(raised_leaks(&events).is_empty(), "{events:#}");
}

/// Two runs on one user-given prefix: the second is refused before it starts a
/// stage, naming the first; the first is not disturbed.
#[test]
fn a_second_run_on_the_same_prefix_is_refused() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("prefix");
    let prefix = format!("shared{}", std::process::id());
    let run = |out: &str, seconds: &str| {
        Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .args([
                "run",
                "--rig",
                &rig_id("sole"),
                "--scenario",
                "closed-loop-sine",
                "--seconds",
                seconds,
                "--out",
            ])
            .arg(d.join(out))
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let first = run("first", "6");
    let first_pid = first.id();
    wait_for_stage("estimator", "sole");
    let second = run("second", "2").wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "is in use by another leakwatch run (process {first_pid}"
        )),
        "{err}"
    );
    assert!(!d.join("second").join("run.mcap").exists());
    finish(first);
    let lat = json(&d.join("first").join("latency.json"));
    assert_eq!(
        lat["stages"]["acquisition"]["frames_out"].as_u64(),
        Some(6000),
        "{lat:#}"
    );
    assert_eq!(
        lat["stages"]["estimator"]["frames_in"].as_u64(),
        Some(6000),
        "{lat:#}"
    );
}
