//! The classifier's settings and a rig's commissioning (its learned healthy state).

use crate::events::nan;
use schema::{int, num};
use serde::{Deserialize, Serialize};

schema::config_struct! {
    /// What a healthy commissioning run taught about the leak filter's estimates:
    /// loaded at start, it arms the detector at once, so that a leak already
    /// present when monitoring starts shows against it (`[classifier.commissioning]`,
    /// written by `leakwatch commission`).
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Commissioning {
        /// Healthy offset (median) of each single-leak size (ext1, ext2, int), L/min at the nominal drop.
        pub offsets_lpm: [f64; 3],
        /// Healthy spread of each (upper semi-deviation: RMS above the median), L/min at the nominal drop.
        pub spreads_lpm: [f64; 3],
        /// Healthy spread of each kind's rises where that kind explains them clearly
        /// (the test that names it): their RMS above the median, at most `spreads_lpm`,
        /// L/min at the nominal drop; it sets the threshold a named leak must pass
        /// (NaN: not learned, `spreads_lpm` stands in).
        #[serde(default = "nan_per_kind")]
        pub clear_spreads_lpm: [f64; 3],
        /// Upcrossings of the healthy offset per second, per kind (for the threshold, Rice's formula).
        pub crossings_per_s: [f64; 3],
        /// Seconds of healthy, converged data learned from, s.
        pub healthy_s: f64 => ["s"],
        /// Mean normalised innovation squared of the healthy data (NaN: unknown).
        #[serde(default = "nan")]
        pub nis_mean: f64,
        /// Where it was learned (the recording's path).
        #[serde(default)]
        pub source: String,
        /// The internal leak's pressure factors (r1, r2) of the chamber-flow
        /// signatures ([`crate::signatures_with`]), 1: ssqrt(p1 − p2)/√p_i at the
        /// recording's mean pressures where p1 − p2 kept its sign, else (1, 1).
        #[serde(default = "nominal_factors")]
        pub internal_factors: [f64; 2],
        /// The least offset the detector names on p1 and on p2 (kPa) and on x
        /// (mm), on a duty cycle like the recording's, as `commission` stated
        /// it: inf, that channel is not watched; NaN, not stated.
        #[serde(default = "nan_per_kind")]
        pub least_offsets_named: [f64; 3],
        /// The offset on p1 and on p2 the healthy rises fit over the
        /// recording, in its swing about the baseline, kPa (measured minus
        /// true; 0: none taken): the model's own error swinging with the flow
        /// as a misreading does, which the offset watch takes off the rises
        /// before it fits. `commission` sets it.
        #[serde(default)]
        pub healthy_offsets_kpa: [f64; 2],
        /// The same as a span error on p1 and on p2, 1 (the channel reads
        /// (1 + g)·p; 0: none taken), where a span error fits the healthy
        /// rises better. `commission` sets it.
        #[serde(default)]
        pub healthy_span_errors: [f64; 2],
        /// How uncertain the transducers' delay taken off the leak sizes is,
        /// s: how far it lies from the identification's lag, and at least a
        /// fifth of it (0: not stated). The levels a rise must pass to raise
        /// or name a leak widen by it times the leak sizes' response to a
        /// delay ([`filter::Estimate::delay_response_lpm_per_ms`]).
        /// `commission` sets it.
        #[serde(default)]
        pub delay_uncertainty_s: f64 => ["s"],
        /// The response to a delay on both transducers (per kind: ext1, ext2,
        /// int; L/min per ms) the healthy spreads saw the delay's uncertainty
        /// at: only what a response has beyond it widens the levels. 0 after
        /// a sure fit of the delay; otherwise the response 99 % of the
        /// recording's samples stay within. `commission` sets it.
        #[serde(default)]
        pub delay_response_reach_lpm_per_ms: [f64; 3],
    }
}

fn nan_per_kind() -> [f64; 3] {
    [f64::NAN; 3]
}

fn nominal_factors() -> [f64; 2] {
    crate::NOMINAL_INTERNAL_FACTORS
}

impl Commissioning {
    /// The healthy rises' own misreading commissioning took, if any.
    pub fn healthy_misreading(&self) -> Option<crate::offset::HealthyMisreading> {
        crate::offset::HealthyMisreading::from_kept(self.healthy_offsets_kpa, self.healthy_span_errors)
    }

