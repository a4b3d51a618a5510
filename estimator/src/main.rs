//! The `estimator` process: sensor frames in, estimate frames out, over
//! iceoryx2 (a thin shell around [`estimator::EstimatorStage`]).
//!
//! ```text
//! estimator --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use bus::{run_stage, Bus, BusConfig, StageOptions, WaitMode};
use clap::Parser;
use estimator::{EstimatorStage, StageEstimate, Tuning};
use frames::{estimate_flags, EstimateFrame, SensorFrame, THESIS_STATES};
use model::{ActuatorParams, Sample};
use serde::Deserialize;

#[derive(Parser)]
#[command(
    name = "estimator",
    about = "leakwatch estimator stage: sensor frames -> EKF estimates over iceoryx2"
)]
struct Args {
    /// Rig id (service names are namespaced by it).
    #[arg(long, default_value = "rig1")]
    rig: String,
    /// leakwatch configuration file ([model], [estimator], [leak_filter] are used).
    #[arg(long)]
    config: Option<PathBuf>,
    /// How to wait for frames: event, low-latency or busy-poll.
    #[arg(long, default_value = "event")]
    mode: String,
    /// Exit when the sensor stream ends (default: wait for the next stream).
    #[arg(long)]
    exit_at_end: bool,
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

fn load(path: Option<&Path>) -> Result<StageConfig, String> {
    let Some(path) = path else {
        return Ok(StageConfig::default());
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("cannot read config {}: {e}", path.display()))?;
    toml::from_str(&text).map_err(|e| format!("config {}: {}", path.display(), e.message().trim()))
}

/// The sample a sensor frame carries.
fn sample_of(f: &SensorFrame) -> Sample {
    Sample {
        t_s: f.t_s,
        u_v: f.u_v,
        x_m: f.x_m,
        p1_pa: f.p1_pa,
        p2_pa: f.p2_pa,
        x_sp_m: f.x_sp_m,
        f_load_n: f.f_load_n,
        ref_m: f.ref_m,
        q_leak_lpm: f.q_leak_lpm,
    }
}

fn flags_of(f: u32) -> u32 {
    let mut out = 0;
    if f & estimator::FLAG_RESET != 0 {
        out |= estimate_flags::RESET;
    }
    if f & estimator::FLAG_SKIPPED != 0 {
        out |= estimate_flags::SKIPPED;
    }
    if f & estimator::FLAG_CLAMPED != 0 {
        out |= estimate_flags::CLAMPED;
    }
    if f & estimator::FLAG_CONVERGING != 0 {
        out |= estimate_flags::CONVERGING;
    }
    if f & estimator::FLAG_AFTER_GAP != 0 {
        out |= estimate_flags::AFTER_GAP;
    }
    out
}

/// Fills an estimate frame (in shared memory) from the stage's output.
fn fill(out: &mut EstimateFrame, e: &StageEstimate) {
    let l = &e.leak;
    let t = &e.thesis;
    out.t_s = l.t_s;
    out.n_states = l.n_states;
    out.flags = flags_of(l.flags);
    out.state = l.state;
    out.state_sigma = l.sigma;
    out.residual = l.residual;
    out.innovation = l.innovation;
    out.innovation_sigma = l.innovation_sigma;
    out.measured = l.measured;
    out.u_v = l.u_v;
    out.nis = l.nis;
    out.mae_pa = l.mae_pa;
    out.th_flags = flags_of(t.flags);
    out.th_state.copy_from_slice(&t.state[..THESIS_STATES]);
    out.th_residual = t.residual;
    out.th_innovation = t.innovation;
    out.th_mae_pa = t.mae_pa;
    out.th_nis = t.nis;
}

fn run(args: Args) -> Result<(), String> {
    let cfg = load(args.config.as_deref())?;
    let mut stage = EstimatorStage::new(cfg.model, cfg.leak_filter, cfg.estimator)?;
    let mode = WaitMode::parse(&args.mode).map_err(|e| e.to_string())?;
    let stop = bus::stop_on_signals();
    let bus =
        Bus::open(&args.rig, BusConfig::from_env().map_err(|e| e.to_string())?).map_err(|e| e.to_string())?;
    let mut opts = StageOptions::new(frames::stage::ESTIMATOR, mode);
    opts.exit_on_end_of_stream = args.exit_at_end;
    let report = run_stage::<SensorFrame, EstimateFrame>(&bus, &opts, stop, |input, out| {
        let e = stage.on_sample(&sample_of(&input.frame));
        out.seq = input.seq;
        out.acq_mono_ns = input.acq_mono_ns;
        out.est_recv_mono_ns = input.recv_mono_ns;
        fill(out, &e);
        out.est_done_mono_ns = bus::monotonic_ns();
        true
    })
    .map_err(|e| e.to_string())?;
    eprintln!("estimator: {report}");
    Ok(())
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("estimator: error: {e}");
            ExitCode::FAILURE
        }
    }
}
