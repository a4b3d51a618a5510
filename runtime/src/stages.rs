//! The stage processes: which they are, how this binary runs one
//! (`leakwatch stage NAME`), and how the supervisor starts and stops them.

use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use bus::say as errln;

/// A stage process of a run: what `leakwatch stage NAME` runs. The variants
/// are in the alphabetical order of their names, so a map keyed by them lists
/// the stages as one keyed by the names would.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Stage {
    /// Reads the rig (UDP) or simulates it and publishes sensor frames.
    Acquisition,
    /// Turns estimates into leak and sensor events.
    Classifier,
    /// Runs the filters on the sensor frames and publishes estimates.
    Estimator,
    /// The estimator and the classifier in one process (`--placement estimator+classifier`).
    EstimatorClassifier,
    /// Publishes the run to Zenoh (`[zenoh]`).
    Gateway,
    /// Serves the run to Foxglove (`[live_view]`).
    LiveView,
    /// Serves the rig's state and events over OPC UA (`[opcua]`).
    Opcua,
    /// Writes the log.
    Recorder,
}

impl Stage {
    /// Every stage process.
    pub const ALL: [Stage; 8] = [
        Stage::Acquisition,
        Stage::Classifier,
        Stage::Estimator,
        Stage::EstimatorClassifier,
        Stage::Gateway,
        Stage::LiveView,
        Stage::Opcua,
        Stage::Recorder,
    ];

    /// Its name: the argument of `leakwatch stage`, and its log's file name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Acquisition => "acquisition",
            Stage::Classifier => "classifier",
            Stage::Estimator => "estimator",
            Stage::EstimatorClassifier => "estimator+classifier",
            Stage::Gateway => "gateway",
            Stage::LiveView => "liveview",
            Stage::Opcua => "opcua",
            Stage::Recorder => "recorder",
        }
    }

    /// The stage named `name`, if there is one.
    pub fn parse(name: &str) -> Option<Stage> {
        Stage::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Whether its process publishes the run's events (the classifier, alone
    /// or with the estimator).
    pub fn classifies(self) -> bool {
        matches!(self, Stage::Classifier | Stage::EstimatorClassifier)
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The four stage processes of the split placement, in the order they start.
pub const STAGES: [Stage; 4] = [
    Stage::Recorder,
    Stage::Classifier,
    Stage::Estimator,
    Stage::Acquisition,
];

/// The live outputs a run starts (each when asked for).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Outputs {
    /// The Foxglove live view.
    pub live_view: bool,
    /// The Zenoh gateway.
    pub zenoh: bool,
    /// The OPC UA server.
    pub opcua: bool,
}

/// Whether `stage` is a live output (the live view, the Zenoh gateway, the OPC UA
/// server): optional, and not watched by the watchdog (they publish no stats).
pub(super) fn is_output(stage: Stage) -> bool {
    matches!(stage, Stage::LiveView | Stage::Gateway | Stage::Opcua)
}

/// The stages of a run in the order they start: the placement's processes, with the
/// live view, the Zenoh gateway and the OPC UA server (unsupervised by the watchdog:
/// they publish no stats) before the acquisition when asked for.
pub(super) fn run_stages(processes: &[Stage], outputs: Outputs) -> Vec<Stage> {
    // the placement's processes end with the acquisition, which starts last
    let (last, first) = processes
        .split_last()
        .map_or((None, processes), |(l, f)| (Some(*l), f));
    let mut v = first.to_vec();
    if outputs.live_view {
        v.push(Stage::LiveView);
    }
    if outputs.zenoh {
        v.push(Stage::Gateway);
    }
    if outputs.opcua {
        v.push(Stage::Opcua);
    }
    v.extend(last);
    v
}

/// Runs one stage process in this process: `args` is the stage's name followed by
/// its own arguments (`leakwatch stage NAME ARGS...`).
pub fn stage_main(args: &[std::ffi::OsString]) -> std::process::ExitCode {
    let argv = args.iter().cloned();
    let name = args.first().and_then(|n| n.to_str()).unwrap_or("");
    match Stage::parse(name) {
        Some(Stage::Acquisition) => acquisition::shell::main(argv),
        Some(Stage::Estimator) => estimator::shell::main(argv),
        Some(Stage::Classifier) => classifier::shell::main(argv),
        Some(Stage::EstimatorClassifier) => classifier::fused::main(argv),
        Some(Stage::Recorder) => recorder::shell::main(argv),
        Some(Stage::LiveView) => live::shell::liveview_main(argv),
        Some(Stage::Gateway) => live::shell::gateway_main(argv),
        Some(Stage::Opcua) => scada::shell::opcua_main(argv),
        None => {
            errln!(
                "leakwatch stage: unknown stage {name:?}; the stages are acquisition, estimator, classifier, recorder, \
                 liveview, gateway, opcua (and estimator+classifier, the two in one process)"
            );
            std::process::ExitCode::FAILURE
        }
    }
}

/// The program that runs the stages: this binary (`leakwatch stage NAME`), so an
/// installed `leakwatch` needs nothing beside it and `run` never builds anything.
pub fn stage_program() -> Result<PathBuf, String> {
    std::env::current_exe()
        .map_err(|e| format!("cannot locate the leakwatch binary to start its stages: {e}"))
}

/// The recorder's arguments with `--config DIR/config.toml` added when the run
/// wrote its configuration beside the log (`--out DIR/run.mcap`) and the
/// arguments name none: the log then holds the configuration it was made with.
fn with_run_config(stage: Stage, args: &[String]) -> Vec<String> {
    let mut out = args.to_vec();
    if stage != Stage::Recorder || args.iter().any(|a| a == "--config") {
        return out;
    }
    let log = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1));
    if let Some(cfg) = log
        .and_then(|l| Path::new(l).parent())
        .map(|d| d.join("config.toml"))
    {
        if cfg.is_file() {
            out.push("--config".into());
            out.push(cfg.display().to_string());
        }
    }
    out
}

