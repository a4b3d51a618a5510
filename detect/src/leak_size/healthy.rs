//! The healthy state learned from the leak filter's estimates: the kept
//! values and their statistics ([`HealthyRecord`]), the running spread the
//! detector refines its thresholds with ([`RunningSpread`]), and a
//! commissioning's learner ([`CommissioningLearner`]).

use super::{leak_sizes_lpm, Stretch};
use crate::{signatures_with, ClassifierConfig, Commissioning};
use filter::{Estimate, FLAG_AFTER_GAP, FLAG_CONVERGING, FLAG_RESET, FLAG_SKIPPED};

/// Healthy values of the three single-leak sizes kept every 10 ms, and their
/// statistics: the median as the offset, the upper semi-deviation as the
/// spread (the RMS of the values above the median: a leak only adds flow, so
/// the detector tests rises; the healthy estimate's upward wander with the
/// operating point stays in it, its dips do not, a filter kicked down by a
/// transient it cannot follow), and the rate of upcrossings of the median.
#[derive(Debug, Clone, Default)]
pub(super) struct HealthyRecord {
    pub(super) values: [Vec<f64>; 3],
    /// The time of each kept value, s.
    pub(super) times: Vec<f64>,
    next_t_s: f64,
    pub(super) learned_s: f64,
    nis_sum: f64,
    nis_n: f64,
}

impl HealthyRecord {
    /// Interval between kept values, s.
    const EVERY_S: f64 = 0.01;

    pub(super) fn with_capacity_s(seconds: f64) -> Self {
        let n = (seconds / Self::EVERY_S).clamp(0.0, 1e6) as usize + 16;
        HealthyRecord {
            values: std::array::from_fn(|_| Vec::with_capacity(n)),
            times: Vec::with_capacity(n),
            next_t_s: f64::NEG_INFINITY,
            learned_s: 0.0,
            nis_sum: 0.0,
            nis_n: 0.0,
        }
    }

    pub(super) fn push(&mut self, t_s: f64, dt_s: f64, q: [f64; 3], nis: f64) {
        self.learned_s += dt_s;
        if nis.is_finite() {
            self.nis_sum += nis.min(1e6);
            self.nis_n += 1.0;
        }
        if t_s >= self.next_t_s {
            self.next_t_s = t_s + Self::EVERY_S;
            for k in 0..3 {
                self.values[k].push(q[k]);
            }
            self.times.push(t_s);
        }
    }

    /// Mean NIS of the learned samples (NaN if none).
    pub(super) fn nis_mean(&self) -> f64 {
        if self.nis_n > 0.0 {
            self.nis_sum / self.nis_n
        } else {
            f64::NAN
        }
    }

    /// (offsets, spreads, upcrossings per second of the learned time) of the
    /// signatures ([`signatures_with`] with `factors`) of the kept leak sizes.
    pub(super) fn summary(&self, factors: [f64; 2]) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (med, spread, cross, _) = self.summary_with_clear(factors, f64::INFINITY);
        (med, spread, cross)
    }

    /// Fewer kept values than this (1 s of them) where a kind explains the
    /// rises clearly give no clear spread: the whole spread stands in.
    const LEAST_CLEAR_VALUES: f64 = 100.0;

    /// [`HealthyRecord::summary`] and each kind's clear spread, L/min: the RMS
    /// of its rises above the median where the kind explains the rises clearly
    /// (its misfit at most `max_misfit` of its rise: where the test that names
    /// it could alarm), at most its whole spread. A kind's healthy excursions
    /// in another kind's pattern (an internal leak's: chamber 1 losing what
    /// chamber 2 gains) set no threshold of the test that never alarms on them.
    pub(super) fn summary_with_clear(
        &self,
        factors: [f64; 2],
        max_misfit: f64,
    ) -> ([f64; 3], [f64; 3], [f64; 3], [f64; 3]) {
        let mut med = [f64::NAN; 3];
        let mut spread = [f64::NAN; 3];
        let mut clear_spread = [f64::NAN; 3];
        let mut cross = [0.0; 3];
        let n = self.values[0].len();
        let mut signatures: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::with_capacity(n));
        for i in 0..n {
            let w = signatures_with([self.values[0][i], self.values[1][i], self.values[2][i]], factors);
            for k in 0..3 {
                signatures[k].push(w[k]);
            }
        }
        for k in 0..3 {
            if !signatures[k].is_empty() {
                med[k] = median(&signatures[k]);
            }
        }
        let clear = |i: usize, k: usize| {
            let rise: [f64; 3] = std::array::from_fn(|j| signatures[j][i] - med[j]);
            crate::misfits_with(rise, factors)[k] <= max_misfit * rise[k]
        };
        for k in 0..3 {
            let v = &signatures[k];
            if v.is_empty() {
                continue;
            }
            let m = med[k];
            let (mut sum_sq, mut above, mut clear_sum_sq, mut clear_above) = (0.0, 0.0, 0.0, 0.0);
            for (i, x) in v.iter().enumerate().filter(|(_, x)| **x > m) {
                let sq = (x - m).powi(2);
                (sum_sq, above) = (sum_sq + sq, above + 1.0);
                if clear(i, k) {
                    (clear_sum_sq, clear_above) = (clear_sum_sq + sq, clear_above + 1.0);
                }
            }
            spread[k] = (sum_sq / f64::max(above, 1.0)).sqrt();
            clear_spread[k] = if clear_above >= Self::LEAST_CLEAR_VALUES {
                (clear_sum_sq / clear_above).sqrt().min(spread[k])
            } else {
                spread[k]
            };
            let ups = v.windows(2).filter(|w| w[0] <= m && w[1] > m).count();
            cross[k] = ups as f64 / self.learned_s.max(Self::EVERY_S);
        }
        (med, spread, cross, clear_spread)
    }
}

