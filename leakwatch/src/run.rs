//! `leakwatch run`: start the four stage processes over iceoryx2, supervise
//! them, print events as they happen, and write events.json, latency.json and
//! the log (run.mcap) at the end.
//!
//! The stage binaries (`acquisition`, `estimator`, `classifier`, `recorder`)
//! are looked up next to the `leakwatch` binary; inside a Cargo workspace they
//! are built on first use. Every run gets its own iceoryx2 prefix
//! (`LEAKWATCH_IOX_PREFIX`), so runs and tests never see each other.

use std::collections::BTreeMap;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig, WaitMode};
use classifier::{LeakEvent, Phase};
use frames::{LeakEventFrame, SensorFrame, StatsFrame, Topic};
use serde::Serialize;

use crate::config::Config;
use crate::out::outln;

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
    /// Output directory (default ./leakwatch-run).
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
        Some(t) if t.starts_with("udp://") => acquisition::parse_udp_address(t)
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
fn check_udp_args(args: &RunArgs, addr: std::net::SocketAddr) -> Result<f64, String> {
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

/// The four stage binaries.
pub const STAGES: [&str; 4] = ["recorder", "classifier", "estimator", "acquisition"];

/// Runs one stage process in this process: `args` is the stage's name followed by
/// its own arguments (`leakwatch stage NAME ARGS...`).
pub fn stage_main(args: &[std::ffi::OsString]) -> std::process::ExitCode {
    let argv = args.iter().cloned();
    match args.first().and_then(|n| n.to_str()) {
        Some("acquisition") => acquisition::shell::main(argv),
        Some("estimator") => estimator::shell::main(argv),
        Some("classifier") => classifier::shell::main(argv),
        Some("recorder") => recorder::shell::main(argv),
        other => {
            eprintln!(
                "leakwatch stage: unknown stage {:?}; the stages are acquisition, estimator, classifier, recorder",
                other.unwrap_or("")
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

/// Latency and counts of one stage, from its stats frames.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StageFigures {
    /// Frames received.
    pub frames_in: u64,
    /// Frames published.
    pub frames_out: u64,
    /// Frames missing from the input sequence.
    pub seq_gaps: u64,
    /// Missed 1 kHz deadlines (acquisition).
    pub deadline_misses: u64,
    /// Latency since acquisition at this stage's input, µs: median of the 1 s p50s.
    pub latency_p50_us: f64,
    /// The worst one-second p99 of that latency (the largest of the 1 s p99s the
    /// stage reported; not the whole run's p99), µs.
    pub latency_worst_1s_p99_us: f64,
    /// Largest latency, µs.
    pub latency_max_us: f64,
    /// Processing time per frame: median of the 1 s p50s, µs.
    pub proc_p50_us: f64,
    /// Largest 1 s p99 of the processing time, µs.
    pub proc_p99_us: f64,
    /// Mean CPU use, fraction of a core.
    pub cpu_fraction: f64,
    /// Largest resident set size, MB.
    pub rss_mb: f64,
    /// Stats frames seen.
    pub intervals: u64,
}

#[derive(Default)]
struct StageAcc {
    last: Option<StatsFrame>,
    p50s: Vec<f64>,
    proc_p50s: Vec<f64>,
    fig: StageFigures,
    cpu_sum: f64,
}

impl StageAcc {
    fn push(&mut self, s: &StatsFrame) {
        let f = &mut self.fig;
        f.intervals += 1;
        // counters run from the process start: keep the latest (a restart starts again: add up)
        if let Some(prev) = self.last {
            if s.pid != prev.pid {
                f.frames_in += prev.frames_in;
                f.frames_out += prev.frames_out;
                f.seq_gaps += prev.seq_gaps;
                f.deadline_misses += prev.deadline_misses;
            }
        }
        self.last = Some(*s);
        if s.lat_ns_p50 > 0 {
            self.p50s.push(s.lat_ns_p50 as f64 / 1e3);
            f.latency_worst_1s_p99_us = f.latency_worst_1s_p99_us.max(s.lat_ns_p99 as f64 / 1e3);
            f.latency_max_us = f.latency_max_us.max(s.lat_ns_max as f64 / 1e3);
        }
        if s.proc_ns_p50 > 0 {
            self.proc_p50s.push(s.proc_ns_p50 as f64 / 1e3);
            f.proc_p99_us = f.proc_p99_us.max(s.proc_ns_p99 as f64 / 1e3);
        }
        self.cpu_sum += s.cpu_fraction;
        f.rss_mb = f.rss_mb.max(s.rss_bytes as f64 / 1e6);
    }
    fn finish(mut self) -> StageFigures {
        let med = |v: &mut Vec<f64>| {
            if v.is_empty() {
                return f64::NAN;
            }
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        if let Some(l) = self.last {
            self.fig.frames_in += l.frames_in;
            self.fig.frames_out += l.frames_out;
            self.fig.seq_gaps += l.seq_gaps;
            self.fig.deadline_misses += l.deadline_misses;
        }
        self.fig.latency_p50_us = med(&mut self.p50s);
        self.fig.proc_p50_us = med(&mut self.proc_p50s);
        self.fig.cpu_fraction = self.cpu_sum / self.fig.intervals.max(1) as f64;
        self.fig
    }
}

/// What latency.json holds.
#[derive(Debug, Clone, Serialize)]
pub struct LatencyReport {
    /// Wait mode of the stages.
    pub mode: String,
    /// Per stage (acquisition, estimator, classifier, recorder).
    pub stages: BTreeMap<String, StageFigures>,
    /// Restarts of crashed stages.
    pub restarts: BTreeMap<String, u32>,
}

const STAGE_NAMES: [&str; 4] = ["acquisition", "estimator", "classifier", "recorder"];

/// The result of a run.
#[derive(Debug)]
pub struct RunOutcome {
    /// Every event received.
    pub events: Vec<LeakEvent>,
    /// Latency and counts.
    pub latency: LatencyReport,
    /// The output directory.
    pub out_dir: PathBuf,
}

fn spawn(program: &Path, name: &str, args: &[String], prefix: &str, log: &Path) -> Result<Child, String> {
    // the outputs were checked at start (an earlier run's only with --force)
    let err = crate::out::create(log, true, &[])?;
    let mut cmd = Command::new(program);
    // The stage dies with its supervisor (SIGTERM when the supervisor's thread
    // that spawned it ends, whatever the cause, SIGKILL included).
    // SAFETY: prctl is async-signal-safe and touches no memory of the parent.
    unsafe {
        cmd.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM as libc::c_ulong, 0, 0, 0) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.arg("stage")
        .arg(name)
        .args(args)
        .env(bus::PREFIX_ENV, prefix)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(err)
        .spawn()
        .map_err(|e| format!("cannot start stage {name} ({}): {e}", program.display()))
}

fn terminate(child: &mut Child) {
    // SAFETY-free: kill(2) via libc with SIGTERM for a clean stop.
    let pid = child.id() as i32;
    unsafe {
        libc::kill(pid, libc::SIGTERM);
    }
}

/// The scenario `run` simulates by default (with the demonstration leak when no
/// fault or config is given).
pub const DEFAULT_SCENARIO: &str = "loaded-sine";

/// Runs the pipeline; prints events as they come; writes the outputs.
pub fn run_pipeline(args: &RunArgs, quiet: bool) -> Result<RunOutcome, String> {
    let program = stage_program()?;
    frames::RigId::new(&args.rig).map_err(|e| format!("--rig {}: {e}", args.rig))?;
    let source = parse_source(args.source.as_deref())?;
    let udp = match source {
        RunSource::Udp(addr) => Some((addr, check_udp_args(args, addr)?)),
        RunSource::Sim => {
            if args.udp_idle_timeout_s.is_some() {
                return Err("--udp-idle-timeout-s is for --source udp://IP:PORT".into());
            }
            None
        }
    };
    let out_dir = args.out.clone().unwrap_or_else(|| PathBuf::from("leakwatch-run"));
    crate::out::dir(&out_dir)?;
    // An earlier run's outputs are replaced only with --force; refused before anything starts.
    let mut outputs = vec!["config.toml", "events.json", "latency.json", "run.mcap"];
    outputs.extend(STAGES.iter().map(|n| match *n {
        "recorder" => "recorder.log",
        "classifier" => "classifier.log",
        "estimator" => "estimator.log",
        _ => "acquisition.log",
    }));
    let inputs: Vec<&Path> = args.config.iter().map(|p| p.as_path()).collect();
    for name in outputs {
        crate::out::check(&out_dir.join(name), args.force, &inputs)?;
    }
    // The demonstration (a leak on an off-nominal rig) is what `run` does without
    // faults or a config; naming the default scenario explicitly changes nothing.
    // `--fault none` asks for a healthy run.
    let scenario = args.scenario.clone().unwrap_or_else(|| DEFAULT_SCENARIO.into());
    let demo =
        udp.is_none() && scenario == DEFAULT_SCENARIO && args.faults.is_empty() && args.config.is_none();
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
        cfg.rig = Some(crate::demo::off_nominal_rig(&cfg.model));
    }
    // A private iceoryx2 prefix per run, unless the user names one (to attach other tools).
    let prefix = match std::env::var(bus::PREFIX_ENV) {
        Ok(p) if !p.is_empty() => p,
        _ => format!("run{}", std::process::id()),
    };
    let bus_cfg = BusConfig {
        iox_prefix: Some(prefix.clone()),
        ..BusConfig::default()
    };
    // The run owns its prefix until it ends: a second run on it is refused here,
    // before it could touch the first one's shared memory.
    let _prefix_lock = bus_cfg.lock_prefix().map_err(|e| e.to_string())?;
    let cfg_path = out_dir.join("config.toml");
    let cfg_text = toml::to_string(&cfg).map_err(|e| e.to_string())?;
    crate::out::write(&cfg_path, cfg_text.as_bytes(), args.force, &inputs)?;
    let bus = Bus::open(&args.rig, bus_cfg.clone()).map_err(|e| e.to_string())?;
    let mut events_rx = bus
        .subscriber::<LeakEventFrame>(WaitMode::Event)
        .map_err(|e| e.to_string())?;
    let mut stats_rx = bus
        .subscriber::<StatsFrame>(WaitMode::Event)
        .map_err(|e| e.to_string())?;
    // Only acquisition publishes frames and only the classifier events: another
    // publisher is another process of this user feeding the pipeline (docs/security.md).
    let frames_watch = bus.topic_watch::<SensorFrame>().map_err(|e| e.to_string())?;
    let events_watch = bus.topic_watch::<LeakEventFrame>().map_err(|e| e.to_string())?;
    let mut frames_pubs = bus::PublisherWatch::new(Topic::Frames, 1);
    let mut events_pubs = bus::PublisherWatch::new(Topic::Events, 1);
    let mut last_watch = Instant::now();
    let stop = bus::stop_on_signals();

    let s = |v: &str| v.to_string();
    let cfg_arg = cfg_path.display().to_string();
    let log = out_dir.join("run.mcap").display().to_string();
    let stage_args = |name: &str| -> Vec<String> {
        match name {
            "recorder" => {
                let mut a = vec![
                    s("--rig"),
                    args.rig.clone(),
                    s("--out"),
                    log.clone(),
                    s("--grace-ms"),
                    s("1500"),
                ];
                if args.force {
                    a.push(s("--force"));
                }
                a
            }
            "classifier" | "estimator" => {
                vec![
                    s("--rig"),
                    args.rig.clone(),
                    s("--config"),
                    cfg_arg.clone(),
                    s("--mode"),
                    args.mode.clone(),
                ]
            }
            _ => {
                if let Some((addr, idle)) = udp {
                    return vec![
                        s("--rig"),
                        args.rig.clone(),
                        s("--udp"),
                        addr.to_string(),
                        s("--udp-idle-timeout-s"),
                        idle.to_string(),
                        s("--config"),
                        cfg_arg.clone(),
                        s("--wait-subscribers"),
                        s("2"),
                    ];
                }
                let mut a = vec![
                    s("--rig"),
                    args.rig.clone(),
                    s("--scenario"),
                    scenario.clone(),
                    s("--seconds"),
                    seconds.to_string(),
                    s("--config"),
                    cfg_arg.clone(),
                    s("--wait-subscribers"),
                    s("2"),
                ];
                for f in &faults {
                    a.push(s("--fault"));
                    a.push(f.clone());
                }
                a
            }
        }
    };
    if !quiet {
        match udp {
            Some((addr, idle)) => outln!(
                "leakwatch run: rig {}, UDP sensor stream on {addr} (until the sender's end of stream or {idle} s \
                 without datagrams), {} mode; output {}",
                args.rig,
                args.mode,
                out_dir.display()
            ),
            None => outln!(
                "leakwatch run: rig {}, scenario {scenario}, {seconds} s at 1 kHz, faults [{}], {} mode{}; output {}",
                args.rig,
                faults.join(", "),
                args.mode,
                if demo { ", off-nominal rig (demonstration)" } else { "" },
                out_dir.display()
            ),
        }
        if let Ok(c) = classifier::Classifier::new(cfg.classifier.clone()) {
            outln!("note: {}", c.start_note());
        }
    }
    let mut children: BTreeMap<&str, Child> = BTreeMap::new();
    for name in STAGES {
        let child = spawn(
            &program,
            name,
            &stage_args(name),
            &prefix,
            &out_dir.join(format!("{name}.log")),
        )?;
        children.insert(name, child);
        if name != "acquisition" {
            std::thread::sleep(Duration::from_millis(150));
        }
    }
    let mut restarts: BTreeMap<String, u32> = BTreeMap::new();
    let mut events = Vec::new();
    let mut accs: BTreeMap<u32, StageAcc> = BTreeMap::new();
    let started = Instant::now();
    let mut ended_at: Option<Instant> = None;
    // a UDP stream lasts as long as its sender streams
    let deadline = udp.is_none().then(|| Duration::from_secs_f64(seconds + 30.0));
    // A failure ends the run, but what was gathered is still written.
    let mut failure: Option<String> = None;
    // Events published by anything but this run's classifier are left out.
    let mut foreign_events = 0u64;
    loop {
        while let Ok(Some(f)) = events_rx.try_receive() {
            if let Some(ev) = own_event(&f, &children, &mut foreign_events) {
                if !quiet {
                    print_event(&ev)?;
                }
                events.push(ev);
            }
        }
        while let Ok(Some(st)) = stats_rx.try_receive() {
            accs.entry(st.stage).or_default().push(&st.frame);
        }
        if last_watch.elapsed() >= Duration::from_secs(1) {
            last_watch = Instant::now();
            let counts = [frames_watch.publisher_count(), events_watch.publisher_count()];
            for (watch, count) in [&mut frames_pubs, &mut events_pubs].into_iter().zip(counts) {
                if let Some(w) = watch.observe(count) {
                    eprintln!("leakwatch run: warning: {w}");
                }
            }
        }
        if stop.load(Ordering::Relaxed) {
            eprintln!("leakwatch run: stopping (signal)");
            break;
        }
        // Supervision.
        let mut acquisition_done = false;
        for name in STAGES {
            let Some(child) = children.get_mut(name) else {
                continue;
            };
            if let Ok(Some(status)) = child.try_wait() {
                if name == "acquisition" {
                    if !status.success() {
                        failure = Some(format!(
                            "acquisition failed ({status}); see {}",
                            out_dir.join("acquisition.log").display()
                        ));
                    }
                    acquisition_done = true;
                } else if ended_at.is_none() || name != "recorder" {
                    let n = restarts.entry(name.to_string()).or_default();
                    *n += 1;
                    eprintln!("leakwatch run: stage {name} exited ({status}); restarting it (restart {n})");
                    if *n > 5 {
                        failure = Some(format!(
                            "stage {name} keeps failing; see {}",
                            out_dir.join(format!("{name}.log")).display()
                        ));
                        break;
                    }
                    let mut a = stage_args(name);
                    if name == "recorder" {
                        a[3] = out_dir.join(format!("run-{n}.mcap")).display().to_string();
                    }
                    match spawn(
                        &program,
                        name,
                        &a,
                        &prefix,
                        &out_dir.join(format!("{name}-{n}.log")),
                    ) {
                        Ok(c) => {
                            children.insert(name, c);
                        }
                        Err(e) => {
                            failure = Some(e);
                            break;
                        }
                    }
                }
            }
        }
        if failure.is_some() {
            break;
        }
        if acquisition_done {
            children.remove("acquisition");
            ended_at.get_or_insert_with(Instant::now);
        }
        if let Some(t) = ended_at {
            // let the last frames drain and the recorder finish its file
            if t.elapsed() > Duration::from_millis(2500) {
                break;
            }
        }
        if deadline.is_some_and(|d| started.elapsed() > d) {
            eprintln!("leakwatch run: the run did not end in time; stopping");
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    // the classifier's pid, for the events still queued once it has stopped
    let classifier_pids: BTreeMap<&str, u32> = children
        .iter()
        .filter(|(n, _)| **n == "classifier")
        .map(|(n, c)| (*n, c.id()))
        .collect();
    for (_, c) in children.iter_mut() {
        terminate(c);
    }
    for (_, mut c) in children {
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(5) {
            if let Ok(Some(_)) = c.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = c.kill();
        let _ = c.wait();
    }
    while let Ok(Some(st)) = stats_rx.try_receive() {
        accs.entry(st.stage).or_default().push(&st.frame);
    }
    while let Ok(Some(f)) = events_rx.try_receive() {
        if let Some(ev) = own_event(&f, &classifier_pids, &mut foreign_events) {
            events.push(ev);
        }
    }
    let mut stages = BTreeMap::new();
    for (code, acc) in accs {
        let name = STAGE_NAMES.get(code as usize).copied().unwrap_or("unknown");
        stages.insert(name.to_string(), acc.finish());
    }
    let latency = LatencyReport {
        mode: args.mode.clone(),
        stages,
        restarts,
    };
    crate::replay::write_events(&out_dir.join("events.json"), &events, args.force, &inputs)?;
    let text = serde_json::to_string_pretty(&latency).map_err(|e| e.to_string())?;
    crate::out::write(
        &out_dir.join("latency.json"),
        (text + "\n").as_bytes(),
        args.force,
        &inputs,
    )?;
    drop(events_rx);
    drop(stats_rx);
    drop((frames_watch, events_watch));
    drop(bus);
    let _ = bus_cfg.remove_isolated_files();
    if let Some(f) = failure {
        return Err(format!(
            "{f} (events.json and latency.json in {} hold what the run gathered)",
            out_dir.display()
        ));
    }
    Ok(RunOutcome {
        events,
        latency,
        out_dir,
    })
}

/// The classifier's process id in `children` (a map of running children, or of pids).
trait ClassifierPid {
    fn classifier_pid(&self) -> Option<u32>;
}

impl ClassifierPid for BTreeMap<&str, Child> {
    fn classifier_pid(&self) -> Option<u32> {
        self.get("classifier").map(Child::id)
    }
}

impl ClassifierPid for BTreeMap<&str, u32> {
    fn classifier_pid(&self) -> Option<u32> {
        self.get("classifier").copied()
    }
}

/// The event of a frame if this run's classifier published it (iceoryx2's sample
/// header names the publishing process); a frame from any other publisher, or one
/// not understood, is reported on stderr, counted in `foreign` and left out.
fn own_event(
    f: &bus::Received<LeakEventFrame>,
    children: &impl ClassifierPid,
    foreign: &mut u64,
) -> Option<LeakEvent> {
    let own = children.classifier_pid();
    if f.publisher_pid != 0 && own.is_some_and(|pid| pid != f.publisher_pid) {
        *foreign += 1;
        if *foreign <= 10 {
            eprintln!(
                "leakwatch run: warning: an event from process {} (not this run's classifier, process {}) was left out",
                f.publisher_pid,
                own.unwrap_or(0)
            );
        }
        return None;
    }
    match LeakEvent::try_from(&f.frame) {
        Ok(ev) => Some(ev),
        Err(e) => {
            eprintln!("leakwatch run: an event frame was not understood ({e}); left out");
            None
        }
    }
}

fn print_event(ev: &LeakEvent) -> Result<(), String> {
    let size = if ev.size_lpm.is_finite() {
        format!(" size {:.3} ± {:.3} L/min", ev.size_lpm, ev.size_lpm_sigma)
    } else {
        String::new()
    };
    outln!(
        "  t = {:7.3} s  {:<10} {:<8} {:<16} onset {:.2} s{size}  confidence {:.2}",
        ev.t_detect_s,
        ev.detector,
        format!("{:?}", ev.phase).to_lowercase(),
        ev.kind.name(),
        ev.t_onset_s,
        ev.confidence
    );
    Ok(())
}

/// `leakwatch run`.
pub fn run(args: RunArgs) -> Result<(), String> {
    let o = run_pipeline(&args, false)?;
    outln!("\n| stage | frames in | frames out | missing | latency p50 µs (median 1-s p50) | worst 1-s p99 µs | max µs | proc p50 µs | CPU % | RSS MB |");
    outln!("|---|---|---|---|---|---|---|---|---|---|");
    for (name, f) in &o.latency.stages {
        outln!(
            "| {name} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
            f.frames_in,
            f.frames_out,
            f.seq_gaps,
            f.latency_p50_us,
            f.latency_worst_1s_p99_us,
            f.latency_max_us,
            f.proc_p50_us,
            f.cpu_fraction * 100.0,
            f.rss_mb
        );
    }
    let leaks: Vec<&LeakEvent> = o
        .events
        .iter()
        .filter(|e| e.kind.is_leak() && e.phase == Phase::Raised && e.detector == "leak-size")
        .collect();
    match leaks.first() {
        Some(e) => outln!(
            "\ndetected: {} leak at t = {:.2} s (onset {:.2} s), {:.3} L/min at the measured pressures",
            e.kind.name(),
            e.t_detect_s,
            e.t_onset_s,
            o.events
                .iter()
                .rev()
                .find(|x| x.event_id == e.event_id && x.detector == e.detector)
                .map_or(e.size_lpm, |x| x.size_lpm)
        ),
        None => match o
            .events
            .iter()
            .find(|e| e.kind.is_leak_alarm() && e.phase == Phase::Raised && e.detector == "leak-size")
        {
            Some(e) => outln!(
                "\ndetected: a leak at t = {:.2} s (onset {:.2} s), kind not decided yet ({})",
                e.t_detect_s,
                e.t_onset_s,
                e.detail
            ),
            None => outln!("\nno leak detected"),
        },
    }
    if matches!(parse_source(args.source.as_deref()), Ok(RunSource::Udp(_))) {
        // the stream's counts (lost, duplicated, late, malformed), from the acquisition's closing line
        let log = std::fs::read_to_string(o.out_dir.join("acquisition.log")).unwrap_or_default();
        if let Some(line) = log.lines().find_map(|l| l.strip_prefix("acquisition: udp: ")) {
            outln!("UDP stream: {line}");
        }
    }
    outln!(
        "wrote {}/events.json, latency.json, run.mcap",
        o.out_dir.display()
    );
    Ok(())
}
