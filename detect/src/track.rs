//! What the detectors share: the arming state, the event being tracked, and the
//! running statistics of a healthy estimate.

use crate::{ClassifierConfig, EventKind};
use filter::{Estimate, FLAG_CONVERGING, FLAG_SKIPPED};

/// Running mean and spread (Welford).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Stats {
    pub(crate) n: f64,
    pub(crate) mean: f64,
    pub(crate) m2: f64,
    pub(crate) max: f64,
}

impl Stats {
    pub(crate) fn push(&mut self, v: f64) {
        self.n += 1.0;
        let d = v - self.mean;
        self.mean += d / self.n;
        self.m2 += d * (v - self.mean);
        if self.n == 1.0 || v > self.max {
            self.max = v;
        }
    }
    pub(crate) fn std(&self) -> f64 {
        if self.n > 1.0 {
            (self.m2 / (self.n - 1.0)).sqrt()
        } else {
            0.0
        }
    }
}

/// Where a detector is in its life.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Arming {
    /// Waiting for the filter to converge.
    Converging,
    /// Converged since this time, s; waiting `settle_s` for the slow states to settle.
    Settling(f64),
    /// Learning the healthy statistics since this time, s.
    Learning(f64),
    /// Thresholds learned.
    Armed,
}

/// An event being tracked by a detector.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Active {
    pub(crate) kind: EventKind,
    pub(crate) id: u64,
    pub(crate) t_onset_s: f64,
    pub(crate) last_size_lpm: f64,
    pub(crate) last_update_s: f64,
    pub(crate) below_since_s: Option<f64>,
    /// Since when another kind has explained the data clearly better, s.
    pub(crate) other_since_s: Option<(usize, f64)>,
}

impl Active {
    /// Whether the event's clearing condition, `low` now, has held for `clear_s`
    /// (s) at sample time `t_s` (s); the timer restarts whenever it does not hold.
    pub(crate) fn low_for(&mut self, low: bool, t_s: f64, clear_s: f64) -> bool {
        if low {
            t_s - *self.below_since_s.get_or_insert(t_s) >= clear_s
        } else {
            self.below_since_s = None;
            false
        }
    }
}

pub(crate) fn arm_step(arming: &mut Arming, cfg: &ClassifierConfig, e: &Estimate) -> Option<bool> {
    // Returns Some(true) when the warm-up just ended, Some(false) while learning, None otherwise.
    match *arming {
        Arming::Converging => {
            if e.flags & FLAG_CONVERGING == 0 && e.flags & FLAG_SKIPPED == 0 {
                *arming = Arming::Settling(e.t_s);
            }
            None
        }
        Arming::Settling(t0) => {
            if e.t_s - t0 >= cfg.settle_s {
                *arming = Arming::Learning(e.t_s);
                Some(false)
            } else {
                None
            }
        }
        Arming::Learning(t0) => {
            if e.t_s - t0 >= cfg.warmup_s {
                *arming = Arming::Armed;
                Some(true)
            } else {
                Some(false)
            }
        }
        Arming::Armed => None,
    }
}