impl HealthyRecord {
    /// Most passes of [`HealthyRecord::leak_like`] (each leaves out more or stops).
    const LEAK_LIKE_PASSES: usize = 8;

    /// This record without the kept values whose rises above the median make
    /// a pattern no leak can make, by more than the thresholds under `cfg`
    /// the rest gives ([`crate::leak_can_make_with`] with `factors`): the
    /// detector takes no evidence from such a pattern, so it sets no
    /// threshold. Repeated until no more values leave; with the time left
    /// out, s.
    pub(super) fn leak_like(&self, cfg: &ClassifierConfig, factors: [f64; 2]) -> (HealthyRecord, f64) {
        let n = self.values[0].len().min(self.times.len());
        let signatures: Vec<[f64; 3]> = (0..n)
            .map(|i| signatures_with([self.values[0][i], self.values[1][i], self.values[2][i]], factors))
            .collect();
        let mut keep = vec![true; n];
        let mut kept = self.clone();
        for _ in 0..Self::LEAK_LIKE_PASSES {
            let (med, spreads, crossings) = kept.summary(factors);
            let (_, thr) = crate::thresholds(cfg, spreads, crossings);
            let now: Vec<bool> = signatures
                .iter()
                .map(|w| crate::leak_can_make_with(std::array::from_fn(|k| w[k] - med[k]), thr, factors))
                .collect();
            if now == keep || now.iter().all(|k| !k) {
                break;
            }
            keep = now;
            kept = self.keeping(&keep);
        }
        let left_out_s = self.learned_s - kept.learned_s;
        (kept, left_out_s)
    }

    /// The record of the values where `keep` holds, its learned time cut by
    /// the share left out.
    fn keeping(&self, keep: &[bool]) -> HealthyRecord {
        let mut out = HealthyRecord {
            values: Default::default(),
            times: Vec::with_capacity(keep.len()),
            ..self.clone()
        };
        for (i, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
            for k in 0..3 {
                out.values[k].push(self.values[k][i]);
            }
            out.times.push(self.times[i]);
        }
        let share = out.times.len() as f64 / keep.len().max(1) as f64;
        out.learned_s = self.learned_s * share;
        out
    }
}

/// The median of `v` (the mean of the middle two of an even count; NaN if empty).
pub(super) fn median(v: &[f64]) -> f64 {
    let mut sorted = v.to_vec();
    sorted.sort_by(f64::total_cmp);
    match sorted.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => sorted[n / 2],
        n => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    }
}

/// Running statistics of the healthy rises of the three single-leak sizes,
/// kept every 10 ms without storing them: mean and spread (Welford) and the
/// upcrossings of the running mean, over all the time learned.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RunningSpread {
    n: f64,
    mean: [f64; 3],
    m2: [f64; 3],
    ups: [f64; 3],
    above: [bool; 3],
    next_t_s: f64,
    pub(super) learned_s: f64,
}

impl RunningSpread {
    pub(super) fn push(&mut self, t_s: f64, dt_s: f64, v: [f64; 3]) {
        self.learned_s += dt_s;
        if self.n > 0.0 && t_s < self.next_t_s {
            return;
        }
        self.next_t_s = t_s + HealthyRecord::EVERY_S;
        self.n += 1.0;
        for k in 0..3 {
            let d = v[k] - self.mean[k];
            self.mean[k] += d / self.n;
            self.m2[k] += d * (v[k] - self.mean[k]);
            let above = v[k] > self.mean[k];
            if above && !self.above[k] && self.n > 1.0 {
                self.ups[k] += 1.0;
            }
            self.above[k] = above;
        }
    }

