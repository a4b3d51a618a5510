//! The classifier stage: turns the estimator's output into leak events.
//!
//! Two detectors read the same [`estimator::Estimate`] stream:
//!
//! - [`LeakSizeDetector`] (leakwatch's own): the 10-state filter estimates the
//!   three leak sizes q_e1, q_e2, q_i directly (m³/s at the nominal drop). After
//!   a healthy warm-up has learned each estimate's offset and spread (a healthy
//!   rig that differs from the model, e.g. a spool null bias, leaves a steady
//!   offset), a leak is declared when one size rises above
//!   max(`threshold_sigma`·spread, `min_size_lpm`) and stays there for
//!   `confirm_s`. The rise is measured from a healthy baseline that follows
//!   the estimate slowly (time constant `baseline_tau_s`, frozen while a leak
//!   is reported, and while a rise is past `baseline_hold` of its threshold once
//!   the baseline has settled): an off-nominal rig makes the healthy estimate
//!   wander with the operating point over tens of seconds, a leak steps or
//!   ramps in seconds. Whatever the baseline has absorbed since the warm-up is judged
//!   against the larger `slow_leak_lpm`, so a leak that grows over minutes is
//!   still reported (detail `slowly growing`). Isolation: the kind whose rise
//!   is largest relative to its threshold. Size: the rise above the baseline,
//!   with the filter's σ. Onset: the last time the rise was below a
//!   quarter of the threshold.
//! - [`MaeDetector`] (the thesis' baseline, MODEL.md §5): the moving averages of
//!   |residual| of p1 and p2; thresholds = `margin` × the largest healthy MAE
//!   seen in the warm-up; p1 only → ext1, p2 only → ext2, both → internal. It
//!   cannot size a leak.
//!
//! Both debounce: one leak gives one `raised` event, then `updated` events as
//! the size estimate moves, and `cleared` when it goes away. Sensor checks
//! raise `sensor-stuck`, `sensor-saturated` and `sensor-dead` events, and a
//! filter reset raises `estimator-reset` (and restarts the warm-up).

// The detectors walk parallel per-kind arrays by index; iterators would hide that.
#![allow(clippy::needless_range_loop)]

use estimator::{Estimate, FLAG_AFTER_GAP, FLAG_CONVERGING, FLAG_RESET, FLAG_SKIPPED};

pub mod shell;
pub mod wire;
use serde::{Deserialize, Serialize};

/// Half-width of the band the valve command must swing through to count as a reversal, V.
pub const COMMAND_REVERSAL_BAND_V: f64 = 1.0;
/// Time over which the baseline is taken again after a stretch the model could not
/// follow (it follows the estimates with a 0.5 s time constant meanwhile, and no
/// evidence counts), s.
pub const REACQUIRE_S: f64 = 4.0;

/// Time constant of the command reversal rate, s.
pub const COMMAND_RATE_WINDOW_S: f64 = 2.0;

/// Time constant of the NIS average that the NIS-ratio gate compares, s.
pub const NIS_RATIO_WINDOW_S: f64 = 5.0;
/// While a leak's kind is pending, the rises are averaged over this time, s: the
/// mismatch a leak leaves swings with the operating point (a sine or step period),
/// its kind is read from the average.
pub const KIND_AVERAGE_S: f64 = 1.0;

/// Cubic metres per second in one litre per minute.
const M3_S_PER_LPM: f64 = 1.0e-3 / 60.0;

/// What an event is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventKind {
    /// External leak, chamber 1 to tank.
    Ext1,
    /// External leak, chamber 2 to tank.
    Ext2,
    /// Internal (cross-piston) leak.
    Int,
    /// A leak whose kind is not decided yet (raised as soon as the leak is clear; the
    /// same event id is raised again with its kind once the kind has stayed the same
    /// for `kind_confirm_s`).
    Leak,
    /// The estimator had to restart its filter.
    EstimatorReset,
    /// A sensor's value did not change for too long.
    SensorStuck,
    /// A sensor sat at the end of its range.
    SensorSaturated,
    /// A sensor delivered no usable value for too long.
    SensorDead,
    /// The warm-up was too short (or too disturbed) to learn thresholds: detection is not armed.
    NotArmed,
}

impl EventKind {
    /// The leak kinds, in state order (q_e1, q_e2, q_i).
    pub const LEAKS: [EventKind; 3] = [EventKind::Ext1, EventKind::Ext2, EventKind::Int];

    /// The name used in events.json: `ext1`, `ext2`, `int`, `estimator-reset`, ...
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Ext1 => "ext1",
            EventKind::Ext2 => "ext2",
            EventKind::Int => "int",
            EventKind::Leak => "leak",
            EventKind::EstimatorReset => "estimator-reset",
            EventKind::SensorStuck => "sensor-stuck",
            EventKind::SensorSaturated => "sensor-saturated",
            EventKind::SensorDead => "sensor-dead",
            EventKind::NotArmed => "not-armed",
        }
    }

    /// Whether this is a named leak kind (ext1, ext2, int).
    pub fn is_leak(self) -> bool {
        matches!(self, EventKind::Ext1 | EventKind::Ext2 | EventKind::Int)
    }

    /// Whether this is a leak alarm: a named leak kind or a leak whose kind is pending.
    pub fn is_leak_alarm(self) -> bool {
        self.is_leak() || self == EventKind::Leak
    }
}

/// The life of an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// First report.
    Raised,
    /// A better size estimate for an event already raised.
    Updated,
    /// The condition went away.
    Cleared,
}

/// One event, as written to events.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LeakEvent {
    /// What it is about.
    pub kind: EventKind,
    /// Raised, updated or cleared.
    pub phase: Phase,
    /// Which detector (`leak-size`, `thesis-mae`, `sensors`).
    pub detector: String,
    /// Identifier shared by all phases of one event.
    pub event_id: u64,
    /// Time of this decision, s (sample time).
    pub t_detect_s: f64,
    /// Estimated onset time, s (NaN if unknown).
    pub t_onset_s: f64,
    /// Leak flow at the measured pressures, L/min (NaN if not sized): the
    /// estimated coefficient times the mean of √Δp over the last
    /// `size_window_s` (Δp = p1, p2 or |p1 − p2| for ext1, ext2, int).
    pub size_lpm: f64,
    /// One standard deviation of `size_lpm`, L/min.
    pub size_lpm_sigma: f64,
    /// The same leak at the nominal pressure drop p_s/2, L/min (NaN if not sized).
    #[serde(default = "nan")]
    pub size_nominal_lpm: f64,
    /// Leak coefficient of the square-root law q = k·√Δp, m³/(s·√Pa) (NaN if not sized).
    #[serde(default = "nan")]
    pub coefficient_m3_s_sqrt_pa: f64,
    /// Decision statistic: the rise in healthy spreads (NaN where not applicable).
    #[serde(default = "nan")]
    pub statistic: f64,
    /// Threshold of the statistic, in healthy spreads (NaN where not applicable).
    #[serde(default = "nan")]
    pub threshold: f64,
    /// Confidence in [0, 1] that the kind is right and the leak is real.
    pub confidence: f64,
    /// For sensor events: which channel (`x`, `p1`, `p2`); empty otherwise.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub channel: String,
    /// Human-readable detail.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub detail: String,
}

fn nan() -> f64 {
    f64::NAN
}

impl LeakEvent {
    /// An event of `detector` with no size or statistic (NaN), confidence 1, no channel or detail.
    pub fn plain(
        kind: EventKind,
        phase: Phase,
        detector: &str,
        event_id: u64,
        t_detect_s: f64,
        t_onset_s: f64,
    ) -> Self {
        LeakEvent {
            kind,
            phase,
            detector: detector.into(),
            event_id,
            t_detect_s,
            t_onset_s,
            size_lpm: f64::NAN,
            size_lpm_sigma: f64::NAN,
            size_nominal_lpm: f64::NAN,
            coefficient_m3_s_sqrt_pa: f64::NAN,
            statistic: f64::NAN,
            threshold: f64::NAN,
            confidence: 1.0,
            channel: String::new(),
            detail: String::new(),
        }
    }
}

/// What a healthy commissioning run taught about the leak filter's estimates:
/// loaded at start, it arms the detector at once, so that a leak already
/// present when monitoring starts shows against it (`[classifier.commissioning]`,
/// written by `leakwatch commission`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Commissioning {
    /// Healthy offset of each single-leak size (ext1, ext2, int), L/min at the nominal drop.
    pub offsets_lpm: [f64; 3],
    /// Healthy spread (standard deviation) of each, L/min at the nominal drop.
    pub spreads_lpm: [f64; 3],
    /// Upcrossings of the healthy offset per second, per kind (for the threshold, Rice's formula).
    pub crossings_per_s: [f64; 3],
    /// Seconds of healthy, converged data learned from, s.
    pub healthy_s: f64,
    /// Mean normalised innovation squared of the healthy data (NaN: unknown).
    #[serde(default = "nan")]
    pub nis_mean: f64,
    /// Where it was learned (the recording's path).
    #[serde(default)]
    pub source: String,
}

