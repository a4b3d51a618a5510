//! What the workflow returns: the gap, the effects found, the rounds of the
//! selection, the data used, the traces ([`Calibration`], [`EffectFit`]).

use std::collections::BTreeMap;

use model::params::ActuatorParams;
use serde::{Deserialize, Serialize};

use crate::{CalibrateOptions, RegimeBin};

/// RMS simulation-vs-measurement error on the validation windows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Gap {
    /// Rod position, m.
    pub x_m: f64,
    /// Chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Every channel normalised by its scale, combined RMS (dimensionless).
    pub normalised: f64,
    /// Force balance error (equation-error comparison), N.
    #[serde(default)]
    pub force_n: f64,
    /// Spool position error (equation-error comparison with a measured spool), m.
    #[serde(default)]
    pub spool_m: f64,
}

/// One effect added to the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoundEffect {
    /// Effect name (`friction-asymmetry`, `spool-bias`, ...).
    pub name: String,
    /// Which form of it was fitted.
    pub form: String,
    /// Fitted parameters by dotted field name, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Approximate standard deviation of each parameter, SI.
    pub parameter_std: BTreeMap<String, f64>,
    /// Relative reduction of the normalised validation gap when this effect was added
    /// (1 − gap after / gap before this step).
    pub gap_reduction: f64,
    /// Relative reduction of the validation gap of the nominal model, up to and including this effect.
    pub cumulative_gap_reduction: f64,
    /// The validation gap after adding it.
    pub gap_after: Gap,
    /// The residual signature of this effect.
    pub signature: String,
    /// What this data cannot tell about the effect, if anything (contains
    /// [`NOT_IDENTIFIABLE`](crate::NOT_IDENTIFIABLE)): for `bulk-modulus`, whether β depends on
    /// pressure, when the other form explains the record about as well (the
    /// chamber pressures visited do not separate them). The fitted value then
    /// holds near the pressures visited, not beyond.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caveat: Option<String>,
    /// Parameters of the effect this data cannot pin down, each with why
    /// (contains [`NOT_IDENTIFIABLE`](crate::NOT_IDENTIFIABLE)); they keep the model's value.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_identifiable: Vec<String>,
    /// The effect in engineering units (N, µm, kN/m, MPa, L/min, Hz, ...), one line per quantity.
    #[serde(default)]
    pub engineering: Vec<String>,
}

/// How one candidate fared in one round of the selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    /// Effect name.
    pub name: String,
    /// Its form.
    pub form: String,
    /// Fitted parameters, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Relative reduction of the validation gap (negative: worse).
    pub gap_reduction: f64,
    /// Change of the BIC on the fitting part (negative favours the effect).
    pub delta_bic: f64,
    /// Whether every parameter is seen by the data.
    pub identifiable: bool,
    /// Verdict: `added`, `explains too little`, `not identifiable from this data`, `screened out`, ...
    pub status: String,
}

/// One round of the greedy forward selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Round {
    /// Normalised validation gap at the start of the round.
    pub gap_before: f64,
    /// Every candidate, best first.
    pub candidates: Vec<CandidateScore>,
}

/// Facts about the data used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataSummary {
    /// Samples used.
    pub samples: usize,
    /// Span used, s.
    pub seconds: f64,
    /// Sample period, s.
    pub sample_period_s: f64,
    /// Shooting window length, s.
    pub window_s: f64,
    /// Windows in the fitting part.
    pub fit_windows: usize,
    /// Windows in the validation part.
    pub validation_windows: usize,
    /// Time at which validation starts, s.
    pub validation_start_s: f64,
    /// How the windows were split into fitting and validation.
    pub split: String,
}

/// Re-anchored traces over the validation part, for plots.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Traces {
    /// Time, s (NaN between windows to break lines).
    pub t_s: Vec<f64>,
    /// Measured [x m, p1 Pa, p2 Pa].
    pub measured: Vec<[f64; 3]>,
    /// Nominal model.
    pub before: Vec<[f64; 3]>,
    /// Calibrated model.
    pub after: Vec<[f64; 3]>,
}

/// The result of the workflow.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Effects added, in order.
    pub effects: Vec<FoundEffect>,
    /// Validation gap of the model given.
    pub gap_before: Gap,
    /// Validation gap of the calibrated model.
    pub gap_after: Gap,
    /// Overall relative reduction of the normalised validation gap.
    pub gap_reduction: f64,
    /// Every round of the selection with every candidate's score.
    pub rounds: Vec<Round>,
    /// Residual breakdown of the model given (validation part).
    pub breakdown_before: Vec<RegimeBin>,
    /// Residual breakdown of the calibrated model (validation part).
    pub breakdown_after: Vec<RegimeBin>,
    /// RMS of measured spool minus model spool, before and after, m (when x_sp is measured).
    pub spool_rms_m: Option<[f64; 2]>,
    /// Data used.
    pub data: DataSummary,
    /// The options used.
    pub options: CalibrateOptions,
    /// The model given.
    pub model_before: ActuatorParams,
    /// The calibrated model.
    pub model_after: ActuatorParams,
    /// Traces for plots (empty unless `keep_traces`).
    #[serde(skip)]
    pub traces: Traces,
    /// What the user should know about the data used (gaps, stretch used, no motion).
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Wall time, s.
    pub elapsed_s: f64,
}

impl Calibration {
    /// Names of the effects found, in order.
    pub fn names(&self) -> Vec<String> {
        self.effects.iter().map(|e| e.name.clone()).collect()
    }

    /// This calibration followed by `next`, a search from this one's model
    /// after a refit: every effect of both in order (each effect's cumulative
    /// reduction against this one's gap before), this one's model and gap
    /// before, `next`'s model and gap after, both rounds' candidates.
    pub fn followed_by(self, next: Calibration) -> Calibration {
        let before = self.gap_before.normalised.max(1e-300);
        let mut effects = self.effects;
        effects.extend(next.effects.into_iter().map(|mut e| {
            e.cumulative_gap_reduction = 1.0 - e.gap_after.normalised / before;
            e
        }));
        let mut rounds = self.rounds;
        rounds.extend(next.rounds);
        let mut warnings = self.warnings;
        for w in next.warnings {
            if !warnings.contains(&w) {
                warnings.push(w);
            }
        }
        let traces = Traces {
            after: next.traces.after,
            ..self.traces
        };
        Calibration {
            effects,
            gap_before: self.gap_before,
            gap_reduction: 1.0 - next.gap_after.normalised / before,
            gap_after: next.gap_after,
            rounds,
            breakdown_before: self.breakdown_before,
            breakdown_after: next.breakdown_after,
            spool_rms_m: match (self.spool_rms_m, next.spool_rms_m) {
                (Some([b, _]), Some([_, a])) => Some([b, a]),
                _ => next.spool_rms_m,
            },
            data: next.data,
            options: next.options,
            model_before: self.model_before,
            model_after: next.model_after,
            traces,
            warnings,
            elapsed_s: self.elapsed_s + next.elapsed_s,
        }
    }
}

/// One effect fitted on its own ([`fit_effect`](crate::fit_effect)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectFit {
    /// The effect.
    pub name: String,
    /// Its form.
    pub form: String,
    /// Fitted parameters, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Approximate standard deviations, SI.
    pub parameter_std: BTreeMap<String, f64>,
    /// Validation gap without the effect.
    pub gap_before: Gap,
    /// Validation gap with it.
    pub gap_after: Gap,
    /// 1 − gap after / gap before (normalised).
    pub gap_reduction: f64,
}
