//! The pressure transducers' misreading at the working point, fitted to the
//! healthy leak estimates (docs/plant.md, "Commissioning fits the transducers'
//! misreading").
//!
//! A transducer that reads z above the chamber moves the leak filter's leak
//! sizes by R(t)·z, where R is the filter's own response to a misreading of
//! 1 MPa on that channel since the start ([`filter::Estimate::offset_response_lpm_per_mpa`]).
//! R swings with the duty cycle, so on a healthy recording (leak sizes
//! constant but for noise) the misreading is the z whose R(t)·z best
//! explains the leak sizes' swings: a linear least-squares fit over every
//! settled sample, the three kinds together, each about its own mean.

use model::units::m3_s_to_lpm;
use nalgebra::{Matrix2, Vector2};

/// One kind's sums of the normal equations of q(t) = m + R(t)·z: R the
/// responses to p1 and p2 (L/min per MPa), q the leak size (L/min).
#[derive(Debug, Clone, Copy, Default)]
struct KindSums {
    /// Settled samples.
    n: f64,
    /// Σ q.
    q: f64,
    /// Σ R.
    r: Vector2<f64>,
    /// Σ R·Rᵀ.
    rr: Matrix2<f64>,
    /// Σ R·q.
    rq: Vector2<f64>,
}

/// What the fit keeps of a recording: each kind's (ext1, ext2, int) sums,
/// and each channel's mean reading.
#[derive(Debug, Clone, Default)]
pub struct MisreadingFit {
    kinds: [KindSums; 3],
    /// Σ of the p1 and p2 readings, Pa.
    sum_p_pa: Vector2<f64>,
    /// Readings counted.
    n_p: f64,
}

/// The least share of the healthy spreads' energy (Σ spread²) a fitted
/// misreading must take away to be taken (1): on the in-repo lift a fit that
/// took 27 % lowered a naming threshold its runs then crossed four times in
/// 0.4 h, while on the press every fit that took a third or more held
/// (docs/plant.md, "Commissioning fits the transducers' misreading").
pub const MISREADING_LEAST_SHARE: f64 = 1.0 / 3.0;

/// The misreading fitted to a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Misreading {
    /// What p1 and p2 read above the chambers, Pa (within `bound_pa`).
    pub pa: [f64; 2],
    /// The datasheet's largest misreading at each channel's mean reading, Pa:
    /// its zero offset plus its span error times that reading.
    pub bound_pa: [f64; 2],
}

/// A fitted misreading and whether commissioning took it: the healthy spreads'
/// energy must fall by [`MISREADING_LEAST_SHARE`] with it taken off the readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MisreadingTaken {
    /// The fit.
    pub found: Misreading,
    /// Whether the model now takes it off each reading.
    pub taken: bool,
    /// The healthy spreads (ext1, ext2, int) without and with it, L/min at p_s/2.
    pub spreads_lpm: [[f64; 3]; 2],
}

impl MisreadingTaken {
    /// The terminal's line.
    pub fn line(&self) -> String {
        let [z1, z2] = self.found.pa.map(|v| v * 1e-3);
        let [b1, b2] = self.found.bound_pa.map(|v| v * 1e-3);
        let s = |v: [f64; 3]| format!("{:.3}/{:.3}/{:.3}", v[0], v[1], v[2]);
        let outcome = if self.taken {
            "taken off each reading".to_string()
        } else {
            format!(
                "not taken: the spreads' energy did not fall by {:.0} %",
                100.0 * MISREADING_LEAST_SHARE
            )
        };
        format!(
            "transducers' misreading at the working point: p1 {z1:+.1} kPa, p2 {z2:+.1} kPa \
             (fitted to the healthy leak estimates' swings; the datasheet allows ±{b1:.0}/±{b2:.0} kPa there): \
             {outcome} (healthy spreads {} -> {} L/min)",
            s(self.spreads_lpm[0]),
            s(self.spreads_lpm[1])
        )
    }
}

