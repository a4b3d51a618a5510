//! The arguments of `leakwatch run` and the checks made on them before any stage starts.

use std::path::PathBuf;

/// What `leakwatch run` was asked to do.
#[derive(Debug, Clone)]
pub struct RunArgs {
    /// Simulated seconds (default 40).
    pub seconds: Option<f64>,
    /// Scenario (default loaded-sine).
    pub scenario: Option<String>,
    /// Faults (default: ext1:0.5lpm@20s when nothing else is given).
    pub faults: Vec<String>,
    /// Rig id.
    pub rig: String,
    /// Configuration file.
    pub config: Option<PathBuf>,
    /// Wait mode of the stages: event, low-latency or busy-poll.
    pub mode: String,
    /// Output directory (default ./leakwatch-run-YYYYMMDD-HHMMSS, its UTC start time: a new folder each run).
    pub out: Option<PathBuf>,
    /// Also report the thesis' MAE baseline detector's decisions.
    pub thesis_baseline: bool,
    /// Replace the outputs of an earlier run in the same directory (`--force`).
    pub force: bool,
    /// Where samples come from: `sim` (default, the simulated rig) or
    /// `udp://IP:PORT` (a real rig's UDP sensor stream).
    pub source: Option<String>,
    /// UDP stream: it ends when no datagram came for this long, s (default 5).
    pub udp_idle_timeout_s: Option<f64>,
    /// Where the stages run: `split` (default, a process each) or
    /// `estimator+classifier` (those two in one process).
    pub placement: Option<String>,
    /// `--live-view [PORT]`: serve the live view (0: the configured port, default 8765).
    pub live_view: Option<u16>,
    /// `--zenoh`: run the Zenoh gateway.
    pub zenoh: bool,
    /// `--zenoh-connect`: the gateway's endpoints instead of the config's.
    pub zenoh_connect: Vec<String>,
    /// `--runs-dir`: a new folder in it per run (not with `out`), the earlier ones pruned.
    pub runs_dir: Option<PathBuf>,
    /// `--keep-days`: with `runs_dir`, earlier runs older than this are removed, days.
    pub keep_days: Option<f64>,
    /// `--keep-gib`: with `runs_dir`, the runs' total size kept within this, GiB.
    pub keep_gib: Option<f64>,
    /// `--opcua [PORT]`: serve the OPC UA server (0: the configured port, default 4840).
    pub opcua: Option<u16>,
}

/// Where a run's samples come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunSource {
    /// The simulated rig.
    Sim,
    /// A real rig's UDP sensor stream received on this address.
    Udp(std::net::SocketAddr),
}

/// Parses `--source`: `sim` (or nothing) or `udp://IP:PORT`; the error names the problem.
pub fn parse_source(text: Option<&str>) -> Result<RunSource, String> {
    match text {
        None | Some("sim") => Ok(RunSource::Sim),
        Some(t) if t.starts_with("udp://") => config::udp::parse_udp_address(t)
            .map(RunSource::Udp)
            .map_err(|e| format!("--source {e}")),
        Some(t) => Err(format!(
            "--source {t}: expected `sim` (the simulated rig) or udp://IP:PORT (a rig's UDP sensor stream, \
             e.g. udp://0.0.0.0:5005)"
        )),
    }
}

/// Default idle timeout of a UDP stream, s.
pub const UDP_IDLE_TIMEOUT_S: f64 = 5.0;

/// Checks the arguments of a UDP run (before anything starts): no simulation
/// arguments, a valid idle timeout, an address this machine can listen on.
pub(super) fn check_udp_args(args: &RunArgs, addr: std::net::SocketAddr) -> Result<f64, String> {
    if args.scenario.is_some() || !args.faults.is_empty() || args.seconds.is_some() {
        return Err(format!(
            "--source udp://{addr}: --scenario, --fault and --seconds are for the simulated rig; a UDP stream \
             runs until its sender ends it or no datagram comes for --udp-idle-timeout-s"
        ));
    }
    let idle = args.udp_idle_timeout_s.unwrap_or(UDP_IDLE_TIMEOUT_S);
    if !(idle > 0.0 && idle <= 1e6) {
        return Err(format!(
            "--udp-idle-timeout-s {idle}: must be a number of seconds in (0, 1e6]"
        ));
    }
    // the acquisition stage binds it again at once
    std::net::UdpSocket::bind(addr)
        .map_err(|e| format!("--source udp://{addr}: cannot listen there: {e}"))?;
    Ok(idle)
}

/// The scenario `run` simulates by default (with the demonstration leak when no
/// fault or config is given).
pub const DEFAULT_SCENARIO: &str = "loaded-sine";
