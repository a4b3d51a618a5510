//! The recording process: subscribes to every topic of a rig and writes them
//! into one MCAP log (see the `recorder` library).
//!
//! ```text
//! recorder --rig rig1 --out run.mcap
//! ```
//!
//! Every sensor frame, event, health, stats and gap record is logged; the
//! estimates every `--estimates-every`-th sample (default 100: 10 Hz at 1 kHz)
//! and whenever one marks a reset, a gap or the end of the stream: `leakwatch
//! replay` of the log (with its stored `--config`) gives every estimate again,
//! bit for bit. `--config FILE` stores the run's configuration in the log
//! (metadata record `leakwatch.config`, key `toml`).
//!
//! It stops cleanly on SIGINT/SIGTERM, or after the frames stream ends
//! (`END_OF_STREAM`) once the other topics have been quiet for the grace
//! period (the estimator and classifier have drained). `--keep-running`
//! records one stream after another until a signal. `--continues PART`
//! (given by `leakwatch run` to a restarted recorder, which writes
//! `run-N.mcap`) names the earlier parts of the log: the frames in none of
//! them are logged as one gap (see [`crate::resume`]). The recorder publishes
//! its own stats (stage 3): frames in = messages received, out = queued for
//! the writer (not the estimates left out), deadline misses = messages dropped because the disk stalled.
//!
//! Every hour it closes its file and continues in the next, `run.1.mcap`, ...
//! (see [`crate::parts`]), so its memory stays flat over days.
//!
//! A log it cannot write (a full disk, a file-size limit, an I/O error) ends it
//! with the line `recorder: error: cannot write the log FILE: REASON` and exit
//! status [`EXIT_LOG_UNWRITABLE`] (74), which `leakwatch run` does not restart.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Duration;

use crate::resume::{existing_parts, Continuation};
use crate::{Entry, GapRecord, LogWriter, RecorderError, WriterOptions};
use bus::{monotonic_ns, say, Bus, BusConfig, Received, StageStats, Subscriber, WaitMode};
use clap::Parser;
use frames::{EstimateFrame, Frame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame};

/// Exit status of a recorder that cannot write its log (a full disk, a file too
/// large, an I/O error; `EX_IOERR` of sysexits.h): a recorder started again on
/// the same disk would fail the same way, so `leakwatch run` does not restart it.
/// Its last line on stderr names the file and the reason.
pub const EXIT_LOG_UNWRITABLE: u8 = 74;

/// The first words of the recorder's line on stderr that names a log it cannot write.
pub const LOG_UNWRITABLE_LINE: &str = "recorder: error: cannot write the log";

/// Why the recorder stopped with an error.
#[derive(Debug)]
enum Failure {
    /// The log cannot be written: restarting does not help.
    Log(RecorderError),
    /// Anything else (the bus, arguments, an earlier part).
    Other(String),
}

impl From<String> for Failure {
    fn from(e: String) -> Self {
        Failure::Other(e)
    }
}

impl From<RecorderError> for Failure {
    fn from(e: RecorderError) -> Self {
        if e.is_write_error() {
            Failure::Log(e)
        } else {
            Failure::Other(e.to_string())
        }
    }
}

/// Record every topic of a rig into an MCAP file.
#[derive(Debug, Parser)]
#[command(name = "recorder", version)]
struct Args {
    /// Rig id ([A-Za-z0-9_-]{1,32}).
    #[arg(long)]
    rig: String,
    /// The log file to write (MCAP; an existing file only with --force; never through a symbolic link).
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing log file.
    #[arg(long)]
    force: bool,
    /// After the frames stream ended, stop once no frame, estimate, event or
    /// health message came for this long, ms.
    #[arg(long, default_value_t = 1000)]
    grace_ms: u64,
    /// Do not stop at the end of a stream; record until SIGINT/SIGTERM.
    #[arg(long)]
    keep_running: bool,
    /// Target uncompressed chunk size, KiB (a killed recorder loses at most one chunk).
    #[arg(long, default_value_t = 1024)]
    chunk_kib: u64,
    /// Time between two drains of every topic, ms. The recorder needs no low
    /// latency: waking once per batch instead of once per frame keeps it off the
    /// CPU at the instant the estimator wakes for the same frame. Must stay well
    /// below the subscriber buffer (256 frames = 256 ms at 1 kHz).
    #[arg(long, default_value_t = 10)]
    batch_ms: u64,
    /// Log every N-th estimate (by sequence number; 1: every one) and every one
    /// that marks a reset, a gap or the end of the stream. 100 is 10 Hz at 1 kHz.
    #[arg(long, default_value_t = 100)]
    estimates_every: u64,
    /// The configuration of the run (TOML), stored in the log as the metadata
    /// record `leakwatch.config` (key `toml`) for `leakwatch info` and replay.
    #[arg(long)]
    config: Option<PathBuf>,
    /// An earlier part of this run's log, written by a recorder that was killed
    /// (repeat, earliest first): this part continues it, and the frames in no
    /// part are recorded as a gap (see `recorder::resume`).
    #[arg(long = "continues", value_name = "PART")]
    continues: Vec<PathBuf>,
}