pub(super) fn spawn(
    program: &Path,
    stage: Stage,
    args: &[String],
    prefix: &str,
    log: &Path,
    cpu: Option<usize>,
) -> Result<Child, String> {
    let args = &with_run_config(stage, args);
    // the outputs were checked at start (an earlier run's only with --force)
    let err = pipeline::out::create(log, true, &[])?;
    let mut cmd = Command::new(program);
    // The stage dies with its supervisor (SIGTERM when the supervisor's thread
    // that spawned it ends, whatever the cause, SIGKILL included).
    // SAFETY: prctl is async-signal-safe and touches no memory of the parent.
    // Pinned to `cpu` ([run] cpus) before it starts, so every thread it makes is too.
    // SAFETY: prctl and sched_setaffinity are async-signal-safe system calls and
    // touch no memory of the parent (the CPU set is built on the child's stack).
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM as libc::c_ulong, 0, 0, 0) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            if let Some(cpu) = cpu {
                let mut set: libc::cpu_set_t = std::mem::zeroed();
                libc::CPU_SET(cpu, &mut set);
                if libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
            }
            Ok(())
        });
    }
    cmd.arg("stage")
        .arg(stage.name())
        .args(args)
        .env(bus::PREFIX_ENV, prefix)
        // the run's time base (bus::init_epoch_offset at its start)
        .env(bus::EPOCH_OFFSET_ENV, bus::epoch_offset_ns().to_string())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(err)
        .spawn()
        .map_err(|e| format!("cannot start stage {stage} ({}): {e}", program.display()))
}

pub(super) fn terminate(child: &mut Child) {
    // SAFETY-free: kill(2) via libc with SIGTERM for a clean stop.
    let pid = child.id() as i32;
    unsafe {
        libc::kill(pid, libc::SIGTERM);
    }
}
