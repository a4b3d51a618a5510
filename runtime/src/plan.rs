//! What a run is, checked before any stage starts: its outputs, its plan
//! (scenario, seconds, faults, config), its iceoryx2 prefix, how each stage is
//! started, and what it says on the console first.

use std::path::Path;

use bus::WaitMode;
use config::Config;
use pipeline::out::outln;

use crate::args::{RunArgs, DEFAULT_SCENARIO};
use crate::launch::{is_log_part, Samples, StageArgs, FRAME_SUBSCRIBERS};
use crate::placement::Placement;

/// How each stage process of the run is started: its config file `cfg_path`,
/// the wait mode, the output directory, its sensor stream (UDP or the
/// simulated scenario `sim`: name, seconds, leak faults).
pub(crate) fn stage_args(
    args: &RunArgs,
    cfg_path: &Path,
    out_dir: &Path,
    cfg: &Config,
    udp: Option<(std::net::SocketAddr, f64)>,
    sim: (&str, f64, &[String]),
) -> StageArgs {
    let (scenario, seconds, faults) = sim;
    StageArgs {
        rig: args.rig.clone(),
        config: cfg_path.display().to_string(),
        mode: args.mode.clone(),
        out_dir: out_dir.to_path_buf(),
        force: args.force,
        frame_subscribers: FRAME_SUBSCRIBERS,
        spin_us: if args.mode.starts_with("low-latency") || args.mode == "busy-poll" {
            cfg.run.low_latency_spin_us
        } else {
            0
        },
        samples: match udp {
            Some((addr, idle_s)) => Samples::Udp { addr, idle_s },
            None => Samples::Sim {
                scenario: scenario.to_string(),
                seconds,
                faults: faults.to_vec(),
            },
        },
    }
}

/// Says on the console what the run watches (its sensor stream or simulated
/// scenario `sim`: name, seconds, leak faults, the demonstration) and how the
/// detector starts.
pub(crate) fn announce(
    args: &RunArgs,
    udp: Option<(std::net::SocketAddr, f64)>,
    placement: Placement,
    out_dir: &Path,
    cfg: &Config,
    sim: (&str, f64, &[String], bool),
) -> Result<(), String> {
    let (scenario, seconds, faults, demo) = sim;
    match udp {
        Some((addr, idle)) => outln!(
            "leakwatch run: rig {}, UDP sensor stream on {addr} (until the sender's end of stream or {idle} s \
             without datagrams), {} mode; output {}",
            args.rig,
            args.mode,
            out_dir.display()
        ),
        None => outln!(
            "leakwatch run: rig {}, scenario {scenario}, {seconds} s at 1 kHz, faults [{}], {} mode{}{}; output {}",
            args.rig,
            faults.join(", "),
            args.mode,
            match placement {
                Placement::Split => String::new(),
                p => format!(", {} in one process", p.name()),
            },
            if demo { ", off-nominal rig (demonstration)" } else { "" },
            out_dir.display()
        ),
    }
    if let Ok(c) = detect::Classifier::new(cfg.classifier.clone()) {
        outln!("note: {}", c.start_note());
    }
    Ok(())
}

/// The run's iceoryx2 prefix: a private one per run, unless the user names one
/// (to attach other tools; checked as it is read, its length against
/// `bus::MAX_PREFIX_LEN`).
pub(crate) fn run_prefix() -> Result<String, String> {
    Ok(match std::env::var(bus::PREFIX_ENV) {
        Ok(p) if !p.is_empty() => {
            bus::validate_prefix(&p).map_err(|e| e.to_string())?;
            p
        }
        _ => format!("run{}", std::process::id()),
    })
}

/// Refuses, before anything starts, to replace an earlier run's outputs in
/// `out_dir` without `force` (`inputs` never): the config, events, latency,
/// the log and its further parts, each process's log.
pub(crate) fn check_outputs(
    out_dir: &Path,
    processes: &[crate::stages::Stage],
    force: bool,
    inputs: &[&Path],
) -> Result<(), String> {
    let mut outputs: Vec<String> = [
        "config.toml",
        "events.json",
        "latency.json",
        "run.mcap",
        "metadata.yaml",
    ]
    .map(String::from)
    .into();
    outputs.extend(processes.iter().map(|n| format!("{n}.log")));
    // an earlier run's further log parts (its recorder was restarted): a restarted
    // recorder of this run must not find them in its way
    if let Ok(entries) = std::fs::read_dir(out_dir) {
        let names = entries.flatten().filter_map(|e| e.file_name().into_string().ok());
        outputs.extend(names.filter(|n| is_log_part(n)));
    }
    for name in outputs {
        pipeline::out::check(&out_dir.join(name), force, inputs)?;
    }
    Ok(())
}

/// What a run simulates, checked before any stage starts, and its config.
pub(crate) struct Plan {
    /// The scenario's name.
    pub(crate) scenario: String,
    /// The demonstration: a leak on an off-nominal rig.
    pub(crate) demo: bool,
    /// Run length, s.
    pub(crate) seconds: f64,
    /// Leak fault specs.
    pub(crate) faults: Vec<String>,
    /// The config every stage reads.
    pub(crate) cfg: Config,
}

/// The run's plan from `args` (`udp`: the sensor stream is a UDP one).
pub(crate) fn plan(args: &RunArgs, udp: bool) -> Result<Plan, String> {
    // The demonstration (a leak on an off-nominal rig) is what `run` does without
    // faults or a config; naming the default scenario explicitly changes nothing.
    // `--fault none` asks for a healthy run.
    let scenario = args.scenario.clone().unwrap_or_else(|| DEFAULT_SCENARIO.into());
    let demo = !udp && scenario == DEFAULT_SCENARIO && args.faults.is_empty() && args.config.is_none();
    let seconds = args.seconds.unwrap_or(40.0);
    let faults: Vec<String> = if demo {
        vec!["ext1:0.5lpm@20s".to_string()]
    } else {
        args.faults
            .iter()
            .filter(|f| f.as_str() != "none")
            .cloned()
            .collect()
    };
    // One config for every stage: the user's, and for the demonstration an off-nominal rig.
    let mut cfg = Config::load_or_default(args.config.as_deref())?;
    // Every argument is checked here, before any stage starts.
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 3.6e6) {
        return Err(format!(
            "--seconds {seconds}: must be a number of seconds in (0, 3.6e6]"
        ));
    }
    model::Scenario::by_name(&scenario, 0, seconds).map_err(|e| format!("--scenario {scenario}: {e}"))?;
    for spec in &faults {
        model::Fault::parse(spec, &cfg.model).map_err(|e| format!("--fault {spec}: {e}"))?;
    }
    WaitMode::parse(&args.mode).map_err(|e| format!("--mode {}: {e}", args.mode))?;
    cfg.classifier.thesis_baseline |= args.thesis_baseline;
    if demo {
        cfg.rig = Some(pipeline::demo::off_nominal_rig(&cfg.model));
    }
    Ok(Plan {
        scenario,
        demo,
        seconds,
        faults,
        cfg,
    })
}