/// Whether an estimate goes into the log: every `every`-th by sequence number,
/// and every one that marks a reset, a gap or the end of its stream.
pub fn keep_estimate(e: &EstimateFrame, every: u64) -> bool {
    const MARKS: u32 = frames::estimate_flags::RESET
        | frames::estimate_flags::AFTER_GAP
        | frames::estimate_flags::END_OF_STREAM;
    every <= 1 || e.seq.is_multiple_of(every) || e.flags & MARKS != 0
}

/// One subscription and how its frames become log entries (`None`: not logged).
struct Topic<T: Frame> {
    rx: Subscriber<T>,
    entry: Box<dyn Fn(T, u64) -> Option<Entry>>,
    /// The first frame received: sequence number and receive time, ns.
    first: Option<(u64, u64)>,
}

impl<T: Frame> Topic<T> {
    fn new(bus: &Bus, entry: impl Fn(T, u64) -> Option<Entry> + 'static) -> Result<Self, String> {
        // the recorder drains every topic once per batch; it never waits on one
        Ok(Topic {
            rx: bus.subscriber::<T>(WaitMode::Event).map_err(|e| e.to_string())?,
            entry: Box::new(entry),
            first: None,
        })
    }

    /// Queues one received frame (and the gap before it, if any).
    fn log(
        &mut self,
        r: &Received<T>,
        writer: &mut LogWriter,
        stats: &mut StageStats,
    ) -> Result<(), Failure> {
        stats.frames_in += 1;
        if self.first.is_none() {
            self.first = r.seq().map(|s| (s, r.recv_mono_ns));
        }
        if r.missing_before > 0 {
            stats.seq_gaps += r.missing_before;
            let got = r.seq().unwrap_or(0);
            let gap = GapRecord {
                topic: T::TOPIC,
                expected_seq: got - r.missing_before,
                got_seq: got,
                missing: r.missing_before,
                recv_mono_ns: r.recv_mono_ns,
            };
            queue(writer, stats, Entry::Gap(gap))?;
        }
        if let Some(acq) = r.acq_mono_ns() {
            if acq > 0 && r.recv_mono_ns >= acq {
                stats.record_latency_ns(r.recv_mono_ns - acq);
            }
        }
        match (self.entry)(r.frame, r.recv_mono_ns) {
            Some(entry) => queue(writer, stats, entry),
            // an estimate left out by --estimates-every
            None => Ok(()),
        }
    }

    /// Logs everything buffered; returns how many frames and whether one ended its stream.
    fn drain(&mut self, writer: &mut LogWriter, stats: &mut StageStats) -> Result<(u64, bool), Failure> {
        let mut n = 0;
        let mut eos = false;
        while let Some(r) = self.rx.try_receive().map_err(|e| e.to_string())? {
            self.log(&r, writer, stats)?;
            eos |= r.is_end_of_stream();
            n += 1;
        }
        Ok((n, eos))
    }
}

fn queue(writer: &mut LogWriter, stats: &mut StageStats, entry: Entry) -> Result<(), Failure> {
    if writer.write(entry)? {
        stats.frames_out += 1;
    } else {
        stats.deadline_misses += 1;
    }
    Ok(())
}

/// Logs the frames a continued log lost (in no part) as a gap.
fn log_continuation_gap(
    gap: Option<GapRecord>,
    writer: &mut LogWriter,
    stats: &mut StageStats,
) -> Result<(), Failure> {
    if let Some(g) = gap {
        stats.seq_gaps += g.missing;
        queue(writer, stats, Entry::Gap(g))?;
    }
    Ok(())
}

