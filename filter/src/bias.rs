//! How the filter's estimates answer a transducer that reads off.
//!
//! A constant offset b on channel c (p1, p2 or x) moves the estimate by δ·b,
//! where δ follows the filter's own linear recursion along the trajectory:
//!
//! - time update: δ⁻ = F·δ⁺ (F the step's Jacobian);
//! - measurement update: δ⁺ = δ⁻ + K·(e_c − H·δ⁻) (K the step's gain, e_c the
//!   unit vector of channel c, H the measured states).
//!
//! A span error g on channel c (the reading (1 + g)·p_c) is an offset g·p_c(t)
//! that moves with the pressure: its response follows the same recursion
//! with e_c·p_c(t) in the update in place of e_c (p_c the reading).
//!
//! A transducer that lags by a delay d reads p_c(t − d) ≈ p_c − d·ṗ_c: an
//! offset −d·ṗ_c that moves with the pressure's rate. Its response per second
//! of delay follows the recursion with −ṗ_c (the step's predicted rate) in the
//! update in place of e_c. The leak filter takes it off the leak sizes it
//! publishes ([`BiasResponse::lag_imprint`]).
//!
//! The leak sizes' part of δ is the pattern a misreading leaves on them: it
//! swings with the valve's flow (an offset moves the orifice's drop), while a
//! leak's is steady. An offset on x moves the chambers' volumes the model
//! reads, one up and one down, and with them the pressure each flow makes.
//! The detector compares the patterns with a leak's
//! ([`BiasResponse::leak_sizes_lpm_per_mpa`], [`BiasResponse::leak_sizes_lpm_per_span`],
//! [`BiasResponse::leak_sizes_lpm_per_mm`]).

use model::process::{FIRST_RANDOM_WALK, I_QE1, I_QI};
use model::units::M3_S_PER_LPM;
use nalgebra::{SMatrix, SVector};

use crate::ekf::Ekf;
use crate::MAX_LAYOUT_STATES;

/// The measured pressures an offset is followed on (index into the measurement
/// [x, p1, p2]).
pub const OFFSET_CHANNELS: [usize; 2] = [1, 2];

/// Cubic metres per second per pascal in one L/min per MPa.
const M3_S_PA_PER_LPM_MPA: f64 = M3_S_PER_LPM / 1.0e6;

/// The measured position (index into the measurement [x, p1, p2]).
const POSITION_CHANNEL: usize = 0;

/// Cubic metres per second per metre in one L/min per mm.
const M3_S_M_PER_LPM_MM: f64 = M3_S_PER_LPM * 1.0e3;

/// The misreadings followed, as rows of δ: an offset of 1 Pa on p1 and on
/// p2, then a span error of 1 (a reading of 2·p) on p1 and on p2, then an
/// offset of 1 m on x, then a delay of 1 s on p1 and on p2.
const ROWS: usize = 7;

/// The row of δ for an offset on x.
const POSITION_ROW: usize = 4;

/// The rows of δ for a delay on p1 and on p2.
const LAG_ROWS: [usize; 2] = [5, 6];

/// δ for an offset of 1 Pa on p1 and on p2 (state units per Pa), for a
/// span error of 1 on p1 and on p2 (state units), for an offset of 1 m
/// on x (state units per m), and for a delay of 1 s on p1 and on p2 (state
/// units per s); zero until the filter has stepped with leak sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasResponse {
    delta: [[f64; MAX_LAYOUT_STATES]; ROWS],
}

impl Default for BiasResponse {
    fn default() -> Self {
        BiasResponse {
            delta: [[0.0; MAX_LAYOUT_STATES]; ROWS],
        }
    }
}

impl BiasResponse {
    /// Forgets the past: an offset is measured from here on (a start or a re-anchoring).
    pub fn clear(&mut self) {
        *self = BiasResponse::default();
    }

