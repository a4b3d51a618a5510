//! The supervisor: checks every argument, starts the four stages, restarts
//! those that exit (with backoff: [`crate::restart`]; the acquisition
//! continuing its stream after the last frame it published), watches that each
//! makes progress ([`crate::watchdog`]), gathers events and stats, and writes
//! the outputs at the end, whatever ended the run.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use bus::{Bus, BusConfig, WaitMode};
use detect::LeakEvent;
use frames::{EstimateFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};

use crate::args::{check_udp_args, parse_source, RunArgs, RunSource, DEFAULT_SCENARIO};
use crate::events::{own_event, print_event};
use crate::figures::{LatencyReport, StageAcc, STAGE_NAMES};
use crate::launch::{is_log_part, Resume, Samples, StageArgs, FRAME_SUBSCRIBERS};
use crate::placement::Placement;
use crate::restart::{Backoff, Decision, HEALTHY_RUN, MAX_RESTARTS};
use crate::stages::{spawn, stage_program, terminate, FUSED};
use crate::watchdog::{stall_cause, Alarm, Watchdog};
use bus::say as errln;
use config::Config;
use pipeline::out::outln;

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
    /// written elsewhere (or nowhere), a live view or gateway given up.
    pub output_failures: Vec<String>,
    /// Where events.json was written (the output directory's, or the fallback), if anywhere.
    pub events_path: Option<PathBuf>,
    /// Where latency.json was written, as [`RunOutcome::events_path`].
    pub latency_path: Option<PathBuf>,
}

/// Stages whose failure does not end the run: monitoring (acquisition,
/// estimator, classifier) goes on without them.
const OPTIONAL_STAGES: [&str; 3] = ["recorder", "liveview", "gateway"];