fn run(args: &Args) -> Result<(), Failure> {
    let stop = bus::stop_on_signals();
    let bus_cfg = BusConfig::from_env().map_err(|e| e.to_string())?;
    // the run's one time base (LEAKWATCH_EPOCH_OFFSET_NS), before any message
    let epoch_offset_ns = bus::init_epoch_offset().map_err(|e| e.to_string())?;
    let bus = Bus::open(&args.rig, bus_cfg).map_err(|e| e.to_string())?;
    if args.estimates_every == 0 {
        return Err("--estimates-every 0: must be 1 (every estimate) or more"
            .to_string()
            .into());
    }
    let config_toml = match &args.config {
        Some(p) => Some(std::fs::read_to_string(p).map_err(|e| format!("--config {}: {e}", p.display()))?),
        None => None,
    };
    let every = args.estimates_every;
    let mut frames_t = Topic::<SensorFrame>::new(&bus, |f, t| Some(Entry::Frame(f, t)))?;
    let mut estimates_t = Topic::<EstimateFrame>::new(&bus, move |f, t| {
        keep_estimate(&f, every).then_some(Entry::Estimate(f, t))
    })?;
    let mut events_t = Topic::<LeakEventFrame>::new(&bus, |f, t| Some(Entry::Event(f, t)))?;
    let mut health_t = Topic::<HealthFrame>::new(&bus, |f, t| Some(Entry::Health(f, t)))?;
    let mut stats_t = Topic::<StatsFrame>::new(&bus, |f, t| Some(Entry::Stats(f, t)))?;
    let mut stats_tx = bus.publisher::<StatsFrame>().map_err(|e| e.to_string())?;

    let metadata = BTreeMap::from([
        ("rig".to_string(), bus.rig().to_string()),
        ("recorder_pid".to_string(), std::process::id().to_string()),
        (
            "command".to_string(),
            std::env::args().collect::<Vec<_>>().join(" "),
        ),
        ("estimates_every".to_string(), every.to_string()),
    ]);
    let options = WriterOptions {
        chunk_size: args.chunk_kib.max(1) * 1024,
        metadata,
        config_toml,
        overwrite: args.force,
        rig: bus.rig().to_string(),
        epoch_offset_ns: Some(epoch_offset_ns),
        ..WriterOptions::default()
    };
    let mut writer = LogWriter::create(&args.out, options)?;
    say!("recorder: rig {} -> {}", bus.rig(), args.out.display());
    let mut continuation = if args.continues.is_empty() {
        None
    } else {
        Some(Continuation::start(existing_parts(&args.continues, &args.out))?)
    };

    let mut stats = StageStats::new(frames::stage::RECORDER);
    let mut next_stats = monotonic_ns() + 1_000_000_000;
    let mut ended_at: Option<u64> = None;
    let mut last_data = monotonic_ns();
    let grace_ns = args.grace_ms * 1_000_000;
    if args.batch_ms == 0 || args.batch_ms > 100 {
        return Err(format!("--batch-ms {}: must be 1 to 100 ms", args.batch_ms).into());
    }
    let batch = Duration::from_millis(args.batch_ms);
    let reason = loop {
        if stop.load(Ordering::Relaxed) {
            break "signal";
        }
        // sleep one batch, then take everything buffered on every topic
        std::thread::sleep(batch);
        let t0 = monotonic_ns();
        let (mut n, eos) = frames_t.drain(&mut writer, &mut stats)?;
        n += estimates_t.drain(&mut writer, &mut stats)?.0;
        n += events_t.drain(&mut writer, &mut stats)?.0;
        n += health_t.drain(&mut writer, &mut stats)?.0;
        stats_t.drain(&mut writer, &mut stats)?;
        if let Some(gap) = continuation.as_mut().and_then(|c| c.gap(frames_t.first, false)) {
            continuation = None;
            log_continuation_gap(gap, &mut writer, &mut stats)?;
        }
        let now = monotonic_ns();
        if n > 0 {
            stats.record_proc_ns(now - t0);
            last_data = now;
        }
        if eos && !args.keep_running {
            ended_at.get_or_insert(now);
        }
        if now >= next_stats {
            stats_tx.send(&stats.take_frame()).map_err(|e| e.to_string())?;
            next_stats += 1_000_000_000;
        }
        if ended_at.is_some() && now.saturating_sub(last_data) >= grace_ns {
            break "end of stream";
        }
    };
    if let Some(gap) = continuation.as_mut().and_then(|c| c.gap(frames_t.first, true)) {
        log_continuation_gap(gap, &mut writer, &mut stats)?;
    }
    // the last stats frame goes into the log too
    let last = stats.take_frame();
    stats_tx.send(&last).map_err(|e| e.to_string())?;
    writer.write(Entry::Stats(last, monotonic_ns()))?;
    let summary = writer.finish()?;
    say!(
        "recorder: stopped by {reason}; {} bytes in {} files, messages {:?}, {} dropped, {} missing from \
         sequences\n  latency since acquisition: {}",
        summary.bytes,
        summary.parts.len(),
        summary.messages,
        summary.dropped,
        stats.seq_gaps,
        stats.latency_total()
    );
    Ok(())
}

/// Runs the recorder process with command-line arguments `args` (the first is the
/// program name, as from `std::env::args_os`); the exit code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    let args = Args::parse_from(args);
    // A log that outgrows the file-size limit (RLIMIT_FSIZE) is a write error that
    // names the file (EFBIG), not a silent death by SIGXFSZ.
    // SAFETY: setting a signal's disposition to SIG_IGN touches no memory.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Log(e)) => {
            // the file and the reason, e.g. `DIR/run.mcap: No space left on device (os error 28)`
            say!("{LOG_UNWRITABLE_LINE} {e}; stopping (a restart cannot help until the disk has room)");
            ExitCode::from(EXIT_LOG_UNWRITABLE)
        }
        Err(Failure::Other(e)) => {
            say!("recorder: error: {e}");
            ExitCode::FAILURE
        }
    }
}