    /// A re-anchoring: the offsets are measured from here on; a delay's
    /// imprint on the slow states, which the filter keeps, stays (its part of
    /// the fast states, set from the readings again, is zero).
    pub fn reanchor(&mut self) {
        let lags = LAG_ROWS.map(|row| self.delta[row]);
        self.clear();
        for (row, mut d) in LAG_ROWS.into_iter().zip(lags) {
            d[..FIRST_RANDOM_WALK].fill(0.0);
            self.delta[row] = d;
        }
    }

    /// The time update, δ⁻ = F·δ⁺, with the step's Jacobian `f` (SI), whose
    /// rows from [`FIRST_RANDOM_WALK`] on are the identity's (random walks).
    #[inline(always)]
    pub(crate) fn predict<const N: usize>(&mut self, f: &SMatrix<f64, N, N>) {
        if N <= I_QI {
            return;
        }
        // row i of F·δ summed over j in order from −0.0 (as `Iterator::sum`
        // does), the rows side by side: F by columns, so each j adds one
        // column's first rows, in vector registers
        for d in &mut self.delta {
            let mut acc = [-0.0; FIRST_RANDOM_WALK];
            for (column, before) in f.as_slice().chunks_exact(N).zip(&d[..N]) {
                for (a, f_ij) in acc.iter_mut().zip(column) {
                    *a += f_ij * before;
                }
            }
            d[..FIRST_RANDOM_WALK].copy_from_slice(&acc);
        }
    }

    /// The measurement update with the gain of the update `e` just made, over
    /// the channels `use_channel` of the measured states `states`, with the
    /// readings `y` (SI; a span error's offset is g times its channel's) and
    /// the measured states' predicted rates `rates` (SI per s; a delay's
    /// offset is −d times its channel's).
    #[inline(always)]
    pub(crate) fn update<const N: usize, const W: usize>(
        &mut self,
        e: &Ekf<N, 3, W>,
        states: [usize; 3],
        use_channel: [bool; 3],
        y: &SVector<f64, 3>,
        rates: [f64; 3],
    ) {
        if N <= I_QI {
            return;
        }
        // (a plain loop, not a closure: the gains compile with the caller's
        // vector unit, inlined into the filter's step)
        let mut gains = [SVector::<f64, N>::zeros(); 3];
        for (i, gain) in gains.iter_mut().enumerate() {
            if use_channel[i] {
                *gain = e.gain_column(states[i], i);
            }
        }
        for (row, d) in self.delta.iter_mut().enumerate() {
            let c = if row == POSITION_ROW {
                POSITION_CHANNEL
            } else if row > POSITION_ROW {
                OFFSET_CHANNELS[row - LAG_ROWS[0]]
            } else {
                OFFSET_CHANNELS[row % 2]
            };
            // the misreading's part of channel c's reading: 1 Pa, 1 m, g·p_c or −d·ṗ_c
            let misread = if row > POSITION_ROW {
                -rates[c]
            } else if row < 2 || row == POSITION_ROW {
                1.0
            } else {
                y[c]
            };
            let before = *d;
            for (i, k) in gains.iter().enumerate() {
                if use_channel[i] {
                    let unit = if i == c { misread } else { 0.0 };
                    let innovation = unit - before[states[i]];
                    for j in 0..N {
                        d[j] += k[j] * innovation;
                    }
                }
            }
        }
    }

    /// How an offset of 1 MPa on p1 (row 0) and on p2 (row 1) moves the leak
    /// sizes q_e1, q_e2, q_i, L/min per MPa (nominal drop).
    pub fn leak_sizes_lpm_per_mpa(&self) -> [[f64; 3]; 2] {
        [0, 1].map(|row| std::array::from_fn(|k| self.delta[row][I_QE1 + k] / M3_S_PA_PER_LPM_MPA))
    }

    /// How a span error of 1 on p1 (row 0) and on p2 (row 1) moves the leak
    /// sizes q_e1, q_e2, q_i, L/min (a span error g moves them g times as much).
    pub fn leak_sizes_lpm_per_span(&self) -> [[f64; 3]; 2] {
        [2, 3].map(|row| std::array::from_fn(|k| self.delta[row][I_QE1 + k] / M3_S_PER_LPM))
    }

