//! End-to-end runs of the live pipeline: real processes (acquisition,
//! estimator, classifier, recorder) over real iceoryx2 shared memory, started
//! and supervised by `leakwatch run`. Each run has its own isolation prefix.

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

mod common;
use common::*;

#[path = "pipeline/detection.rs"]
mod detection;
#[path = "pipeline/entry_points.rs"]
mod entry_points;
#[path = "pipeline/isolation.rs"]
mod isolation;
#[path = "pipeline/killed_stages.rs"]
mod killed_stages;
#[path = "pipeline/stalled_stages.rs"]
mod stalled_stages;

/// The runs share two cores: one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn start_run(rig: &str, seconds: &str, fault: Option<&str>, out: &Path, cfg: &Path) -> Child {
    start_run_with(rig, seconds, fault, out, cfg, &[])
}

/// [`start_run`] with `extra` arguments.
fn start_run_with(
    rig: &str,
    seconds: &str,
    fault: Option<&str>,
    out: &Path,
    cfg: &Path,
    extra: &[&str],
) -> Child {
    run_command(rig, seconds, fault, out, cfg, extra)
        .spawn()
        .expect("leakwatch runs")
}

/// The command of [`start_run_with`], not started.
fn run_command(
    rig: &str,
    seconds: &str,
    fault: Option<&str>,
    out: &Path,
    cfg: &Path,
    extra: &[&str],
) -> Command {
    let mut args = vec![
        "run".to_string(),
        "--rig".into(),
        rig_id(rig),
        "--scenario".into(),
        "loaded-sine".into(),
        "--seconds".into(),
        seconds.into(),
        "--config".into(),
        cfg.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ];
    if let Some(f) = fault {
        args.push("--fault".into());
        args.push(f.into());
    }
    args.extend(extra.iter().map(|a| a.to_string()));
    let mut c = Command::new(env!("CARGO_BIN_EXE_leakwatch"));
    c.args(&args).stdout(Stdio::piped()).stderr(Stdio::piped());
    c
}

/// The health topic of the run on iceoryx2 prefix `prefix` and rig `rig`, read by the test.
struct Health {
    rx: bus::Subscriber<frames::HealthFrame>,
    _bus: bus::Bus,
}

impl Health {
    fn open(prefix: &str, rig: &str) -> Health {
        let cfg = bus::BusConfig {
            iox_prefix: Some(prefix.to_string()),
            ..bus::BusConfig::default()
        };
        let bus = bus::Bus::open(&rig_id(rig), cfg).expect("the run's bus opens");
        let rx = bus.subscriber(bus::WaitMode::Event).expect("a health subscriber");
        Health { rx, _bus: bus }
    }

    /// Waits (up to 60 s) for a classifier process other than `not_pid` to say it
    /// has learned the healthy rig; returns the rig time of that health frame, s,
    /// and the process id.
    fn wait_until_armed(&mut self, not_pid: u32) -> (f64, u32) {
        let stop = std::sync::atomic::AtomicBool::new(false);
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(60) {
            if let Some(h) = self.rx.wait(Duration::from_millis(200), &stop).unwrap() {
                if h.status == frames::health_status::HEALTHY && h.publisher_pid != not_pid {
                    return (h.t_s, h.publisher_pid);
                }
            }
        }
        panic!("the classifier never said it was armed");
    }
}

fn finish(child: Child) -> Output {
    let o = child.wait_with_output().unwrap();
    // 3: it ran but its detector never armed (a short run); still a run that worked
    assert!(
        matches!(o.status.code(), Some(0) | Some(3)),
        "leakwatch run failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Kind, phase, detection time and size (bits), event id.
type EventKey = (String, String, Option<u64>, Option<u64>, u64);

/// The key of each event of an events.json, in order.
fn event_keys(v: &serde_json::Value) -> Vec<EventKey> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["kind"].as_str().unwrap().to_string(),
                e["phase"].as_str().unwrap().to_string(),
                e["t_detect_s"].as_f64().map(f64::to_bits),
                e["size_lpm"].as_f64().map(f64::to_bits),
                e["event_id"].as_u64().unwrap(),
            )
        })
        .collect()
}

fn raised_leaks(events: &serde_json::Value) -> Vec<serde_json::Value> {
    events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["phase"] == "raised" && e["detector"] == "leak-size")
        .filter(|e| matches!(e["kind"].as_str(), Some("ext1" | "ext2" | "int")))
        .cloned()
        .collect()
}

fn log_of(out: &Path) -> recorder::Log {
    recorder::LogReader::open(&out.join("run.mcap"))
        .unwrap()
        .read()
        .unwrap()
}

/// The gaps of the frames topic the recorder logged, samples.
fn frame_gaps(log: &recorder::Log) -> Vec<u64> {
    log.gaps
        .iter()
        .filter(|g| g.topic == frames::Topic::Frames)
        .map(|g| g.missing)
        .collect()
}

/// The leak-size alarms (a kind pending or named) raised before `t_s`: false alarms
/// when the leak starts at `t_s`.
fn alarms_before(events: &serde_json::Value, t_s: f64) -> Vec<serde_json::Value> {
    events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["phase"] == "raised" && e["detector"] == "leak-size")
        .filter(|e| e["t_detect_s"].as_f64().is_none_or(|t| t < t_s))
        .cloned()
        .collect()
}
