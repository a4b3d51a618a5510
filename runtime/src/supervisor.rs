//! The supervisor: checks every argument, starts the four stages, restarts
//! those that exit (with backoff: [`crate::restart`]; the acquisition
//! continuing its stream after the last frame it published), watches that each
//! makes progress ([`crate::watchdog`]), gathers events and stats, and writes
//! the outputs at the end, whatever ended the run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig, WaitMode};
use detect::LeakEvent;
use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};

use crate::args::{check_udp_args, parse_source, RunArgs, RunSource};
use crate::error::RunError;
use crate::events::{own_event, print_event};
use crate::figures::{LatencyReport, StageAcc, STAGE_CODES};
use crate::notify::ServiceNotify;
use crate::outputs::live_stages;
use crate::placement::Placement;
use crate::plan::{announce, check_outputs, plan, run_prefix, stage_args, Plan};
use crate::retention::Retention;
use crate::run_dir::{out_dir_of, write_bag_metadata};
use crate::service::Service;
use crate::stages::{stage_program, Stage};
use crate::supervision::Supervision;
use bus::say as errln;

/// The result of a run.
#[derive(Debug)]
pub struct RunOutcome {
    /// Every event received.
    pub events: Vec<LeakEvent>,
    /// Latency and counts.
    pub latency: LatencyReport,
    /// The output directory.
    pub out_dir: PathBuf,
    /// Why the log could not be written (the recorder's file and reason), if it could not:
    /// the run monitored on without it.
    pub log_failure: Option<String>,
    /// Other outputs that failed while monitoring went on: events.json or latency.json
    /// written elsewhere (or nowhere), a live view, gateway or OPC UA server given up.
    pub output_failures: Vec<String>,
    /// Where events.json was written (the output directory's, or the fallback), if anywhere.
    pub events_path: Option<PathBuf>,
    /// Where latency.json was written, as [`RunOutcome::events_path`].
    pub latency_path: Option<PathBuf>,
}

/// Runs the pipeline; prints events as they come; writes the outputs. The
/// steps: [`check`] (nothing started), [`prepare`] and the stages' start,
/// the watch, [`finish`] (the outputs, whatever ended the run).
pub fn run_pipeline(args: &RunArgs, quiet: bool) -> Result<RunOutcome, RunError> {
    let c = check(args, quiet).map_err(RunError::Invalid)?;
    let (mut p, prefix, bus_cfg) = prepare(args, &c).map_err(RunError::Start)?;
    let launch = stage_args(
        args,
        &p.cfg_path,
        &c.out_dir,
        &c.plan.cfg,
        c.udp,
        (&c.plan.scenario, c.plan.seconds, &c.plan.faults),
    );
    if !quiet {
        let plan = &c.plan;
        let sim = (
            plan.scenario.as_str(),
            plan.seconds,
            plan.faults.as_slice(),
            plan.demo,
        );
        announce(args, c.udp, c.placement, &c.out_dir, &plan.cfg, sim).map_err(RunError::Watch)?;
    }
    let mut sup = Supervision::new(
        &c.program,
        &prefix,
        &c.out_dir,
        &bus_cfg,
        &c.plan.cfg,
        launch,
        c.udp.is_some(),
    );
    sup.start(&c.stages).map_err(RunError::Start)?;
    p.start_cleanup.started();
    // a UDP stream lasts as long as its sender streams
    let deadline = c
        .udp
        .is_none()
        .then(|| Duration::from_secs_f64(c.plan.seconds + 30.0));
    let mut service = Service::new(
        ServiceNotify::from_env(),
        c.retention.clone(),
        c.out_dir.clone(),
        &args.rig,
    );
    service.prune(Instant::now());
    let gathered = watch(
        &mut sup,
        &mut p.topics,
        &c.stages,
        (c.placement, quiet),
        (p.stop, deadline),
        (p.started, &mut service),
    )
    .map_err(RunError::Watch)?;
    service
        .notify
        .stopping(gathered.failure.as_deref().unwrap_or("the run ended"));
    finish(args, &c, &bus_cfg, (p, sup), gathered)
}

