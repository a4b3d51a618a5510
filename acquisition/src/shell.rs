//! The acquisition process: reads a [`Source`] (the simulated rig, a CSV
//! file or a real rig's UDP sensor stream) and publishes one [`SensorFrame`]
//! per sample on `leakwatch/<rig>/frames`, with its [`StatsFrame`] once a
//! second. The simulated rig and files are paced on absolute deadlines (1 kHz
//! by default; `lat_ns_*` = lateness of the publish instants against the
//! schedule). The UDP stream is paced by its sender: each sample is published
//! as it arrives (`lat_ns_*` = datagram arrival to publish), and the closing
//! line on stderr counts lost, duplicated, late, malformed, rejected, foreign
//! and wrong-rate datagrams, sender restarts, time jumps and rate errors
//! ([`crate::UdpCounts`]; a rate error that still lasts is named on it). The
//! UDP source is told the rig's sample period (`[sim] sample_period_s`) and
//! the expected sender (`[udp] sender`). The last frame carries `END_OF_STREAM`;
//! the process then exits 0. SIGINT/SIGTERM stop it cleanly.
//!
//! A paced acquisition that could not run for longer than `--max-catch-up-ms`
//! (stopped, starved of CPU) does not publish the samples it missed in a
//! burst: as on a real rig, whose DAQ FIFO would have overflowed, they are
//! lost. The source moves on over the missed time without publishing, so rig
//! time stays wall time, and the next frame's `seq` jumps by the samples lost
//! (downstream reads that as a gap; the frame is flagged `AFTER_GAP`).
//!
//! A restarted acquisition continues the stream of the one before it
//! (`--resume-seq`, `--resume-t-s`, `--resume-mono-ns`: the last frame the
//! supervisor saw): the source moves over the samples already published
//! (the simulation is deterministic: same seed, same faults), the schedule
//! continues the earlier one, and the time it was down is a gap of as many
//! samples.
//!
//! A UDP stream ends with the sender's end of stream (its last sample flagged,
//! which is then the last frame), or with a sample-less end mark or the idle
//! timeout: then one more frame closes the stream, `END_OF_STREAM` at the last
//! sample's time with every channel NaN (the estimator skips it).
//!
//! ```text
//! acquisition --rig rig1 --scenario closed-loop-sine --seconds 10 --fault ext1:0.25@4
//! acquisition --rig rig1 --csv measured.csv --rate-hz 0      # as fast as possible
//! acquisition --rig rig1 --udp 0.0.0.0:5005 --config rig.toml # a real rig's DAQ
//! acquisition --rig rig1 --scenario loaded-sine --seconds 40 \
//!     --resume-seq 12345 --resume-t-s 12.345 --resume-mono-ns 81234567890  # a restart
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use crate::{Acquired, CsvSource, SimSource, Source, UdpOptions, UdpSource};
use bus::{monotonic_ns, Bus, BusConfig, Pacer, Publisher, StageStats};
use clap::Parser;
use frames::{sensor_flags, SensorFrame, StatsFrame};
use model::{Fault, FaultSchedule, Scenario, Simulator};

