//! The supervisor's watchdog: notices a stage whose process is alive but makes
//! no progress (stopped, hung, or receiving nothing while its input is published),
//! reports it once when it starts and once when it ends, counts the stalls for
//! latency.json, and asks for a stage stalled too long to be killed (and so
//! restarted).
//!
//! Signs of progress: for the acquisition, each frame the supervisor receives
//! (to the millisecond); for the other stages, each stats frame (once a second)
//! unless `frames_in` stood still while the stage's upstream published, twice
//! running (once is the upstream's stats frame, out of phase, counting frames
//! the stage had already received, e.g. at the end of the stream). A stall of
//! a stage other than the acquisition is therefore measured to within the 1 s
//! stats period; one of a starved stage is noticed 1.5 s after its second
//! stats frame without input.

use crate::stages::Stage;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use serde::Serialize;

/// No progress for this long is a stall (the stats period is 1 s).
pub(super) const STALL_AFTER: Duration = Duration::from_millis(1500);
/// A stage stalled this long is killed so that it is restarted (not the
/// recorder: a slow disk stalls it, and a restart would not help).
pub(super) const KILL_AFTER: Duration = Duration::from_secs(5);
/// Time a (re)started process has before its first sign of progress is due
/// on top of [`STALL_AFTER`] (start-up; the first stats frame comes after 1 s).
pub(super) const START_ALLOWANCE: Duration = Duration::from_secs(2);

/// The stalls of one stage, in latency.json.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct StallFigures {
    /// Times the stage made no progress for more than 1.5 s.
    pub count: u32,
    /// The longest time without progress, s (0 if none).
    pub longest_s: f64,
    /// Times it was killed (and restarted) after 5 s without progress.
    pub killed: u32,
}

/// What the watchdog asks of the supervisor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Alarm {
    /// The stage has made no progress for this long: report it.
    Stalled(Duration),
    /// The stage has made no progress for this long: kill it (it is restarted).
    Kill(Duration),
}

#[derive(Debug, Default)]
struct Watch {
    /// The last sign of progress (after a start: the start plus the allowance);
    /// `None` while no process of the stage runs.
    last_progress: Option<Instant>,
    /// At the stage's previous stats frame: its pid, its `frames_in`, and its
    /// upstream's output so far.
    prev: Option<(u32, u64, u64)>,
    /// Stats frames running in which `frames_in` stood still while the upstream published.
    starved: u32,
    /// A stall is reported and not over.
    stalled: bool,
    /// The kill was asked for.
    kill_asked: bool,
    figures: StallFigures,
}

impl Watch {
    /// The stall in progress, if any, ends at `now`; returns how long it lasted.
    fn end_stall(&mut self, now: Instant) -> Option<Duration> {
        if !std::mem::take(&mut self.stalled) {
            return None;
        }
        let d = now.saturating_duration_since(self.last_progress?);
        self.figures.longest_s = self.figures.longest_s.max(d.as_secs_f64());
        Some(d)
    }
}

/// The watches of every stage.
#[derive(Debug, Default)]
pub(super) struct Watchdog {
    watches: BTreeMap<Stage, Watch>,
}

impl Watchdog {
    /// A process of `stage` started at `now`.
    pub(super) fn started(&mut self, stage: Stage, now: Instant) {
        let w = self.watches.entry(stage).or_default();
        w.end_stall(now);
        w.last_progress = Some(now + START_ALLOWANCE);
        w.prev = None;
        w.kill_asked = false;
    }

    /// The process of `stage` exited at `now` (a stall in progress ends there).
    pub(super) fn exited(&mut self, stage: Stage, now: Instant) {
        if let Some(w) = self.watches.get_mut(&stage) {
            w.end_stall(now);
            w.last_progress = None;
        }
    }

    /// `stage` showed progress at `now`; returns the length of the stall this ends.
    pub(super) fn progress(&mut self, stage: Stage, now: Instant) -> Option<Duration> {
        let w = self.watches.get_mut(&stage)?;
        w.last_progress?;
        let ended = w.end_stall(now);
        w.last_progress = Some(now);
        ended
    }

    /// A stats frame of `stage`'s process `pid` with its `frames_in`, when its
    /// upstream had published `upstream_out` frames in all; it is progress unless
    /// `frames_in` stood still while the upstream published, in this frame's
    /// interval and the one before. Returns the length of the stall this ends.
    pub(super) fn stats(
        &mut self,
        stage: Stage,
        pid: u32,
        frames_in: u64,
        upstream_out: u64,
        now: Instant,
    ) -> Option<Duration> {
        let w = self.watches.get_mut(&stage)?;
        let starved = match w.prev {
            Some((p, fin, up)) if p == pid => frames_in == fin && upstream_out > up,
            _ => false,
        };
        w.starved = if starved { w.starved + 1 } else { 0 };
        w.prev = Some((pid, frames_in, upstream_out));
        if w.starved < 2 {
            self.progress(stage, now)
        } else {
            None
        }
    }

    /// Whether `stage` has stalled at `now` (reported once per stall) or, if
    /// `may_kill`, stalled long enough to be killed (asked once per process).
    pub(super) fn check(&mut self, stage: Stage, now: Instant, may_kill: bool) -> Option<Alarm> {
        let w = self.watches.get_mut(&stage)?;
        let idle = now.checked_duration_since(w.last_progress?)?;
        if may_kill && idle > KILL_AFTER && !w.kill_asked {
            w.kill_asked = true;
            w.figures.killed += 1;
            return Some(Alarm::Kill(idle));
        }
        if idle > STALL_AFTER && !w.stalled {
            w.stalled = true;
            w.figures.count += 1;
            return Some(Alarm::Stalled(idle));
        }
        None
    }