/// Runs the pipeline; prints events as they come; writes the outputs.
pub fn run_pipeline(args: &RunArgs, quiet: bool) -> Result<RunOutcome, String> {
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
    let out_dir = match &args.out {
        Some(dir) => dir.clone(),
        None => default_out_dir(),
    };
    pipeline::out::dir(&out_dir)?;
    // An earlier run's outputs are replaced only with --force; refused before anything starts.
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
    if let Ok(entries) = std::fs::read_dir(&out_dir) {
        let names = entries.flatten().filter_map(|e| e.file_name().into_string().ok());
        outputs.extend(names.filter(|n| is_log_part(n)));
    }
    let inputs: Vec<&Path> = args.config.iter().map(|p| p.as_path()).collect();
    for name in outputs {
        pipeline::out::check(&out_dir.join(name), args.force, &inputs)?;
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
        cfg.rig = Some(pipeline::demo::off_nominal_rig(&cfg.model));
    }
    let stages = live_stages(args, &mut cfg, &out_dir, &inputs, quiet, processes)?;
    // A private iceoryx2 prefix per run, unless the user names one (to attach
    // other tools; checked as it is read, its length against bus::MAX_PREFIX_LEN).
    let prefix = match std::env::var(bus::PREFIX_ENV) {
        Ok(p) if !p.is_empty() => {
            bus::validate_prefix(&p).map_err(|e| e.to_string())?;
            p
        }
        _ => format!("run{}", std::process::id()),
    };
    // The run's one time base, fixed now: every stage gets it (stages.rs), so
    // the log and the live view put the same Unix time on the same message.
    bus::init_epoch_offset().map_err(|e| e.to_string())?;
    let bus_cfg = BusConfig {
        iox_prefix: Some(prefix.clone()),
        ..BusConfig::default()
    };
    // The run owns its prefix until it ends: a second run on it is refused here,
    // before it could touch the first one's shared memory.
    let _prefix_lock = bus_cfg.lock_prefix().map_err(|e| e.to_string())?;
    // what a killed run on this prefix left in shared memory: removed, and said
    crate::clean::remove_at_start(&bus_cfg);
    // a management segment of another user, or a damaged one that could not be
    // removed (a process of the prefix still runs): no stage could start
    if let Some(why) = crate::blocked::why_blocked(&bus_cfg, None) {
        return Err(format!("cannot start on the iceoryx2 prefix {prefix:?}: {why}"));
    }
    // a start that fails from here on removes what it made on the prefix
    let start_cleanup = crate::clean::StartCleanup::new(&bus_cfg);
    let cfg_path = out_dir.join("config.toml");
    let cfg_text = toml::to_string(&cfg).map_err(|e| e.to_string())?;
    pipeline::out::write(&cfg_path, cfg_text.as_bytes(), args.force, &inputs)?;
    let bus = Bus::open(&args.rig, bus_cfg.clone()).map_err(|e| e.to_string())?;
    let mut events_rx = bus
        .subscriber::<LeakEventFrame>(WaitMode::Event)
        .map_err(|e| e.to_string())?;
    let mut stats_rx = bus
        .subscriber::<StatsFrame>(WaitMode::Event)
        .map_err(|e| e.to_string())?;
    // the frames: the acquisition's progress, and where a restarted one takes over
    let mut frames_rx = bus
        .subscriber::<SensorFrame>(WaitMode::Event)
        .map_err(|e| e.to_string())?;
    // the estimates: where a restarted estimator or classifier takes over
    let mut estimates_rx = bus
        .subscriber::<EstimateFrame>(WaitMode::Event)
        .map_err(|e| e.to_string())?;
    // Only acquisition publishes frames and only the classifier events: another
    // publisher is another process of this user feeding the pipeline (docs/security.md).
    let frames_watch = bus.topic_watch::<SensorFrame>().map_err(|e| e.to_string())?;
    let events_watch = bus.topic_watch::<LeakEventFrame>().map_err(|e| e.to_string())?;
    let mut frames_pubs = bus::PublisherWatch::new(Topic::Frames, 1);
    let mut events_pubs = bus::PublisherWatch::new(Topic::Events, 1);
    let mut last_watch = Instant::now();
    let stop = bus::stop_on_signals();

    let mut launch = StageArgs {
        rig: args.rig.clone(),
        config: cfg_path.display().to_string(),
        mode: args.mode.clone(),
        out_dir: out_dir.clone(),
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
                scenario: scenario.clone(),
                seconds,
                faults: faults.clone(),
            },
        },
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
    }
    let mut children: BTreeMap<&str, Child> = BTreeMap::new();
    let mut watchdog = Watchdog::default();
    for &name in &stages {
        let child = spawn(
            &program,
            name,
            &launch.of(name, 0, &Resume::default()),
            &prefix,
            &out_dir.join(format!("{name}.log")),
            cfg.run.cpu_of(name),
        );
        let child = match child {
            Ok(child) => child,
            Err(e) => {
                // the stages already started go first, so that their files can go too
                for (_, mut c) in std::mem::take(&mut children) {
                    let _ = c.kill();
                    let _ = c.wait();
                }
                return Err(format!("cannot start the {name}: {e}"));
            }
        };
        children.insert(name, child);
        watchdog.started(name, Instant::now());
        if name != "acquisition" {
            std::thread::sleep(Duration::from_millis(150));
        }
    }
    start_cleanup.started();
    // a UDP stream is paced by its sender: no datagram is no stall
    // (the live view and the gateway publish no stats: restarted when they exit, not watched)
    let watched =
        |name: &str| !["liveview", "gateway"].contains(&name) && (udp.is_none() || name != "acquisition");
    let mut restarts: BTreeMap<String, u32> = BTreeMap::new();
    let mut backoffs: BTreeMap<&str, Backoff> = BTreeMap::new();
    let mut started_at: BTreeMap<&str, Instant> = stages.iter().map(|n| (*n, Instant::now())).collect();
    let mut restart_at: BTreeMap<&str, Instant> = BTreeMap::new();
    // the last frame published, where a restarted acquisition takes over
    let mut last_frame: Option<SensorFrame> = None;
    // the last estimate published, and where a stage that exited had read the estimates to
    let mut last_estimate: Option<u64> = None;
    let mut read_to_at_exit: BTreeMap<&str, Option<u64>> = BTreeMap::new();
    let mut events = Vec::new();
    let mut accs: BTreeMap<u32, StageAcc> = BTreeMap::new();
    let started = Instant::now();
    let mut ended_at: Option<Instant> = None;
    // a UDP stream lasts as long as its sender streams
    let deadline = udp.is_none().then(|| Duration::from_secs_f64(seconds + 30.0));
    // A failure ends the run, but what was gathered is still written.
    let mut failure: Option<String> = None;
    // A failed output (the log, the live view, the gateway) does not: monitoring goes on.
    let mut log_failure: Option<String> = None;
    let mut output_failures: Vec<String> = Vec::new();
    // Events published by anything but this run's classifier are left out.
    let mut foreign_events = 0u64;
    let stall_ended = |name: &str, d: Duration| {
        errln!(
            "leakwatch run: the {name} runs again after {:.1} s without progress",
            d.as_secs_f64()
        );
    };
    loop {
        let now = Instant::now();
        while let Ok(Some(f)) = events_rx.try_receive() {
            if let Some(ev) = own_event(&f, &children, &mut foreign_events) {
                if !quiet {
                    print_event(&ev)?;
                }
                events.push(ev);
            }
        }
        while let Ok(Some(f)) = frames_rx.try_receive() {
            last_frame = Some(f.frame);
            if let Some(d) = watchdog
                .progress("acquisition", now)
                .filter(|_| watched("acquisition"))
            {
                stall_ended("acquisition", d);
            }
        }
        while let Ok(Some(e)) = estimates_rx.try_receive() {
            last_estimate = Some(e.seq);
        }
        while let Ok(Some(st)) = stats_rx.try_receive() {
            accs.entry(st.stage).or_default().push(&st.frame);
            let Some(&stage) = STAGE_NAMES.get(st.stage as usize) else {
                continue;
            };
            // the stats of this stage's running process, against its upstream's output
            // (the fused process: its estimator's, the first of the two)
            let name = placement.process_of(stage);
            if stage == "acquisition"
                || (name == FUSED && stage == "classifier")
                || children.get(name).map(Child::id) != Some(st.pid)
            {
                continue;
            }
            let upstream = if stage == "classifier" { 1 } else { 0 };
            let up_out = accs.get(&upstream).map_or(0, StageAcc::frames_out_total);
            if let Some(d) = watchdog.stats(name, st.pid, st.frames_in, up_out, now) {
                stall_ended(name, d);
            }
        }
        if last_watch.elapsed() >= Duration::from_secs(1) {
            last_watch = Instant::now();
            let counts = [frames_watch.publisher_count(), events_watch.publisher_count()];
            for (watch, count) in [&mut frames_pubs, &mut events_pubs].into_iter().zip(counts) {
                if let Some(w) = watch.observe(count) {
                    errln!("leakwatch run: warning: {w}");
                }
            }
        }
        if stop.load(Ordering::Relaxed) {
            errln!("leakwatch run: stopping (signal)");
            break;
        }
        // Supervision: exits, restarts with backoff, stalls.
        for &name in &stages {
            if let Some(child) = children.get_mut(name) {
                match child.try_wait() {
                    Ok(Some(status)) => {
                        children.remove(name);
                        watchdog.exited(name, now);
                        // the classifier had read the estimates up to about here (the estimator's
                        // last is known once it is down: the last published)
                        read_to_at_exit.insert(name, last_estimate);
                        if name == "acquisition" && status.success() {
                            // the end of the stream: let the last frames drain
                            ended_at.get_or_insert(now);
                            continue;
                        }
                        if name == "recorder" && ended_at.is_some() {
                            // it finished its file
                            continue;
                        }
                        let ran = now.saturating_duration_since(started_at[name]);
                        let backoff = backoffs.entry(name).or_default();
                        let log = out_dir.join(match restarts.get(name) {
                            Some(n) => format!("{name}-{n}.log"),
                            None => format!("{name}.log"),
                        });
                        if name == "recorder"
                            && status.code() == Some(i32::from(recorder::shell::EXIT_LOG_UNWRITABLE))
                        {
                            // a full disk or an I/O error: a restart would fail the same way
                            let part = launch.log_part(restarts.get(name).copied().unwrap_or(0));
                            let why = crate::clean::log_write_error(&log, &part);
                            errln!(
                                "leakwatch run: error: {why}; the recorder is not restarted: monitoring goes on \
                                 without a log (events are printed here and written to events.json at the end)"
                            );
                            log_failure = Some(why);
                            launch.frame_subscribers = launch.frame_subscribers.saturating_sub(1);
                            continue;
                        }
                        // a prefix on which no node can start: a restart would fail the same way
                        if let Some(why) = crate::blocked::why_blocked(&bus_cfg, Some(&log)) {
                            if let Some(f) = crate::blocked::give_up(
                                name,
                                &why,
                                OPTIONAL_STAGES.contains(&name),
                                &mut log_failure,
                                &mut output_failures,
                                &mut launch.frame_subscribers,
                            ) {
                                failure = Some(f);
                                break;
                            }
                            continue;
                        }
                        match backoff.on_exit(ran) {
                            Decision::RestartIn(delay) => {
                                errln!(
                                    "leakwatch run: stage {name} exited ({status}) after {:.1} s; restarting it in {:.1} s \
                                     (restart {} since it last ran {} s; see {})",
                                    ran.as_secs_f64(),
                                    delay.as_secs_f64(),
                                    backoff.failures(),
                                    HEALTHY_RUN.as_secs(),
                                    log.display()
                                );
                                restart_at.insert(name, now + delay);
                            }
                            Decision::GiveUp if OPTIONAL_STAGES.contains(&name) => {
                                let why = format!(
                                    "stage {name} keeps failing: it exited {} times without running {} s in between \
                                     (last: {status}); see {}",
                                    MAX_RESTARTS + 1,
                                    HEALTHY_RUN.as_secs(),
                                    log.display()
                                );
                                errln!("leakwatch run: error: {why}; given up: monitoring goes on without it");
                                if name == "recorder" {
                                    log_failure = Some(why);
                                    launch.frame_subscribers = launch.frame_subscribers.saturating_sub(1);
                                } else {
                                    output_failures.push(why);
                                }
                            }
                            Decision::GiveUp => {
                                failure = Some(format!(
                                    "stage {name} keeps failing: it exited {} times without running {} s in between \
                                     (last: {status}); see {}",
                                    MAX_RESTARTS + 1,
                                    HEALTHY_RUN.as_secs(),
                                    log.display()
                                ));
                                break;
                            }
                        }
                    }
                    Ok(None) if watched(name) => match watchdog.check(name, now, name != "recorder") {
                        Some(Alarm::Stalled(idle)) => errln!(
                            "leakwatch run: warning: the {name} has made no progress for {:.1} s (process {} {})",
                            idle.as_secs_f64(),
                            child.id(),
                            stall_cause(child.id())
                        ),
                        Some(Alarm::Kill(idle)) => {
                            errln!(
                                "leakwatch run: the {name} has made no progress for {:.1} s; killing it to restart it",
                                idle.as_secs_f64()
                            );
                            let _ = child.kill();
                        }
                        None => {}
                    },
                    _ => {}
                }
            }
            if restart_at.get(name).is_some_and(|t| now >= *t) {
                restart_at.remove(name);
                // checked again: the prefix may have been damaged while the stage waited
                if let Some(why) = crate::blocked::why_blocked(&bus_cfg, None) {
                    if let Some(f) = crate::blocked::give_up(
                        name,
                        &why,
                        OPTIONAL_STAGES.contains(&name),
                        &mut log_failure,
                        &mut output_failures,
                        &mut launch.frame_subscribers,
                    ) {
                        failure = Some(f);
                        break;
                    }
                    continue;
                }
                let n = restarts.entry(name.to_string()).or_default();
                *n += 1;
                match spawn(
                    &program,
                    name,
                    &launch.of(
                        name,
                        *n,
                        &Resume {
                            last_frame,
                            after_estimate: match name {
                                "classifier" => read_to_at_exit.get(name).copied().flatten(),
                                _ => last_estimate,
                            },
                        },
                    ),
                    &prefix,
                    &out_dir.join(format!("{name}-{n}.log")),
                    cfg.run.cpu_of(name),
                ) {
                    Ok(c) => {
                        children.insert(name, c);
                        started_at.insert(name, now);
                        watchdog.started(name, now);
                    }
                    Err(e) => {
                        failure = Some(e);
                        break;
                    }
                }
            }
        }
        if failure.is_some() {
            break;
        }
        if let Some(t) = ended_at {
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
    // the classifier's pid, for the events still queued once it has stopped
    let classifier_pids: BTreeMap<&str, u32> = children
        .iter()
        .filter(|(n, _)| **n == "classifier" || **n == FUSED)
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
        stalls: watchdog.finish(Instant::now()),
    };
    // Written whatever ended the run; one that cannot be written into the output
    // directory (a full disk) goes to the temporary directory, said on stderr, and
    // masks no earlier failure.
    let events_path = crate::clean::write_somewhere(
        &out_dir,
        "events.json",
        &args.rig,
        &mut output_failures,
        |path, force| pipeline::replay::write_events(path, &events, force, &inputs),
        args.force,
    );
    let text = serde_json::to_string_pretty(&latency).map_err(|e| e.to_string())? + "\n";
    let latency_path = crate::clean::write_somewhere(
        &out_dir,
        "latency.json",
        &args.rig,
        &mut output_failures,
        |path, force| pipeline::out::write(path, text.as_bytes(), force, &inputs),
        args.force,
    );
    write_bag_metadata(&out_dir, args.force, &inputs);
    drop(events_rx);
    drop(stats_rx);
    drop(frames_rx);
    drop(estimates_rx);
    drop((frames_watch, events_watch));
    drop(bus);
    let _ = bus_cfg.remove_isolated_files();
    if let Some(f) = failure {
        let held: Vec<String> = [events_path, latency_path]
            .iter()
            .flatten()
            .map(|p| p.display().to_string())
            .collect();
        let also: Vec<&String> = log_failure.iter().chain(&output_failures).collect();
        return Err(format!(
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
        ));
    }
    Ok(RunOutcome {
        events,
        latency,
        out_dir,
        log_failure,
        output_failures,
        events_path,
        latency_path,
    })
}