/// Publish rig samples on the leakwatch bus.
#[derive(Debug, Parser)]
#[command(name = "acquisition", version)]
struct Args {
    /// Rig id: names the services (`leakwatch/<rig>/...`), [A-Za-z0-9_-]{1,32}.
    #[arg(long)]
    rig: String,
    /// Scenario of the simulated rig (ignored with --csv).
    #[arg(long, default_value = "open-loop-sine")]
    scenario: String,
    /// Run length of the simulation, s (default: the scenario's own).
    #[arg(long)]
    seconds: Option<f64>,
    /// Noise and reference seed of the simulation.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Fault of the simulated rig, `KIND:SIZE@ONSET[,ramp=S][,law=sqrt|linear]` (repeatable).
    #[arg(long = "fault")]
    faults: Vec<String>,
    /// Replay this CSV file (t,u,x,p1,p2[,x_sp,f_load,ref,q_leak,temp_c]) instead of simulating.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Receive a real rig's UDP sensor stream on IP:PORT (format: frames/README.md,
    /// examples/udp) instead of simulating; published as it arrives (the sender paces).
    #[arg(long, value_name = "ADDR:PORT", conflicts_with_all = ["csv", "seconds", "faults", "scenario", "rate_hz"])]
    udp: Option<String>,
    /// With --udp: the stream ends when no datagram came for this long, s (counted
    /// from the first datagram; before it the acquisition waits until stopped).
    #[arg(long, default_value_t = 5.0)]
    udp_idle_timeout_s: f64,
    /// Publishing rate, Hz (0 = as fast as possible; not with --udp, whose sender paces).
    #[arg(long, default_value_t = 1000.0)]
    rate_hz: f64,
    /// Configuration file (TOML, the `leakwatch` format); its [rig] (or [model]),
    /// [sensors] and [sim] sections set up the simulated rig.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Wait until this many subscribers are on the frames topic before
    /// publishing (at most --wait-timeout-s).
    #[arg(long, default_value_t = 0)]
    wait_subscribers: usize,
    /// Longest wait for --wait-subscribers, s.
    #[arg(long, default_value_t = 10.0)]
    wait_timeout_s: f64,
    /// Spin this long before each deadline instead of sleeping, µs (less jitter, more CPU).
    #[arg(long, default_value_t = 0)]
    spin_us: u64,
    /// Stay alive this long after the last frame so subscribers can drain, ms.
    #[arg(long, default_value_t = 300)]
    linger_ms: u64,
    /// Lateness a paced source still catches up in a burst, ms (a DAQ FIFO's
    /// depth in time; within a subscriber's 256-frame buffer at 1 kHz); after a
    /// longer stall the missed samples are skipped (lost, a gap downstream).
    #[arg(long, default_value_t = 100.0)]
    max_catch_up_ms: f64,
    /// Continue a stream (a restarted acquisition): the sequence number of the
    /// last frame published before. Needs --resume-t-s and --resume-mono-ns.
    #[arg(long, requires_all = ["resume_t_s", "resume_mono_ns"])]
    resume_seq: Option<u64>,
    /// With --resume-seq: that frame's sample time, s (rig time); the source
    /// moves over every sample up to it without publishing.
    #[arg(long, requires = "resume_seq")]
    resume_t_s: Option<f64>,
    /// With --resume-seq: when that frame was published, `CLOCK_MONOTONIC` ns
    /// (its `acq_mono_ns`); the schedule continues from it.
    #[arg(long, requires = "resume_seq")]
    resume_mono_ns: Option<u64>,
}

/// Where a restarted acquisition takes over: the last frame published before.
#[derive(Debug, Clone, Copy)]
struct Resume {
    /// Its sequence number.
    seq: u64,
    /// Its sample time, s.
    t_s: f64,
    /// Its publish instant, `CLOCK_MONOTONIC` ns.
    mono_ns: u64,
}

impl Args {
    fn resume(&self) -> Result<Option<Resume>, String> {
        let (Some(seq), Some(t_s), Some(mono_ns)) = (self.resume_seq, self.resume_t_s, self.resume_mono_ns)
        else {
            return Ok(None);
        };
        if !t_s.is_finite() {
            return Err(format!("--resume-t-s {t_s}: must be a finite sample time, s"));
        }
        Ok(Some(Resume { seq, t_s, mono_ns }))
    }
}