    /// The stalls of every stage watched; a stall still in progress counts up to `now`.
    pub(super) fn finish(mut self, now: Instant) -> BTreeMap<String, StallFigures> {
        self.watches
            .iter_mut()
            .map(|(name, w)| {
                w.end_stall(now);
                (name.to_string(), w.figures.clone())
            })
            .collect()
    }
}

/// Why process `pid` may make no progress, from its state in `/proc/PID/stat`.
pub(super) fn stall_cause(pid: u32) -> &'static str {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    // the state follows the command name, which is in parentheses and may hold any byte
    let state = stat
        .rfind(')')
        .and_then(|i| stat[i + 1..].split_whitespace().next());
    match state {
        Some("T") => "stopped: SIGSTOP?",
        Some("t") => "stopped by a debugger",
        Some("D") => "waiting on I/O",
        _ => "hung, or receiving nothing while its input is published?",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(x: f64) -> Duration {
        Duration::from_secs_f64(x)
    }

    /// A stage stopped for 2 s between two stats frames: reported once at 1.5 s,
    /// ended by the next stats frame, counted with its length.
    #[test]
    fn a_stage_without_stats_for_two_seconds_is_one_stall() {
        let t0 = Instant::now();
        let mut w = Watchdog::default();
        w.started(Stage::Estimator, t0);
        assert_eq!(w.stats(Stage::Estimator, 7, 1000, 1000, t0 + s(1.0)), None);
        assert_eq!(w.check(Stage::Estimator, t0 + s(2.4), true), None);
        assert_eq!(
            w.check(Stage::Estimator, t0 + s(2.6), true),
            Some(Alarm::Stalled(s(1.6)))
        );
        assert_eq!(
            w.check(Stage::Estimator, t0 + s(2.9), true),
            None,
            "reported once"
        );
        assert_eq!(
            w.stats(Stage::Estimator, 7, 1300, 4000, t0 + s(3.5)),
            Some(s(2.5))
        );
        assert_eq!(w.check(Stage::Estimator, t0 + s(4.0), true), None);
        let f = w.finish(t0 + s(5.0));
        assert_eq!(
            f["estimator"],
            StallFigures {
                count: 1,
                longest_s: 2.5,
                killed: 0
            }
        );
    }

    /// Stats keep coming but `frames_in` stands still while the upstream
    /// publishes: a stall; while the upstream is idle too: none.
    #[test]
    fn a_stage_starved_while_its_upstream_publishes_is_stalled() {
        let t0 = Instant::now();
        let mut w = Watchdog::default();
        w.started(Stage::Classifier, t0);
        w.stats(Stage::Classifier, 9, 500, 500, t0 + s(1.0));
        // upstream idle: not a stall
        w.stats(Stage::Classifier, 9, 500, 500, t0 + s(2.0));
        w.stats(Stage::Classifier, 9, 500, 500, t0 + s(3.0));
        assert_eq!(w.check(Stage::Classifier, t0 + s(3.9), true), None);
        // the upstream's last stats frame counts frames the stage already had
        // (the end of the stream): once is not a stall
        w.stats(Stage::Classifier, 9, 500, 700, t0 + s(4.0));
        w.stats(Stage::Classifier, 9, 500, 700, t0 + s(5.0));
        assert_eq!(w.check(Stage::Classifier, t0 + s(6.4), true), None);
        // upstream publishes, the stage receives nothing, twice running
        w.stats(Stage::Classifier, 9, 500, 1700, t0 + s(6.0));
        w.stats(Stage::Classifier, 9, 500, 2700, t0 + s(7.0));
        assert_eq!(w.check(Stage::Classifier, t0 + s(7.4), true), None);
        assert_eq!(
            w.check(Stage::Classifier, t0 + s(7.6), true),
            Some(Alarm::Stalled(s(1.6)))
        );
        // a new process (restart) is progress
        assert_eq!(w.stats(Stage::Classifier, 10, 0, 2800, t0 + s(8.0)), Some(s(2.0)));
    }

    /// A stage stalled past 5 s is to be killed once (unless it may not be),
    /// and the stall ends with its exit.
    #[test]
    fn a_long_stall_asks_for_one_kill() {
        let t0 = Instant::now();
        let mut w = Watchdog::default();
        w.started(Stage::Acquisition, t0);
        w.started(Stage::Recorder, t0);
        w.progress(Stage::Acquisition, t0 + s(0.5));
        w.progress(Stage::Recorder, t0 + s(0.5));
        assert!(matches!(
            w.check(Stage::Acquisition, t0 + s(2.1), true),
            Some(Alarm::Stalled(_))
        ));
        assert!(matches!(
            w.check(Stage::Recorder, t0 + s(2.1), false),
            Some(Alarm::Stalled(_))
        ));
        assert_eq!(
            w.check(Stage::Acquisition, t0 + s(5.6), true),
            Some(Alarm::Kill(s(5.1)))
        );
        assert_eq!(w.check(Stage::Acquisition, t0 + s(5.7), true), None);
        assert_eq!(w.check(Stage::Recorder, t0 + s(5.7), false), None, "never killed");
        w.exited(Stage::Acquisition, t0 + s(5.8));
        assert_eq!(
            w.check(Stage::Acquisition, t0 + s(9.0), true),
            None,
            "not running"
        );
        let f = w.finish(t0 + s(6.5));
        assert_eq!((f["acquisition"].count, f["acquisition"].killed), (1, 1));
        assert!((f["acquisition"].longest_s - 5.3).abs() < 1e-9);
        assert!(
            (f["recorder"].longest_s - 6.0).abs() < 1e-9,
            "in progress at the end"
        );
    }

    #[test]
    fn this_process_is_running_not_stopped() {
        assert!(stall_cause(std::process::id()).starts_with("hung"));
    }
}
