//! The discretisation: one sample step x(k+1) with its discrete Jacobian
//! (forward Euler sub-steps), and the clamps that keep the state physical.

use nalgebra::{SMatrix, SVector};

use super::{Guard, ProcessModel, BULK_SCALE_RANGE, I_BULK};

/// Euler sub-steps per sample while the rod is in an end stop (h = 0.125 ms at
/// 1 kHz: |λ|·h ≈ 0.4 for the stop's modes).
pub const STOP_SUBSTEPS: u32 = 8;

impl ProcessModel {
    /// One sample step: x(k+1) and the discrete Jacobian F = ∂x(k+1)/∂x(k)
    /// (Euler in `substeps` sub-steps: forward for the 6- and 7-state layouts,
    /// the thesis'; symplectic for the layouts with leaks, whose rod velocity
    /// steps with the pressures at the end of the step), with the state kept physical.
    pub fn step<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
    ) -> (SVector<f64, N>, SMatrix<f64, N, N>, Guard) {
        let mut x = *s;
        let mut jac = SMatrix::<f64, N, N>::zeros();
        let guard = self.step_into(s, u_v, &mut x, &mut jac);
        (x, jac, guard)
    }

    /// [`Self::step`] into `x` (x(k+1)) and `jac` (F), which it overwrites (a
    /// filter's own buffers: nothing is copied on the way).
    #[inline(always)]
    pub fn step_into<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
        x: &mut SVector<f64, N>,
        jac: &mut SMatrix<f64, N, N>,
    ) -> Guard {
        // In an end stop (a 1e8 N/m spring on a 10 kg rod, damped: its modes are
        // near −3000 1/s, past forward Euler's reach at 1 ms) the step is taken in
        // [`STOP_SUBSTEPS`] sub-steps (the layouts with stops: 10 states and more).
        let in_stop = N >= 10 && (s[3] < self.params.x_min_m || s[3] > self.params.x_max_m);
        let n = if in_stop {
            self.substeps.max(STOP_SUBSTEPS)
        } else {
            self.substeps.max(1)
        };
        let h = self.dt_s / n as f64;
        let mut f = SVector::<f64, N>::zeros();
        if n == 1 {
            // F = I + A·h, built in place (A is sparse: most entries stay 0 or 1).
            self.linearise_into(s, u_v, &mut f, jac);
            for ((x, s), f) in x.iter_mut().zip(s.iter()).zip(f.iter()) {
                *x = s + f * h;
            }
            for v in jac.as_mut_slice() {
                *v *= h;
            }
            if N >= 10 {
                self.semi_implicit_velocity(s, x, jac);
            }
            for d in 0..N {
                jac[(d, d)] += 1.0;
            }
        } else {
            *x = *s;
            let mut step_jac = SMatrix::<f64, N, N>::zeros();
            for i in 0..n {
                let start = *x;
                self.linearise_into(&start, u_v, &mut f, &mut step_jac);
                *x += f * h;
                // I + A·h
                step_jac *= h;
                if N >= 10 {
                    self.semi_implicit_velocity(&start, x, &mut step_jac);
                }
                for d in 0..N {
                    step_jac[(d, d)] += 1.0;
                }
                *jac = if i == 0 { step_jac } else { step_jac * *jac };
            }
        }
        self.keep_physical(x)
    }

    /// Symplectic Euler for the hydraulic mode: the rod's velocity steps with
    /// the chamber pressures at the end of the (sub-)step. `s` the state at its
    /// start, `x` the forward-Euler state at its end (its velocity corrected
    /// here), `a_h` = h·A (its velocity row corrected to the step's
    /// derivative; the identity not yet added).
    #[inline(always)]
    fn semi_implicit_velocity<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        x: &mut SVector<f64, N>,
        a_h: &mut SMatrix<f64, N, N>,
    ) {
        // (both gains read before the row changes)
        let (k1, k2) = (a_h[(4, 1)], a_h[(4, 2)]);
        x[4] += k1 * (x[1] - s[1]) + k2 * (x[2] - s[2]);
        for c in 0..N {
            let add = k1 * a_h[(1, c)] + k2 * a_h[(2, c)];
            a_h[(4, c)] += add;
        }
    }

    /// Clamps pressures into [p_min, p_max], the rod into its stroke plus
    /// 1 cm and the oil-stiffness scale θ (12 states) into [`BULK_SCALE_RANGE`];
    /// reports what was done. (Inlined: a filter's step compiles it with its own.)
    #[inline(always)]
    pub fn keep_physical<const N: usize>(&self, x: &mut SVector<f64, N>) -> Guard {
        let mut g = Guard::default();
        for i in [1, 2] {
            let c = x[i].clamp(self.p_min_pa, self.p_max_pa);
            if c != x[i] || !x[i].is_finite() {
                g.pressure_clamped = true;
                x[i] = if x[i].is_finite() {
                    c
                } else {
                    self.params.nominal_chamber_pressure_pa()
                };
            }
        }
        let (lo, hi) = (self.params.x_min_m - 0.01, self.params.x_max_m + 0.01);
        if x[3] < lo || x[3] > hi {
            g.position_clamped = true;
            x[3] = x[3].clamp(lo, hi);
        }
        if N == 12 {
            let (lo, hi) = BULK_SCALE_RANGE;
            if !(lo..=hi).contains(&x[I_BULK]) {
                g.bulk_clamped = true;
                x[I_BULK] = if x[I_BULK].is_finite() {
                    x[I_BULK].clamp(lo, hi)
                } else {
                    1.0
                };
            }
        }
        g
    }
}