fn build_source(args: &Args, stop: &'static AtomicBool) -> Result<Box<dyn Source>, String> {
    // the simulated rig, the physical ranges of measured data ([model]), the UDP stream's scaling ([udp])
    let cfg = config::Config::load_or_default(args.config.as_deref())?;
    if let Some(addr) = &args.udp {
        let idle = args.udp_idle_timeout_s;
        if !(idle > 0.0 && idle <= 1e6) {
            return Err(format!(
                "--udp-idle-timeout-s {idle}: must be a number of seconds in (0, 1e6]"
            ));
        }
        let addr = config::udp::parse_udp_address(addr).map_err(|e| format!("--udp {e}"))?;
        // measured data: the ranges of the rig the estimator models, as for replay
        let opts = UdpOptions {
            scaling: cfg.udp,
            limits: dataset::Limits::for_model(&cfg.model, cfg.sim.sample_period_s),
            idle_timeout: Duration::from_secs_f64(idle),
            stop: Some(stop),
            // the rig's sample period: a sender at another rate is a rate error
            sample_period_s: cfg.sim.sample_period_s,
            sender: cfg.udp.sender,
        };
        return Ok(Box::new(UdpSource::bind(addr, opts)?));
    }
    let rig = cfg.rig.clone().unwrap_or_else(|| cfg.model.clone());
    if let Some(csv) = &args.csv {
        let limits = dataset::Limits::for_model(&rig, cfg.sim.sample_period_s);
        let src = CsvSource::open(csv, limits).map_err(|e| e.to_string())?;
        return Ok(Box::new(src));
    }
    let max_seconds = args.seconds.unwrap_or(60.0);
    let scenario = Scenario::by_name(&args.scenario, args.seed, max_seconds).map_err(|e| e.to_string())?;
    let seconds = args.seconds.unwrap_or(scenario.default_seconds);
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(format!(
            "--seconds {seconds} must be a positive number of seconds"
        ));
    }
    let mut schedule = FaultSchedule::default();
    for spec in &args.faults {
        schedule
            .faults
            .push(Fault::parse(spec, &rig).map_err(|e| format!("--fault {spec}: {e}"))?);
    }
    let sim = Simulator::new(rig, cfg.sensors, cfg.sim, scenario, schedule, args.seed)
        .map_err(|e| e.to_string())?;
    Ok(Box::new(SimSource::new(sim, seconds)))
}

/// The next usable sample as a frame; unusable rows are reported on stderr,
/// counted, and flag the following frame as after a gap; samples missing
/// before a frame are added to `stats.seq_gaps`.
fn next_frame(src: &mut dyn Source, unusable: &mut u64, stats: &mut StageStats) -> Option<SensorFrame> {
    let mut flags = 0;
    loop {
        match src.next_item()? {
            Acquired::Sample(s) => {
                return Some(SensorFrame {
                    flags,
                    ..SensorFrame::from(&s)
                })
            }
            Acquired::AfterGap { sample, missing } => {
                stats.seq_gaps += missing;
                return Some(SensorFrame {
                    flags: flags | sensor_flags::AFTER_GAP,
                    ..SensorFrame::from(&sample)
                });
            }
            Acquired::Unusable(why) => {
                *unusable += 1;
                if *unusable <= 10 {
                    bus::say!("acquisition: skipped {why}");
                }
                flags |= sensor_flags::AFTER_GAP;
            }
        }
    }
}

/// What a publishing loop did.
struct Published {
    frames: u64,
    unusable: u64,
    stats: StageStats,
}

