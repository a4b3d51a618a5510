//! leakwatch's detector: thresholds on the rise of the estimated leak sizes above
//! a healthy baseline, the kind decided by the chamber flows each hypothesis
//! implies (the per-sample step is in `step.rs`, `evidence.rs` and `decide.rs`;
//! the healthy state it learns, and a commissioning's learner, in `healthy.rs`).

use crate::track::{Active, Arming, Stats};
use crate::{signatures_with, ClassifierConfig, EventKind, LeakEvent, Phase, M3_S_PER_LPM};
use filter::Estimate;

mod blind;
mod decide;
mod evidence;
mod flow_hold;
mod healthy;
mod step;
mod stretch;

use blind::BlindCauses;
pub use blind::{BlindCause, BlindSeconds};
pub use healthy::CommissioningLearner;
use healthy::{HealthyRecord, RunningSpread};
pub use stretch::{Stretch, STRETCH_SHARE, STRETCH_THRESHOLD_RATIO};

/// leakwatch's detector: thresholds on the estimated leak sizes.
#[derive(Debug, Clone)]
pub struct LeakSizeDetector {
    cfg: ClassifierConfig,
    /// The internal leak's pressure factors of the signatures (the commissioning's, else nominal).
    internal_factors: [f64; 2],
    arming: Arming,
    stats: [Stats; 3],
    /// The healthy values seen while learning.
    record: HealthyRecord,
    /// The healthy rises seen since arming (no leak, valid evidence, every rise
    /// low): the spread the thresholds are refined from.
    refine: RunningSpread,
    /// When the thresholds are next refined, s.
    next_refine_s: f64,
    /// The thresholds (L/min, spreads) and spreads (L/min) the detector armed with:
    /// refining only ever lowers a threshold below these.
    armed_thresholds: ([f64; 3], [f64; 3], [f64; 3]),
    /// Threshold on the rise of each kind, in healthy spreads.
    threshold_z: [f64; 3],
    threshold_lpm: [f64; 3],
    /// Threshold on the rise of each kind that names it (its rise explained
    /// clearly), L/min: from the commissioning's clear spreads, else `threshold_lpm`.
    naming_threshold_lpm: [f64; 3],
    /// The healthy spread `naming_threshold_lpm` stands on, L/min.
    naming_spread_lpm: [f64; 3],
    /// What the oil's temperature adds to each threshold now, L/min: the
    /// laminar flows' uncertainty since the commissioning's temperature
    /// ([`filter::Estimate::laminar_factor_sigma`]) on the model's null leakage
    /// and on the healthy offsets, which the commissioning learned at its temperature.
    oil_band_lpm: [f64; 3],
    /// The part of [`Self::oil_band_lpm`] the offset watch's thresholds take,
    /// L/min: the band as it was while θ read the oil inside its operating
    /// range ([`filter::FLAG_OIL_PAST_RANGE`] unset). A transducer's fault
    /// that pulls θ past the range widens the band there; it does not raise
    /// the level its own misreading is named at.
    watch_band_lpm: [f64; 3],
    /// What the transducers' delay adds to each threshold now, L/min: its
    /// uncertainty ([`crate::Commissioning::delay_uncertainty_s`]) times the
    /// leak sizes' response to a delay ([`crate::delay_band_lpm`]).
    delay_band_lpm: [f64; 3],
    /// The commissioning's [`crate::Commissioning::delay_uncertainty_s`] in ms (0: none).
    delay_uncertainty_ms: f64,
    /// The commissioning's [`crate::Commissioning::delay_response_reach_lpm_per_ms`].
    delay_response_reach_lpm_per_ms: [f64; 3],
    /// Healthy baseline of each hypothesis' size that the rise is measured from, L/min.
    baseline_lpm: [f64; 3],
    /// The baseline when each rise was last low (before a possible onset), L/min.
    baseline_low_lpm: [f64; 3],
    /// Time of the last estimate read, s (for the baseline's time step).
    last_t_s: f64,
    /// When the detector armed, s.
    armed_at_s: f64,
    /// Since when the baseline has been held, and whether by a rise (true) or a fall, s.
    hold_since_s: Option<(bool, f64)>,
    above_since_s: [Option<f64>; 3],
    /// Evidence gathered since `above_since_s`: the time above the threshold, each
    /// second counted `min(rise/threshold, confirm_gain_cap)` times, s.
    above_evidence_s: [f64; 3],
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
    /// The same seconds, charged to their causes.
    blind_causes: BlindCauses,
    /// Mean of √(Δp/Δp_n) over `size_window_s` for ext1, ext2, int (real flow per nominal flow).
    flow_factor: [f64; 3],
    last_low_s: [f64; 3],
    /// When the command last left its rest band: a rise that came with the flow waits.
    flow_hold: flow_hold::FlowHold,
    /// While a leak's kind is pending: its rise of each hypothesis averaged over
    /// [`KIND_AVERAGE_S`] (the kind is read from the averaged mismatch), L/min.
    pending_rise_lpm: [f64; 3],
    /// Since when some hypothesis' rise has been past `pending_factor` times its
    /// threshold (with evidence), s.
    strong_since_s: Option<f64>,
    active: Option<Active>,
    next_id: u64,
    /// A pressure transducer that reads off, told from a leak.
    offsets: crate::offset::OffsetWatch,
    /// A `sensor-offset` event waiting for [`Self::take_sensor_event`].
    sensor_event: Option<LeakEvent>,
    /// The position has repeated exactly since a moment the pressures misfit:
    /// perhaps a frozen encoder on a moving rod ([`Self::suspect_frozen_position`]).
    frozen_position: bool,
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

/// The leak-size detector's thresholds (ext1, ext2, int) for healthy spreads
/// `spreads` (L/min at p_s/2) with `crossings_per_s` upcrossings of the mean per
/// second: in spreads (from the false-alarm rate, [`rice_threshold`]) and in L/min
/// (at least the floors `min_size_lpm`, `min_internal_size_lpm`).
pub fn thresholds(
    cfg: &ClassifierConfig,
    spreads: [f64; 3],
    crossings_per_s: [f64; 3],
) -> ([f64; 3], [f64; 3]) {
    let (mut z, mut lpm) = ([0.0; 3], [0.0; 3]);
    for k in 0..3 {
        z[k] = rice_threshold(crossings_per_s[k], cfg.false_alarms_per_hour, cfg.threshold_sigma);
        let floor = if k == 2 {
            cfg.min_internal_size_lpm
        } else {
            cfg.min_size_lpm
        };
        lpm[k] = (z[k] * spreads[k]).max(floor);
    }
    (z, lpm)
}

/// The leak sizes [q_e1, q_e2, q_i] of an estimate, L/min at the nominal drop.
pub(crate) fn leak_sizes_lpm(e: &Estimate) -> [f64; 3] {
    [
        e.state[7] / M3_S_PER_LPM,
        e.state[8] / M3_S_PER_LPM,
        e.state[9] / M3_S_PER_LPM,
    ]
}

impl LeakSizeDetector {
    /// A detector with settings `cfg`.
    pub fn new(cfg: ClassifierConfig) -> Self {
        let offsets = crate::offset::OffsetWatch::new(cfg.pressure_full_scale_pa)
            .with_transducer_tolerance(cfg.pressure_zero_offset_max_pa, cfg.pressure_span_error_max);
        let x_unwatched = cfg.commissioning.as_ref().is_some_and(|c| !c.position_watched());
        let offsets = if x_unwatched {
            offsets.without_position()
        } else {
            offsets
        };
        let offsets =
            offsets.with_healthy_misreading(cfg.commissioning.as_ref().and_then(|c| c.healthy_misreading()));
        let delay_uncertainty_ms = cfg
            .commissioning
            .as_ref()
            .map_or(0.0, |c| 1e3 * c.delay_uncertainty_s)
            .max(0.0);
        let delay_response_reach_lpm_per_ms = cfg
            .commissioning
            .as_ref()
            .map_or([0.0; 3], |c| c.delay_response_reach_lpm_per_ms);
        LeakSizeDetector {
            internal_factors: cfg
                .commissioning
                .as_ref()
                .map_or(crate::NOMINAL_INTERNAL_FACTORS, |c| c.internal_factors),
            record: HealthyRecord::with_capacity_s(cfg.warmup_s),
            refine: RunningSpread::default(),
            next_refine_s: f64::NEG_INFINITY,
            armed_thresholds: ([f64::NAN; 3], [f64::NAN; 3], [f64::NAN; 3]),
            cfg,
            arming: Arming::Converging,
            stats: [Stats::default(); 3],
            threshold_z: [f64::NAN; 3],
            threshold_lpm: [f64::NAN; 3],
            naming_threshold_lpm: [f64::NAN; 3],
            naming_spread_lpm: [f64::NAN; 3],
            oil_band_lpm: [0.0; 3],
            watch_band_lpm: [0.0; 3],
            delay_band_lpm: [0.0; 3],
            delay_uncertainty_ms,
            delay_response_reach_lpm_per_ms,
            baseline_lpm: [f64::NAN; 3],
            baseline_low_lpm: [f64::NAN; 3],
            last_t_s: f64::NAN,
            armed_at_s: f64::NAN,
            hold_since_s: None,
            above_since_s: [None; 3],
            above_evidence_s: [0.0; 3],
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
            blind_causes: BlindCauses::default(),
            flow_factor: [f64::NAN; 3],
            last_low_s: [0.0; 3],
            flow_hold: flow_hold::FlowHold::default(),
            pending_rise_lpm: [0.0; 3],
            strong_since_s: None,
            active: None,
            next_id: 1,
            offsets,
            sensor_event: None,
            frozen_position: false,
        }
    }

