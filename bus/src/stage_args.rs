//! The command-line arguments every processing stage takes (the estimator, the
//! classifier, and the two in one process), defined once and flattened into
//! each stage's own argument type.

use std::path::PathBuf;

use crate::{Bus, BusConfig, WaitMode};

/// Arguments common to the processing stages.
#[derive(Debug, Clone, clap::Args)]
pub struct StageArgs {
    /// Rig id (service names are namespaced by it).
    #[arg(long, default_value = "rig1")]
    pub rig: String,
    /// leakwatch configuration file (each stage reads its own sections).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// How to wait for input: event, low-latency[:LEAD_US] or busy-poll.
    #[arg(long, default_value = "event")]
    pub mode: String,
    /// Exit when the input stream ends (default: wait for the next stream).
    #[arg(long)]
    pub exit_at_end: bool,
    /// This process takes over from one that handled the stream up to this
    /// sequence number (a restart): what lies between is counted as a gap, and
    /// its first output is marked as after a gap (an estimator's also as a
    /// reset: the classifier takes no evidence until the new filter converges).
    #[arg(long)]
    pub resume_after_seq: Option<u64>,
}

impl StageArgs {
    /// The wait mode `--mode` names; the error names the value.
    pub fn wait_mode(&self) -> Result<WaitMode, String> {
        WaitMode::parse(&self.mode).map_err(|e| format!("--mode {}: {e}", self.mode))
    }

    /// Opens the rig's bus with the environment's settings (`LEAKWATCH_IOX_PREFIX`).
    pub fn open_bus(&self) -> Result<Bus, String> {
        let config = BusConfig::from_env().map_err(|e| e.to_string())?;
        Bus::open(&self.rig, config).map_err(|e| e.to_string())
    }
}