impl MisreadingFit {
    /// Takes estimate `e` when the filter is settled and its leak sizes and
    /// responses are finite.
    pub fn push(&mut self, e: &filter::Estimate) {
        if e.flags & filter::FLAGS_UNSETTLED != 0 || e.n_states < 10 {
            return;
        }
        let resp = e.offset_response_lpm_per_mpa;
        for (k, sums) in self.kinds.iter_mut().enumerate() {
            let q = m3_s_to_lpm(e.state[7 + k]);
            let r = Vector2::new(resp[0][k], resp[1][k]);
            if !(q.is_finite() && r.iter().all(|v| v.is_finite())) {
                continue;
            }
            sums.n += 1.0;
            sums.q += q;
            sums.r += r;
            sums.rr += r * r.transpose();
            sums.rq += r * q;
        }
        let p = Vector2::new(e.measured[1], e.measured[2]);
        if p.iter().all(|v| v.is_finite()) {
            self.sum_p_pa += p;
            self.n_p += 1.0;
        }
    }

    /// The centred normal equations A·z = b (z in MPa), the kinds summed.
    fn normal_equations(&self) -> (Matrix2<f64>, Vector2<f64>) {
        let (mut a, mut b) = (Matrix2::zeros(), Vector2::zeros());
        for k in self.kinds.iter().filter(|k| k.n >= 2.0) {
            a += k.rr - k.r * k.r.transpose() / k.n;
            b += k.rq - k.r * (k.q / k.n);
        }
        (a, b)
    }

    /// The misreading for transducers whose zero offset is at most
    /// `zero_offset_max_pa` (Pa) and span error at most `span_error_max` (1)
    /// of the reading, on a recording the filters read less `taken_pa` (Pa):
    /// `taken_pa` plus the least-squares z, each channel held within that
    /// bound at its mean reading. `None` without a bound, or when the
    /// recording's responses do not tell the channels apart.
    pub fn solve(
        &self,
        zero_offset_max_pa: f64,
        span_error_max: f64,
        taken_pa: [f64; 2],
    ) -> Option<Misreading> {
        if self.n_p < 1.0 {
            return None;
        }
        let bound_pa: [f64; 2] = std::array::from_fn(|i| {
            detect::offset::sound_transducer_misreading(
                zero_offset_max_pa,
                span_error_max,
                self.sum_p_pa[i] / self.n_p,
            )
        });
        if bound_pa.iter().any(|b| !(b.is_finite() && *b > 0.0)) {
            return None;
        }
        let (a, b) = self.normal_equations();
        // a determinant this small against the diagonal: the channels' responses move together
        let det = a.determinant();
        if !(det.is_finite() && det > 1e-9 * a[(0, 0)] * a[(1, 1)]) {
            return None;
        }
        let z_mpa = a.try_inverse()? * b;
        // the box the total stays in, about what is taken already
        let lo: [f64; 2] = std::array::from_fn(|i| (-bound_pa[i] - taken_pa[i]) * 1e-6);
        let hi: [f64; 2] = std::array::from_fn(|i| (bound_pa[i] - taken_pa[i]) * 1e-6);
        let z = clamp_to_box(&a, &b, [z_mpa[0], z_mpa[1]], lo, hi);
        Some(Misreading {
            pa: std::array::from_fn(|i| taken_pa[i] + z[i] * 1e6),
            bound_pa,
        })
    }
}