/// What [`check`] found: the run, checked, before anything starts.
struct Checked {
    /// The leakwatch binary the stages run from.
    program: PathBuf,
    /// Where the estimator and the classifier run.
    placement: Placement,
    /// A UDP source's address and idle timeout (s); `None` for the simulated rig.
    udp: Option<(std::net::SocketAddr, f64)>,
    /// The run's folder.
    out_dir: PathBuf,
    /// What to keep of the earlier runs, with `--runs-dir`.
    retention: Option<Retention>,
    /// The scenario, faults and the config every stage reads.
    plan: Plan,
    /// The stages to start (the live outputs among them when asked for).
    stages: Vec<Stage>,
}

/// Checks every argument, the config and the outputs; starts nothing.
fn check(args: &RunArgs, quiet: bool) -> Result<Checked, String> {
    let program = stage_program()?;
    frames::RigId::new(&args.rig).map_err(|e| format!("--rig {}: {e}", args.rig))?;
    let source = parse_source(args.source.as_deref())?;
    let placement = Placement::parse(args.placement.as_deref())?;
    let processes = placement.processes();
    let udp = match source {
        RunSource::Udp(addr) => Some((addr, check_udp_args(args, addr)?)),
        RunSource::Sim => {
            if args.udp_idle_timeout_s.is_some() {
                return Err("--udp-idle-timeout-s is for --source udp://IP:PORT".into());
            }
            None
        }
    };
    let (out_dir, retention) = out_dir_of(args)?;
    pipeline::out::dir(&out_dir)?;
    let inputs = inputs_of(args);
    check_outputs(&out_dir, processes, args.force, &inputs)?;
    let mut plan = plan(args, udp.is_some())?;
    let stages = live_stages(args, &mut plan.cfg, &out_dir, &inputs, quiet, processes)?;
    Ok(Checked {
        program,
        placement,
        udp,
        out_dir,
        retention,
        plan,
        stages,
    })
}

/// The run's inputs (its config file), which no output may be.
fn inputs_of(args: &RunArgs) -> Vec<&Path> {
    args.config.iter().map(|p| p.as_path()).collect()
}

/// The run's own iceoryx2 prefix, its bus and topics, and the config the
/// stages read: what the stages start on. Fields drop in their order: the
/// topics and the bus, then the start's clean-up, then the prefix's lock.
struct Prepared {
    /// The topics the supervisor reads itself.
    topics: Topics,
    /// The run's bus.
    bus: Bus,
    /// Removes what a failed start made on the prefix (while the lock is held).
    start_cleanup: crate::clean::StartCleanup,
    /// The run owns its prefix until it ends.
    _prefix_lock: bus::PrefixLock,
    /// The config file the stages read (in the run's folder).
    cfg_path: PathBuf,
    /// Set by SIGINT and SIGTERM.
    stop: &'static AtomicBool,
    /// When the watch of publishers started.
    started: Instant,
}

