//! The stretch of a commissioning recording that sets a threshold: the
//! longest run of kept values above the median, by its share of the upper
//! semi-variance (the spread's square). A threshold set by one stretch (a
//! move the model does not follow, a transient) is said, with the threshold
//! the rest of the recording would give.

use super::healthy::{median, HealthyRecord};
use crate::{signatures_with, ClassifierConfig, Commissioning};

/// Share of a kind's upper semi-variance from which one stretch is said to
/// set its threshold (1).
pub const STRETCH_SHARE: f64 = 0.5;

/// A stretch sets a threshold when the rest of the recording would give
/// less than this share of it (1).
pub const STRETCH_THRESHOLD_RATIO: f64 = 0.5;

/// One stretch of a commissioning recording above the median of one kind's
/// healthy values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stretch {
    /// Its first and last kept value's time, s of the recording.
    pub from_s: f64,
    /// See [`Self::from_s`], s.
    pub to_s: f64,
    /// The largest value above the median in it, L/min at p_s/2.
    pub peak_lpm: f64,
    /// Its share of the kind's upper semi-variance (1).
    pub share: f64,
    /// The spread the rest of the recording gives, L/min at p_s/2.
    pub spread_without_lpm: f64,
}

impl HealthyRecord {
    /// Per kind (ext1, ext2, int), the run of consecutive kept values above
    /// the median with the largest sum of squares, with `factors` the
    /// internal leak's pressure factors ([`signatures_with`]); `None` for a
    /// kind with no value above its median.
    pub(super) fn largest_stretches(&self, factors: [f64; 2]) -> [Option<Stretch>; 3] {
        let n = self.values[0].len().min(self.times.len());
        let signatures: Vec<[f64; 3]> = (0..n)
            .map(|i| signatures_with([self.values[0][i], self.values[1][i], self.values[2][i]], factors))
            .collect();
        std::array::from_fn(|k| {
            let v: Vec<f64> = signatures.iter().map(|s| s[k]).collect();
            largest_stretch(&v, &self.times[..n])
        })
    }
}

/// Per kind, the stretch of `stretches` that sets the threshold of
/// commissioning `c` under settings `cfg`: it holds at least
/// [`STRETCH_SHARE`] of the kind's spread, and the rest of the recording
/// would give less than [`STRETCH_THRESHOLD_RATIO`] of the threshold; with
/// the threshold the rest gives, L/min at p_s/2.
pub(super) fn setting_thresholds(
    cfg: &ClassifierConfig,
    c: &Commissioning,
    stretches: [Option<Stretch>; 3],
) -> [Option<(Stretch, f64)>; 3] {
    let (_, thr) = crate::thresholds(cfg, c.spreads_lpm, c.crossings_per_s);
    std::array::from_fn(|k| {
        let s = stretches[k].filter(|s| s.share >= STRETCH_SHARE)?;
        let mut spreads = c.spreads_lpm;
        spreads[k] = s.spread_without_lpm;
        let (_, without) = crate::thresholds(cfg, spreads, c.crossings_per_s);
        (without[k] < STRETCH_THRESHOLD_RATIO * thr[k]).then_some((s, without[k]))
    })
}