/// The least-squares `z` of A·z = b held within `lo`..`hi` per channel:
/// where the free solution leaves the box, one channel sits on an edge and
/// the other is refitted (and held) given it; the best of those.
fn clamp_to_box(a: &Matrix2<f64>, b: &Vector2<f64>, z: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> [f64; 2] {
    if (0..2).all(|i| (lo[i]..=hi[i]).contains(&z[i])) {
        return z;
    }
    // ½zᵀAz − bᵀz: the sum of squares less a constant
    let cost = |c: [f64; 2]| {
        let v = Vector2::new(c[0], c[1]);
        0.5 * (v.transpose() * a * v)[0] - b.dot(&v)
    };
    let mut best = [0.0f64.clamp(lo[0], hi[0]), 0.0f64.clamp(lo[1], hi[1])];
    for fixed in 0..2 {
        let other = 1 - fixed;
        for edge in [lo[fixed], hi[fixed]] {
            let mut c = [0.0; 2];
            c[fixed] = edge;
            let free = if a[(other, other)] > 0.0 {
                (b[other] - a[(other, fixed)] * edge) / a[(other, other)]
            } else {
                0.0
            };
            c[other] = free.clamp(lo[other], hi[other]);
            if cost(c) < cost(best) {
                best = c;
            }
        }
    }
    best
}

/// The pressure transducers' tolerances `cfg`'s sensors give (from its
/// datasheet), `None` when neither is given.
pub(super) fn transducer_tolerance(cfg: &config::Config) -> Option<identify::TransducerTolerance> {
    let s = &cfg.sensors;
    (s.pressure_zero_offset_max_pa > 0.0 || s.pressure_span_error_max > 0.0).then_some(
        identify::TransducerTolerance {
            zero_offset_max_pa: s.pressure_zero_offset_max_pa,
            span_error_max_fraction: s.pressure_span_error_max,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An estimate at time `t_s` with leak sizes `q_lpm` and responses `r` (L/min per MPa).
    fn estimate(t_s: f64, q_lpm: [f64; 3], r: [[f64; 3]; 2]) -> filter::Estimate {
        let mut e = filter::Estimate {
            t_s,
            n_states: 12,
            ..filter::Estimate::default()
        };
        for (state, q) in e.state[7..10].iter_mut().zip(q_lpm) {
            *state = model::units::lpm_to_m3_s(q);
        }
        e.offset_response_lpm_per_mpa = r;
        e.measured = [0.1, 10e6, 9e6];
        e.flags = 0;
        e
    }

    /// Leak sizes that swing with responses as a misreading `z_mpa` makes them,
    /// about offsets of their own.
    fn fit_of(z_mpa: [f64; 2]) -> MisreadingFit {
        let mut fit = MisreadingFit::default();
        for i in 0..5000 {
            let t = i as f64 * 1e-3;
            let r = [
                [
                    0.3 * (t * 2.0).sin(),
                    -0.2 * (t * 2.0).sin(),
                    0.25 * (t * 0.7).cos(),
                ],
                [
                    -0.1 * (t * 1.3).cos(),
                    0.35 * (t * 2.0).sin(),
                    -0.2 * (t * 0.5).sin(),
                ],
            ];
            let q: [f64; 3] =
                std::array::from_fn(|k| 0.02 * k as f64 + r[0][k] * z_mpa[0] + r[1][k] * z_mpa[1]);
            fit.push(&estimate(t, q, r));
        }
        fit
    }

    #[test]
    fn the_misreading_that_made_the_swings_is_found() {
        let m = fit_of([0.06, -0.04]).solve(50e3, 0.005, [0.0; 2]).unwrap();
        assert!(
            (m.pa[0] - 60e3).abs() < 1.0 && (m.pa[1] + 40e3).abs() < 1.0,
            "{:?}",
            m.pa
        );
        // the bound: 50 kPa plus 0.5 % of the mean readings (10 and 9 MPa)
        assert!((m.bound_pa[0] - 100e3).abs() < 1e-6 && (m.bound_pa[1] - 95e3).abs() < 1e-6);
    }

    #[test]
    fn a_misreading_beyond_the_datasheet_is_held_at_its_edge() {
        let m = fit_of([0.3, -0.04]).solve(50e3, 0.005, [0.0; 2]).unwrap();
        assert!((m.pa[0] - 100e3).abs() < 1e-6, "{:?}", m.pa);
        assert!(m.pa[1].abs() <= 95e3 + 1e-6);
    }

    #[test]
    fn no_bound_or_no_swing_fits_nothing() {
        assert!(fit_of([0.06, -0.04]).solve(0.0, 0.0, [0.0; 2]).is_none());
        let mut flat = MisreadingFit::default();
        for i in 0..100 {
            flat.push(&estimate(i as f64 * 1e-3, [0.0; 3], [[0.1; 3], [0.2; 3]]));
        }
        assert!(flat.solve(50e3, 0.005, [0.0; 2]).is_none());
    }
}