/// Takes the run's prefix (removing what a dead run left on it), writes the
/// stages' config and opens the bus and the topics the supervisor reads;
/// with the prefix and the bus settings on it.
fn prepare(args: &RunArgs, c: &Checked) -> Result<(Prepared, String, BusConfig), String> {
    let prefix = run_prefix()?;
    // The run's one time base, fixed now: every stage gets it (stages.rs), so
    // the log and the live view put the same Unix time on the same message.
    bus::init_epoch_offset().map_err(|e| e.to_string())?;
    let bus_cfg = BusConfig {
        iox_prefix: Some(prefix.clone()),
        ..BusConfig::default()
    };
    // The run owns its prefix until it ends: a second run on it is refused here,
    // before it could touch the first one's shared memory.
    let prefix_lock = bus_cfg.lock_prefix().map_err(|e| e.to_string())?;
    // what a killed run on this prefix left in shared memory: removed, and said
    crate::clean::remove_at_start(&bus_cfg);
    // a management segment of another user, or a damaged one that could not be
    // removed (a process of the prefix still runs): no stage could start
    if let Some(why) = crate::blocked::why_blocked(&bus_cfg, None) {
        return Err(format!("cannot start on the iceoryx2 prefix {prefix:?}: {why}"));
    }
    // a start that fails from here on removes what it made on the prefix
    let start_cleanup = crate::clean::StartCleanup::new(&bus_cfg);
    let cfg_path = c.out_dir.join("config.toml");
    let cfg_text = toml::to_string(&c.plan.cfg).map_err(|e| e.to_string())?;
    pipeline::out::write(&cfg_path, cfg_text.as_bytes(), args.force, &inputs_of(args))?;
    let bus = Bus::open(&args.rig, bus_cfg.clone()).map_err(|e| e.to_string())?;
    let topics = Topics::open(&bus)?;
    let prepared = Prepared {
        topics,
        bus,
        start_cleanup,
        _prefix_lock: prefix_lock,
        cfg_path,
        stop: bus::stop_on_signals(),
        started: Instant::now(),
    };
    Ok((prepared, prefix, bus_cfg))
}

/// After the watch: stops the stages, drains the last stats and events,
/// writes events.json, latency.json and the bag metadata, and releases the
/// prefix. A failure that ended the run is the error, its outputs written.
fn finish(
    args: &RunArgs,
    c: &Checked,
    bus_cfg: &BusConfig,
    (mut p, mut sup): (Prepared, Supervision),
    g: Gathered,
) -> Result<RunOutcome, RunError> {
    let Gathered {
        mut events,
        mut accs,
        mut foreign_events,
        failure,
    } = g;
    // the classifier's pid, for the events still queued once it has stopped
    let classifier_pids = sup.stop();
    while let Ok(Some(st)) = p.topics.stats_rx.try_receive() {
        accs.entry(st.stage).or_default().push(&st.frame);
    }
    while let Ok(Some(f)) = p.topics.events_rx.try_receive() {
        if let Some(ev) = own_event(&f, &classifier_pids, &mut foreign_events) {
            events.push(ev);
        }
    }
    let latency = latency_report(
        &args.mode,
        accs,
        sup.restarts,
        sup.watchdog.finish(Instant::now()),
    );
    let inputs = inputs_of(args);
    let (events_path, latency_path) = write_outputs(
        args,
        &c.out_dir,
        &inputs,
        &events,
        &latency,
        &mut sup.output_failures,
    )
    .map_err(RunError::Output)?;
    write_bag_metadata(&c.out_dir, args.force, &inputs);
    let Prepared {
        topics,
        bus,
        _prefix_lock,
        ..
    } = p;
    drop(topics);
    drop(bus);
    let _ = bus_cfg.remove_isolated_files();
    drop(_prefix_lock);
    if let Some(f) = failure {
        let paths = [events_path.as_deref(), latency_path.as_deref()];
        let message = failure_message(&f, paths, &sup.log_failure, &sup.output_failures);
        return Err(RunError::Failed(message));
    }
    Ok(RunOutcome {
        events,
        latency,
        out_dir: c.out_dir.clone(),
        log_failure: sup.log_failure,
        output_failures: sup.output_failures,
        events_path,
        latency_path,
    })
}

/// The run's latency report: each stage's figures from its stats (`accs`, by
/// stage code), the restarts and the stalls.
fn latency_report(
    mode: &str,
    accs: BTreeMap<u32, StageAcc>,
    restarts: BTreeMap<String, u32>,
    stalls: BTreeMap<String, crate::watchdog::StallFigures>,
) -> LatencyReport {
    let mut stages = BTreeMap::new();
    for (code, acc) in accs {
        let name = STAGE_CODES.get(code as usize).map_or("unknown", |s| s.name());
        stages.insert(name.to_string(), acc.finish());
    }
    LatencyReport {
        mode: mode.to_string(),
        stages,
        restarts,
        stalls,
    }
}