    /// How a delay of 1 ms on p1 (row 0) and on p2 (row 1) moves the leak
    /// sizes q_e1, q_e2, q_i, L/min per ms.
    pub fn leak_sizes_lpm_per_ms_delay(&self) -> [[f64; 3]; 2] {
        LAG_ROWS.map(|row| std::array::from_fn(|k| self.delta[row][I_QE1 + k] / M3_S_PER_LPM * 1.0e-3))
    }

    /// How a delay of `delay_s` on both pressure transducers moves the leak
    /// sizes q_e1, q_e2, q_i, m³/s: what the leak filter takes off them.
    #[inline(always)]
    pub(crate) fn lag_imprint(&self, delay_s: f64) -> [f64; 3] {
        std::array::from_fn(|k| {
            delay_s * (self.delta[LAG_ROWS[0]][I_QE1 + k] + self.delta[LAG_ROWS[1]][I_QE1 + k])
        })
    }

    /// How an offset of 1 mm on x moves the leak sizes q_e1, q_e2, q_i, L/min per mm.
    pub fn leak_sizes_lpm_per_mm(&self) -> [f64; 3] {
        std::array::from_fn(|k| self.delta[POSITION_ROW][I_QE1 + k] / M3_S_M_PER_LPM_MM)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_update_is_the_sum_over_each_row_bit_for_bit() {
        // a fixed LCG's values, with zeros of both signs among them
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            match state >> 60 {
                0 => 0.0,
                1 => -0.0,
                _ => {
                    ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
                        * 10f64.powi((state >> 56) as i32 % 7 - 3)
                }
            }
        };
        for _ in 0..200 {
            let f = SMatrix::<f64, 12, 12>::from_fn(|i, j| {
                if i >= FIRST_RANDOM_WALK {
                    f64::from(u8::from(i == j))
                } else {
                    next()
                }
            });
            let mut r = BiasResponse::default();
            for d in &mut r.delta {
                for v in d.iter_mut() {
                    *v = next();
                }
            }
            let before = r;
            r.predict(&f);
            for (d, b) in r.delta.iter().zip(&before.delta) {
                for i in 0..12 {
                    let expected: f64 = if i < FIRST_RANDOM_WALK {
                        (0..12).map(|j| f[(i, j)] * b[j]).sum()
                    } else {
                        b[i]
                    };
                    assert_eq!(
                        d[i].to_bits(),
                        expected.to_bits(),
                        "row {i}: {} against {expected}",
                        d[i]
                    );
                }
            }
        }
        // an all-zero row sums to −0.0 from −0.0 only when every product is −0.0
        let mut r = BiasResponse::default();
        r.delta[0] = [-1.0; MAX_LAYOUT_STATES];
        let mut f = SMatrix::<f64, 12, 12>::identity();
        f[(0, 0)] = 0.0;
        r.predict(&f);
        assert_eq!(r.delta[0][0].to_bits(), (-0.0f64).to_bits());
    }

    #[test]
    fn a_reanchoring_keeps_the_delays_imprint_on_the_slow_states_only() {
        let mut r = BiasResponse::default();
        for (row, d) in r.delta.iter_mut().enumerate() {
            for (i, v) in d.iter_mut().enumerate() {
                *v = (row * 100 + i + 1) as f64;
            }
        }
        let before = r;
        r.reanchor();
        for (row, d) in r.delta.iter().enumerate() {
            for (i, v) in d.iter().enumerate() {
                let kept = LAG_ROWS.contains(&row) && i >= FIRST_RANDOM_WALK;
                let expected = if kept { before.delta[row][i] } else { 0.0 };
                assert_eq!(*v, expected, "row {row}, state {i}");
            }
        }
        // the imprint taken off the leak sizes is the kept rows' sum times the delay
        let imprint = r.lag_imprint(2.0e-4);
        for (k, v) in imprint.iter().enumerate() {
            let sum = before.delta[LAG_ROWS[0]][I_QE1 + k] + before.delta[LAG_ROWS[1]][I_QE1 + k];
            assert_eq!(*v, 2.0e-4 * sum);
        }
    }
}
