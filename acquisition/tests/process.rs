//! The acquisition binary as a process, publishing into a subscriber of this test.

use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use bus::{Bus, BusConfig, WaitMode};
use frames::{sensor_flags, SensorFrame, StatsFrame};

const BIN: &str = env!("CARGO_BIN_EXE_acquisition");

#[test]
fn publishes_every_frame_paced_and_ends_the_stream() {
    let prefix = format!("acq{}", std::process::id());
    let cfg = BusConfig {
        iox_prefix: Some(prefix.clone()),
        ..BusConfig::default()
    };
    let bus = Bus::open("acqtest", cfg.clone()).unwrap();
    let mut rx = bus.subscriber::<SensorFrame>(WaitMode::Event).unwrap();
    let mut stats_rx = bus.subscriber::<StatsFrame>(WaitMode::Event).unwrap();
    let child = Command::new(BIN)
        .args(["--rig", "acqtest", "--seconds", "1.5", "--wait-subscribers", "1"])
        .env("LEAKWATCH_IOX_PREFIX", &prefix)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stop = AtomicBool::new(false);
    let mut got = Vec::new();
    let mut stats = Vec::new();
    while let Some(r) = rx.wait(Duration::from_secs(10), &stop).unwrap() {
        got.push(r.frame);
        while let Some(s) = stats_rx.try_receive().unwrap() {
            stats.push(s.frame);
        }
        if r.flags & sensor_flags::END_OF_STREAM != 0 {
            break;
        }
    }
    while let Some(s) = stats_rx.wait(Duration::from_millis(200), &stop).unwrap() {
        stats.push(s.frame);
    }
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(got.len(), 1500);
    assert!(got.iter().enumerate().all(|(i, f)| f.seq == i as u64));
    // paced at 1 kHz: 1.5 s of frames take about 1.5 s
    let span_s = (got[1499].acq_mono_ns - got[0].acq_mono_ns) as f64 / 1e9;
    assert!(span_s > 1.45, "{span_s}");
    let last = stats.last().expect("a stats frame");
    assert_eq!(last.stage, frames::stage::ACQUISITION);
    assert_eq!(last.frames_out, 1500);
    drop((rx, stats_rx, bus));
    cfg.remove_isolated_files().unwrap();
}

#[test]
fn bad_arguments_are_refused_with_the_reason() {
    let run = |args: &[&str]| {
        let out = Command::new(BIN).args(args).output().unwrap();
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    assert!(run(&["--rig", "a/b"]).contains("invalid rig id"));
    assert!(run(&["--rig", "r", "--scenario", "nope"]).contains("nope"));
    assert!(run(&["--rig", "r", "--fault", "ext9:1lpm@1s"]).contains("ext9"));
    assert!(run(&["--rig", "r", "--csv", "/nonexistent.csv"]).contains("nonexistent"));
    assert!(run(&["--rig", "r", "--rate-hz=-5"]).contains("rate-hz"));
}