/// Writes events.json and latency.json, whatever ended the run; one that
/// cannot be written into `out_dir` (a full disk) goes to the temporary
/// directory, said on stderr and in `output_failures`, and masks no earlier
/// failure. Returns where each was written, if anywhere.
fn write_outputs(
    args: &RunArgs,
    out_dir: &Path,
    inputs: &[&Path],
    events: &[LeakEvent],
    latency: &LatencyReport,
    output_failures: &mut Vec<String>,
) -> Result<(Option<PathBuf>, Option<PathBuf>), String> {
    let events_path = crate::clean::write_somewhere(
        out_dir,
        "events.json",
        &args.rig,
        output_failures,
        |path, force| pipeline::replay::write_events(path, events, force, inputs),
        args.force,
    );
    let text = serde_json::to_string_pretty(latency).map_err(|e| e.to_string())? + "\n";
    let latency_path = crate::clean::write_somewhere(
        out_dir,
        "latency.json",
        &args.rig,
        output_failures,
        |path, force| pipeline::out::write(path, text.as_bytes(), force, inputs),
        args.force,
    );
    Ok((events_path, latency_path))
}

/// The error of a run that failure `f` ended: what holds what it gathered
/// (`paths`: events.json and latency.json where they were written) and the
/// outputs that failed on the way.
fn failure_message(
    f: &str,
    paths: [Option<&Path>; 2],
    log_failure: &Option<String>,
    output_failures: &[String],
) -> String {
    let held: Vec<String> = paths.iter().flatten().map(|p| p.display().to_string()).collect();
    let also: Vec<&String> = log_failure.iter().chain(output_failures).collect();
    format!(
        "{f} ({} hold what the run gathered){}",
        if held.is_empty() {
            "no output file could be written: the events printed above".to_string()
        } else {
            held.join(" and ")
        },
        if also.is_empty() {
            String::new()
        } else {
            format!(
                "; also: {}",
                also.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("; ")
            )
        }
    )
}

/// What the supervision gathered until the run ended.
struct Gathered {
    /// Every event of this run's classifier.
    events: Vec<LeakEvent>,
    /// Each stage's stats, by stage code.
    accs: BTreeMap<u32, StageAcc>,
    /// Events left out: published by anything but this run's classifier.
    foreign_events: u64,
    /// What ended the run, if a failure did (what was gathered is still written).
    failure: Option<String>,
}