    /// (spreads, upcrossings per second of the learned time).
    pub(super) fn summary(&self) -> ([f64; 3], [f64; 3]) {
        let spread = std::array::from_fn(|k| (self.m2[k] / (self.n - 1.0).max(1.0)).sqrt());
        let cross = std::array::from_fn(|k| self.ups[k] / self.learned_s.max(HealthyRecord::EVERY_S));
        (spread, cross)
    }
}

/// Sums of the chambers' pressures over the healthy samples, for the internal
/// leak's pressure factors ([`signatures_with`]).
#[derive(Debug, Clone, Copy, Default)]
struct PressureSums {
    /// Σ ssqrt(p1 − p2) (√Pa), Σ (p1 − p2)·sgn (Pa), Σ √p1, Σ √p2 (√Pa), count.
    sums: [f64; 5],
}

impl PressureSums {
    /// Adds one sample of the chamber pressures `p1_pa`, `p2_pa` (skipped if not finite).
    fn push(&mut self, p1_pa: f64, p2_pa: f64) {
        if !(p1_pa.is_finite() && p2_pa.is_finite()) {
            return;
        }
        let s = ssqrt(p1_pa - p2_pa);
        for (sum, v) in
            self.sums
                .iter_mut()
                .zip([s, s * s, p1_pa.max(0.0).sqrt(), p2_pa.max(0.0).sqrt(), 1.0])
        {
            *sum += v;
        }
    }

    /// The internal leak's pressure factors (r1, r2): ssqrt(p1 − p2)/√p_i at the
    /// mean pressures where ssqrt(p1 − p2) stayed on one side of zero (its mean
    /// beyond twice its spread), else the nominal (1, 1).
    fn factors(&self) -> [f64; 2] {
        let [s, s2, g1, g2, n] = self.sums;
        if n < 2.0 {
            return crate::NOMINAL_INTERNAL_FACTORS;
        }
        let (mean, g1, g2) = (s / n, g1 / n, g2 / n);
        let spread = (s2 / n - mean * mean).max(0.0).sqrt();
        if mean.abs() > 2.0 * spread && g1 > 0.0 && g2 > 0.0 {
            [mean / g1, mean / g2]
        } else {
            crate::NOMINAL_INTERNAL_FACTORS
        }
    }
}

/// Learns a [`Commissioning`] from the leak filter's estimates of a healthy run:
/// the offset, spread and upcrossing rate of each single-leak size after the
/// filter has converged and settled, gaps and resets left out; and the
/// internal leak's pressure factors ([`signatures_with`]) from the chambers'
/// pressures over the same samples.
#[derive(Debug, Clone)]
pub struct CommissioningLearner {
    settle_s: f64,
    converged_at_s: Option<f64>,
    record: HealthyRecord,
    pressures: PressureSums,
    last_t_s: f64,
}

/// The signed square root, √|x|·sgn x.
fn ssqrt(x: f64) -> f64 {
    x.abs().sqrt().copysign(x)
}

