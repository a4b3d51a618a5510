//! The `estimator` process: sensor frames in, estimate frames out, over
//! iceoryx2 (a thin shell around [`estimator::EstimatorStage`]).
//!
//! ```text
//! estimator --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```

use std::path::Path;
use std::process::ExitCode;

use crate::wire::EstimateWire;
use crate::{EstimatorStage, StageEstimate, Tuning, FLAG_AFTER_GAP, FLAG_RESET};
use bus::{run_stage_with, Received, StageOptions};
use clap::Parser;
use frames::{EstimateFrame, SensorFrame};
use model::{ActuatorParams, Sample};
use serde::Deserialize;

#[derive(Parser)]
#[command(
    name = "estimator",
    about = "leakwatch estimator stage: sensor frames -> EKF estimates over iceoryx2"
)]
struct Args {
    #[command(flatten)]
    stage: bus::StageArgs,
}

/// The sections of the configuration this stage reads; the rest belongs to others.
#[derive(Debug, Deserialize)]
#[serde(default)]
struct StageConfig {
    model: ActuatorParams,
    estimator: Tuning,
    leak_filter: Tuning,
}

impl Default for StageConfig {
    fn default() -> Self {
        StageConfig {
            model: ActuatorParams::default(),
            estimator: Tuning::thesis(),
            leak_filter: Tuning::sensor_derived(),
        }
    }
}

/// The estimator stage the configuration file `path` describes (`[model]`,
/// `[estimator]`, `[leak_filter]`; the defaults without a file).
pub fn load_stage(path: Option<&Path>) -> Result<EstimatorStage, String> {
    let cfg = load(path)?;
    EstimatorStage::new(cfg.model, cfg.leak_filter, cfg.estimator)
}

/// Where an estimator process joins its sensor stream.
#[derive(Debug, Clone, Copy)]
pub struct Join {
    /// No frame estimated yet.
    first: bool,
    /// The frame the stage's previous process handled last (a restart).
    resumed_after: Option<u64>,
}

impl Join {
    /// A process that takes over after frame `resumed_after` (a restart), or
    /// starts afresh (`None`).
    pub fn new(resumed_after: Option<u64>) -> Join {
        Join {
            first: true,
            resumed_after,
        }
    }
}

/// The estimator's work on one sensor frame, whichever process runs it: the
/// estimate of `input` written into `out` (sequence number, clocks, both filters).
/// The first estimate of a process that joins a stream already running (a
/// restart, `join` resumed; or a first frame after frame 0: a stage swapped by
/// hand) is marked reset and after-gap, as its filter starts again without the
/// frames before (said so on stderr, once).
#[inline]
pub fn estimate_frame(
    stage: &mut EstimatorStage,
    input: &Received<SensorFrame>,
    out: &mut EstimateFrame,
    join: &mut Join,
) {
    let mut e = stage.on_sample(&Sample::from(&input.frame));
    if std::mem::take(&mut join.first) && (join.resumed_after.is_some() || input.seq > 0) {
        mark_restart(&mut e);
        match join.resumed_after {
            Some(last) => eprintln!(
                "estimator: restarted after frame {last}: {} frames not estimated before frame {} (a gap); its \
                 estimate is marked reset and after-gap",
                input.missing_before, input.seq
            ),
            None => eprintln!(
                "estimator: joined the stream at frame {}: its estimate is marked reset and after-gap",
                input.seq
            ),
        }
    }
    out.seq = input.seq;
    out.acq_mono_ns = input.acq_mono_ns;
    out.est_recv_mono_ns = input.recv_mono_ns;
    e.write_frame(out);
    out.est_done_mono_ns = bus::monotonic_ns();
}

/// What the leak filter of `stage` makes of the oil's stiffness now, as a line for
/// the process log (printed at exit); `None` if it does not estimate it.
pub fn oil_stiffness(stage: &EstimatorStage) -> Option<String> {
    let leak = stage.leak();
    let (theta, sigma) = leak.bulk_scale()?;
    crate::oil_stiffness_line(theta, sigma, leak.model().params.bulk_modulus_pa)
}

fn load(path: Option<&Path>) -> Result<StageConfig, String> {
    let Some(path) = path else {
        return Ok(StageConfig::default());
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("cannot read config {}: {e}", path.display()))?;
    toml::from_str(&text).map_err(|e| format!("config {}: {}", path.display(), e.message().trim()))
}

fn run(args: Args) -> Result<(), String> {
    let mut stage = load_stage(args.stage.config.as_deref())?;
    let mode = args.stage.wait_mode()?;
    let stop = bus::stop_on_signals();
    let bus = args.stage.open_bus()?;
    let mut opts = StageOptions::new(frames::stage::ESTIMATOR, mode);
    opts.exit_on_end_of_stream = args.stage.exit_at_end;
    opts.resume_after_seq = args.stage.resume_after_seq;
    // the first estimate of one that joins a running stream says that its filter started again
    let mut join = Join::new(args.stage.resume_after_seq);
    // (in low-latency mode both filters take a throw-away step after each sleep,
    // just before the frame is due: the frame's own step finds them in the caches)
    let report = run_stage_with::<SensorFrame, EstimateFrame, _>(
        &bus,
        &opts,
        stop,
        &mut stage,
        |stage, input, out| {
            estimate_frame(stage, input, out, &mut join);
            true
        },
        EstimatorStage::warm_up,
    )
    .map_err(|e| e.to_string())?;
    eprintln!("estimator: {report}");
    if let Some(line) = oil_stiffness(&stage) {
        eprintln!("estimator: {line}");
    }
    Ok(())
}

/// Marks the first estimate of a restarted estimator: both filters started
/// again (reset) after frames they did not see (after-gap).
fn mark_restart(e: &mut StageEstimate) {
    for f in [&mut e.leak, &mut e.thesis] {
        f.flags |= FLAG_RESET | FLAG_AFTER_GAP;
    }
}

/// Runs the estimator process with command-line arguments `args` (the first is the
/// program name, as from `std::env::args_os`); the exit code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    match run(Args::parse_from(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("estimator: error: {e}");
            ExitCode::FAILURE
        }
    }
}
