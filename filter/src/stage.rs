//! The estimator stage as the pipeline runs it: two filters side by side on
//! the same samples, and time kept from the sample stamps.
//!
//! - the **leak filter** (default: 12 states, sensor-derived tuning) estimates
//!   the three leak sizes, the spool bias and the oil's stiffness for
//!   leakwatch's detector;
//! - the **thesis filter** (default: 7 states, the thesis' tuning) gives the
//!   residuals and MAE (docs/model.md#residuals-and-the-mae-pattern) for the
//!   baseline detector.
//!
//! The time step from one sample to the next, `round(Δt / T)` sample periods
//! `T`, is the one place gaps and restarts are decided ([`StepKind`]):
//!
//! - **two periods or more**: samples were lost, `round(Δt / T) − 1` of them
//!   (whether the source flagged the sample after a gap or not): short gaps
//!   are bridged by prediction, longer ones re-anchor the fast states and keep
//!   the leak sizes (see [`crate::Tuning::max_bridged_gap_samples`]); the
//!   estimate is flagged [`crate::FLAG_AFTER_GAP`] (and
//!   [`crate::FLAG_REANCHORED`] when re-anchored);
//! - **time went back** (`Δt < 0`), or a sample its source flagged after a gap
//!   ([`EstimatorStage::on_sample_flagged`]) comes one period or less after
//!   the previous one (the flag says samples are missing, the time says none
//!   are): the **stream restarted** (a sender's reboot, a clock set back).
//!   Neither the time nor the count of missing samples can be trusted, so
//!   nothing is bridged: both filters re-anchor their fast states on the new
//!   sample as after a gap too long to bridge ([`crate::Estimator::on_restart`]),
//!   the estimate is flagged [`crate::FLAG_AFTER_GAP`] and
//!   [`crate::FLAG_REANCHORED`], the restart is counted
//!   ([`EstimatorStage::stream_restarts`]) and kept for the process to report
//!   ([`EstimatorStage::last_restart`]);
//! - **otherwise** (one period, or less without the flag): the next sample.
//!
//! A sample without a finite time decides nothing and is not a time reference.

use std::fmt;

use model::{ActuatorParams, Sample};

use crate::{Estimate, Estimator, Tuning};

/// What the stage reports for one sample (its default: both estimates empty).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageEstimate {
    /// The leak filter's estimate.
    pub leak: Estimate,
    /// The thesis filter's estimate.
    pub thesis: Estimate,
    /// Samples found missing just before this one (0 after a stream restart,
    /// whose count of missing samples is unknown; its flags tell).
    pub missing_before: u64,
}

/// A restart of the sample stream the stage found (see the [module](self) docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamRestart {
    /// Sample time of the last sample before the restart, s.
    pub t_before_s: f64,
    /// Sample time of the first sample after it, s.
    pub t_after_s: f64,
}

impl fmt::Display for StreamRestart {
    /// The line the estimator process writes to stderr for the restart.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.t_after_s < self.t_before_s {
            write!(
                f,
                "sensor stream restarted at t = {} s (time went back from {} s): filters re-anchored",
                self.t_after_s, self.t_before_s
            )
        } else {
            write!(
                f,
                "sensor stream restarted at t = {} s (flagged after a gap, but at most one sample period \
                 after the previous sample at {} s): filters re-anchored",
                self.t_after_s, self.t_before_s
            )
        }
    }
}

/// What the time step to a sample says about the stream (the one place that decides).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum StepKind {
    /// The next sample (or no decision: the first sample, a time that is not finite).
    Next,
    /// This many samples were lost before the sample.
    Gap(u64),
    /// The stream restarted before the sample.
    Restart,
}

/// The kind of the step from a sample at `t_prev_s` to one at `t_s`, s, with
/// sample period `period_s`; `flagged`: the source flagged the sample after a gap.
fn step_kind(t_prev_s: f64, t_s: f64, period_s: f64, flagged: bool) -> StepKind {
    let dt_s = t_s - t_prev_s;
    let steps = (dt_s / period_s).round();
    if steps > 1.0 && steps.is_finite() {
        StepKind::Gap(steps as u64 - 1)
    } else if dt_s < 0.0 || (flagged && steps <= 1.0) {
        StepKind::Restart
    } else {
        StepKind::Next
    }
}

/// Two estimators over one sample stream.
#[derive(Debug, Clone)]
pub struct EstimatorStage {
    leak: Estimator,
    thesis: Estimator,
    /// Whether the thesis filter runs ([`EstimatorStage::with_thesis`]).
    thesis_runs: bool,
    period_s: f64,
    last_t_s: Option<f64>,
    missing: u64,
    restarts: u64,
    last_restart: Option<StreamRestart>,
}

impl EstimatorStage {
    /// A stage for model `params`, with `leak` and `thesis` filter settings.
    pub fn new(params: ActuatorParams, leak: Tuning, thesis: Tuning) -> Result<Self, String> {
        let period_s = leak.sample_period_s;
        Ok(EstimatorStage {
            leak: Estimator::new(params.clone(), leak)?,
            thesis: Estimator::new(params, thesis)?,
            thesis_runs: true,
            period_s,
            last_t_s: None,
            missing: 0,
            restarts: 0,
            last_restart: None,
        })
    }