    /// The detector learning the healthy rises' own misreading over all it
    /// reads ([`LeakSizeDetector::healthy_misreading`]).
    pub fn learning_healthy_misreading(mut self) -> Self {
        self.offsets = self.offsets.learning_healthy_misreading();
        self
    }

    /// The misreading the rises read so far fit best, in its swing form,
    /// where it explains enough of them ([`crate::offset::OffsetWatch::healthy_misreading`]).
    pub fn healthy_misreading(&self) -> Option<crate::offset::HealthyMisreading> {
        self.offsets.healthy_misreading()
    }

    /// No leak evidence before `t_s` (s): a reading the filter took in was an outlier.
    pub fn hold_evidence_until(&mut self, t_s: f64) {
        self.invalid_until(BlindCause::SuspectReading, t_s);
    }

    /// No evidence before `until_s` (s), for `cause`.
    fn invalid_until(&mut self, cause: BlindCause, until_s: f64) {
        self.invalid_until_s = self.invalid_until_s.max(until_s);
        self.blind_causes.hold(cause, until_s);
    }

    /// Whether the position reading may be frozen on a moving rod (the
    /// classifier's watch of x): while it may, no new leak is raised on rises an
    /// internal leak leads. A frozen encoder leaves the rod's travel to the
    /// pressures: one chamber fills and the other empties, an internal leak's
    /// pattern. An external leak shows on one chamber only and is still raised.
    pub fn suspect_frozen_position(&mut self, suspect: bool) {
        self.frozen_position = suspect;
    }