impl Commissioning {
    fn validate(&self) -> Result<(), String> {
        let all = self
            .offsets_lpm
            .iter()
            .chain(&self.spreads_lpm)
            .chain(&self.crossings_per_s)
            .chain(std::iter::once(&self.healthy_s));
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
        Ok(())
    }
}

/// Settings of the detectors, `[classifier]` in the TOML config.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClassifierConfig {
    /// Time after the filter has converged before learning starts (the leak and
    /// bias estimates settle), s.
    pub settle_s: f64,
    /// Healthy warm-up after settling, used to learn thresholds, s.
    pub warmup_s: f64,
    /// Shortest warm-up that can give thresholds, s.
    pub min_warmup_s: f64,
    /// Leak-size detector: the false-alarm rate asked for, per hour. The threshold
    /// on the rise, in healthy spreads, is c = √(2 ln(N₀/rate)) (Rice's formula for
    /// a Gaussian process with N₀ upcrossings of its mean per hour, learned in the
    /// warm-up), never below `threshold_sigma`.
    pub false_alarms_per_hour: f64,
    /// Leak-size detector: least threshold in spreads of the healthy estimate.
    pub threshold_sigma: f64,
    /// Leak-size detector: at the first alarm, the part of the flow mismatch the
    /// named kind leaves unexplained must be below this fraction of its size (the
    /// kind is decided before the alarm is raised).
    pub isolation_max_misfit: f64,
    /// Leak-size detector: window of the measured pressures over which the real
    /// leak flow is averaged, s.
    pub size_window_s: f64,
    /// Leak-size detector: after a gap, a skipped sample or a filter reset, no
    /// evidence for this long (the filter re-converges), s.
    pub recovery_s: f64,
    /// Leak-size detector: a normalised innovation squared above this (an innovation
    /// of about √nis_gate standard deviations) means the filter has lost track for
    /// a moment: no evidence for `recovery_s` after it.
    pub nis_gate: f64,
    /// Leak-size detector: while the NIS averaged over the last 5 s exceeds this
    /// many times its healthy mean (the model no longer tracks the input, e.g. a fast
    /// chirp), evidence does not count (0 = off).
    pub nis_ratio_gate: f64,
    /// Leak-size detector: while the valve command reverses faster than this (its
    /// frequency, from swings through ±1 V over the last 2 s), evidence does not
    /// count: the healthy model's effective load (a random walk) cannot follow the
    /// friction reversals and the leak estimates wander (0 = off), Hz.
    pub max_command_hz: f64,
    /// Emit the thesis' MAE baseline detector's events too (a comparison, off by default).
    pub thesis_baseline: bool,
    /// The healthy state learned by commissioning (absent: learned in a warm-up,
    /// and a leak present at start cannot be seen).
    pub commissioning: Option<Commissioning>,
    /// Leak-size detector: smallest leak ever declared, L/min (at nominal drop).
    pub min_size_lpm: f64,
    /// Leak-size detector: time above threshold before a leak is declared, s.
    pub confirm_s: f64,
    /// Leak-size detector: time constant of the healthy baseline that the rise is
    /// measured from, s (0 = the warm-up offset, never adapted).
    pub baseline_tau_s: f64,
    /// Leak-size detector: while any rise exceeds this fraction of its threshold the
    /// baseline holds, for at most `baseline_hold_s` (a leak opening over seconds is
    /// not absorbed on its way to the threshold, a drift of the operating point is
    /// still followed); only once the baseline has followed the estimates for
    /// `baseline_tau_s` after arming (before that it is still settling).
    pub baseline_hold: f64,
    /// Leak-size detector: longest hold of the baseline by one rise, s.
    pub baseline_hold_s: f64,
    /// Leak-size detector: drift of the baseline since the warm-up that is reported
    /// as a slowly growing leak, L/min (at nominal drop).
    pub slow_leak_lpm: f64,
    /// Supply pressure of the rig, Pa.
    pub supply_pressure_pa: f64,
    /// Leak-size detector: a chamber pressure within this fraction of the supply
    /// pressure from tank or supply is an excursion (the rod against a stop, a land
    /// closed): no evidence is gathered and the baseline holds.
    pub excursion_margin: f64,
    /// Leak-size detector: time after an excursion before evidence is gathered again, s.
    pub excursion_recovery_s: f64,
    /// Leak-size detector: during an excursion, a rise above this many thresholds is
    /// still evidence (a large leak itself drains the chambers towards tank).
    pub excursion_override: f64,
    /// Time below half the threshold before a leak is cleared, s.
    pub clear_s: f64,
    /// Relative change of the size that gives an `updated` event.
    pub update_relative: f64,
    /// Time another kind must explain the data clearly better before an event is re-isolated, s.
    pub reisolate_s: f64,
    /// How long one kind must lead, clearly and above its threshold, before a leak is
    /// named (until then it is raised as `leak`, kind pending), s. At most
    /// `confirm_s`: the kind is named at the first alarm.
    pub kind_confirm_s: f64,
    /// A rise past this many times its threshold for `confirm_s` raises a leak with
    /// its kind pending even while no kind explains the mismatch clearly yet
    /// (a leak that first shows on both chambers); 0 turns it off.
    pub pending_factor: f64,
    /// Shortest time between two `updated` events of one leak, s.
    pub update_interval_s: f64,
    /// Thesis detector: threshold as a multiple of the largest healthy MAE.
    pub mae_margin: f64,
    /// Thesis detector: time above threshold before a decision, s.
    pub mae_confirm_s: f64,
    /// Samples with the same exact value before a sensor is called stuck.
    pub stuck_samples: u32,
    /// Samples at the end of the range before a sensor is called saturated.
    pub saturated_samples: u32,
    /// Samples without a usable value before a sensor is called dead.
    pub dead_samples: u32,
    /// Full-scale range of the pressure transducers, Pa.
    pub pressure_full_scale_pa: f64,
}

impl Default for ClassifierConfig {
    fn default() -> Self {
        ClassifierConfig {
            settle_s: 3.0,
            warmup_s: 5.0,
            min_warmup_s: 3.0,
            false_alarms_per_hour: 0.05,
            threshold_sigma: 4.0,
            isolation_max_misfit: 0.35,
            size_window_s: 2.0,
            recovery_s: 2.0,
            nis_gate: 10000.0,
            nis_ratio_gate: 3.0,
            max_command_hz: 4.0,
            thesis_baseline: false,
            commissioning: None,
            min_size_lpm: 0.06,
            confirm_s: 0.5,
            baseline_tau_s: 15.0,
            baseline_hold: 0.5,
            baseline_hold_s: 5.0,
            slow_leak_lpm: 0.5,
            supply_pressure_pa: 13.8e6,
            excursion_margin: 0.05,
            excursion_recovery_s: 1.0,
            excursion_override: 4.0,
            clear_s: 2.0,
            update_relative: 0.1,
            reisolate_s: 0.5,
            kind_confirm_s: 1.5,
            pending_factor: 2.0,
            update_interval_s: 1.0,
            mae_margin: 1.3,
            mae_confirm_s: 0.5,
            stuck_samples: 2000,
            saturated_samples: 200,
            dead_samples: 200,
            pressure_full_scale_pa: 20.7e6,
        }
    }
}

impl ClassifierConfig {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        // (name, value, least, largest, unit)
        let fields: [(&str, f64, f64, f64, &str); 30] = [
            ("settle_s", self.settle_s, 0.0, 1e6, "s"),
            ("warmup_s", self.warmup_s, 0.0, 1e6, "s"),
            ("min_warmup_s", self.min_warmup_s, 0.0, 1e6, "s"),
            (
                "false_alarms_per_hour",
                self.false_alarms_per_hour,
                1e-9,
                1e6,
                "per hour",
            ),
            (
                "threshold_sigma",
                self.threshold_sigma,
                0.0,
                1e3,
                "healthy spreads",
            ),
            (
                "isolation_max_misfit",
                self.isolation_max_misfit,
                0.0,
                10.0,
                "(fraction of the size)",
            ),
            ("size_window_s", self.size_window_s, 0.0, 1e6, "s"),
            ("recovery_s", self.recovery_s, 0.0, 1e6, "s"),
            (
                "nis_gate",
                self.nis_gate,
                0.0,
                1e15,
                "(normalised innovation squared)",
            ),
            (
                "nis_ratio_gate",
                self.nis_ratio_gate,
                0.0,
                1e6,
                "(times the healthy mean NIS)",
            ),
            ("max_command_hz", self.max_command_hz, 0.0, 1e5, "Hz"),
            ("min_size_lpm", self.min_size_lpm, 0.0, 1e4, "L/min"),
            ("confirm_s", self.confirm_s, 0.0, 1e6, "s"),
            ("baseline_tau_s", self.baseline_tau_s, 0.0, 1e8, "s"),
            (
                "baseline_hold",
                self.baseline_hold,
                0.0,
                1e3,
                "(fraction of the threshold)",
            ),
            ("baseline_hold_s", self.baseline_hold_s, 0.0, 1e6, "s"),
            ("slow_leak_lpm", self.slow_leak_lpm, 0.0, 1e4, "L/min"),
            ("supply_pressure_pa", self.supply_pressure_pa, 1e4, 1e9, "Pa"),
            (
                "excursion_margin",
                self.excursion_margin,
                0.0,
                1.0,
                "(fraction of the supply pressure)",
            ),
            ("excursion_recovery_s", self.excursion_recovery_s, 0.0, 1e6, "s"),
            (
                "excursion_override",
                self.excursion_override,
                0.0,
                1e6,
                "thresholds",
            ),
            ("clear_s", self.clear_s, 0.0, 1e6, "s"),
            (
                "update_relative",
                self.update_relative,
                0.0,
                1e6,
                "(relative change)",
            ),
            ("reisolate_s", self.reisolate_s, 0.0, 1e6, "s"),
            ("kind_confirm_s", self.kind_confirm_s, 0.0, 1e6, "s"),
            (
                "pending_factor",
                self.pending_factor,
                0.0,
                1e6,
                "(times the threshold)",
            ),
            ("update_interval_s", self.update_interval_s, 0.0, 1e6, "s"),
            ("mae_margin", self.mae_margin, 0.0, 1e6, "(times the healthy MAE)"),
            ("mae_confirm_s", self.mae_confirm_s, 0.0, 1e6, "s"),
            (
                "pressure_full_scale_pa",
                self.pressure_full_scale_pa,
                1e5,
                1e9,
                "Pa",
            ),
        ];
        for (name, v, lo, hi, unit) in fields {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(format!(
                    "[classifier] {name} = {v:?}: must be a number from {lo:?} to {hi:?} {unit}"
                ));
            }
        }
        for (name, v) in [
            ("stuck_samples", self.stuck_samples),
            ("saturated_samples", self.saturated_samples),
            ("dead_samples", self.dead_samples),
        ] {
            if !(1..=1_000_000_000).contains(&v) {
                return Err(format!(
                    "[classifier] {name} = {v}: must be 1 to 1000000000 samples"
                ));
            }
        }
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