/// Watches the run until it ends: the acquisition's end of stream (then 2.5 s
/// for the last frames and the recorder's file), a signal (`end.0`), the
/// deadline (`end.1`) or a failure. Each round reads the topics (events printed
/// unless `quiet`), watches who publishes, and supervises each of `stages`.
fn watch(
    sup: &mut Supervision,
    topics: &mut Topics,
    stages: &[Stage],
    (placement, quiet): (Placement, bool),
    end: (&AtomicBool, Option<Duration>),
    (mut last_watch, service): (Instant, &mut Service),
) -> Result<Gathered, String> {
    let (stop, deadline) = end;
    let mut events = Vec::new();
    let mut accs: BTreeMap<u32, StageAcc> = BTreeMap::new();
    let started = Instant::now();
    // A failure ends the run, but what was gathered is still written.
    let mut failure: Option<String> = None;
    // Events published by anything but this run's classifier are left out.
    let mut foreign_events = 0u64;
    loop {
        let now = Instant::now();
        while let Ok(Some(f)) = topics.events_rx.try_receive() {
            if let Some(ev) = own_event(&f, &sup.children, &mut foreign_events) {
                if !quiet {
                    print_event(&ev)?;
                }
                events.push(ev);
            }
        }
        let mut frames = 0;
        while let Ok(Some(f)) = topics.frames_rx.try_receive() {
            sup.on_frame(f.frame, now);
            frames += 1;
        }
        service.on_frames(frames, now);
        service.tick(now, events.len());
        while let Ok(Some(e)) = topics.estimates_rx.try_receive() {
            sup.last_estimate = Some(e.seq);
        }
        while let Ok(Some(st)) = topics.stats_rx.try_receive() {
            accs.entry(st.stage).or_default().push(&st.frame);
            sup.on_stats(&st, &accs, placement, now);
        }
        if last_watch.elapsed() >= Duration::from_secs(1) {
            last_watch = Instant::now();
            topics.watch_publishers();
        }
        if stop.load(Ordering::Relaxed) {
            errln!("leakwatch run: stopping (signal)");
            break;
        }
        // Supervision: exits, restarts with backoff, stalls.
        for &name in stages {
            if let Err(f) = sup.supervise_stage(name, now) {
                failure = Some(f);
                break;
            }
        }
        if failure.is_some() {
            break;
        }
        if let Some(t) = sup.ended_at {
            // let the last frames drain and the recorder finish its file
            if t.elapsed() > Duration::from_millis(2500) {
                break;
            }
        }
        if deadline.is_some_and(|d| started.elapsed() > d) {
            errln!("leakwatch run: the run did not end in time; stopping");
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Ok(Gathered {
        events,
        accs,
        foreign_events,
        failure,
    })
}

/// The topics the supervisor reads itself, and who publishes on two of them.
struct Topics {
    /// The events.
    events_rx: bus::Subscriber<LeakEventFrame>,
    /// Each process's stats.
    stats_rx: bus::Subscriber<StatsFrame>,
    /// The frames: the acquisition's progress, and where a restarted one takes over.
    frames_rx: bus::Subscriber<SensorFrame>,
    /// The estimates: where a restarted estimator or classifier takes over.
    estimates_rx: bus::Subscriber<EstimateFrame>,
    /// Publishers of frames: only the acquisition.
    frames_watch: bus::TopicWatch<SensorFrame>,
    /// Publishers of events: only the classifier.
    events_watch: bus::TopicWatch<LeakEventFrame>,
    /// What was said of the frames' publishers.
    frames_pubs: bus::PublisherWatch,
    /// What was said of the events' publishers.
    events_pubs: bus::PublisherWatch,
    /// The health topic, which the supervisor does not read: created before
    /// any stage starts (the subscribers above hold the other topics).
    _health: bus::TopicHold<HealthFrame>,
}

impl Topics {
    /// Subscribes on `bus`.
    fn open(bus: &Bus) -> Result<Topics, String> {
        let e = |e: bus::BusError| e.to_string();
        Ok(Topics {
            events_rx: bus.subscriber::<LeakEventFrame>(WaitMode::Event).map_err(e)?,
            stats_rx: bus.subscriber::<StatsFrame>(WaitMode::Event).map_err(e)?,
            frames_rx: bus.subscriber::<SensorFrame>(WaitMode::Event).map_err(e)?,
            estimates_rx: bus.subscriber::<EstimateFrame>(WaitMode::Event).map_err(e)?,
            frames_watch: bus.topic_watch::<SensorFrame>().map_err(e)?,
            events_watch: bus.topic_watch::<LeakEventFrame>().map_err(e)?,
            frames_pubs: bus::PublisherWatch::new(Topic::Frames, 1),
            events_pubs: bus::PublisherWatch::new(Topic::Events, 1),
            _health: bus.hold::<HealthFrame>().map_err(e)?,
        })
    }

    /// Warns of another publisher of frames or events: another process of this
    /// user feeding the pipeline (docs/security.md).
    fn watch_publishers(&mut self) {
        let counts = [
            self.frames_watch.publisher_count(),
            self.events_watch.publisher_count(),
        ];
        for (watch, count) in [&mut self.frames_pubs, &mut self.events_pubs]
            .into_iter()
            .zip(counts)
        {
            if let Some(w) = watch.observe(count) {
                errln!("leakwatch run: warning: {w}");
            }
        }
    }
}