/// The stages of the run ([`crate::stages::run_stages`]): the live view
/// (`--live-view [PORT]` or `[live_view] enabled`) and the Zenoh gateway
/// (`--zenoh`, `--zenoh-connect` or `[zenoh] enabled`) set in `cfg` for the
/// stages to read, checked (the live view's port free), and said on the console.
fn live_stages(
    args: &RunArgs,
    cfg: &mut Config,
    out_dir: &Path,
    inputs: &[&Path],
    quiet: bool,
    processes: &[&'static str],
) -> Result<Vec<&'static str>, String> {
    if let Some(port) = args.live_view {
        cfg.live_view.enabled = true;
        if port != 0 {
            cfg.live_view.port = port;
        }
    }
    if args.zenoh || !args.zenoh_connect.is_empty() {
        cfg.zenoh.enabled = true;
    }
    if !args.zenoh_connect.is_empty() {
        cfg.zenoh.connect = args.zenoh_connect.clone();
    }
    cfg.live_view.validate()?;
    cfg.zenoh.validate()?;
    let v = &cfg.live_view;
    if v.enabled {
        // the live view binds it again at once
        std::net::TcpListener::bind((v.bind.as_str(), v.port)).map_err(|e| {
            format!(
                "--live-view {}: cannot listen on {}:{}: {e}",
                v.port, v.bind, v.port
            )
        })?;
    }
    if v.enabled {
        // the shipped Foxglove layout with this rig's topics, beside the run's outputs
        let layout = out_dir.join(live::layout::LAYOUT_FILE_NAME);
        pipeline::out::write(
            &layout,
            live::layout::for_rig(&args.rig).as_bytes(),
            args.force,
            inputs,
        )?;
        if let Some(w) = v.exposure_warning() {
            errln!("leakwatch run: warning: {w}");
        }
        if !quiet {
            outln!(
                "live view: ws://{}:{}{} (Foxglove: Open connection, Foxglove WebSocket; frames {} Hz, estimates {} Hz)",
                v.bind,
                v.port,
                if v.token.is_some() || v.token_file.is_some() {
                    "/?token=TOKEN (the [live_view] token)"
                } else {
                    ""
                },
                v.frames_hz,
                v.estimates_hz
            );
            outln!(
                "live view layout: {} (Foxglove: Layouts, Import from file; {} for rig {})",
                layout.display(),
                live::layout::LAYOUT_REPO_PATH,
                args.rig
            );
        }
    }
    if cfg.zenoh.enabled && !quiet {
        outln!(
            "zenoh: publishing leakwatch/{}/{{events,health,estimates}}, connecting to [{}]",
            args.rig,
            cfg.zenoh.connect.join(", ")
        );
    }
    let stages = crate::stages::run_stages(processes, v.enabled, cfg.zenoh.enabled);
    for name in stages.iter().filter(|n| ["liveview", "gateway"].contains(n)) {
        pipeline::out::check(&out_dir.join(format!("{name}.log")), args.force, inputs)?;
    }
    Ok(stages)
}