    /// The spreads that set the thresholds a named leak must pass, L/min:
    /// [`Commissioning::clear_spreads_lpm`] where learned, else the spreads.
    pub fn naming_spreads_lpm(&self) -> [f64; 3] {
        std::array::from_fn(|k| {
            let c = self.clear_spreads_lpm[k];
            if c.is_nan() {
                self.spreads_lpm[k]
            } else {
                c
            }
        })
    }

    /// Whether an offset on x is watched: not where commissioning found its
    /// response lost in the model's error (`least_offsets_named` on x inf).
    pub fn position_watched(&self) -> bool {
        self.least_offsets_named[2] != f64::INFINITY
    }

    /// What commissioning found the detector cannot watch on this rig, as a
    /// phrase (`None`: nothing, or not stated).
    pub fn not_watched(&self) -> Option<&'static str> {
        (!self.position_watched())
            .then_some("an offset on x is not watched (commissioning found it moves the leak sizes too little on this rig)")
    }

    fn validate(&self) -> Result<(), String> {
        let all = self
            .offsets_lpm
            .iter()
            .chain(&self.spreads_lpm)
            .chain(&self.crossings_per_s)
            .chain(&self.internal_factors)
            .chain(std::iter::once(&self.healthy_s));
        if let Some(v) = self.least_offsets_named.iter().find(|v| **v <= 0.0) {
            return Err(format!(
                "[classifier.commissioning] least_offsets_named holds {v}: each is positive, inf (not watched) or nan (not stated)"
            ));
        }
        for v in all {
            if !v.is_finite() {
                return Err(format!(
                    "[classifier.commissioning] holds {v}: every figure must be finite"
                ));
            }
        }
        if self
            .spreads_lpm
            .iter()
            .chain(&self.crossings_per_s)
            .any(|v| *v < 0.0)
            || self.healthy_s <= 0.0
        {
            return Err(
                "[classifier.commissioning] spreads, crossings and healthy_s must be ≥ 0 (healthy_s > 0)"
                    .into(),
            );
        }
        if self
            .offsets_lpm
            .iter()
            .chain(&self.spreads_lpm)
            .any(|v| v.abs() > 1e4)
            || self.crossings_per_s.iter().any(|v| *v > 1e6)
            || self.healthy_s > 1e9
            || self.nis_mean.is_infinite()
        {
            return Err(
                "[classifier.commissioning] offsets and spreads must be within ±1e4 L/min, crossings \
                 at most 1e6 per s, healthy_s at most 1e9 s, nis_mean finite or NaN"
                    .into(),
            );
        }
        if self
            .clear_spreads_lpm
            .iter()
            .zip(&self.spreads_lpm)
            .any(|(c, s)| !(c.is_nan() || (0.0..=*s).contains(c)))
        {
            return Err(format!(
                "[classifier.commissioning] clear_spreads_lpm = {:?}: each between 0 and its spread (spreads_lpm), or NaN",
                self.clear_spreads_lpm
            ));
        }
        self.validate_healthy_misreading()?;
        let [r1, r2] = self.internal_factors;
        if r1 * r2 <= 0.0 || r1.abs() > 10.0 || r2.abs() > 10.0 {
            return Err(format!(
                "[classifier.commissioning] internal_factors = [{r1}, {r2}]: both of one sign, nonzero and within ±10"
            ));
        }
        Ok(())
    }

    /// The kept healthy misreading: finite, within what a transducer's
    /// misreading can be (±5000 kPa, ±0.5), and one at most (the watch
    /// takes one off).
    fn validate_healthy_misreading(&self) -> Result<(), String> {
        let offsets = self.healthy_offsets_kpa;
        let spans = self.healthy_span_errors;
        if offsets
            .iter()
            .any(|v| v.is_nan() || v.abs() > HEALTHY_OFFSET_MAX_KPA)
        {
            return Err(format!(
                "[classifier.commissioning] healthy_offsets_kpa = {offsets:?}: each finite and within ±{HEALTHY_OFFSET_MAX_KPA} kPa"
            ));
        }
        if spans
            .iter()
            .any(|v| v.is_nan() || v.abs() > HEALTHY_SPAN_ERROR_MAX)
        {
            return Err(format!(
                "[classifier.commissioning] healthy_span_errors = {spans:?}: each finite and within ±{HEALTHY_SPAN_ERROR_MAX}"
            ));
        }
        let kept = offsets.iter().chain(&spans).filter(|v| **v != 0.0).count();
        if kept > 1 {
            return Err(format!(
                "[classifier.commissioning] healthy_offsets_kpa = {offsets:?} and healthy_span_errors = {spans:?}: \
                 one misreading at most is taken (the others 0)"
            ));
        }
        Ok(())
    }
}

