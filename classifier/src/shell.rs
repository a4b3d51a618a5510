//! The `classifier` process: estimate frames in, leak events (and a 10 Hz
//! health summary) out, over iceoryx2; a thin shell around
//! [`classifier::Classifier`].
//!
//! ```text
//! classifier --rig rig1 [--config leakwatch.toml] [--mode event|low-latency|busy-poll]
//! ```

use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Duration;

use crate::node::ClassifierNode;
use crate::ClassifierConfig;
use bus::monotonic_ns;
use clap::Parser;
use frames::{EstimateFrame, Frame};
use serde::Deserialize;

#[derive(Parser)]
#[command(
    name = "classifier",
    about = "leakwatch classifier stage: estimates -> leak events over iceoryx2"
)]
struct Args {
    #[command(flatten)]
    stage: bus::StageArgs,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
struct StageConfig {
    classifier: ClassifierConfig,
}

/// The `[classifier]` settings of the configuration file `path` (the defaults without one).
pub(crate) fn load(path: Option<&Path>) -> Result<ClassifierConfig, String> {
    let Some(path) = path else {
        return Ok(ClassifierConfig::default());
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("cannot read config {}: {e}", path.display()))?;
    let cfg: StageConfig =
        toml::from_str(&text).map_err(|e| format!("config {}: {}", path.display(), e.message().trim()))?;
    Ok(cfg.classifier)
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