/// Running mean and spread (Welford).
#[derive(Debug, Clone, Copy, Default)]
struct Stats {
    n: f64,
    mean: f64,
    m2: f64,
    max: f64,
}

impl Stats {
    fn push(&mut self, v: f64) {
        self.n += 1.0;
        let d = v - self.mean;
        self.mean += d / self.n;
        self.m2 += d * (v - self.mean);
        if self.n == 1.0 || v > self.max {
            self.max = v;
        }
    }
    fn std(&self) -> f64 {
        if self.n > 1.0 {
            (self.m2 / (self.n - 1.0)).sqrt()
        } else {
            0.0
        }
    }
}

/// Where a detector is in its life.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Arming {
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
struct Active {
    kind: EventKind,
    id: u64,
    t_onset_s: f64,
    last_size_lpm: f64,
    last_update_s: f64,
    below_since_s: Option<f64>,
    /// Since when another kind has explained the data clearly better, s.
    other_since_s: Option<(usize, f64)>,
}

/// leakwatch's detector: thresholds on the estimated leak sizes.
#[derive(Debug, Clone)]
pub struct LeakSizeDetector {
    cfg: ClassifierConfig,
    arming: Arming,
    stats: [Stats; 3],
    /// The healthy values seen while learning.
    record: HealthyRecord,
    /// Threshold on the rise of each kind, in healthy spreads.
    threshold_z: [f64; 3],
    threshold_lpm: [f64; 3],
    /// Healthy baseline of each hypothesis' size that the rise is measured from, L/min.
    baseline_lpm: [f64; 3],
    /// The baseline when each rise was last low (before a possible onset), L/min.
    baseline_low_lpm: [f64; 3],
    /// Time of the last estimate read, s (for the baseline's time step).
    last_t_s: f64,
    /// When the detector armed, s.
    armed_at_s: f64,
    /// Since when the baseline has been held by a rise, s.
    hold_since_s: Option<f64>,
    above_since_s: [Option<f64>; 3],
    /// Since when the baseline's drift has exceeded `slow_leak_lpm` (lead kind, time s).
    slow_since_s: Option<(usize, f64)>,
    /// No evidence is gathered before this time (an excursion and its recovery), s.
    blind_until_s: f64,
    /// Evidence is invalid before this time (a gap, a skipped sample, a reset, a NIS burst), s.
    invalid_until_s: f64,
    /// The filter restarted: no evidence until it has converged again.
    awaiting_convergence: bool,
    /// Mean NIS of the healthy data (NaN: unknown).
    nis_healthy: f64,
    /// NIS averaged over the last [`NIS_RATIO_WINDOW_S`].
    nis_avg: f64,
    /// Side of the ±1 V band the command was last on (−1, 0 before the first swing, +1).
    command_side: i8,
    /// Command reversals per second, averaged over [`COMMAND_RATE_WINDOW_S`].
    reversals_per_s: f64,
    /// After a stretch the model could not follow, the baseline is taken again from
    /// this time (s) for [`REACQUIRE_S`], following the estimates quickly.
    reacquire_after_s: f64,
    /// Seconds without evidence since the detector armed (gaps, resets, excursions, NIS), s.
    blind_s: f64,
    /// Mean of √(Δp/Δp_n) over `size_window_s` for ext1, ext2, int (real flow per nominal flow).
    flow_factor: [f64; 3],
    last_low_s: [f64; 3],
    /// While a leak's kind is pending: its rise of each hypothesis averaged over
    /// [`KIND_AVERAGE_S`] (the kind is read from the averaged mismatch), L/min.
    pending_rise_lpm: [f64; 3],
    /// Since when some hypothesis' rise has been past `pending_factor` times its
    /// threshold (with evidence), s.
    strong_since_s: Option<f64>,
    active: Option<Active>,
    next_id: u64,
}

/// The threshold in spreads for a requested false-alarm rate `rate_per_h`, with
/// `crossings_per_s` upcrossings of the mean per second (Rice: the rate of
/// upcrossings of level c·σ by a Gaussian process is N₀·e^(−c²/2)), at least `floor`.
pub fn rice_threshold(crossings_per_s: f64, rate_per_h: f64, floor: f64) -> f64 {
    let n0_per_h = crossings_per_s * 3600.0;
    if n0_per_h > rate_per_h && rate_per_h > 0.0 {
        (2.0 * (n0_per_h / rate_per_h).ln()).sqrt().max(floor)
    } else {
        floor
    }
}

/// Healthy values of the three single-leak sizes kept every 10 ms, and their
/// statistics: the mean as the offset, the standard deviation as the spread
/// (the healthy estimate wanders with the operating point, which a robust
/// spread would hide), and the rate of upcrossings of the mean.
#[derive(Debug, Clone, Default)]
struct HealthyRecord {
    values: [Vec<f64>; 3],
    next_t_s: f64,
    learned_s: f64,
    nis_sum: f64,
    nis_n: f64,
}

impl HealthyRecord {
    /// Interval between kept values, s.
    const EVERY_S: f64 = 0.01;

    fn with_capacity_s(seconds: f64) -> Self {
        let n = (seconds / Self::EVERY_S).clamp(0.0, 1e6) as usize + 16;
        HealthyRecord {
            values: std::array::from_fn(|_| Vec::with_capacity(n)),
            next_t_s: f64::NEG_INFINITY,
            learned_s: 0.0,
            nis_sum: 0.0,
            nis_n: 0.0,
        }
    }

    fn push(&mut self, t_s: f64, dt_s: f64, raw: [f64; 3], nis: f64) {
        self.learned_s += dt_s;
        if nis.is_finite() {
            self.nis_sum += nis.min(1e6);
            self.nis_n += 1.0;
        }
        if t_s >= self.next_t_s {
            self.next_t_s = t_s + Self::EVERY_S;
            for k in 0..3 {
                self.values[k].push(raw[k]);
            }
        }
    }

    /// Mean NIS of the learned samples (NaN if none).
    fn nis_mean(&self) -> f64 {
        if self.nis_n > 0.0 {
            self.nis_sum / self.nis_n
        } else {
            f64::NAN
        }
    }

    /// (offsets, spreads, upcrossings per second of the learned time).
    fn summary(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let mut med = [f64::NAN; 3];
        let mut spread = [f64::NAN; 3];
        let mut cross = [0.0; 3];
        for k in 0..3 {
            let v = &self.values[k];
            if v.is_empty() {
                continue;
            }
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
            med[k] = m;
            spread[k] = var.sqrt();
            let ups = v.windows(2).filter(|w| w[0] <= m && w[1] > m).count();
            cross[k] = ups as f64 / self.learned_s.max(Self::EVERY_S);
        }
        (med, spread, cross)
    }
}

/// Learns a [`Commissioning`] from the leak filter's estimates of a healthy run:
/// the offset, spread and upcrossing rate of each single-leak size after the
/// filter has converged and settled, gaps and resets left out.
#[derive(Debug, Clone)]
pub struct CommissioningLearner {
    settle_s: f64,
    converged_at_s: Option<f64>,
    record: HealthyRecord,
    last_t_s: f64,
}

