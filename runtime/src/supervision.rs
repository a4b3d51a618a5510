//! The supervision of a run's stage processes: each exit noticed, a restart
//! with backoff (the acquisition continuing its stream, the estimator and the
//! classifier resuming after the last estimate), a stage that makes no progress
//! reported, then killed.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Child;
use std::time::{Duration, Instant};

use bus::say as errln;
use bus::BusConfig;
use bus::Received;
use config::Config;
use frames::{SensorFrame, StatsFrame};

use crate::figures::{StageAcc, STAGE_CODES};
use crate::launch::{Resume, StageArgs};
use crate::placement::Placement;
use crate::restart::{Backoff, Decision, HEALTHY_RUN, MAX_RESTARTS};
use crate::stages::{spawn, terminate, Stage};
use crate::watchdog::{stall_cause, Alarm, Watchdog};

/// Stages whose failure does not end the run: monitoring (acquisition,
/// estimator, classifier) goes on without them.
pub(crate) const OPTIONAL_STAGES: [Stage; 4] =
    [Stage::Recorder, Stage::LiveView, Stage::Gateway, Stage::Opcua];

/// Whether the watchdog watches stage `name`: the live view, the gateway and the
/// OPC UA server publish no stats (restarted when they exit, not watched), and a UDP stream
/// (`udp`) is paced by its sender, so no datagram is no stall.
pub(crate) fn watched(name: Stage, udp: bool) -> bool {
    !crate::stages::is_output(name) && (!udp || name != Stage::Acquisition)
}

/// Says that stage `name` made progress again after `d` without.
fn stall_ended(name: Stage, d: Duration) {
    errln!(
        "leakwatch run: the {name} runs again after {:.1} s without progress",
        d.as_secs_f64()
    );
}

/// A run's stage processes and what the supervisor has seen of them.
pub(crate) struct Supervision<'a> {
    /// The leakwatch binary the stages run from.
    pub program: &'a Path,
    /// The run's iceoryx2 prefix.
    pub prefix: &'a str,
    /// The run's output directory (the stages' logs).
    pub out_dir: &'a Path,
    /// The run's bus configuration.
    pub bus_cfg: &'a BusConfig,
    /// The run's configuration.
    pub cfg: &'a Config,
    /// The sensor stream is a UDP one.
    pub udp: bool,
    /// How each stage is started.
    pub launch: StageArgs,
    /// The running stage processes.
    pub children: BTreeMap<Stage, Child>,
    /// Progress of each stage.
    pub watchdog: Watchdog,
    /// Restarts per stage.
    pub restarts: BTreeMap<String, u32>,
    /// Each stage's backoff.
    pub backoffs: BTreeMap<Stage, Backoff>,
    /// When each stage's process started.
    pub started_at: BTreeMap<Stage, Instant>,
    /// When each stage that exited is due to start again.
    pub restart_at: BTreeMap<Stage, Instant>,
    /// The last frame published, where a restarted acquisition takes over.
    pub last_frame: Option<SensorFrame>,
    /// The last estimate published.
    pub last_estimate: Option<u64>,
    /// Where a stage that exited had read the estimates to.
    pub read_to_at_exit: BTreeMap<Stage, Option<u64>>,
    /// When the acquisition ended its stream.
    pub ended_at: Option<Instant>,
    /// Why the log could not be written, if it could not.
    pub log_failure: Option<String>,
    /// Other outputs given up while monitoring went on.
    pub output_failures: Vec<String>,
}

impl<'a> Supervision<'a> {
    /// The supervision of a run whose stages run `program` on iceoryx2 prefix
    /// `prefix`, started as `launch` says, before any has started (`udp`: the
    /// sensor stream is a UDP one).
    pub(crate) fn new(
        program: &'a Path,
        prefix: &'a str,
        out_dir: &'a Path,
        bus_cfg: &'a BusConfig,
        cfg: &'a Config,
        launch: StageArgs,
        udp: bool,
    ) -> Self {
        Supervision {
            program,
            prefix,
            out_dir,
            bus_cfg,
            cfg,
            udp,
            launch,
            started_at: BTreeMap::new(),
            children: BTreeMap::new(),
            watchdog: Watchdog::default(),
            restarts: BTreeMap::new(),
            backoffs: BTreeMap::new(),
            restart_at: BTreeMap::new(),
            last_frame: None,
            last_estimate: None,
            read_to_at_exit: BTreeMap::new(),
            ended_at: None,
            log_failure: None,
            output_failures: Vec::new(),
        }
    }