    /// The leak filter.
    pub fn leak(&self) -> &Estimator {
        &self.leak
    }

    /// The stage with its thesis filter running (`runs`, the default) or not,
    /// for a consumer that reads only the leak filter: each
    /// [`StageEstimate::thesis`] is then empty (NaN, flagged
    /// [`crate::FLAG_SKIPPED`]) and costs nothing. The thesis filter is about
    /// a third of the stage's work.
    pub fn with_thesis(mut self, runs: bool) -> Self {
        self.thesis_runs = runs;
        self
    }

    /// Whether the thesis filter runs (see [`Self::with_thesis`]).
    pub fn thesis_runs(&self) -> bool {
        self.thesis_runs
    }

    /// The thesis filter.
    pub fn thesis(&self) -> &Estimator {
        &self.thesis
    }

    /// Samples found missing so far (gaps in the time stamps; restarts not counted).
    pub fn missing_samples(&self) -> u64 {
        self.missing
    }

    /// Restarts of the sample stream found so far (see the [module](self) docs).
    pub fn stream_restarts(&self) -> u64 {
        self.restarts
    }

    /// The latest restart of the sample stream, if any.
    pub fn last_restart(&self) -> Option<StreamRestart> {
        self.last_restart
    }

    /// A throw-away step of both filters before the next sample is due (see
    /// [`crate::Estimator::warm_up`]); nothing they estimate changes.
    pub fn warm_up(&mut self) {
        self.leak.warm_up();
        if self.thesis_runs {
            self.thesis.warm_up();
        }
    }

    /// Processes one sample (gaps and restarts from its time alone).
    #[inline]
    pub fn on_sample(&mut self, s: &Sample) -> StageEstimate {
        self.on_sample_flagged(s, false)
    }

    /// Processes one sample whose source says whether samples were missing
    /// just before it (`after_gap`: the sensor frame's after-gap flag). A
    /// flagged sample whose time shows no gap is a stream restart; one whose
    /// time shows a gap is processed exactly as without the flag.
    #[inline]
    pub fn on_sample_flagged(&mut self, s: &Sample, after_gap: bool) -> StageEstimate {
        let mut out = StageEstimate::default();
        self.on_sample_flagged_into(s, after_gap, &mut out);
        out
    }

    /// [`Self::on_sample_flagged`] into `out`, which it overwrites whole: the
    /// hot path's form (the estimates are written where the caller keeps them).
    #[inline]
    pub fn on_sample_flagged_into(&mut self, s: &Sample, after_gap: bool, out: &mut StageEstimate) {
        let mut missing_before = 0;
        let mut restarted = false;
        if let (Some(t_prev_s), true) = (self.last_t_s, s.t_s.is_finite()) {
            match step_kind(t_prev_s, s.t_s, self.period_s, after_gap) {
                StepKind::Next => {}
                StepKind::Gap(missing) => {
                    missing_before = missing;
                    self.leak.on_gap(missing_before);
                    if self.thesis_runs {
                        self.thesis.on_gap(missing_before);
                    }
                    self.missing += missing_before;
                }
                StepKind::Restart => {
                    // the new time against the one the next sample was due at
                    let time_shift_s = s.t_s - (t_prev_s + self.period_s);
                    self.leak.on_restart(time_shift_s);
                    if self.thesis_runs {
                        self.thesis.on_restart(time_shift_s);
                    }
                    self.restarts += 1;
                    self.last_restart = Some(StreamRestart {
                        t_before_s: t_prev_s,
                        t_after_s: s.t_s,
                    });
                    restarted = true;
                }
            }
        }
        if s.t_s.is_finite() {
            self.last_t_s = Some(s.t_s);
        }
        self.leak.on_sample_into(s, &mut out.leak);
        if self.thesis_runs {
            self.thesis.on_sample_into(s, &mut out.thesis);
        } else {
            out.thesis = Estimate::empty(s.t_s, self.thesis.tuning().states);
            out.thesis.flags = crate::FLAG_SKIPPED;
        }
        if missing_before > 0 || restarted {
            out.leak.flags |= crate::FLAG_AFTER_GAP;
            out.thesis.flags |= crate::FLAG_AFTER_GAP;
        }
        out.missing_before = missing_before;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_step_decides_gaps_and_restarts() {
        let t = 1e-3;
        for flagged in [false, true] {
            assert_eq!(step_kind(1.0, 1.002, t, flagged), StepKind::Gap(1));
            assert_eq!(step_kind(1.0, 1.0514, t, flagged), StepKind::Gap(50));
            assert_eq!(step_kind(1.0, 0.0, t, flagged), StepKind::Restart);
            assert_eq!(step_kind(1.0, 0.9999, t, flagged), StepKind::Restart);
        }
        assert_eq!(step_kind(1.0, 1.001, t, false), StepKind::Next);
        assert_eq!(step_kind(1.0, 1.0, t, false), StepKind::Next);
        assert_eq!(step_kind(1.0, 1.001, t, true), StepKind::Restart);
        assert_eq!(step_kind(1.0, 1.0, t, true), StepKind::Restart);
        assert_eq!(step_kind(1.0, f64::INFINITY, t, false), StepKind::Next);
    }
}
