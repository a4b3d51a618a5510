//! The loop of a one-input, one-output pipeline stage over the bus.
//!
//! [`run_stage`] owns the plumbing so a stage shell is only its computation:
//!
//! ```text
//! let stop = bus::stop_on_signals();
//! let bus = Bus::open(&rig, BusConfig::from_env()?)?;
//! let opts = StageOptions::new(frames::stage::ESTIMATOR, WaitMode::Event);
//! let report = run_stage::<SensorFrame, EstimateFrame>(&bus, &opts, stop, |input, out| {
//!     *out = estimator.on_frame(&input.frame);        // fill the frame in shared memory
//!     out.est_recv_mono_ns = input.recv_mono_ns;
//!     out.est_done_mono_ns = bus::monotonic_ns();
//!     true                                             // publish it
//! })?;
//! crate::say!("{report}");
//! ```
//!
//! Per input frame: wait (in the chosen [`WaitMode`]), count it and any
//! sequence gap before it, record its latency (receive time − `acq_mono_ns`),
//! loan an output sample (initialised to `O::default()`), call `on_input`
//! with the input and the sample, time that call (the processing time), and
//! send + notify the sample if `on_input` returned true. If the input is the
//! last of its stream, the output is marked so too ([`Frame::mark_end_of_stream`]),
//! so the end propagates down the pipeline. Once a second a [`StatsFrame`]
//! is published on the stats topic. Nothing allocates per frame.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use frames::{Frame, StatsFrame};

use crate::stats::{Percentiles, StageStats};
use crate::{monotonic_ns, Bus, BusError, Received, WaitMode};

/// How [`run_stage`] runs.
#[derive(Debug, Clone)]
pub struct StageOptions {
    /// The stage id published in stats frames (one of [`frames::stage`]).
    pub stage: u32,
    /// How to wait for input.
    pub mode: WaitMode,
    /// Interval between stats frames.
    pub stats_period: Duration,
    /// Return after the input frame marked end-of-stream (else keep waiting
    /// for the next stream, e.g. a restarted acquisition).
    pub exit_on_end_of_stream: bool,
    /// The stage's previous process (before a restart) handled the input up to
    /// this sequence number: the frames missing before the first one received
    /// are a gap (see [`crate::Subscriber::resume_after`]). `None`: a fresh start.
    pub resume_after_seq: Option<u64>,
}

impl StageOptions {
    /// Stats at 1 Hz, keep running after the end of a stream.
    pub fn new(stage: u32, mode: WaitMode) -> StageOptions {
        StageOptions {
            stage,
            mode,
            stats_period: Duration::from_secs(1),
            exit_on_end_of_stream: false,
            resume_after_seq: None,
        }
    }
}

/// Why [`run_stage`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The stop flag was set (SIGINT/SIGTERM).
    Stopped,
    /// The input stream ended and [`StageOptions::exit_on_end_of_stream`] was set.
    EndOfStream,
}

/// What a stage did, for its exit message.
#[derive(Debug, Clone)]
pub struct StageReport {
    /// Input frames received.
    pub frames_in: u64,
    /// Output frames published.
    pub frames_out: u64,
    /// Input frames missing from the sequence.
    pub seq_gaps: u64,
    /// Times the input sequence restarted (a new upstream process).
    pub restarts: u64,
    /// Processing time of `on_input`, ns, over the whole run.
    pub proc: Percentiles,
    /// Receive time − `acq_mono_ns`, ns, over the whole run.
    pub latency: Percentiles,
    /// Why the loop ended.
    pub stopped_by: StopReason,
}

impl std::fmt::Display for StageReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} in, {} out, {} missing, {} restarts ({:?})\n  processing: {}\n  latency since acquisition: {}",
            self.frames_in,
            self.frames_out,
            self.seq_gaps,
            self.restarts,
            self.stopped_by,
            self.proc,
            self.latency
        )
    }
}

/// Runs a stage that turns each `I` into at most one `O` (see the module
/// docs) until `stop` is set or, with `exit_on_end_of_stream`, the input
/// ends. `on_input` returns whether to publish the output it filled.
pub fn run_stage<I: Frame, O: Frame>(
    bus: &Bus,
    opts: &StageOptions,
    stop: &AtomicBool,
    mut on_input: impl FnMut(&Received<I>, &mut O) -> bool,
) -> Result<StageReport, BusError> {
    run_stage_with(
        bus,
        opts,
        stop,
        &mut (),
        |_, input, out| on_input(input, out),
        |_| {},
    )
}

/// [`run_stage`] over a state `state` that `on_input` and `warm_up` share:
/// in low-latency mode `warm_up` runs once before each expected frame, after
/// the wait's sleep ([`crate::Subscriber::wait_then`]), off the frame's path.
pub fn run_stage_with<I: Frame, O: Frame, S>(
    bus: &Bus,
    opts: &StageOptions,
    stop: &AtomicBool,
    state: &mut S,
    mut on_input: impl FnMut(&mut S, &Received<I>, &mut O) -> bool,
    mut warm_up: impl FnMut(&mut S),
) -> Result<StageReport, BusError> {
    let mut rx = bus.subscriber::<I>(opts.mode)?;
    if let Some(seq) = opts.resume_after_seq {
        rx.resume_after(seq);
    }
    let mut tx = bus.publisher::<O>()?;
    let mut stats_tx = bus.publisher::<StatsFrame>()?;
    let mut stats = StageStats::new(opts.stage);
    let period_ns = opts.stats_period.as_nanos().max(1) as u64;
    let mut next_stats = monotonic_ns() + period_ns;

    let stopped_by = loop {
        let now = monotonic_ns();
        if now >= next_stats {
            stats_tx.send(&stats.take_frame())?;
            next_stats = (next_stats + period_ns).max(now + 1);
        }
        let timeout = Duration::from_nanos(next_stats.saturating_sub(now));
        let Some(input) = rx.wait_then(timeout, stop, &mut || warm_up(state))? else {
            if stop.load(Ordering::Relaxed) {
                break StopReason::Stopped;
            }
            continue;
        };
        stats.frames_in += 1;
        stats.seq_gaps += input.missing_before;
        if let Some(acq) = input.acq_mono_ns() {
            if acq > 0 && input.recv_mono_ns >= acq {
                stats.record_latency_ns(input.recv_mono_ns - acq);
            }
        }
        let eos = input.is_end_of_stream();
        let mut proc_ns = 0;
        let sent = tx.send_with(|out| {
            let t0 = monotonic_ns();
            let publish = on_input(state, &input, out);
            proc_ns = monotonic_ns() - t0;
            if publish && eos {
                out.mark_end_of_stream();
            }
            publish
        })?;
        stats.record_proc_ns(proc_ns);
        stats.frames_out += sent as u64;
        if eos && opts.exit_on_end_of_stream {
            break StopReason::EndOfStream;
        }
    };
    stats_tx.send(&stats.take_frame())?;
    Ok(StageReport {
        frames_in: stats.frames_in,
        frames_out: stats.frames_out,
        seq_gaps: stats.seq_gaps,
        restarts: rx.restarts(),
        proc: stats.proc_total(),
        latency: stats.latency_total(),
        stopped_by,
    })
}