impl CommissioningLearner {
    /// A learner that starts `settle_s` after the filter has converged.
    pub fn new(settle_s: f64) -> Self {
        CommissioningLearner {
            settle_s,
            converged_at_s: None,
            record: HealthyRecord::with_capacity_s(600.0),
            last_t_s: f64::NAN,
        }
    }

    /// Reads one estimate of the leak filter.
    pub fn on_estimate(&mut self, e: &Estimate) {
        if e.n_states < 10 {
            return;
        }
        let bad = FLAG_SKIPPED | FLAG_RESET | FLAG_CONVERGING | FLAG_AFTER_GAP;
        if e.flags & bad != 0 {
            if e.flags & (FLAG_RESET | FLAG_CONVERGING) != 0 {
                self.converged_at_s = None;
            }
            self.last_t_s = f64::NAN;
            return;
        }
        let t0 = *self.converged_at_s.get_or_insert(e.t_s);
        if e.t_s - t0 < self.settle_s {
            return;
        }
        let raw = LeakSizeDetector::raw_sizes(e);
        if !raw.iter().all(|v| v.is_finite()) {
            return;
        }
        let dt_s = if self.last_t_s.is_finite() {
            (e.t_s - self.last_t_s).clamp(0.0, 0.1)
        } else {
            0.0
        };
        self.last_t_s = e.t_s;
        self.record.push(e.t_s, dt_s, raw, e.nis);
    }

    /// The commissioning, or why there is none (too little healthy data).
    pub fn finish(&self, min_s: f64, source: &str) -> Result<Commissioning, String> {
        let learned_s = self.record.learned_s;
        if learned_s < min_s {
            return Err(format!(
                "only {learned_s:.1} s of converged healthy data (at least {min_s} s after the filter settles is needed)"
            ));
        }
        let (offsets_lpm, spreads_lpm, crossings_per_s) = self.record.summary();
        Ok(Commissioning {
            offsets_lpm,
            spreads_lpm,
            crossings_per_s,
            healthy_s: learned_s,
            nis_mean: self.record.nis_mean(),
            source: source.to_string(),
        })
    }
}

/// The thesis' detector: thresholds on the MAE of the pressure residuals.
#[derive(Debug, Clone)]
pub struct MaeDetector {
    cfg: ClassifierConfig,
    arming: Arming,
    stats: [Stats; 2],
    threshold_pa: [f64; 2],
    pattern_since: Option<(EventKind, f64)>,
    active: Option<Active>,
    next_id: u64,
}