impl CommissioningLearner {
    /// A learner that starts `settle_s` after the filter has converged.
    pub fn new(settle_s: f64) -> Self {
        CommissioningLearner {
            settle_s,
            converged_at_s: None,
            record: HealthyRecord::with_capacity_s(600.0),
            pressures: PressureSums::default(),
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
        let q = leak_sizes_lpm(e);
        if !q.iter().all(|v| v.is_finite()) {
            return;
        }
        let dt_s = if self.last_t_s.is_finite() {
            (e.t_s - self.last_t_s).clamp(0.0, 0.1)
        } else {
            0.0
        };
        self.last_t_s = e.t_s;
        self.record.push(e.t_s, dt_s, q, e.nis);
        self.pressures.push(e.state[1], e.state[2]);
    }

    /// The internal leak's pressure factors learned so far (see [`Commissioning::internal_factors`]).
    pub fn internal_factors(&self) -> [f64; 2] {
        self.pressures.factors()
    }

    /// Per kind (ext1, ext2, int), the stretch of the learned data that sets
    /// the threshold of commissioning `c` under settings `cfg`, with the
    /// threshold the rest of the data gives ([`Stretch`]); `None` for a kind
    /// whose spread is the whole data's.
    pub fn thresholds_set_by_stretches(
        &self,
        cfg: &ClassifierConfig,
        c: &Commissioning,
    ) -> [Option<(Stretch, f64)>; 3] {
        let factors = self.internal_factors();
        let (record, _) = self.record.leak_like(cfg, factors);
        super::stretch::setting_thresholds(cfg, c, record.largest_stretches(factors))
    }

    /// The time of the learned data the commissioning under `cfg` leaves out,
    /// s: where the leak estimates made a pattern no leak can make
    /// ([`crate::leak_can_make_with`]; the model does not follow the rig there).
    pub fn left_out_s(&self, cfg: &ClassifierConfig) -> f64 {
        self.record.leak_like(cfg, self.internal_factors()).1
    }

    /// The commissioning under settings `cfg`, or why there is none (less than
    /// `min_s` of healthy data, s). The statistics leave out the values no leak
    /// can make ([`CommissioningLearner::left_out_s`]).
    pub fn finish(&self, cfg: &ClassifierConfig, min_s: f64, source: &str) -> Result<Commissioning, String> {
        let internal_factors = self.internal_factors();
        let learned_s = self.record.learned_s;
        if learned_s < min_s {
            return Err(format!(
                "only {learned_s:.1} s of converged healthy data (at least {min_s} s after the filter settles is needed)"
            ));
        }
        let (record, _) = self.record.leak_like(cfg, internal_factors);
        let (offsets_lpm, spreads_lpm, crossings_per_s, clear_spreads_lpm) =
            record.summary_with_clear(internal_factors, cfg.isolation_max_misfit);
        Ok(Commissioning {
            offsets_lpm,
            spreads_lpm,
            clear_spreads_lpm,
            crossings_per_s,
            healthy_s: record.learned_s,
            nis_mean: record.nis_mean(),
            source: source.to_string(),
            internal_factors,
            least_offsets_named: [f64::NAN; 3],
            healthy_offsets_kpa: [0.0; 2],
            healthy_span_errors: [0.0; 2],
            delay_uncertainty_s: 0.0,
            delay_response_reach_lpm_per_ms: [0.0; 3],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 120 s of healthy leak sizes (uniform noise of ±0.01 L/min), with
    /// `stretch` (ext1, ext2, int; L/min) added from 60 to 70 s.
    fn record(stretch: [f64; 3]) -> HealthyRecord {
        let mut r = HealthyRecord::with_capacity_s(120.0);
        let mut seed = 1u64;
        let mut noise = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02
        };
        for i in 0..120_000 {
            let t = i as f64 * 1e-3;
            let q = if (60.0..70.0).contains(&t) {
                stretch
            } else {
                [0.0; 3]
            };
            r.push(t, 1e-3, [q[0] + noise(), q[1] + noise(), q[2] + noise()], 3.0);
        }
        r
    }

    fn thresholds(r: &HealthyRecord) -> [f64; 3] {
        let (_, spreads, crossings) = r.summary(crate::NOMINAL_INTERNAL_FACTORS);
        crate::thresholds(&ClassifierConfig::default(), spreads, crossings).1
    }

    #[test]
    fn an_excursion_in_another_kinds_pattern_sets_no_naming_spread() {
        let factors = crate::NOMINAL_INTERNAL_FACTORS;
        let max_misfit = ClassifierConfig::default().isolation_max_misfit;
        // an internal leak's pattern for 10 s: chamber 1 loses 0.1 L/min, chamber 2
        // gains it; it widens ext1's spread, but ext1's test never alarms on it
        let (_, spread, _, clear) = record([0.0, 0.0, 0.1]).summary_with_clear(factors, max_misfit);
        assert!(spread[0] > 0.03, "{spread:?}");
        assert!(clear[0] < 0.3 * spread[0], "{clear:?} against {spread:?}");
        // the internal leak's own spread stands whole
        assert!(clear[2] > 0.9 * spread[2], "{clear:?} against {spread:?}");
        // an excursion in ext1's own pattern sets ext1's naming spread
        let (_, spread, _, clear) = record([0.1, 0.0, 0.0]).summary_with_clear(factors, max_misfit);
        assert!(spread[0] > 0.03, "{spread:?}");
        assert!(clear[0] > 0.9 * spread[0], "{clear:?} against {spread:?}");
    }

    #[test]
    fn a_pattern_no_leak_can_make_sets_no_threshold() {
        let cfg = ClassifierConfig::default();
        let factors = crate::NOMINAL_INTERNAL_FACTORS;
        // the internal leak's estimate kicked negative for 10 s: chamber 1
        // gains what chamber 2 loses, which reads as an ext2 rise of 0.5 L/min
        let kicked = record([0.0, 0.0, -0.5]);
        assert!(thresholds(&kicked)[1] > 0.2, "{:?}", thresholds(&kicked));
        let (kept, left_out_s) = kicked.leak_like(&cfg, factors);
        assert!((left_out_s - 10.0).abs() < 0.2, "{left_out_s}");
        let thr = thresholds(&kept);
        assert!(thr[1] < 0.05, "{thr:?}");
        // an ext2 rise of the same size is a pattern a leak makes: it stays
        let risen = record([0.0, 0.5, 0.0]);
        let (kept, left_out_s) = risen.leak_like(&cfg, factors);
        assert_eq!(left_out_s, 0.0);
        assert!(thresholds(&kept)[1] > 0.2, "{:?}", thresholds(&kept));
    }
}