/// The run of consecutive values of `v` (kept at `times`, s) above its median
/// with the largest sum of squared excesses.
fn largest_stretch(v: &[f64], times: &[f64]) -> Option<Stretch> {
    let m = median(v);
    let (mut total, mut above) = (0.0, 0usize);
    // (sum of squares, count, first index, last index, peak) of the best run and of the current one
    let mut best = (0.0, 0usize, 0usize, 0usize, 0.0_f64);
    let mut run = best;
    for (i, x) in v.iter().enumerate() {
        if *x > m {
            let d = x - m;
            total += d * d;
            above += 1;
            if run.1 == 0 {
                run = (0.0, 0, i, i, 0.0);
            }
            run = (run.0 + d * d, run.1 + 1, run.2, i, run.4.max(d));
            if run.0 > best.0 {
                best = run;
            }
        } else {
            run.1 = 0;
        }
    }
    if above == 0 || total <= 0.0 {
        return None;
    }
    let rest = above - best.1;
    Some(Stretch {
        from_s: times[best.2],
        to_s: times[best.3],
        peak_lpm: best.4,
        share: best.0 / total,
        spread_without_lpm: ((total - best.0).max(0.0) / rest.max(1) as f64).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stretch is said when it holds half the spread or more and the rest
    /// would give less than half the threshold; the threshold without it is
    /// the rest's spread through the same formula.
    #[test]
    fn a_threshold_set_by_one_stretch_is_said_with_the_rests_threshold() {
        let cfg = ClassifierConfig::default();
        let c = Commissioning {
            offsets_lpm: [0.0; 3],
            spreads_lpm: [0.2, 0.2, 0.2],
            clear_spreads_lpm: [f64::NAN; 3],
            crossings_per_s: [1.0; 3],
            healthy_s: 100.0,
            nis_mean: 3.0,
            source: String::new(),
            internal_factors: crate::NOMINAL_INTERNAL_FACTORS,
            least_offsets_named: [f64::NAN; 3],
            healthy_offsets_kpa: [0.0; 2],
            healthy_span_errors: [0.0; 2],
            delay_uncertainty_s: 0.0,
            delay_response_reach_lpm_per_ms: [0.0; 3],
        };
        let (_, thr) = crate::thresholds(&cfg, c.spreads_lpm, c.crossings_per_s);
        let stretch = |share: f64, spread_without_lpm: f64| Stretch {
            from_s: 10.0,
            to_s: 15.0,
            peak_lpm: 0.6,
            share,
            spread_without_lpm,
        };
        let set = setting_thresholds(
            &cfg,
            &c,
            [
                Some(stretch(0.9, 0.02)),
                Some(stretch(0.4, 0.02)),
                Some(stretch(0.9, 0.15)),
            ],
        );
        let (s, without) = set[0].expect("ext1: 90 % of the spread, the rest a tenth of it");
        assert_eq!(s, stretch(0.9, 0.02));
        let (_, expected) = crate::thresholds(&cfg, [0.02, 0.2, 0.2], c.crossings_per_s);
        assert_eq!(without, expected[0]);
        assert!(without < 0.5 * thr[0], "{without} against {}", thr[0]);
        assert!(
            set[1].is_none(),
            "ext2: 40 % of the spread is not one stretch's threshold"
        );
        assert!(
            set[2].is_none(),
            "int: the rest alone gives three quarters of the threshold"
        );
    }

    #[test]
    fn one_excursion_is_found_with_its_share_and_the_spread_without_it() {
        // a square wave of ±0.01 around 0, and from 5.0 to 5.99 s a rise of 0.5
        let times: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
        let v: Vec<f64> = (0..1000)
            .map(|i| {
                if (500..600).contains(&i) {
                    0.5
                } else if i % 2 == 0 {
                    0.01
                } else {
                    -0.01
                }
            })
            .collect();
        let s = largest_stretch(&v, &times).expect("values above the median");
        assert_eq!((s.from_s, s.to_s), (5.0, 5.99));
        // the median is 0.01 (more than half the values are 0.01 or above)
        assert!((s.peak_lpm - 0.49).abs() < 1e-12, "{s:?}");
        // the only other values above the median: none, so all the semi-variance is the excursion's
        assert!((s.share - 1.0).abs() < 1e-12, "{s:?}");
        assert_eq!(s.spread_without_lpm, 0.0);
    }

    #[test]
    fn a_spread_of_many_short_rises_has_no_stretch_with_a_large_share() {
        let times: Vec<f64> = (0..1000).map(|i| i as f64 * 0.01).collect();
        let v: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.37).sin() * 0.02).collect();
        let s = largest_stretch(&v, &times).expect("values above the median");
        assert!(s.share < 0.05, "{s:?}");
        // the rest is the whole: about the RMS of the upper half of a sine, 0.02/√2
        assert!((s.spread_without_lpm - 0.02 / 2f64.sqrt()).abs() < 0.002, "{s:?}");
        assert!(largest_stretch(&[0.0; 10], &times[..10]).is_none());
    }
}