    /// Starts each of `stages` in turn (the acquisition first; 150 ms between
    /// the others). A stage that cannot start ends the start: the ones already
    /// started are killed first, so that their files can go too.
    pub(crate) fn start(&mut self, stages: &[Stage]) -> Result<(), String> {
        for &name in stages {
            let child = spawn(
                self.program,
                name,
                &self.launch.of(name, 0, &Resume::default()),
                self.prefix,
                &self.out_dir.join(format!("{name}.log")),
                self.cfg.run.cpu_of(name.name()),
            );
            let child = match child {
                Ok(child) => child,
                Err(e) => {
                    for (_, mut c) in std::mem::take(&mut self.children) {
                        let _ = c.kill();
                        let _ = c.wait();
                    }
                    return Err(format!("cannot start the {name}: {e}"));
                }
            };
            self.children.insert(name, child);
            self.watchdog.started(name, Instant::now());
            if name != Stage::Acquisition {
                std::thread::sleep(Duration::from_millis(150));
            }
        }
        self.started_at = stages.iter().map(|n| (*n, Instant::now())).collect();
        Ok(())
    }

    /// Stage `name` exited with `status` at `now`: the end of the stream (the
    /// acquisition), a log that cannot be written (the recorder), a prefix no
    /// node can start on, or a restart with backoff until it keeps failing.
    /// True when nothing more is done for it this round; an error is a failure
    /// that ends the run.
    fn on_exit(
        &mut self,
        name: Stage,
        status: std::process::ExitStatus,
        now: Instant,
    ) -> Result<bool, String> {
        self.children.remove(&name);
        self.watchdog.exited(name, now);
        // the classifier had read the estimates up to about here (the estimator's
        // last is known once it is down: the last published)
        self.read_to_at_exit.insert(name, self.last_estimate);
        if name == Stage::Acquisition && status.success() {
            // the end of the stream: let the last frames drain
            self.ended_at.get_or_insert(now);
            return Ok(true);
        }
        if name == Stage::Recorder && self.ended_at.is_some() {
            // it finished its file
            return Ok(true);
        }
        let ran = now.saturating_duration_since(self.started_at[&name]);
        let backoff = self.backoffs.entry(name).or_default();
        let log = self.out_dir.join(match self.restarts.get(name.name()) {
            Some(n) => format!("{name}-{n}.log"),
            None => format!("{name}.log"),
        });
        if name == Stage::Recorder && status.code() == Some(i32::from(recorder::shell::EXIT_LOG_UNWRITABLE)) {
            // a full disk or an I/O error: a restart would fail the same way
            let part = self
                .launch
                .log_part(self.restarts.get(name.name()).copied().unwrap_or(0));
            let why = crate::clean::log_write_error(&log, &part);
            errln!(
                "leakwatch run: error: {why}; the recorder is not restarted: monitoring goes on \
                 without a log (events are printed here and written to events.json at the end)"
            );
            self.log_failure = Some(why);
            self.launch.frame_subscribers = self.launch.frame_subscribers.saturating_sub(1);
            return Ok(true);
        }
        // a prefix on which no node can start: a restart would fail the same way
        if let Some(why) = crate::blocked::why_blocked(self.bus_cfg, Some(&log)) {
            self.give_up(name, format!("the {name} cannot be restarted: {why}"))?;
            return Ok(true);
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
                self.restart_at.insert(name, now + delay);
            }
            Decision::GiveUp => {
                self.give_up(
                    name,
                    format!(
                        "stage {name} keeps failing: it exited {} times without running {} s in between \
                         (last: {status}); see {}",
                        MAX_RESTARTS + 1,
                        HEALTHY_RUN.as_secs(),
                        log.display()
                    ),
                )?;
            }
        }
        Ok(false)
    }

    /// Gives stage `name` up for `why`: a stage monitoring needs ends the run
    /// (the error); an optional one (the recorder, the live view, the gateway)
    /// is said on stderr and kept in `log_failure` (the recorder: its frame
    /// subscription no longer awaited) or `output_failures`, and monitoring goes on.
    fn give_up(&mut self, name: Stage, why: String) -> Result<(), String> {
        if !OPTIONAL_STAGES.contains(&name) {
            return Err(why);
        }
        errln!("leakwatch run: error: {why}; given up: monitoring goes on without it");
        if name == Stage::Recorder {
            self.log_failure = Some(why);
            self.launch.frame_subscribers = self.launch.frame_subscribers.saturating_sub(1);
        } else {
            self.output_failures.push(why);
        }
        Ok(())
    }

    /// A frame the acquisition published: where a restarted one takes over, and
    /// its progress.
    pub(crate) fn on_frame(&mut self, frame: SensorFrame, now: Instant) {
        self.last_frame = Some(frame);
        if let Some(d) = self
            .watchdog
            .progress(Stage::Acquisition, now)
            .filter(|_| watched(Stage::Acquisition, self.udp))
        {
            stall_ended(Stage::Acquisition, d);
        }
    }

    /// A stats frame `st`: the progress of its stage's running process (the
    /// fused process: its estimator's), against its upstream's output as the
    /// stats gathered so far (`accs`, by stage code) say.
    pub(crate) fn on_stats(
        &mut self,
        st: &Received<StatsFrame>,
        accs: &BTreeMap<u32, StageAcc>,
        placement: Placement,
        now: Instant,
    ) {
        let Some(&stage) = STAGE_CODES.get(st.stage as usize) else {
            return;
        };
        let name = placement.process_of(stage);
        if stage == Stage::Acquisition
            || (name == Stage::EstimatorClassifier && stage == Stage::Classifier)
            || self.children.get(&name).map(Child::id) != Some(st.pid)
        {
            return;
        }
        let upstream = if stage == Stage::Classifier { 1 } else { 0 };
        let up_out = accs.get(&upstream).map_or(0, StageAcc::frames_out_total);
        if let Some(d) = self.watchdog.stats(name, st.pid, st.frames_in, up_out, now) {
            stall_ended(name, d);
        }
    }

    /// Ends every stage process (SIGTERM, then SIGKILL after 5 s) and returns
    /// the pid of the classifier's process, for the events still queued.
    pub(crate) fn stop(&mut self) -> BTreeMap<Stage, u32> {
        let classifier_pids = self
            .children
            .iter()
            .filter(|(n, _)| n.classifies())
            .map(|(n, c)| (*n, c.id()))
            .collect();
        for (_, c) in self.children.iter_mut() {
            terminate(c);
        }
        for (_, mut c) in std::mem::take(&mut self.children) {
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
        classifier_pids
    }

    /// Stage `name` at `now`: its exit noticed (a restart scheduled, or the
    /// stage given up), a stall reported or the stalled process killed, a
    /// restart that is due made. An error is a failure that ends the run.
    pub(crate) fn supervise_stage(&mut self, name: Stage, now: Instant) -> Result<(), String> {
        if let Some(child) = self.children.get_mut(&name) {
            match child.try_wait() {
                Ok(Some(status)) => {
                    let done = self.on_exit(name, status, now)?;
                    if done {
                        return Ok(());
                    }
                }
                Ok(None) if watched(name, self.udp) => {
                    match self.watchdog.check(name, now, name != Stage::Recorder) {
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
                    }
                }
                _ => {}
            }
        }
        if self.restart_at.get(&name).is_some_and(|t| now >= *t) {
            self.restart_at.remove(&name);
            // checked again: the prefix may have been damaged while the stage waited
            if let Some(why) = crate::blocked::why_blocked(self.bus_cfg, None) {
                return self.give_up(name, format!("the {name} cannot be restarted: {why}"));
            }
            let n = self.restarts.entry(name.to_string()).or_default();
            *n += 1;
            match spawn(
                self.program,
                name,
                &self.launch.of(
                    name,
                    *n,
                    &Resume {
                        last_frame: self.last_frame,
                        after_estimate: match name {
                            Stage::Classifier => self.read_to_at_exit.get(&name).copied().flatten(),
                            _ => self.last_estimate,
                        },
                    },
                ),
                self.prefix,
                &self.out_dir.join(format!("{name}-{n}.log")),
                self.cfg.run.cpu_of(name.name()),
            ) {
                Ok(c) => {
                    self.children.insert(name, c);
                    self.started_at.insert(name, now);
                    self.watchdog.started(name, now);
                }
                Err(e) => {
                    return Err(e);
                }
            }
        }
        Ok(())
    }
}