    /// The `sensor-offset` event the last estimate gave, if any (taken once).
    pub fn take_sensor_event(&mut self) -> Option<LeakEvent> {
        self.sensor_event.take()
    }

    /// The pressure transducer named as reading off, if one stands.
    pub fn standing_offset(&self) -> Option<crate::offset::StandingOffset> {
        self.offsets.standing()
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

    /// The thresholds that name each kind (ext1, ext2, int) on its rise
    /// explained clearly, L/min at the nominal drop (NaN before arming): the
    /// smallest leak named ([`crate::Commissioning::clear_spreads_lpm`]).
    pub fn thresholds_lpm(&self) -> [f64; 3] {
        self.naming_threshold_lpm
    }

    /// The thresholds that name each kind in force on the last estimate read,
    /// L/min at the nominal drop (NaN before arming): [`Self::thresholds_lpm`]
    /// widened by what the oil's temperature and the transducers' delay left
    /// uncertain on it.
    pub fn thresholds_in_force_lpm(&self) -> [f64; 3] {
        self.past_the_delay(self.naming_thresholds_now())
    }

    /// The thresholds in healthy spreads (from the requested false-alarm rate; NaN before arming).
    pub fn thresholds_sigma(&self) -> [f64; 3] {
        self.threshold_z
    }

    /// When the thresholds were learned (the detector armed), s; `None` if never.
    pub fn armed_at_s(&self) -> Option<f64> {
        (self.is_armed() && self.armed_at_s.is_finite()).then_some(self.armed_at_s)
    }

    /// The mean NIS of the healthy state the detector armed with (NaN before arming).
    pub fn nis_healthy(&self) -> f64 {
        self.nis_healthy
    }

    /// Seconds in which no evidence was gathered after arming (gaps, resets, excursions, NIS), s.
    pub fn blind_s(&self) -> f64 {
        self.blind_s
    }

    /// The seconds of [`Self::blind_s`] by cause, s (they add up to it).
    pub fn blind_by_cause(&self) -> BlindSeconds {
        self.blind_causes.seconds()
    }

    /// The healthy offsets of the three hypothesis sizes learned in the warm-up, L/min.
    pub fn offsets_lpm(&self) -> [f64; 3] {
        [self.stats[0].mean, self.stats[1].mean, self.stats[2].mean]
    }

    /// Current rise of each hypothesis' size (ext1, ext2, int; [`signatures_with`])
    /// above its healthy baseline, L/min (NaN if unknown or not armed).
    pub fn rise_lpm(&self, e: &Estimate) -> [f64; 3] {
        let mut r = [f64::NAN; 3];
        if e.n_states >= 10 {
            let raw = self.raw_sizes(e);
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
        self.offsets.restart();
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
    /// (before the healthy offsets are removed): see [`signatures_with`].
    fn raw_sizes(&self, e: &Estimate) -> [f64; 3] {
        signatures_with(leak_sizes_lpm(e), self.internal_factors)
    }

    /// Arms at time `t_s` (s) with healthy `means` and `spreads` (L/min), the
    /// spreads of the naming test `naming_spreads` (L/min) and `crossings_per_s`
    /// upcrossings of the mean per second.
    fn arm_with(
        &mut self,
        means: [f64; 3],
        spreads: [f64; 3],
        naming_spreads: [f64; 3],
        crossings_per_s: [f64; 3],
        t_s: f64,
    ) {
        self.set_thresholds(spreads, crossings_per_s);
        self.naming_spread_lpm = naming_spreads;
        self.naming_threshold_lpm = thresholds(&self.cfg, naming_spreads, crossings_per_s).1;
        self.armed_thresholds = (self.threshold_lpm, self.threshold_z, spreads);
        for k in 0..3 {
            self.last_low_s[k] = t_s;
            self.baseline_lpm[k] = means[k];
            self.baseline_low_lpm[k] = means[k];
            self.stats[k].mean = means[k];
        }
        self.arming = Arming::Armed;
        self.armed_at_s = t_s;
        self.last_t_s = t_s;
    }

    /// The thresholds (spreads and L/min) for healthy spreads `spreads` (L/min) with
    /// `crossings_per_s` upcrossings of the mean per second.
    fn set_thresholds(&mut self, spreads: [f64; 3], crossings_per_s: [f64; 3]) {
        let (z, lpm) = thresholds(&self.cfg, spreads, crossings_per_s);
        self.threshold_z = z;
        self.threshold_lpm = lpm;
        for (k, spread) in spreads.iter().enumerate() {
            self.stats[k].m2 = spread * spread;
            self.stats[k].n = 2.0;
        }
    }

    /// Learns the healthy spread on from the rises `rise` (L/min) of a sample that is
    /// healthy evidence, and every second, once `refine_after_s` of it has been
    /// learned, takes the thresholds from it where they are lower than the warm-up's:
    /// the warm-up is short and holds the
    /// filter's start-up transient, the time since arming is long and ordinary.
    fn refine_thresholds(&mut self, t_s: f64, dt_s: f64, rise: [f64; 3]) {
        if self.cfg.refine_after_s <= 0.0 || self.cfg.commissioning.is_some() {
            return;
        }
        self.refine.push(t_s, dt_s, rise);
        if self.refine.learned_s >= self.cfg.refine_after_s && t_s >= self.next_refine_s {
            self.next_refine_s = t_s + 1.0;
            let (spreads, crossings) = self.refine.summary();
            self.set_thresholds(spreads, crossings);
            // Only ever lower: a leak growing too slowly to pass the threshold adds
            // its rise to the spread learned meanwhile and must not lift it.
            let (thr, z, spread) = self.armed_thresholds;
            for k in 0..3 {
                if self.threshold_lpm[k].is_nan() || self.threshold_lpm[k] > thr[k] {
                    self.threshold_lpm[k] = thr[k];
                    self.threshold_z[k] = z[k];
                    self.stats[k].m2 = spread[k] * spread[k];
                }
            }
            // (refined only without a commissioning: the naming test's spread is the whole spread)
            self.naming_threshold_lpm = self.threshold_lpm;
            self.naming_spread_lpm = std::array::from_fn(|k| self.stats[k].std());
        }
    }

    /// The smallest real flow declared for hypothesis `k` (ext1, ext2, int), L/min.
    fn min_size_of(&self, k: usize) -> f64 {
        if k == 2 {
            self.cfg.min_internal_size_lpm
        } else {
            self.cfg.min_size_lpm
        }
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
        // (the statistic against the spread of the naming test, whose threshold in spreads is the same)
        let spread = self.naming_spread_lpm[k].max(1e-12);
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

#[cfg(test)]
mod tests;