fn arm_step(arming: &mut Arming, cfg: &ClassifierConfig, e: &Estimate) -> Option<bool> {
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

impl LeakSizeDetector {
    /// A detector with settings `cfg`.
    pub fn new(cfg: ClassifierConfig) -> Self {
        LeakSizeDetector {
            record: HealthyRecord::with_capacity_s(cfg.warmup_s),
            cfg,
            arming: Arming::Converging,
            stats: [Stats::default(); 3],
            threshold_z: [f64::NAN; 3],
            threshold_lpm: [f64::NAN; 3],
            baseline_lpm: [f64::NAN; 3],
            baseline_low_lpm: [f64::NAN; 3],
            last_t_s: f64::NAN,
            armed_at_s: f64::NAN,
            hold_since_s: None,
            above_since_s: [None; 3],
            slow_since_s: None,
            blind_until_s: f64::NEG_INFINITY,
            invalid_until_s: f64::NEG_INFINITY,
            awaiting_convergence: false,
            nis_healthy: f64::NAN,
            nis_avg: f64::NAN,
            command_side: 0,
            reversals_per_s: 0.0,
            reacquire_after_s: f64::NEG_INFINITY,
            blind_s: 0.0,
            flow_factor: [f64::NAN; 3],
            last_low_s: [0.0; 3],
            pending_rise_lpm: [0.0; 3],
            strong_since_s: None,
            active: None,
            next_id: 1,
        }
    }

    /// Whether a leak event (kind pending or named) is open.
    pub fn has_active_leak(&self) -> bool {
        self.active.is_some()
    }

    /// Whether the thresholds have been learned.
    pub fn is_armed(&self) -> bool {
        self.arming == Arming::Armed
    }

    /// Whether the healthy state comes from a commissioning (a leak present at start is seen).
    pub fn is_commissioned(&self) -> bool {
        self.cfg.commissioning.is_some()
    }

    /// The thresholds on the rise of the ext1, ext2 and int sizes, L/min at the nominal drop (NaN before arming).
    pub fn thresholds_lpm(&self) -> [f64; 3] {
        self.threshold_lpm
    }

    /// The thresholds in healthy spreads (from the requested false-alarm rate; NaN before arming).
    pub fn thresholds_sigma(&self) -> [f64; 3] {
        self.threshold_z
    }

    /// Seconds in which no evidence was gathered after arming (gaps, resets, excursions, NIS), s.
    pub fn blind_s(&self) -> f64 {
        self.blind_s
    }

    /// The healthy offsets of the three hypothesis sizes learned in the warm-up, L/min.
    pub fn offsets_lpm(&self) -> [f64; 3] {
        [self.stats[0].mean, self.stats[1].mean, self.stats[2].mean]
    }

    /// Current rise of each hypothesis' size (ext1, ext2, int; [`signatures_lpm`])
    /// above its healthy baseline, L/min (NaN if unknown or not armed).
    pub fn rise_lpm(&self, e: &Estimate) -> [f64; 3] {
        let mut r = [f64::NAN; 3];
        if e.n_states >= 10 {
            let raw = Self::raw_sizes(e);
            for (k, v) in r.iter_mut().enumerate() {
                *v = raw[k] - self.baseline_lpm[k];
            }
        }
        r
    }

    /// The healthy baseline of each hypothesis' size that rises are measured from,
    /// L/min (NaN before arming; equal to [`Self::offsets_lpm`] with `baseline_tau_s = 0`).
    pub fn baseline_lpm(&self) -> [f64; 3] {
        self.baseline_lpm
    }

    /// Mean √(Δp/Δp_n) of ext1, ext2 and int over the size window: the real flow
    /// of a leak per L/min of nominal size.
    pub fn flow_factors(&self) -> [f64; 3] {
        self.flow_factor
    }

    /// After a filter reset: an armed detector keeps what it learned and gathers no
    /// evidence until the filter has converged again and `recovery_s` has passed;
    /// one not yet armed starts its warm-up again.
    pub fn restart(&mut self) {
        if self.is_armed() {
            self.awaiting_convergence = true;
            return;
        }
        let cfg = self.cfg.clone();
        let id = self.next_id;
        *self = LeakSizeDetector::new(cfg);
        self.next_id = id;
    }

    /// After a sensor fault, whose wrong values the filter has folded into its leak
    /// estimates: the healthy state is learned again from the estimates as they are
    /// now (a commissioning no longer applies to them).
    pub fn relearn(&mut self) {
        let mut cfg = self.cfg.clone();
        cfg.commissioning = None;
        let id = self.next_id;
        *self = LeakSizeDetector::new(cfg);
        self.next_id = id;
    }

    /// The three single-leak sizes that explain the estimated leak flows, L/min
    /// (before the healthy offsets are removed): see [`signatures_lpm`].
    fn raw_sizes(e: &Estimate) -> [f64; 3] {
        signatures_lpm([
            e.state[7] / M3_S_PER_LPM,
            e.state[8] / M3_S_PER_LPM,
            e.state[9] / M3_S_PER_LPM,
        ])
    }

    fn arm_with(&mut self, means: [f64; 3], spreads: [f64; 3], crossings_per_s: [f64; 3], t_s: f64) {
        for k in 0..3 {
            let z = rice_threshold(
                crossings_per_s[k],
                self.cfg.false_alarms_per_hour,
                self.cfg.threshold_sigma,
            );
            self.threshold_z[k] = z;
            self.threshold_lpm[k] = (z * spreads[k]).max(self.cfg.min_size_lpm);
            self.last_low_s[k] = t_s;
            self.baseline_lpm[k] = means[k];
            self.baseline_low_lpm[k] = means[k];
            self.stats[k].mean = means[k];
            self.stats[k].m2 = spreads[k] * spreads[k];
            self.stats[k].n = 2.0;
        }
        self.arming = Arming::Armed;
        self.armed_at_s = t_s;
        self.last_t_s = t_s;
    }

    /// A chamber pressure within `excursion_margin` of tank or supply.
    fn excursion(&self, e: &Estimate) -> bool {
        let (lo, hi) = (
            self.cfg.excursion_margin * self.cfg.supply_pressure_pa,
            (1.0 - self.cfg.excursion_margin) * self.cfg.supply_pressure_pa,
        );
        e.measured[1..].iter().any(|p| *p < lo || *p > hi)
    }

    fn update_flow_factor(&mut self, e: &Estimate, dt_s: f64) {
        let pn = 0.5 * self.cfg.supply_pressure_pa;
        let p = |i: usize| {
            if e.measured[i].is_finite() {
                e.measured[i]
            } else {
                e.state[i]
            }
        };
        let (p1, p2) = (p(1), p(2));
        let g = [
            (p1.max(0.0) / pn).sqrt(),
            (p2.max(0.0) / pn).sqrt(),
            ((p1 - p2).abs() / pn).sqrt(),
        ];
        let a = (dt_s / self.cfg.size_window_s.max(1e-3)).clamp(0.0, 1.0);
        for k in 0..3 {
            if !g[k].is_finite() {
                continue;
            }
            if self.flow_factor[k].is_finite() {
                self.flow_factor[k] += a * (g[k] - self.flow_factor[k]);
            } else {
                self.flow_factor[k] = g[k];
            }
        }
    }

    /// Reads one estimate; pushes any event into `out` (at most one per call).
    pub fn on_estimate(&mut self, e: &Estimate, out: &mut Option<LeakEvent>) {
        if e.n_states < 10 {
            return;
        }
        let dt_s = if self.last_t_s.is_finite() {
            (e.t_s - self.last_t_s).clamp(0.0, 1.0)
        } else {
            0.0
        };
        // Validity gate: a gap, a skipped sample or a reset blinds the detector for
        // `recovery_s`; so does a filter whose innovations are far beyond its own
        // covariance (not tracking). The baseline holds while blind.
        let recover = e.t_s + self.cfg.recovery_s;
        if e.flags & (FLAG_SKIPPED | FLAG_AFTER_GAP | FLAG_RESET) != 0 {
            self.invalid_until_s = self.invalid_until_s.max(recover);
        }
        if e.flags & FLAG_SKIPPED != 0 {
            return;
        }
        // A channel left out of the update (NaN or out of range) leaves the leak
        // states to drift on the others: no evidence until it has been back for a while.
        if e.residual.iter().any(|r| r.is_nan()) {
            self.invalid_until_s = self.invalid_until_s.max(recover);
        }
        if e.nis.is_finite() && e.nis > self.cfg.nis_gate {
            self.invalid_until_s = self.invalid_until_s.max(recover);
        }
        if e.nis.is_finite() {
            let nis = e.nis.min(1e6);
            // Averaged over 5 s: the burst of a leak's onset (under a second) does not
            // trip it, a sustained loss of tracking does.
            self.nis_avg = if self.nis_avg.is_finite() {
                self.nis_avg + (dt_s / NIS_RATIO_WINDOW_S).min(1.0) * (nis - self.nis_avg)
            } else {
                nis
            };
            if self.cfg.nis_ratio_gate > 0.0 && self.nis_avg > self.cfg.nis_ratio_gate * self.nis_healthy {
                self.invalid_until_s = self.invalid_until_s.max(e.t_s);
            }
        }
        if e.u_v.is_finite() {
            let side = if e.u_v > COMMAND_REVERSAL_BAND_V {
                1
            } else if e.u_v < -COMMAND_REVERSAL_BAND_V {
                -1
            } else {
                0
            };
            let mut impulse = 0.0;
            if side != 0 && side != self.command_side {
                if self.command_side != 0 {
                    impulse = 1.0;
                }
                self.command_side = side;
            }
            self.reversals_per_s += (impulse - self.reversals_per_s * dt_s) / COMMAND_RATE_WINDOW_S;
            if self.cfg.max_command_hz > 0.0 && 0.5 * self.reversals_per_s > self.cfg.max_command_hz {
                self.invalid_until_s = self.invalid_until_s.max(e.t_s + 1.0);
                // The leak estimates wander while the model cannot follow the input and
                // relax slowly afterwards: take the baseline again once it is over.
                self.reacquire_after_s = self.invalid_until_s;
            }
        }
        if self.awaiting_convergence {
            if e.flags & (FLAG_CONVERGING | FLAG_RESET) != 0 {
                self.invalid_until_s = self.invalid_until_s.max(recover);
            } else {
                self.awaiting_convergence = false;
            }
        }
        self.update_flow_factor(e, dt_s);
        let raw = Self::raw_sizes(e);
        if !raw.iter().all(|v| v.is_finite()) {
            return;
        }
        if !self.is_armed() {
            // (the figures are copied out: no clone of the commissioning, which holds a String, per sample)
            if let (Arming::Converging, Some(c)) = (self.arming, self.cfg.commissioning.as_ref()) {
                let (nis, offsets, spreads, crossings) =
                    (c.nis_mean, c.offsets_lpm, c.spreads_lpm, c.crossings_per_s);
                if e.flags & FLAG_CONVERGING == 0 {
                    self.nis_healthy = nis;
                    self.arm_with(offsets, spreads, crossings, e.t_s);
                }
                return;
            }
            // Learning takes every valid sample: the transients a healthy rig shows
            // (reference steps, excursions) are part of the spread the threshold
            // must stand above. Gaps, resets and skipped samples are left out.
            let blind = e.t_s < self.invalid_until_s;
            match self.arming {
                Arming::Converging if e.flags & FLAG_CONVERGING == 0 => {
                    self.arming = Arming::Settling(e.t_s);
                }
                Arming::Settling(t0) if e.t_s - t0 >= self.cfg.settle_s => {
                    self.arming = Arming::Learning(e.t_s);
                }
                Arming::Learning(_) if !blind => {
                    self.record.push(e.t_s, dt_s, raw, e.nis);
                    if self.record.learned_s >= self.cfg.warmup_s {
                        let (offsets, spreads, crossings) = self.record.summary();
                        self.nis_healthy = self.record.nis_mean();
                        self.arm_with(offsets, spreads, crossings, e.t_s);
                    }
                }
                _ => {}
            }
            self.last_t_s = e.t_s;
            return;
        }
        self.last_t_s = e.t_s;
        // During an excursion to tank or supply pressure (where the healthy model is
        // worst and its errors move the leak estimates for a while) and a recovery
        // after it, the baseline holds and no evidence is gathered.
        let excursion = self.excursion(e);
        if excursion {
            self.blind_until_s = self.blind_until_s.max(e.t_s + self.cfg.excursion_recovery_s);
        }
        // After a gap, a reset or while the filter is not tracking nothing counts, not
        // even a large rise; during an excursion only a very large one does.
        let reacquiring = e.t_s >= self.reacquire_after_s && e.t_s < self.reacquire_after_s + REACQUIRE_S;
        let invalid = e.t_s < self.invalid_until_s || self.awaiting_convergence || reacquiring;
        let blind = invalid || e.t_s < self.blind_until_s;
        if blind {
            self.blind_s += dt_s;
        }
        // A rise past `baseline_hold` of its threshold holds the baseline for up to
        // `baseline_hold_s`: a leak that opens over seconds is not absorbed before it
        // reaches the threshold; a slow drift of the operating point is followed again.
        let settled = e.t_s - self.armed_at_s >= self.cfg.baseline_tau_s;
        let past = settled
            && (0..3).any(|k| raw[k] - self.baseline_lpm[k] > self.cfg.baseline_hold * self.threshold_lpm[k]);
        if !past {
            self.hold_since_s = None;
        }
        let holding = past && e.t_s - *self.hold_since_s.get_or_insert(e.t_s) <= self.cfg.baseline_hold_s;
        if self.active.is_none() && self.cfg.baseline_tau_s > 0.0 {
            let a = if reacquiring {
                (dt_s / 0.5).min(1.0)
            } else if blind || holding {
                0.0
            } else {
                (dt_s / self.cfg.baseline_tau_s).min(1.0)
            };
            for k in 0..3 {
                self.baseline_lpm[k] += a * (raw[k] - self.baseline_lpm[k]);
                if reacquiring {
                    // The reference of the slow-leak check moves with it: what the
                    // baseline takes up here is not a leak growing.
                    self.stats[k].mean = self.baseline_lpm[k];
                }
            }
        }
        // Rise of each hypothesis' size above its healthy baseline, and how badly the
        // hypothesis fits (the part of the flow mismatch it leaves unexplained).
        let rise: [f64; 3] = std::array::from_fn(|k| raw[k] - self.baseline_lpm[k]);
        let misfit = misfits(rise);
        let sigma_q = [
            e.sigma[7] / M3_S_PER_LPM,
            e.sigma[8] / M3_S_PER_LPM,
            e.sigma[9] / M3_S_PER_LPM,
        ];
        // σ of each hypothesis' size: the filter's marginal σ (correlations ignored)
        // combined with the spread the healthy estimate showed in the warm-up (the
        // filter alone is overconfident about model error).
        let sigma_filter = [
            sigma_q[0].hypot(sigma_q[2]),
            sigma_q[1].hypot(sigma_q[2]),
            0.5 * (sigma_q[0].powi(2) + sigma_q[1].powi(2) + 4.0 * sigma_q[2].powi(2)).sqrt(),
        ];
        let sigma_lpm: [f64; 3] = std::array::from_fn(|k| sigma_filter[k].hypot(self.stats[k].std()));
        let score: [f64; 3] = std::array::from_fn(|k| (rise[k] - misfit[k]) / self.threshold_lpm[k]);
        // What the baseline has absorbed since the warm-up, judged against `slow_leak_lpm`.
        let drift: [f64; 3] = std::array::from_fn(|k| self.baseline_lpm[k] - self.stats[k].mean);
        let drift_misfit = misfits(drift);
        let slow_lead = (0..3)
            .map(|k| (k, (drift[k] - drift_misfit[k]) / self.cfg.slow_leak_lpm.max(1e-9)))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        if self.active.is_none() && self.cfg.baseline_tau_s > 0.0 && slow_lead.1 > 1.0 {
            match self.slow_since_s {
                Some((j, _)) if j == slow_lead.0 => {}
                _ => self.slow_since_s = Some((slow_lead.0, e.t_s)),
            }
        } else {
            self.slow_since_s = None;
        }
        let (lead, best) = (0..3)
            .map(|k| (k, score[k]))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        let second = (0..3)
            .filter(|k| *k != lead)
            .map(|k| score[k])
            .fold(f64::NEG_INFINITY, f64::max);
        let mut strong = None;
        for k in 0..3 {
            let thr = self.threshold_lpm[k];
            if rise[k] < 0.25 * thr {
                self.last_low_s[k] = e.t_s;
                self.baseline_low_lpm[k] = self.baseline_lpm[k];
            }
            let evidence = !invalid && (!blind || rise[k] > self.cfg.excursion_override * thr);
            let ratio = rise[k] / thr;
            if evidence
                && self.cfg.pending_factor > 0.0
                && ratio > self.cfg.pending_factor
                && strong.is_none_or(|(_, r)| ratio > r)
            {
                strong = Some((k, ratio));
            }
            // The kind is decided before the alarm: the named kind must explain the
            // mismatch (what it leaves unexplained is a small part of its size).
            let clear = misfit[k] <= self.cfg.isolation_max_misfit * rise[k];
            // (a named event is followed while its kind leads; a pending one waits for a clear kind)
            let named = self.active.is_some_and(|a| a.kind != EventKind::Leak);
            if k == lead && rise[k] > thr && best > 0.5 && evidence && (clear || named) {
                self.above_since_s[k].get_or_insert(e.t_s);
            } else {
                self.above_since_s[k] = None;
            }
        }
        match strong {
            Some(_) => {
                self.strong_since_s.get_or_insert(e.t_s);
            }
            None => self.strong_since_s = None,
        }
        match self.active {
            None => {
                // A leak is raised once one kind has explained the mismatch clearly for
                // `confirm_s` (named if it has led for `kind_confirm_s`), or once some
                // hypothesis' rise has been past `pending_factor` thresholds for
                // `confirm_s` (kind pending: the mismatch shows on both chambers).
                let clear_ready = self.above_since_s[lead].filter(|t0| e.t_s - t0 >= self.cfg.confirm_s);
                let strong_ready = strong.filter(|_| {
                    self.strong_since_s
                        .is_some_and(|t0| e.t_s - t0 >= self.cfg.confirm_s)
                });
                let ready = match (clear_ready, strong_ready) {
                    (Some(t0), _) => Some((lead, e.t_s - t0 >= self.cfg.kind_confirm_s)),
                    (None, Some((k, _))) => Some((k, false)),
                    (None, None) => None,
                };
                if let Some((lead, decided)) = ready {
                    // Measure the leak from the baseline before its onset: what the
                    // baseline absorbed while the leak rose is part of the leak.
                    self.baseline_lpm = self.baseline_low_lpm;
                    let rise: [f64; 3] = std::array::from_fn(|k| raw[k] - self.baseline_lpm[k]);
                    let id = self.next_id;
                    self.next_id += 1;
                    // The kind is named at once only if it has led long enough;
                    // otherwise the leak is raised with its kind pending.
                    let kind = EventKind::LEAKS[lead];
                    self.active = Some(Active {
                        kind: if decided { kind } else { EventKind::Leak },
                        id,
                        t_onset_s: self.last_low_s[lead],
                        last_size_lpm: rise[lead],
                        last_update_s: e.t_s,
                        below_since_s: None,
                        // (pending: since when the kind now leading has led, on average)
                        other_since_s: (!decided).then_some((lead, e.t_s)),
                    });
                    self.pending_rise_lpm = rise;
                    let mut ev = self.event(
                        kind,
                        Phase::Raised,
                        id,
                        e.t_s,
                        rise[lead],
                        sigma_lpm[lead],
                        best,
                        second,
                    );
                    if !decided {
                        ev.kind = EventKind::Leak;
                        ev.detail = format!(
                            "kind pending ({} leads; named once one kind has led for {} s): {}",
                            kind.name(),
                            self.cfg.kind_confirm_s,
                            ev.detail
                        );
                    }
                    *out = Some(ev);
                } else if let (true, Some((j, t0))) = (
                    self.above_since_s[lead].is_none() && self.strong_since_s.is_none(),
                    self.slow_since_s,
                ) {
                    if e.t_s - t0 >= self.cfg.confirm_s {
                        // A leak that grew too slowly for the rise: measure it from the
                        // warm-up offset from now on (the baseline goes back there).
                        self.slow_since_s = None;
                        for k in 0..3 {
                            self.baseline_lpm[k] = self.stats[k].mean;
                            self.baseline_low_lpm[k] = self.stats[k].mean;
                        }
                        let size = raw[j] - self.stats[j].mean;
                        let id = self.next_id;
                        self.next_id += 1;
                        let kind = EventKind::LEAKS[j];
                        self.active = Some(Active {
                            kind,
                            id,
                            t_onset_s: f64::NAN,
                            last_size_lpm: size,
                            last_update_s: e.t_s,
                            below_since_s: None,
                            other_since_s: None,
                        });
                        let mut ev = self.event(
                            kind,
                            Phase::Raised,
                            id,
                            e.t_s,
                            size,
                            sigma_lpm[j],
                            slow_lead.1,
                            0.0,
                        );
                        ev.detail = format!(
                            "slowly growing: the healthy baseline drifted {size:.3} L/min (at p_s/2) since the warm-up; {}",
                            ev.detail
                        );
                        *out = Some(ev);
                    }
                }
            }
            Some(mut a) if a.kind == EventKind::Leak => {
                // Kind pending: name it once one kind has led, clearly (it explains the
                // mismatch) and with a rise past half its threshold, for `kind_confirm_s`
                // (the same event id, raised again with its kind).
                if !invalid {
                    let w = (dt_s / KIND_AVERAGE_S).min(1.0);
                    for k in 0..3 {
                        self.pending_rise_lpm[k] += w * (rise[k] - self.pending_rise_lpm[k]);
                    }
                }
                let avg = self.pending_rise_lpm;
                let avg_misfit = misfits(avg);
                let lead = (0..3)
                    .map(|k| (k, (avg[k] - avg_misfit[k]) / self.threshold_lpm[k]))
                    .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a })
                    .0;
                let leads = !invalid
                    && avg[lead] > 0.5 * self.threshold_lpm[lead]
                    && avg_misfit[lead] <= self.cfg.isolation_max_misfit * avg[lead];
                a.other_since_s = match a.other_since_s {
                    Some((j, t0)) if leads && j == lead => Some((j, t0)),
                    _ if leads => Some((lead, e.t_s)),
                    _ => None,
                };
                if let Some((_, t0)) = a.other_since_s {
                    if e.t_s - t0 >= self.cfg.kind_confirm_s {
                        a.other_since_s = None;
                        a.kind = EventKind::LEAKS[lead];
                        a.last_size_lpm = rise[lead];
                        a.last_update_s = e.t_s;
                        a.below_since_s = None;
                        self.active = Some(a);
                        let mut ev = self.event(
                            a.kind,
                            Phase::Raised,
                            a.id,
                            e.t_s,
                            rise[lead],
                            sigma_lpm[lead],
                            best,
                            second,
                        );
                        ev.detail = format!(
                            "kind decided: {} has led for {:.1} s; names the pending leak event {}; {}",
                            a.kind.name(),
                            e.t_s - t0,
                            a.id,
                            ev.detail
                        );
                        *out = Some(ev);
                        return;
                    }
                }
                let low = (0..3).all(|k| rise[k] < 0.5 * self.threshold_lpm[k]);
                if low && !invalid {
                    let since = *a.below_since_s.get_or_insert(e.t_s);
                    if e.t_s - since >= self.cfg.clear_s {
                        self.active = None;
                        let mut ev = self.event(
                            EventKind::LEAKS[lead],
                            Phase::Cleared,
                            a.id,
                            e.t_s,
                            rise[lead],
                            sigma_lpm[lead],
                            0.0,
                            0.0,
                        );
                        ev.kind = EventKind::Leak;
                        *out = Some(ev);
                        return;
                    }
                } else {
                    a.below_since_s = None;
                }
                self.active = Some(a);
            }
            Some(mut a) => {
                let mut k = EventKind::LEAKS.iter().position(|x| *x == a.kind).unwrap_or(0);
                // Re-isolation: when another kind explains the data clearly better for
                // `reisolate_s`, a new event of that kind is raised (it replaces this one).
                if lead != k
                    && best > 1.0
                    && best - score[k] > 1.0
                    && misfit[lead] <= self.cfg.isolation_max_misfit * rise[lead]
                {
                    match a.other_since_s {
                        Some((j, t0)) if j == lead => {
                            if e.t_s - t0 >= self.cfg.reisolate_s {
                                let from = (a.kind, a.id);
                                let id = self.next_id;
                                self.next_id += 1;
                                a.kind = EventKind::LEAKS[lead];
                                a.id = id;
                                a.other_since_s = None;
                                a.below_since_s = None;
                                a.last_size_lpm = rise[lead];
                                a.last_update_s = e.t_s;
                                k = lead;
                                self.active = Some(a);
                                let mut ev = self.event(
                                    a.kind,
                                    Phase::Raised,
                                    a.id,
                                    e.t_s,
                                    rise[k],
                                    sigma_lpm[k],
                                    best,
                                    score[from.0 as usize % 3].min(best),
                                );
                                ev.detail = format!(
                                    "re-isolated: replaces event {} ({}); {}",
                                    from.1,
                                    from.0.name(),
                                    ev.detail
                                );
                                *out = Some(ev);
                                return;
                            }
                        }
                        _ => a.other_since_s = Some((lead, e.t_s)),
                    }
                } else {
                    a.other_since_s = None;
                }
                let size = rise[k];
                if size < 0.5 * self.threshold_lpm[k] && !invalid {
                    let since = *a.below_since_s.get_or_insert(e.t_s);
                    if e.t_s - since >= self.cfg.clear_s {
                        self.active = None;
                        *out = Some(self.event(
                            a.kind,
                            Phase::Cleared,
                            a.id,
                            e.t_s,
                            size,
                            sigma_lpm[k],
                            0.0,
                            0.0,
                        ));
                        return;
                    }
                } else {
                    a.below_since_s = None;
                }
                if !invalid
                    && e.t_s - a.last_update_s >= self.cfg.update_interval_s
                    && (size - a.last_size_lpm).abs()
                        > self.cfg.update_relative * a.last_size_lpm.abs().max(1e-3)
                {
                    a.last_size_lpm = size;
                    a.last_update_s = e.t_s;
                    let others = (0..3)
                        .filter(|j| *j != k)
                        .map(|j| score[j])
                        .fold(f64::NEG_INFINITY, f64::max);
                    let mut ev = self.event(
                        a.kind,
                        Phase::Updated,
                        a.id,
                        e.t_s,
                        size,
                        sigma_lpm[k],
                        score[k],
                        others,
                    );
                    ev.t_onset_s = a.t_onset_s;
                    *out = Some(ev);
                }
                self.active = Some(a);
            }
        }
    }

    /// An event of kind `kind` whose nominal size (at p_s/2) is `size_nominal_lpm`:
    /// the reported size is the real flow at the measured pressures.
    #[allow(clippy::too_many_arguments)]
    fn event(
        &self,
        kind: EventKind,
        phase: Phase,
        id: u64,
        t_s: f64,
        size_nominal_lpm: f64,
        sigma_nominal_lpm: f64,
        score: f64,
        second: f64,
    ) -> LeakEvent {
        // Confidence: how clearly the leading kind beats the others, and the threshold.
        let margin = (score - second.max(0.0)).max(0.0);
        let confidence = if phase == Phase::Cleared {
            0.0
        } else {
            1.0 - (-margin).exp()
        };
        let k = EventKind::LEAKS.iter().position(|x| *x == kind).unwrap_or(0);
        let g = self.flow_factor[k];
        let pn = 0.5 * self.cfg.supply_pressure_pa;
        let spread = self.stats[k].std().max(1e-12);
        let z = size_nominal_lpm / spread;
        let mut ev = LeakEvent::plain(
            kind,
            phase,
            "leak-size",
            id,
            t_s,
            self.active.map(|a| a.t_onset_s).unwrap_or(f64::NAN),
        );
        ev.size_lpm = size_nominal_lpm * g;
        ev.size_lpm_sigma = sigma_nominal_lpm * g;
        ev.size_nominal_lpm = size_nominal_lpm;
        ev.coefficient_m3_s_sqrt_pa = size_nominal_lpm * M3_S_PER_LPM / pn.sqrt();
        ev.statistic = z;
        ev.threshold = self.threshold_z[k];
        ev.confidence = confidence;
        ev.detail = format!(
            "rise {z:.1} healthy spreads (threshold {:.1}, for {} false alarms/h); {:.3} L/min at the measured \
             pressures (mean over {} s), {:.3} L/min at p_s/2, k = {:.3e} m³/(s·√Pa)",
            self.threshold_z[k],
            self.cfg.false_alarms_per_hour,
            ev.size_lpm,
            self.cfg.size_window_s,
            size_nominal_lpm,
            ev.coefficient_m3_s_sqrt_pa
        );
        ev
    }
}

