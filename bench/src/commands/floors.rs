//! The machine's own limits, measured in the same run as the pipeline so that
//! every latency figure of `leakwatch bench latency` has its floor beside it:
//! how late a 1 kHz timer wakes (with and without the pacer's spin finish),
//! how long waking a blocked thread through a pipe takes, and a bare iceoryx2
//! hop (one publisher, one subscriber, nothing else) in each wait mode.
//! Each figure is a whole-run percentile of one 1 kHz stream.

use std::io::{Read, Write};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use bus::{monotonic_ns, Bus, BusConfig, Pacer, WaitMode};
use frames::SensorFrame;
use hdrhistogram::Histogram;
use serde::Serialize;

use pipeline::out::outln;

/// One floor: what was measured and its percentiles.
#[derive(Debug, Clone, Serialize)]
pub struct Floor {
    /// What the figure is.
    pub what: String,
    /// Median, µs.
    pub p50_us: f64,
    /// 99th percentile, µs.
    pub p99_us: f64,
    /// Largest, µs.
    pub max_us: f64,
    /// Events measured.
    pub samples: u64,
}

/// 1 kHz.
const PERIOD_NS: u64 = 1_000_000;

fn histogram() -> Histogram<u64> {
    // ns, 1 ns to 10 s, 3 significant digits
    Histogram::new_with_bounds(1, 10_000_000_000, 3)
        .unwrap_or_else(|_| Histogram::new(3).expect("hdrhistogram"))
}

fn floor(what: &str, h: &Histogram<u64>) -> Floor {
    let us = |p: f64| h.value_at_quantile(p) as f64 / 1e3;
    Floor {
        what: what.to_string(),
        p50_us: us(0.5),
        p99_us: us(0.99),
        max_us: h.max() as f64 / 1e3,
        samples: h.len(),
    }
}

/// Lateness of a 1 kHz pacer (absolute deadlines, timer slack 1 ns) with a
/// spin finish of `spin_ns` (0 = sleep only), over `ticks` ticks.
pub fn timer(ticks: u64, spin_ns: u64) -> Floor {
    let mut pacer = Pacer::new(PERIOD_NS, spin_ns);
    let mut h = histogram();
    pacer.wait();
    for _ in 0..ticks {
        let t = pacer.wait();
        let _ = h.record(t.late_ns.max(1));
    }
    let what = if spin_ns == 0 {
        "timer lateness, 1 kHz sleep (absolute deadline, 1 ns slack)".to_string()
    } else {
        format!("timer lateness, 1 kHz sleep + {} µs spin", spin_ns / 1000)
    };
    floor(&what, &h)
}

/// A thread blocked in `read` on a pipe, woken by another thread's 8-byte
/// write at 1 kHz: the time from just before the write to the reader holding
/// the bytes.
pub fn pipe_wake(ticks: u64) -> Result<Floor, String> {
    let (mut rx, mut tx) = std::io::pipe().map_err(|e| format!("pipe: {e}"))?;
    let writer = std::thread::spawn(move || {
        let mut pacer = Pacer::new(PERIOD_NS, 0);
        for _ in 0..ticks + 1 {
            pacer.wait();
            if tx.write_all(&monotonic_ns().to_le_bytes()).is_err() {
                return;
            }
        }
    });
    let mut h = histogram();
    let mut buf = [0u8; 8];
    for k in 0..ticks + 1 {
        if rx.read_exact(&mut buf).is_err() {
            break;
        }
        let now = monotonic_ns();
        if k > 0 {
            let _ = h.record(now.saturating_sub(u64::from_le_bytes(buf)).max(1));
        }
    }
    let _ = writer.join();
    Ok(floor("process wake-up through a pipe (write → read)", &h))
}

/// A bare iceoryx2 hop: a sensor frame published at 1 kHz (with the wake
/// event) by one thread and received by another in `mode`, nothing else in
/// between; latency from the stamp taken before sending to the receive.
pub fn iceoryx2_hop(ticks: u64, mode: WaitMode) -> Result<Floor, String> {
    let rig = format!(
        "floor-{}-{}",
        std::process::id(),
        mode_name(mode).replace(':', "-")
    );
    let config = BusConfig::from_env().map_err(|e| e.to_string())?;
    let stop = AtomicBool::new(false);
    let bus = Bus::open(&rig, config.clone()).map_err(|e| e.to_string())?;
    let mut rx = bus.subscriber::<SensorFrame>(mode).map_err(|e| e.to_string())?;
    let rig_tx = rig.clone();
    let writer = std::thread::spawn(move || -> Result<(), String> {
        let bus = Bus::open(&rig_tx, config).map_err(|e| e.to_string())?;
        let mut tx = bus.publisher::<SensorFrame>().map_err(|e| e.to_string())?;
        let never = AtomicBool::new(false);
        tx.wait_for_subscribers(1, Duration::from_secs(5), &never);
        let mut pacer = Pacer::new(PERIOD_NS, 0);
        for seq in 0..ticks + 20 {
            pacer.wait();
            let frame = SensorFrame {
                seq,
                acq_mono_ns: monotonic_ns(),
                ..SensorFrame::default()
            };
            tx.send(&frame).map_err(|e| e.to_string())?;
        }
        Ok(())
    });
    let mut h = histogram();
    let mut got = 0u64;
    while got < ticks + 20 {
        match rx.wait(Duration::from_secs(2), &stop) {
            Ok(Some(r)) => {
                got += 1;
                // the first frames teach the low-latency mode the schedule
                if got > 20 {
                    let _ = h.record(r.recv_mono_ns.saturating_sub(r.frame.acq_mono_ns).max(1));
                }
            }
            Ok(None) => break,
            Err(e) => return Err(e.to_string()),
        }
    }
    writer
        .join()
        .map_err(|_| "the publishing thread panicked".to_string())??;
    Ok(floor(
        &format!("bare iceoryx2 hop, {} (threads, nothing else)", mode_name(mode)),
        &h,
    ))
}

fn mode_name(mode: WaitMode) -> String {
    match mode {
        WaitMode::Event => "event".into(),
        WaitMode::LowLatency { lead_us } => format!("low-latency:{lead_us}"),
        WaitMode::BusyPoll => "busy-poll".into(),
    }
}

/// All floors, `seconds` each (at 1 kHz).
pub fn measure(seconds: f64) -> Result<Vec<Floor>, String> {
    let ticks = (seconds * 1000.0).round().max(100.0) as u64;
    eprintln!("machine floors: timer, pipe wake-up, bare iceoryx2 hops ({seconds} s each) ...");
    Ok(vec![
        timer(ticks, 0),
        timer(ticks, 60_000),
        pipe_wake(ticks)?,
        iceoryx2_hop(ticks, WaitMode::Event)?,
        iceoryx2_hop(ticks, WaitMode::LOW_LATENCY)?,
    ])
}

/// Prints the floors as a table.
pub fn print(floors: &[Floor]) -> Result<(), String> {
    outln!("| machine floor | p50 µs | p99 µs | max µs | samples |");
    outln!("|---|---|---|---|---|");
    for f in floors {
        outln!(
            "| {} | {:.1} | {:.1} | {:.1} | {} |",
            f.what,
            f.p50_us,
            f.p99_us,
            f.max_us,
            f.samples
        );
    }
    Ok(())
}