/// Publishes a source the acquisition paces (simulated rig, file): each frame
/// on its deadline, the frame after next produced right after a publish, so
/// that the last frame is known and carries `END_OF_STREAM`. Deadlines the
/// pacer skipped after a stall drop as many samples (the last one is always
/// published); a resumed stream first moves over the samples published before.
fn publish_paced(
    args: &Args,
    resume: Option<Resume>,
    source: &mut dyn Source,
    tx: &mut Publisher<SensorFrame>,
    stats_tx: &mut Publisher<StatsFrame>,
    stop: &AtomicBool,
) -> Result<Published, String> {
    let period_ns = if args.rate_hz > 0.0 {
        (1e9 / args.rate_hz).round() as u64
    } else {
        0
    };
    let mut pacer =
        Pacer::new(period_ns, args.spin_us * 1000).skip_after((args.max_catch_up_ms * 1e6).round() as u64);
    let mut stats = StageStats::new(frames::stage::ACQUISITION);
    let mut unusable = 0u64;
    let mut seq = 0u64;
    let mut current = next_frame(source, &mut unusable, &mut stats);
    if let Some(r) = resume {
        // the samples up to the resume point were published by the process before
        let mut scratch = StageStats::new(frames::stage::ACQUISITION);
        let mut scratch_unusable = 0;
        let half_period_s = source.sample_period_s() / 2.0;
        let mut passed = 0u64;
        while current.as_ref().is_some_and(|f| f.t_s <= r.t_s + half_period_s) {
            current = next_frame(source, &mut scratch_unusable, &mut scratch);
            passed += 1;
        }
        bus::say!(
            "acquisition: resuming after frame {} (t = {} s): {passed} samples moved over",
            r.seq,
            r.t_s
        );
        seq = r.seq + 1;
        pacer = pacer.resume_after(r.mono_ns);
    }
    let mut following = next_frame(source, &mut unusable, &mut stats);
    let mut next_stats = monotonic_ns() + 1_000_000_000;
    let mut published = 0u64;

    while let Some(mut frame) = current {
        if stop.load(Ordering::Relaxed) {
            bus::say!("acquisition: stopped by signal after {published} frames");
            break;
        }
        let tick = pacer.wait();
        stats.record_latency_ns(tick.late_ns);
        stats.deadline_misses += tick.missed as u64;
        // the samples of skipped deadlines are lost (a real rig's would be)
        let mut dropped = 0u64;
        while dropped < tick.skipped {
            let Some(next) = following.take() else { break };
            frame = SensorFrame {
                flags: next.flags | frame.flags,
                ..next
            };
            following = next_frame(source, &mut unusable, &mut stats);
            dropped += 1;
        }
        if dropped > 0 {
            frame.flags |= sensor_flags::AFTER_GAP;
            stats.seq_gaps += dropped;
            seq += dropped;
            bus::say!(
                "acquisition: {} ms behind schedule (stopped, or restarted): {dropped} samples skipped, t = {:.3} s",
                tick.skipped * period_ns / 1_000_000,
                frame.t_s
            );
        }
        frame.seq = seq;
        if following.is_none() {
            frame.flags |= sensor_flags::END_OF_STREAM;
        }
        frame.acq_mono_ns = monotonic_ns();
        tx.send(&frame).map_err(|e| e.to_string())?;
        seq += 1;
        published += 1;
        stats.frames_out += 1;
        // produce the frame after next now, off the publish instant
        let t0 = monotonic_ns();
        current = following;
        following = next_frame(source, &mut unusable, &mut stats);
        let now = monotonic_ns();
        stats.record_proc_ns(now - t0);
        if now >= next_stats {
            stats_tx.send(&stats.take_frame()).map_err(|e| e.to_string())?;
            next_stats += 1_000_000_000;
        }
    }
    Ok(Published {
        frames: published,
        unusable,
        stats,
    })
}

/// Publishes a live source (the UDP stream) on arrival: no pacing, no
/// look-ahead. The sender's flagged last sample is the last frame; a stream
/// that ends otherwise (end mark, idle timeout) is closed by an
/// `END_OF_STREAM` frame at the last sample's time with every channel NaN; a
/// signal stops it without one, as for the other sources.
///
/// A resumed stream continues the sequence: the first frame's `seq` follows the
/// last one before by the sample periods between their times (at least one).
fn publish_live(
    resume: Option<Resume>,
    source: &mut dyn Source,
    tx: &mut Publisher<SensorFrame>,
    stats_tx: &mut Publisher<StatsFrame>,
    stop: &AtomicBool,
) -> Result<Published, String> {
    let mut stats = StageStats::new(frames::stage::ACQUISITION);
    let mut unusable = 0u64;
    let mut seq = 0u64;
    let mut published = 0u64;
    let mut pending_resume = resume;
    let mut last_t = f64::NAN;
    let mut closed = false;
    let mut next_stats = monotonic_ns() + 1_000_000_000;
    while let Some(mut frame) = next_frame(source, &mut unusable, &mut stats) {
        if let Some(r) = pending_resume.take() {
            let steps = ((frame.t_s - r.t_s) / source.sample_period_s()).round();
            let steps = if steps.is_finite() && steps >= 1.0 {
                steps.min(1e12) as u64
            } else {
                1
            };
            seq = r.seq + steps;
            if steps > 1 {
                stats.seq_gaps += steps - 1;
                frame.flags |= sensor_flags::AFTER_GAP;
            }
        }
        frame.seq = seq;
        if source.ended() {
            frame.flags |= sensor_flags::END_OF_STREAM;
            closed = true;
        }
        last_t = frame.t_s;
        frame.acq_mono_ns = monotonic_ns();
        tx.send(&frame).map_err(|e| e.to_string())?;
        if let Some(arrived) = source.arrival_mono_ns() {
            // latency: arrival to the publish instant; processing: arrival to published
            stats.record_latency_ns(frame.acq_mono_ns.saturating_sub(arrived));
            stats.record_proc_ns(monotonic_ns().saturating_sub(arrived));
        }
        seq += 1;
        published += 1;
        stats.frames_out += 1;
        stats.frames_in += 1;
        if frame.acq_mono_ns >= next_stats {
            stats_tx.send(&stats.take_frame()).map_err(|e| e.to_string())?;
            next_stats = frame.acq_mono_ns + 1_000_000_000;
        }
        if closed {
            break;
        }
    }
    if stop.load(Ordering::Relaxed) {
        bus::say!("acquisition: stopped by signal after {published} frames");
    } else if !closed && published > 0 {
        let end = SensorFrame {
            seq,
            t_s: last_t,
            flags: sensor_flags::END_OF_STREAM,
            acq_mono_ns: monotonic_ns(),
            ..SensorFrame::default()
        };
        tx.send(&end).map_err(|e| e.to_string())?;
        published += 1;
        stats.frames_out += 1;
    }
    Ok(Published {
        frames: published,
        unusable,
        stats,
    })
}