impl MaeDetector {
    /// A detector with settings `cfg`.
    pub fn new(cfg: ClassifierConfig) -> Self {
        MaeDetector {
            cfg,
            arming: Arming::Converging,
            stats: [Stats::default(); 2],
            threshold_pa: [f64::NAN; 2],
            pattern_since: None,
            active: None,
            next_id: 1,
        }
    }

    /// Whether the thresholds have been learned.
    pub fn is_armed(&self) -> bool {
        self.arming == Arming::Armed
    }

    /// The learned MAE thresholds of p1 and p2, Pa.
    pub fn thresholds_pa(&self) -> [f64; 2] {
        self.threshold_pa
    }

    /// Restarts the warm-up (after a filter reset).
    pub fn restart(&mut self) {
        let cfg = self.cfg.clone();
        let id = self.next_id;
        *self = MaeDetector::new(cfg);
        self.next_id = id;
    }

    /// Reads one estimate; pushes any event into `out`.
    pub fn on_estimate(&mut self, e: &Estimate, out: &mut Option<LeakEvent>) {
        if e.flags & FLAG_SKIPPED != 0 || !e.mae_pa.iter().all(|m| m.is_finite()) {
            return;
        }
        match arm_step(&mut self.arming, &self.cfg, e) {
            Some(false) => {
                self.stats[0].push(e.mae_pa[0]);
                self.stats[1].push(e.mae_pa[1]);
                return;
            }
            Some(true) => {
                for k in 0..2 {
                    self.threshold_pa[k] = self.cfg.mae_margin * self.stats[k].max;
                }
                return;
            }
            None if !self.is_armed() => return,
            None => {}
        }
        let high = [
            e.mae_pa[0] > self.threshold_pa[0],
            e.mae_pa[1] > self.threshold_pa[1],
        ];
        let kind = match high {
            [true, false] => Some(EventKind::Ext1),
            [false, true] => Some(EventKind::Ext2),
            [true, true] => Some(EventKind::Int),
            [false, false] => None,
        };
        match (kind, self.pattern_since) {
            (Some(k), Some((pk, _))) if k == pk => {}
            (Some(k), _) => self.pattern_since = Some((k, e.t_s)),
            (None, _) => self.pattern_since = None,
        }
        let ratio = [
            e.mae_pa[0] / self.threshold_pa[0],
            e.mae_pa[1] / self.threshold_pa[1],
        ];
        match self.active {
            None => {
                if let Some((k, t0)) = self.pattern_since {
                    if e.t_s - t0 >= self.cfg.mae_confirm_s {
                        let id = self.next_id;
                        self.next_id += 1;
                        // The MAE window delays the rise: place the onset half a window back is not
                        // possible without the window; report the start of the pattern.
                        self.active = Some(Active {
                            kind: k,
                            id,
                            t_onset_s: t0,
                            last_size_lpm: f64::NAN,
                            last_update_s: e.t_s,
                            below_since_s: None,
                            other_since_s: None,
                        });
                        let margin = (ratio[0].max(ratio[1]) - 1.0).max(0.0);
                        let mut ev = LeakEvent::plain(k, Phase::Raised, "thesis-mae", id, e.t_s, t0);
                        ev.confidence = 1.0 - (-4.0 * margin).exp();
                        ev.detail = format!(
                            "thesis baseline (not a leakwatch decision): MAE p1 {:.0} Pa, p2 {:.0} Pa",
                            e.mae_pa[0], e.mae_pa[1]
                        );
                        *out = Some(ev);
                    }
                }
            }
            Some(mut a) => {
                if kind.is_none() {
                    let since = *a.below_since_s.get_or_insert(e.t_s);
                    if e.t_s - since >= self.cfg.clear_s {
                        self.active = None;
                        let mut ev =
                            LeakEvent::plain(a.kind, Phase::Cleared, "thesis-mae", a.id, e.t_s, a.t_onset_s);
                        ev.confidence = 0.0;
                        *out = Some(ev);
                        return;
                    }
                } else {
                    a.below_since_s = None;
                }
                self.active = Some(a);
            }
        }
    }
}

