//! The estimator and the classifier in one process (`leakwatch stage
//! estimator+classifier`, `leakwatch run --placement estimator+classifier`):
//! sensor frames in; estimates, events, health and both stages' stats out.
//! One iceoryx2 hop fewer between a sample and its event.
//!
//! ```text
//! leakwatch stage estimator+classifier --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```
//!
//! It runs the estimator's loop ([`bus::run_stage`], sensor frames to estimate
//! frames, with [`estimator::shell::estimate_frame`]) and hands each estimate,
//! still in its wire form, to the [`ClassifierNode`] the classifier process
//! runs: the events are those of the split placement, sample for sample. The
//! estimates are still published (the recorder logs them). The classifier's
//! stats frame gives as its latency the time from acquisition to the estimate
//! being ready, and counts as missing the frames the estimator missed.

use std::process::ExitCode;

use crate::node::ClassifierNode;
use bus::{run_stage_with, StageOptions};
use clap::Parser;
use frames::{EstimateFrame, Frame, SensorFrame};

#[derive(Parser)]
#[command(
    name = "estimator+classifier",
    about = "leakwatch estimator and classifier in one process: sensor frames -> estimates and leak events over iceoryx2"
)]
struct Args {
    #[command(flatten)]
    stage: bus::StageArgs,
}

fn run(args: Args) -> Result<(), String> {
    let mut stage = estimator::shell::load_stage(args.stage.config.as_deref())?;
    let cfg = crate::shell::load(args.stage.config.as_deref())?;
    let mode = args.stage.wait_mode()?;
    let stop = bus::stop_on_signals();
    let bus = args.stage.open_bus()?;
    let mut node = ClassifierNode::new(&bus, cfg, None)?;
    let mut opts = StageOptions::new(frames::stage::ESTIMATOR, mode);
    opts.exit_on_end_of_stream = args.stage.exit_at_end;
    opts.resume_after_seq = args.stage.resume_after_seq;
    let mut join = estimator::shell::Join::new(args.stage.resume_after_seq);
    // the first failure of the classifier's side ends the process (after the loop's next wait)
    let mut failed: Option<String> = None;
    // (in low-latency mode both filters take a throw-away step after each sleep,
    // just before the frame is due: the frame's own step finds them in the caches)
    let on_input =
        |stage: &mut filter::EstimatorStage, input: &bus::Received<SensorFrame>, out: &mut EstimateFrame| {
            estimator::shell::estimate_frame(stage, input, out, &mut join);
            if failed.is_none() {
                let ready = out.est_done_mono_ns;
                let done = node.tick(ready).map_err(|e| e.to_string()).and_then(|()| {
                    node.on_estimate(out, input.missing_before, ready, input.is_end_of_stream())
                });
                if let Err(e) = done {
                    failed = Some(e);
                    stop.store(true, std::sync::atomic::Ordering::Relaxed);
                }
            }
            true
        };
    let report = run_stage_with(
        &bus,
        &opts,
        stop,
        &mut stage,
        on_input,
        filter::EstimatorStage::warm_up,
    )
    .map_err(|e| e.to_string())?;
    if let Some(e) = failed {
        return Err(e);
    }
    let (read, events, missing) = node.finish()?;
    bus::say!(
        "estimator+classifier: estimator {report}\n  classifier: {read} estimates read, {events} events out, {missing} \
         missing"
    );
    if let Some(line) = estimator::shell::oil_stiffness(&stage) {
        bus::say!("estimator+classifier: {line}");
    }
    Ok(())
}

/// Runs the fused estimator+classifier process with command-line arguments
/// `args` (the first is the program name, as from `std::env::args_os`); the exit
/// code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    match run(Args::parse_from(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            bus::say!("estimator+classifier: error: {e}");
            ExitCode::FAILURE
        }
    }
}
