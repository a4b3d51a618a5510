//! The estimator stage as the pipeline runs it: two filters side by side on
//! the same samples, and time kept from the sample stamps.
//!
//! - the **leak filter** (default: 12 states, sensor-derived tuning) estimates
//!   the three leak sizes, the spool bias and the oil's stiffness for
//!   leakwatch's detector;
//! - the **thesis filter** (default: 7 states, the thesis' tuning) gives the
//!   residuals and MAE of MODEL.md §5 for the baseline detector.
//!
//! Samples that arrive more than one period after the previous one mean that
//! samples were lost: short gaps are bridged by prediction, longer ones
//! re-anchor the fast states and keep the leak sizes (see
//! [`crate::Tuning::max_bridged_gap_samples`]).

use model::{ActuatorParams, Sample};

use crate::{Estimate, Estimator, Tuning};

/// What the stage reports for one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StageEstimate {
    /// The leak filter's estimate.
    pub leak: Estimate,
    /// The thesis filter's estimate.
    pub thesis: Estimate,
    /// Samples found missing just before this one.
    pub missing_before: u64,
}

/// Two estimators over one sample stream.
#[derive(Debug, Clone)]
pub struct EstimatorStage {
    leak: Estimator,
    thesis: Estimator,
    period_s: f64,
    last_t_s: Option<f64>,
    missing: u64,
}

impl EstimatorStage {
    /// A stage for model `params`, with `leak` and `thesis` filter settings.
    pub fn new(params: ActuatorParams, leak: Tuning, thesis: Tuning) -> Result<Self, String> {
        let period_s = leak.sample_period_s;
        Ok(EstimatorStage {
            leak: Estimator::new(params.clone(), leak)?,
            thesis: Estimator::new(params, thesis)?,
            period_s,
            last_t_s: None,
            missing: 0,
        })
    }

    /// The leak filter.
    pub fn leak(&self) -> &Estimator {
        &self.leak
    }

    /// The thesis filter.
    pub fn thesis(&self) -> &Estimator {
        &self.thesis
    }

    /// Samples found missing so far (gaps in the time stamps).
    pub fn missing_samples(&self) -> u64 {
        self.missing
    }

    /// A throw-away step of both filters before the next sample is due (see
    /// [`crate::Estimator::warm_up`]); nothing they estimate changes.
    pub fn warm_up(&mut self) {
        self.leak.warm_up();
        self.thesis.warm_up();
    }

    /// Processes one sample.
    #[inline]
    pub fn on_sample(&mut self, s: &Sample) -> StageEstimate {
        let mut missing_before = 0;
        if let Some(t_prev) = self.last_t_s {
            let steps = ((s.t_s - t_prev) / self.period_s).round();
            if steps > 1.0 && steps.is_finite() {
                missing_before = steps as u64 - 1;
                self.leak.on_gap(missing_before);
                self.thesis.on_gap(missing_before);
                self.missing += missing_before;
            }
        }
        if s.t_s.is_finite() {
            self.last_t_s = Some(s.t_s);
        }
        let mut leak = self.leak.on_sample(s);
        let mut thesis = self.thesis.on_sample(s);
        if missing_before > 0 {
            leak.flags |= crate::FLAG_AFTER_GAP;
            thesis.flags |= crate::FLAG_AFTER_GAP;
        }
        StageEstimate {
            leak,
            thesis,
            missing_before,
        }
    }
}