/// Largest healthy offset `[classifier.commissioning]` may keep, kPa.
const HEALTHY_OFFSET_MAX_KPA: f64 = 5000.0;

/// Largest healthy span error `[classifier.commissioning]` may keep, 1.
const HEALTHY_SPAN_ERROR_MAX: f64 = 0.5;

schema::config_struct! {
    /// Settings of the detectors, `[classifier]` in the TOML config.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct ClassifierConfig {
        /// Time after the filter has converged before learning starts (the leak and
        /// bias estimates settle), s.
        pub settle_s: f64 = 3.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Healthy warm-up after settling, used to learn thresholds, s.
        pub warmup_s: f64 = 5.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Shortest warm-up that can give thresholds, s.
        pub min_warmup_s: f64 = 3.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: the false-alarm rate asked for, per hour. The threshold
        /// on the rise, in healthy spreads, is c = √(2 ln(N₀/rate)) (Rice's formula for
        /// a Gaussian process with N₀ upcrossings of its mean per hour, learned in the
        /// warm-up), never below `threshold_sigma`.
        pub false_alarms_per_hour: f64 = 0.05 => ["per hour", num!("a number", 1e-9, 1000000.0)],
        /// Leak-size detector: least threshold in spreads of the healthy estimate.
        pub threshold_sigma: f64 = 4.0 => ["healthy spreads", num!("a number", 0.0, 1000.0)],
        /// Leak-size detector: at the first alarm, the part of the flow mismatch the
        /// named kind leaves unexplained must be below this fraction of its size (the
        /// kind is decided before the alarm is raised).
        pub isolation_max_misfit: f64 = 0.35 => ["(fraction of the size)", num!("a number", 0.0, 10.0)],
        /// Leak-size detector: window of the measured pressures over which the real
        /// leak flow is averaged, s.
        pub size_window_s: f64 = 2.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: after a gap, a skipped sample or a filter reset, no
        /// evidence for this long (the filter re-converges), s.
        pub recovery_s: f64 = 2.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: a normalised innovation squared above this (an innovation
        /// of about √nis_gate standard deviations) means the filter has lost track for
        /// a moment: no evidence for `recovery_s` after it (the model's errors in such a
        /// moment, a reversal with the valve saturated, move the leak estimates).
        pub nis_gate: f64 = 2000.0 => ["(normalised innovation squared)", num!("a number", 0.0, 1000000000000000.0)],
        /// Leak-size detector: while the NIS averaged over the last 5 s exceeds this
        /// many times its healthy mean (the model no longer tracks the input, e.g. a fast
        /// chirp), evidence does not count (0 = off).
        pub nis_ratio_gate: f64 = 3.0 => ["(times the healthy mean NIS)", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: while the valve command reverses faster than this (its
        /// frequency, from swings through ±1 V over the last 2 s), evidence does not
        /// count (0 = off, the default), Hz. For a rig whose model is known not to
        /// follow fast inputs; leakwatch's own model follows the 10.5 Hz chirp since
        /// the filters hold each command over the interval after its sample
        /// (2026-11-25; the gate was 3 Hz before).
        pub max_command_hz: f64 = 0.0 => ["Hz", num!("a number", 0.0, 100000.0)],
        /// Emit the thesis' MAE baseline detector's events too (a comparison, off by
        /// default; the live estimator runs the thesis filter only then).
        pub thesis_baseline: bool = false,
        /// The healthy state learned by commissioning (absent: learned in a warm-up,
        /// and a leak present at start cannot be seen).
        pub commissioning: Option<Commissioning> = None,
        /// Leak-size detector: once this much healthy evidence has been seen after arming
        /// (no leak, every rise below `baseline_hold` of its threshold), the thresholds
        /// are taken from the spread of the rises since arming, refined every second,
        /// where lower than the warm-up's (0 = keep the warm-up's); not with a
        /// commissioning, s.
        pub refine_after_s: f64 = 5.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: smallest external leak (ext1, ext2) ever declared, L/min
        /// of real flow at the measured pressures (its threshold at p_s/2 is at least
        /// this divided by √(Δp/(p_s/2)) averaged over `size_window_s`).
        pub min_size_lpm: f64 = 0.03 => ["L/min", num!("a number", 0.0, 10000.0)],
        /// Leak-size detector: smallest internal leak ever declared, L/min of real flow
        /// at the measured pressures (as `min_size_lpm`). Higher than the external
        /// floor: one chamber losing what the other gains is also what a spool null
        /// error or a rod held by stiction makes the healthy model show.
        pub min_internal_size_lpm: f64 = 0.04 => ["L/min", num!("a number", 0.0, 10000.0)],
        /// Leak-size detector: evidence (time above threshold, weighted by `confirm_gain_cap`) before a leak is declared, s.
        pub confirm_s: f64 = 0.2 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: evidence before an external leak is declared while it
        /// alone explains the mismatch clearly (one chamber loses flow, the other does
        /// not), s; at most `confirm_s`. A transient of the rod or the spool (a
        /// breakaway from stiction, a reference step) moves both chambers' flows at
        /// once, in opposite directions: the pattern of an internal leak or of both
        /// kinds together, which keeps `confirm_s`.
        pub confirm_external_s: f64 = 0.1 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: a rise r thresholds high counts min(r, this) seconds of
        /// evidence per second towards `confirm_s` (1 = plain time above threshold; a
        /// leak far above its threshold is confirmed sooner).
        pub confirm_gain_cap: f64 = 2.0 => ["(thresholds)", num!("a number", 1.0, 100.0)],
        /// Leak-size detector: time constant of the healthy baseline that the rise is
        /// measured from, s (0 = the warm-up offset, never adapted).
        pub baseline_tau_s: f64 = 15.0 => ["s", num!("a number", 0.0, 100000000.0)],
        /// Leak-size detector: while any rise exceeds this fraction of its threshold the
        /// baseline holds, for at most `baseline_hold_s` (a leak opening over seconds is
        /// not absorbed on its way to the threshold, a drift of the operating point is
        /// still followed); only once the baseline has followed the estimates for
        /// `baseline_tau_s` after arming (before that it is still settling).
        pub baseline_hold: f64 = 0.5 => ["(fraction of the threshold)", num!("a number", 0.0, 1000.0)],
        /// Leak-size detector: longest hold of the baseline by one rise, s.
        pub baseline_hold_s: f64 = 5.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: drift of the baseline since the warm-up that is reported
        /// as a slowly growing leak, L/min (at nominal drop).
        pub slow_leak_lpm: f64 = 0.5 => ["L/min", num!("a number", 0.0, 10000.0)],
        /// Supply pressure of the rig, Pa: a rig fact, not a setting. It is not read
        /// from or written to a config file; the config loader sets it from
        /// `[model] supply_pressure_pa` (leakwatch's `Config`), so it is written once.
        #[serde(skip)]
        pub supply_pressure_pa: f64 = 13.8e6 => ["Pa", num!("a number", 10000.0, 1000000000.0)],
        /// Leak-size detector: a chamber pressure within this fraction of the supply
        /// pressure from tank or supply is an excursion (the rod against a stop, a land
        /// closed): no evidence is gathered and the baseline holds.
        pub excursion_margin: f64 = 0.05 => ["(fraction of the supply pressure)", num!("a number", 0.0, 1.0)],
        /// Leak-size detector: time after an excursion before evidence is gathered again, s.
        pub excursion_recovery_s: f64 = 0.2 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Leak-size detector: during an excursion, a rise above this many thresholds is
        /// still evidence (a large leak itself drains the chambers towards tank).
        pub excursion_override: f64 = 4.0 => ["thresholds", num!("a number", 0.0, 1000000.0)],
        /// Time below half the threshold before a leak is cleared, s.
        pub clear_s: f64 = 2.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Relative change of the size that gives an `updated` event.
        pub update_relative: f64 = 0.1 => ["(relative change)", num!("a number", 0.0, 1000000.0)],
        /// Time another kind must explain the data clearly better before an event is re-isolated, s.
        pub reisolate_s: f64 = 0.5 => ["s", num!("a number", 0.0, 1000000.0)],
        /// How long one kind must lead, clearly and above its threshold, before a leak is
        /// named (until then it is raised as `leak`, kind pending), s. At most
        /// `confirm_s`: the kind is named at the first alarm.
        pub kind_confirm_s: f64 = 1.5 => ["s", num!("a number", 0.0, 1000000.0)],
        /// A rise past this many times its threshold for `confirm_s` raises a leak with
        /// its kind pending even while no kind explains the mismatch clearly yet
        /// (a leak that first shows on both chambers, as one opening over seconds
        /// on a single-rod lift does); 0 turns it off.
        pub pending_factor: f64 = 1.5 => ["(times the threshold)", num!("a number", 0.0, 1000000.0)],
        /// Shortest time between two `updated` events of one leak, s.
        pub update_interval_s: f64 = 1.0 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Thesis detector: threshold as a multiple of the largest healthy MAE.
        pub mae_margin: f64 = 1.3 => ["(times the healthy MAE)", num!("a number", 0.0, 1000000.0)],
        /// Thesis detector: time above threshold before a decision, s.
        pub mae_confirm_s: f64 = 0.5 => ["s", num!("a number", 0.0, 1000000.0)],
        /// Samples with the same exact value before a sensor is called stuck.
        pub stuck_samples: u32 = 2000 => ["samples", int!(1, 1000000000)],
        /// Samples at the end of the range before a sensor is called saturated.
        pub saturated_samples: u32 = 200 => ["samples", int!(1, 1000000000)],
        /// Samples without a usable value before a sensor is called dead.
        pub dead_samples: u32 = 200 => ["samples", int!(1, 1000000000)],
        /// Full-scale range of the pressure transducers, Pa: a rig fact, not a
        /// setting, set by the config loader from `[sensors] pressure_full_scale_pa`
        /// (not read from or written to a config file).
        #[serde(skip)]
        pub pressure_full_scale_pa: f64 = 20.7e6 => ["Pa", num!("a number", 100000.0, 1000000000.0)],
        /// The pressure transducers' largest zero offset, Pa (the datasheet's; 0:
        /// not given): a rig fact, not a setting, set by the config loader from
        /// `[sensors] pressure_zero_offset_max_pa` (not read from or written to a
        /// config file). A standing offset is named from what a sound transducer
        /// may read off, where that is under the range's share.
        #[serde(skip)]
        pub pressure_zero_offset_max_pa: f64 = 0.0 => ["Pa", num!("an offset", 0.0, 10000000.0)],
        /// The pressure transducers' largest span error, a fraction of the reading
        /// (the datasheet's; 0: not given): a rig fact, set by the config loader
        /// from `[sensors] pressure_span_error_max` (not read from or written to a
        /// config file).
        #[serde(skip)]
        pub pressure_span_error_max: f64 = 0.0 => ["", num!("a fraction", 0.0, 0.5)],
        /// Noise of the position reading over one count of it (standard
        /// deviation, counts): a rig fact, not a setting, set by the config loader
        /// from `[sensors] position_noise_m / encoder_resolution_m` (not read from
        /// or written to a config file). From one count up a healthy reading does
        /// not repeat for long ([`crate::stage::X_NOISY_COUNTS`]).
        #[serde(skip)]
        pub position_noise_counts: f64 = 0.0 => ["counts", num!("a number", 0.0, 10000000.0)],
    }
}

impl ClassifierConfig {
    /// Checks every field against its declared range, naming the first bad
    /// one (`[classifier] warmup_s = ...: must be ...`) with its range and
    /// unit, then the commissioning and the warm-ups against each other.
    pub fn validate(&self) -> Result<(), String> {
        self.check_ranges("").map_err(|e| format!("[classifier] {e}"))?;
        if let Some(c) = &self.commissioning {
            c.validate()?;
        }
        if self.min_warmup_s > self.warmup_s {
            return Err(format!(
                "[classifier] min_warmup_s = {} exceeds warmup_s = {}",
                self.min_warmup_s, self.warmup_s
            ));
        }
        Ok(())
    }
}
