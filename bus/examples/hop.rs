//! Measures the latency since `acq_mono_ns`: subscribes to a rig's frames
//! (one hop) or estimates (two hops, see the `relay` example) in a wait mode
//! and prints the latency percentiles and this process's CPU use.
//!
//! ```text
//! acquisition --rig r1 --seconds 12 &
//! cargo run -p bus --example hop -- r1 low-latency 10 [frames|estimates]
//! ```

use std::time::Duration;

use bus::{Bus, BusConfig, StageStats, WaitMode};
use frames::{EstimateFrame, Frame, SensorFrame};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let rig = args.get(1).map(String::as_str).unwrap_or("r1");
    let mode = WaitMode::parse(args.get(2).map(String::as_str).unwrap_or("event"))?;
    let seconds: f64 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(5.0);
    match args.get(4).map(String::as_str).unwrap_or("frames") {
        "frames" => measure::<SensorFrame>(rig, mode, seconds),
        "estimates" => measure::<EstimateFrame>(rig, mode, seconds),
        other => Err(format!("unknown topic {other:?}: frames or estimates").into()),
    }
}

fn measure<T: Frame>(rig: &str, mode: WaitMode, seconds: f64) -> Result<(), Box<dyn std::error::Error>> {
    let stop = bus::stop_on_signals();
    let bus = Bus::open(rig, BusConfig::from_env()?)?;
    let mut rx = bus.subscriber::<T>(mode)?;
    // start measuring at the first frame
    let first = rx
        .wait(Duration::from_secs(30), stop)?
        .ok_or("no frames within 30 s")?;
    let mut stats = StageStats::new(frames::stage::ESTIMATOR);
    let end = first.recv_mono_ns + (seconds * 1e9) as u64;
    let debug = std::env::var_os("HOP_DEBUG").is_some();
    let mut next_debug = 0;
    while bus::monotonic_ns() < end {
        let due = rx.schedule().next_due_ns();
        match rx.wait(Duration::from_millis(100), stop)? {
            Some(r) => {
                if debug && stats.frames_in >= next_debug {
                    next_debug += 500;
                    let d = due.unwrap_or(0) as i64;
                    let acq = r.acq_mono_ns().unwrap_or(0);
                    println!(
                        "seq {:?} acq-due {} µs, recv-acq {} µs, period {:?}",
                        r.seq(),
                        (acq as i64 - d) / 1000,
                        r.recv_mono_ns.saturating_sub(acq) / 1000,
                        rx.schedule().period_ns()
                    );
                }
                stats.frames_in += 1;
                let acq = r.acq_mono_ns().unwrap_or(r.recv_mono_ns);
                stats.record_latency_ns(r.recv_mono_ns.saturating_sub(acq));
            }
            None if stop.load(std::sync::atomic::Ordering::Relaxed) => break,
            None => {}
        }
    }
    let f = stats.take_frame();
    println!(
        "{} {mode:?}: {} frames, {} missing, hop latency {}, CPU {:.1} %, RSS {:.1} MB",
        T::TOPIC,
        stats.frames_in,
        rx.seq_gaps(),
        stats.latency_total(),
        f.cpu_fraction * 100.0,
        f.rss_bytes as f64 / 1e6
    );
    Ok(())
}
