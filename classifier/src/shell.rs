//! The `classifier` process: estimate frames in, leak events (and a 10 Hz
//! health summary) out, over iceoryx2; a thin shell around
//! [`classifier::Classifier`].
//!
//! ```text
//! classifier --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Duration;

use crate::wire::EventWire;
use crate::{Classifier, ClassifierConfig, LeakEvent};
use bus::{monotonic_ns, Bus, BusConfig, StageStats, WaitMode};
use clap::Parser;
use estimator::wire::EstimateWire;
use estimator::StageEstimate;
use frames::{health_status, EstimateFrame, Frame, HealthFrame, LeakEventFrame, StatsFrame};
use serde::Deserialize;

#[derive(Parser)]
#[command(
    name = "classifier",
    about = "leakwatch classifier stage: estimates -> leak events over iceoryx2"
)]
struct Args {
    /// Rig id (service names are namespaced by it).
    #[arg(long, default_value = "rig1")]
    rig: String,
    /// leakwatch configuration file ([classifier] is used).
    #[arg(long)]
    config: Option<PathBuf>,
    /// How to wait for estimates: event, low-latency or busy-poll.
    #[arg(long, default_value = "event")]
    mode: String,
    /// Exit when the estimate stream ends (default: wait for the next stream).
    #[arg(long)]
    exit_at_end: bool,
    /// This process takes over from a classifier that had read the estimates up
    /// to this sequence number (a restart): the estimates between are counted
    /// as a gap (in its stats and log) and its first estimate is treated as
    /// after a gap (no evidence from it).
    #[arg(long)]
    resume_after_seq: Option<u64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct StageConfig {
    classifier: ClassifierConfig,
}

fn load(path: Option<&Path>) -> Result<ClassifierConfig, String> {
    let Some(path) = path else {
        return Ok(ClassifierConfig::default());
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("cannot read config {}: {e}", path.display()))?;
    let cfg: StageConfig =
        toml::from_str(&text).map_err(|e| format!("config {}: {}", path.display(), e.message().trim()))?;
    Ok(cfg.classifier)
}

/// Events found while handling one estimate (at most a few; no allocation).
struct Pending {
    events: [Option<LeakEvent>; 4],
    n: usize,
}

fn run(args: Args) -> Result<(), String> {
    let cfg = load(args.config.as_deref())?;
    let mut cls = Classifier::new(cfg)?;
    let mode = WaitMode::parse(&args.mode).map_err(|e| e.to_string())?;
    let stop = bus::stop_on_signals();
    let bus =
        Bus::open(&args.rig, BusConfig::from_env().map_err(|e| e.to_string())?).map_err(|e| e.to_string())?;
    let e = |e: bus::BusError| e.to_string();
    let mut rx = bus.subscriber::<EstimateFrame>(mode).map_err(e)?;
    if let Some(seq) = args.resume_after_seq {
        rx.resume_after(seq);
    }
    let mut first_after_restart = args.resume_after_seq;
    let mut events_tx = bus.publisher::<LeakEventFrame>().map_err(e)?;
    let mut health_tx = bus.publisher::<HealthFrame>().map_err(e)?;
    let mut stats_tx = bus.publisher::<StatsFrame>().map_err(e)?;
    let mut stats = StageStats::new(frames::stage::CLASSIFIER);
    let mut next_stats = monotonic_ns() + 1_000_000_000;
    let mut next_health_t = f64::NEG_INFINITY;
    let mut health_seq = 0;
    let mut pending = Pending {
        events: [None, None, None, None],
        n: 0,
    };
    loop {
        let now = monotonic_ns();
        if now >= next_stats {
            stats_tx.send(&stats.take_frame()).map_err(e)?;
            next_stats = (next_stats + 1_000_000_000).max(now + 1);
        }
        let Some(input) = rx
            .wait(Duration::from_nanos(next_stats.saturating_sub(now)), stop)
            .map_err(e)?
        else {
            if stop.load(Ordering::Relaxed) {
                break;
            }
            continue;
        };
        stats.frames_in += 1;
        stats.seq_gaps += input.missing_before;
        if let Some(last) = first_after_restart.take() {
            eprintln!(
                "classifier: restarted after estimate {last}: {} estimates not read before estimate {} (a gap)",
                input.missing_before, input.seq
            );
        }
        if input.acq_mono_ns > 0 && input.recv_mono_ns >= input.acq_mono_ns {
            stats.record_latency_ns(input.recv_mono_ns - input.acq_mono_ns);
        }
        let t0 = monotonic_ns();
        let se = StageEstimate::from_frame(&input.frame, input.missing_before);
        let last_t = se.leak.t_s;
        pending.n = 0;
        cls.on_stage(&se, |ev| {
            if pending.n < pending.events.len() {
                pending.events[pending.n] = Some(ev);
                pending.n += 1;
            }
        });
        let done = monotonic_ns();
        stats.record_proc_ns(done - t0);
        for ev in pending.events.iter_mut().take(pending.n) {
            let Some(ev) = ev.take() else { continue };
            let frame = ev.to_frame(input.seq, input.acq_mono_ns, done);
            events_tx.send(&frame).map_err(e)?;
            stats.frames_out += 1;
        }
        if se.leak.t_s >= next_health_t {
            next_health_t = se.leak.t_s + 0.1;
            health_seq += 1;
            let rise = cls.leak_size.rise_lpm(&se.leak);
            let active = u32::from(cls.leak_size.has_active_leak());
            let status = if active > 0 {
                health_status::LEAK
            } else if cls.leak_size.is_armed() {
                health_status::HEALTHY
            } else {
                health_status::WARMING_UP
            };
            let h = HealthFrame {
                seq: health_seq,
                mono_ns: monotonic_ns(),
                t_s: se.leak.t_s,
                status,
                active_events: active,
                leak_flow_lpm: rise,
                leak_flow_sigma_lpm: [
                    se.leak.sigma[7] * 6e4,
                    se.leak.sigma[8] * 6e4,
                    se.leak.sigma[9] * 6e4,
                ],
            };
            health_tx.send(&h).map_err(e)?;
        }
        if input.is_end_of_stream() {
            cls.finish(last_t, |ev| {
                let frame = ev.to_frame(input.seq, input.acq_mono_ns, monotonic_ns());
                let _ = events_tx.send(&frame);
            });
            if args.exit_at_end {
                break;
            }
            cls = Classifier::new(load(args.config.as_deref())?)?;
        }
    }
    stats_tx.send(&stats.take_frame()).map_err(e)?;
    eprintln!(
        "classifier: {} estimates in, {} events out, {} missing",
        stats.frames_in, stats.frames_out, stats.seq_gaps
    );
    Ok(())
}

/// Runs the classifier process with command-line arguments `args` (the first is the
/// program name, as from `std::env::args_os`); the exit code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    match run(Args::parse_from(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("classifier: error: {e}");
            ExitCode::FAILURE
        }
    }
}