/// Per-channel sensor watch: stuck, saturated, dead.
#[derive(Debug, Clone, Copy, Default)]
struct ChannelWatch {
    last: f64,
    same: u32,
    saturated: u32,
    dead: u32,
    raised: Option<(EventKind, u64)>,
}

/// The classifier stage: both detectors plus sensor and filter-health checks.
#[derive(Debug, Clone)]
pub struct Classifier {
    cfg: ClassifierConfig,
    /// leakwatch's detector.
    pub leak_size: LeakSizeDetector,
    /// The thesis' detector.
    pub thesis: MaeDetector,
    channels: [ChannelWatch; 3],
    next_id: u64,
    not_armed_reported: bool,
    learning_since_s: Option<f64>,
}

/// How badly each single-leak hypothesis (ext1, ext2, int) fits rises `r` =
/// [w1, w2, (w1 − w2)/2] of the chamber flows, L/min: the part of the flow
/// mismatch it leaves unexplained (ext1 leaves w2, ext2 leaves w1, an internal
/// leak leaves the common part (w1 + w2)/√2).
pub fn misfits(r: [f64; 3]) -> [f64; 3] {
    let (w1, w2) = (r[0], r[1]);
    [w2.abs(), w1.abs(), (w1 + w2).abs() / std::f64::consts::SQRT_2]
}