fn run(args: &Args) -> Result<(), String> {
    if !(args.rate_hz >= 0.0 && args.rate_hz.is_finite()) {
        return Err(format!(
            "--rate-hz {} must be ≥ 0 (0 = as fast as possible)",
            args.rate_hz
        ));
    }
    if !(args.max_catch_up_ms >= 0.0 && args.max_catch_up_ms <= 3.6e6) {
        return Err(format!(
            "--max-catch-up-ms {}: must be a number of milliseconds in [0, 3.6e6]",
            args.max_catch_up_ms
        ));
    }
    let resume = args.resume()?;
    let stop = bus::stop_on_signals();
    let mut source = build_source(args, stop)?;
    let bus =
        Bus::open(&args.rig, BusConfig::from_env().map_err(|e| e.to_string())?).map_err(|e| e.to_string())?;
    let mut tx = bus.publisher::<SensorFrame>().map_err(|e| e.to_string())?;
    let mut stats_tx = bus.publisher::<StatsFrame>().map_err(|e| e.to_string())?;
    if args.wait_subscribers > 0 {
        let timeout = Duration::from_secs_f64(args.wait_timeout_s.max(0.0));
        if !tx.wait_for_subscribers(args.wait_subscribers, timeout, stop) {
            return Err(format!(
                "{} subscriber(s) on leakwatch/{}/frames expected, {} after {} s",
                args.wait_subscribers,
                bus.rig(),
                tx.subscriber_count(),
                args.wait_timeout_s
            ));
        }
    }
    let live = source.is_live();
    if live {
        bus::say!(
            "acquisition: {} on rig {}, published as it arrives (the sender paces); waiting for datagrams",
            source.describe(),
            bus.rig()
        );
    } else {
        bus::say!(
            "acquisition: {} on rig {} at {} Hz",
            source.describe(),
            bus.rig(),
            args.rate_hz
        );
    }
    let mut p = if live {
        publish_live(resume, source.as_mut(), &mut tx, &mut stats_tx, stop)?
    } else {
        publish_paced(args, resume, source.as_mut(), &mut tx, &mut stats_tx, stop)?
    };
    stats_tx.send(&p.stats.take_frame()).map_err(|e| e.to_string())?;
    let (what, proc) = if live {
        (
            "datagram arrival to publish instant",
            "datagram arrival to published",
        )
    } else {
        ("schedule lateness", "sample production")
    };
    bus::say!(
        "acquisition: {} frames, {} unusable rows skipped, {} samples missing, {} deadline misses\n  {what}: {}\n  {proc}: {}",
        p.frames,
        p.unusable,
        p.stats.seq_gaps,
        p.stats.deadline_misses,
        p.stats.latency_total(),
        p.stats.proc_total()
    );
    if let Some(summary) = source.summary() {
        bus::say!("acquisition: {summary}");
    }
    // let subscribers take the last frames before the publisher goes away
    let linger_end = monotonic_ns() + args.linger_ms * 1_000_000;
    while monotonic_ns() < linger_end && !stop.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(10));
    }
    Ok(())
}

/// Runs the acquisition process with command-line arguments `args` (the first is the
/// program name, as from `std::env::args_os`); the exit code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    let args = Args::parse_from(args);
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            bus::say!("acquisition: error: {e}");
            ExitCode::FAILURE
        }
    }
}
