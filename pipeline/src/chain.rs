//! The estimator stage and the detectors as one chain ([`Chain`]), built
//! from [`ChainSettings`].

use detect::{Classifier, ClassifierConfig, LeakEvent};
use filter::{EstimatorStage, StageEstimate, Tuning};
use model::{ActuatorParams, Sample};

/// What a chain is built from: the model the filters believe in, their
/// tunings and the detectors' settings.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainSettings {
    /// The model the filters believe in.
    pub model: ActuatorParams,
    /// The leak filter's tuning.
    pub leak_filter: Tuning,
    /// The thesis filter's tuning.
    pub thesis_filter: Tuning,
    /// The detectors.
    pub classifier: ClassifierConfig,
}

impl Default for ChainSettings {
    /// The built-in rig: the thesis rig's model, the sensor-derived leak filter,
    /// the thesis' tuning and the default detectors.
    fn default() -> Self {
        ChainSettings {
            model: ActuatorParams::default(),
            leak_filter: Tuning::sensor_derived(),
            thesis_filter: Tuning::thesis(),
            classifier: ClassifierConfig::default(),
        }
    }
}

impl From<&config::Config> for ChainSettings {
    /// `[model]`, `[leak_filter]`, `[estimator]` and `[classifier]` of a loaded config.
    fn from(cfg: &config::Config) -> Self {
        ChainSettings {
            model: cfg.model.clone(),
            leak_filter: cfg.leak_filter.clone(),
            thesis_filter: cfg.estimator.clone(),
            classifier: cfg.classifier.clone(),
        }
    }
}

impl ChainSettings {
    /// The estimator stage alone with its leak filter only (the thesis filter
    /// off): what commissioning's learners read.
    pub fn leak_stage(&self) -> Result<EstimatorStage, String> {
        Ok(EstimatorStage::new(
            self.model.clone(),
            self.leak_filter.clone(),
            self.thesis_filter.clone(),
        )?
        .with_thesis(false))
    }
}

/// The estimator stage and the detectors, one sample at a time.
pub struct Chain {
    stage: EstimatorStage,
    classifier: Classifier,
    /// The latest sample's estimates, written in place each step.
    estimate: StageEstimate,
}

impl Chain {
    /// The chain `set` describes. Its thesis filter runs only with the thesis'
    /// baseline detector (`classifier.thesis_baseline`), the one reader of it
    /// ([`Chain::with_thesis`] to run it for its estimates).
    pub fn new(set: &ChainSettings) -> Result<Chain, String> {
        let stage = EstimatorStage::new(
            set.model.clone(),
            set.leak_filter.clone(),
            set.thesis_filter.clone(),
        )?
        .with_thesis(set.classifier.thesis_baseline);
        Ok(Chain {
            stage,
            classifier: Classifier::new(set.classifier.clone())?,
            estimate: StageEstimate::default(),
        })
    }

    /// The chain with its thesis filter running (`runs`) or not.
    pub fn with_thesis(mut self, runs: bool) -> Chain {
        self.stage = self.stage.with_thesis(runs);
        self
    }

    /// Estimates `sample`, hands it to the detectors (each event to
    /// `on_event`) and returns the estimate.
    #[inline]
    pub fn step(&mut self, sample: &Sample, on_event: impl FnMut(LeakEvent)) -> &StageEstimate {
        self.stage
            .on_sample_flagged_into(sample, false, &mut self.estimate);
        self.classifier.on_stage(&self.estimate, on_event);
        &self.estimate
    }

    /// Ends the stream at sample time `t_s` (s): the detectors report a warm-up
    /// that never completed (to `on_event`).
    pub fn finish(&mut self, t_s: f64, on_event: impl FnMut(LeakEvent)) {
        self.classifier.finish(t_s, on_event);
    }

    /// The estimator stage.
    pub fn stage(&self) -> &EstimatorStage {
        &self.stage
    }

    /// The detectors.
    pub fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    /// Both halves, to run them on two threads (replay's channel wiring): the
    /// stage estimates, the detectors take each estimate in order.
    pub fn parts_mut(&mut self) -> (&mut EstimatorStage, &mut Classifier) {
        (&mut self.stage, &mut self.classifier)
    }
}