/// The size of each single-leak hypothesis that best explains estimated leak
/// sizes `q_lpm` = [q_e1, q_e2, q_i] (L/min at nominal drop), judged by the
/// flows they take from each chamber: w1 = q_e1 + q_i out of chamber 1 and
/// w2 = q_e2 − q_i out of chamber 2. An external leak at chamber 1 is
/// (w1, w2) = (q, 0), at chamber 2 (0, q), an internal leak (q, −q); so the
/// sizes are [w1, w2, (w1 − w2)/2]. (The three estimates are strongly
/// correlated, e.g. ext2 ≈ ext1 + a negative internal leak while the filter
/// settles; the chamber flows are what the data pins down.)
pub fn signatures_lpm(q_lpm: [f64; 3]) -> [f64; 3] {
    let w1 = q_lpm[0] + q_lpm[2];
    let w2 = q_lpm[1] - q_lpm[2];
    [w1, w2, 0.5 * (w1 - w2)]
}

/// Names of the measured channels, in measurement order.
pub const CHANNELS: [&str; 3] = ["x", "p1", "p2"];

impl Classifier {
    /// A classifier with settings `cfg`.
    pub fn new(cfg: ClassifierConfig) -> Result<Self, String> {
        cfg.validate()?;
        Ok(Classifier {
            leak_size: LeakSizeDetector::new(cfg.clone()),
            thesis: MaeDetector::new(cfg.clone()),
            cfg,
            channels: [ChannelWatch::default(); 3],
            next_id: 1_000_000,
            not_armed_reported: false,
            learning_since_s: None,
        })
    }

    /// Reads one output of the estimator stage (the leak filter's and the thesis
    /// filter's estimates) and calls `emit` for each event it gives (usually none).
    pub fn on_stage(&mut self, s: &estimator::StageEstimate, mut emit: impl FnMut(LeakEvent)) {
        if s.missing_before > 0 && s.leak.flags & FLAG_AFTER_GAP == 0 {
            // Frames lost between the estimator and the classifier: the same gate.
            let mut leak = s.leak;
            leak.flags |= FLAG_AFTER_GAP;
            self.on_estimates(&leak, &s.thesis, &mut emit);
        } else {
            self.on_estimates(&s.leak, &s.thesis, &mut emit);
        }
    }

    /// Whether a commissioning was loaded (else a leak present at start cannot be seen).
    pub fn is_commissioned(&self) -> bool {
        self.leak_size.is_commissioned()
    }

    /// The note to show at start about what the detector can see.
    pub fn start_note(&self) -> String {
        match &self.cfg.commissioning {
            Some(c) => format!(
                "commissioned from {} ({:.0} s of healthy data): a leak present at start is seen once the filter has converged",
                if c.source.is_empty() { "a healthy recording" } else { &c.source },
                c.healthy_s
            ),
            None => format!(
                "not commissioned: the healthy state is learned in the first {:.0} s after the filter converges; a leak \
                 present now or opening in that time cannot be seen (run `leakwatch commission HEALTHY.csv` and pass its \
                 file with --config)",
                self.cfg.settle_s + self.cfg.warmup_s
            ),
        }
    }

    /// Reads one estimate of a single filter (both detectors read it) and calls
    /// `emit` for each event.
    pub fn on_estimate(&mut self, e: &Estimate, mut emit: impl FnMut(LeakEvent)) {
        self.on_estimates(e, e, &mut emit);
    }

    /// Reads the leak filter's estimate `e` and the thesis filter's `thesis`.
    pub fn on_estimates(&mut self, e: &Estimate, thesis: &Estimate, mut emit: impl FnMut(LeakEvent)) {
        if e.flags & FLAG_RESET != 0 {
            // (the detector decides itself whether it keeps what it learned)
            if std::ptr::eq(e, thesis) {
                self.thesis.restart();
            }
            let detail = if self.leak_size.is_armed() {
                "the leak filter restarted; no leak evidence until it has converged again (the learned healthy state is kept)"
            } else {
                "the leak filter restarted; warm-up begins again"
            };
            let ev = self.plain(EventKind::EstimatorReset, e.t_s, "", detail);
            self.leak_size.restart();
            emit(ev);
        }
        if thesis.flags & FLAG_RESET != 0 && !std::ptr::eq(e, thesis) {
            self.thesis.restart();
            let ev = self.plain(
                EventKind::EstimatorReset,
                e.t_s,
                "",
                "the thesis filter restarted; its warm-up begins again",
            );
            emit(ev);
        }
        let faulty_before = self.channels.iter().any(|c| c.raised.is_some());
        self.check_sensors(e, &mut emit);
        let faulty = self.channels.iter().any(|c| c.raised.is_some());
        if faulty {
            // A sensor fault corrupts what the filters estimate: no leak decision
            // while it lasts, and the thresholds are learned again after it.
            return;
        }
        if faulty_before {
            self.leak_size.relearn();
            self.thesis.restart();
        }
        if self.learning_since_s.is_none() && e.flags & FLAG_CONVERGING == 0 {
            self.learning_since_s = Some(e.t_s);
        }
        let mut ev = None;
        self.leak_size.on_estimate(e, &mut ev);
        if let Some(ev) = ev.take() {
            emit(ev);
        }
        if self.cfg.thesis_baseline {
            self.thesis.on_estimate(thesis, &mut ev);
            if let Some(ev) = ev {
                emit(ev);
            }
        }
    }

    /// Ends the stream: reports a warm-up that never completed (thresholds not learned).
    pub fn finish(&mut self, t_s: f64, mut emit: impl FnMut(LeakEvent)) {
        if !self.leak_size.is_armed() && !self.thesis.is_armed() && !self.not_armed_reported {
            self.not_armed_reported = true;
            let seen = self.learning_since_s.map(|t0| t_s - t0).unwrap_or(0.0);
            emit(self.plain(
                EventKind::NotArmed,
                t_s,
                "",
                &format!(
                    "warm-up too short to learn thresholds: {seen:.2} s of converged healthy data, {} s needed \
                     ({} s to settle + {} s to learn)",
                    self.cfg.settle_s + self.cfg.warmup_s,
                    self.cfg.settle_s,
                    self.cfg.warmup_s
                ),
            ));
        }
    }

    fn plain(&mut self, kind: EventKind, t_s: f64, channel: &str, detail: &str) -> LeakEvent {
        let id = self.next_id;
        self.next_id += 1;
        let mut ev = LeakEvent::plain(kind, Phase::Raised, "sensors", id, t_s, t_s);
        ev.channel = channel.into();
        ev.detail = detail.into();
        ev
    }

    fn check_sensors(&mut self, e: &Estimate, emit: &mut impl FnMut(LeakEvent)) {
        for c in 0..3 {
            let v = e.measured[c];
            let mut w = self.channels[c];
            if v.is_finite() {
                w.dead = 0;
                w.same = if v == w.last { w.same + 1 } else { 0 };
                w.last = v;
                let sat = c > 0 && (v <= 0.0 || v >= self.cfg.pressure_full_scale_pa);
                w.saturated = if sat { w.saturated + 1 } else { 0 };
            } else {
                w.dead += 1;
                w.same = 0;
                w.saturated = 0;
            }
            // The rod may legitimately rest (stiction): only pressures can be stuck.
            let now = if w.dead >= self.cfg.dead_samples {
                Some(EventKind::SensorDead)
            } else if w.saturated >= self.cfg.saturated_samples {
                Some(EventKind::SensorSaturated)
            } else if c > 0 && w.same >= self.cfg.stuck_samples {
                Some(EventKind::SensorStuck)
            } else {
                None
            };
            match (now, w.raised) {
                (Some(k), None) => {
                    let detail = match k {
                        EventKind::SensorDead => {
                            format!("no usable {} value for {} samples", CHANNELS[c], w.dead)
                        }
                        EventKind::SensorSaturated => format!("{} at the end of its range", CHANNELS[c]),
                        _ => format!("{} has not changed for {} samples", CHANNELS[c], w.same),
                    };
                    let ev = self.plain(k, e.t_s, CHANNELS[c], &detail);
                    w.raised = Some((k, ev.event_id));
                    emit(ev);
                }
                (None, Some((k, id))) => {
                    let mut ev = self.plain(k, e.t_s, CHANNELS[c], "the channel is back");
                    ev.phase = Phase::Cleared;
                    ev.event_id = id;
                    w.raised = None;
                    emit(ev);
                }
                _ => {}
            }
            self.channels[c] = w;
        }
    }
}