/// Where a run without `--out` writes: `leakwatch-run-YYYYMMDD-HHMMSS` (its
/// UTC start time, as rosbag2 names a recording by its start), so a second run
/// never collides with the first; `-2`, `-3`, ... within one second.
fn default_out_dir() -> PathBuf {
    let ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i128);
    // "YYYY-MM-DD hh:mm:ss.mmm UTC" -> "YYYYMMDD-hhmmss"
    let digits: String = recorder::info::utc(ns)
        .chars()
        .take(19)
        .filter(char::is_ascii_digit)
        .collect();
    let stamp = format!("leakwatch-run-{}-{}", &digits[..8], &digits[8..]);
    let mut dir = PathBuf::from(&stamp);
    let mut n = 2;
    while dir.exists() {
        dir = PathBuf::from(format!("{stamp}-{n}"));
        n += 1;
    }
    dir
}

/// Writes the rosbag2 `metadata.yaml` beside the run's log, so that rosbag2
/// readers open the run's folder as a bag (`ros2 bag info DIR`, `rosbags`).
/// A log that cannot be read or a file that cannot be written is said on
/// stderr; the run's other outputs stand.
fn write_bag_metadata(out_dir: &Path, force: bool, inputs: &[&Path]) {
    let log = out_dir.join("run.mcap");
    if !log.is_file() {
        return;
    }
    let written = pipeline::logs::read_log(&log).and_then(|(l, parts, bytes)| {
        let mut info = recorder::Info::from_log(&log, bytes, &l);
        info.later_parts = parts.into_iter().skip(1).collect();
        let text = recorder::rosbag2::metadata_yaml(&info);
        pipeline::out::write(&out_dir.join("metadata.yaml"), text.as_bytes(), force, inputs)
    });
    if let Err(e) = written {
        eprintln!("leakwatch run: no rosbag2 metadata.yaml beside the log: {e}");
    }
}
