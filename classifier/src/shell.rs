//! The `classifier` process: estimate frames in, leak events (and a 10 Hz
//! health summary) out, over iceoryx2; a thin shell around
//! [`detect::Classifier`].
//!
//! ```text
//! classifier --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```

use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Duration;

use crate::node::ClassifierNode;
use bus::monotonic_ns;
use clap::Parser;
use detect::ClassifierConfig;
use frames::{EstimateFrame, Frame};

#[derive(Parser)]
#[command(
    name = "classifier",
    about = "leakwatch classifier stage: estimates -> leak events over iceoryx2"
)]
struct Args {
    #[command(flatten)]
    stage: bus::StageArgs,
}

/// The `[classifier]` settings of the configuration file `path` (the defaults
/// without one), with the rig facts the loader derives: the supply pressure
/// from `[model]` (or `[datasheet]`), the transducers' range from `[sensors]`.
pub(crate) fn load(path: Option<&Path>) -> Result<ClassifierConfig, String> {
    Ok(config::Config::load_or_default(path)?.classifier)
}

fn run(args: Args) -> Result<(), String> {
    let cfg = load(args.stage.config.as_deref())?;
    let mode = args.stage.wait_mode()?;
    let stop = bus::stop_on_signals();
    let bus = args.stage.open_bus()?;
    let e = |e: bus::BusError| e.to_string();
    let mut rx = bus.subscriber::<EstimateFrame>(mode).map_err(e)?;
    if let Some(seq) = args.stage.resume_after_seq {
        rx.resume_after(seq);
    }
    let mut node = ClassifierNode::new(&bus, cfg, args.stage.resume_after_seq)?;
    loop {
        let now = monotonic_ns();
        node.tick(now).map_err(e)?;
        let timeout = Duration::from_nanos(node.next_stats_ns().saturating_sub(now));
        let Some(input) = rx.wait(timeout, stop).map_err(e)? else {
            if stop.load(Ordering::Relaxed) {
                break;
            }
            continue;
        };
        let eos = input.is_end_of_stream();
        node.on_estimate(&input.frame, input.missing_before, input.recv_mono_ns, eos)?;
        if eos && args.stage.exit_at_end {
            break;
        }
    }
    let (read, events, missing) = node.finish()?;
    bus::say!("classifier: {read} estimates in, {events} events out, {missing} missing");
    Ok(())
}

/// Runs the classifier process with command-line arguments `args` (the first is the
/// program name, as from `std::env::args_os`); the exit code says whether it succeeded.
pub fn main(args: impl IntoIterator<Item = std::ffi::OsString>) -> ExitCode {
    match run(Args::parse_from(args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            bus::say!("classifier: error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The classifier process takes the rig facts from where the config writes
    /// them once (`[datasheet]`: the example lift's 21 MPa supply and 25 MPa
    /// transducers), as `leakwatch` does, not the thesis rig's defaults.
    #[test]
    fn the_stage_takes_the_rig_facts_from_the_datasheet() {
        let dir = std::env::temp_dir().join(format!("leakwatch-cls-ds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("lift.toml");
        std::fs::write(&path, config::init::template(&config::init::example(true))).expect("written");
        let cfg = load(Some(&path)).expect("loads");
        assert_eq!(
            (cfg.supply_pressure_pa, cfg.pressure_full_scale_pa),
            (21.0e6, 25.0e6)
        );
        let default = load(None).expect("defaults");
        assert_eq!(default.supply_pressure_pa, 13.8e6);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
