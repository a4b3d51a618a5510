//! The discretisation: one sample step x(k+1) with its discrete Jacobian
//! (forward Euler sub-steps), and the clamps that keep the state physical.

use nalgebra::{SMatrix, SVector};

use super::{Guard, ProcessModel, BULK_SCALE_RANGE, I_BIAS, I_BULK};

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
        // (the spool's exact step, in the layouts with leaks: computed once per model and step length)
        let spool = if N >= 10 {
            self.spool_step_for(h)
        } else {
            SpoolStep::UNUSED
        };
        let mut f = SVector::<f64, N>::zeros();
        if n == 1 {
            // F = I + A·h, built in place (A is sparse: most entries stay 0 or 1).
            self.euler_substep(s, u_v, &spool, h, &mut f, x, jac);
        } else {
            let mut step_jac = SMatrix::<f64, N, N>::zeros();
            let mut start = *s;
            for i in 0..n {
                self.euler_substep(&start, u_v, &spool, h, &mut f, x, &mut step_jac);
                start = *x;
                *jac = if i == 0 { step_jac } else { step_jac * *jac };
            }
        }
        self.keep_physical(x)
    }

    /// One (sub-)step of length `h` (s) from `s` under `u_v` (V): its end into
    /// `x` and its F = I + A·h into `jac` (symplectic in the rod's velocity and
    /// the spool stepped exactly in the layouts with leaks); `f` is scratch.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn euler_substep<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
        spool: &SpoolStep,
        h: f64,
        f: &mut SVector<f64, N>,
        x: &mut SVector<f64, N>,
        jac: &mut SMatrix<f64, N, N>,
    ) {
        self.linearise_over_step(s, u_v, spool, f, jac);
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
        if N >= 10 {
            self.exact_spool_step(s, u_v, spool, x, jac);
        }
    }

    /// f and A = ∂f/∂x for a (sub-)step (its spool step `spool`) from `s` under `u_v` (V).
    /// In the layouts with leaks the valve's flows are taken at the spool's
    /// mean position over the step (its exact step's mean, [`spool_mean`]), as
    /// the chambers receive them; A's spool column is chained through that
    /// mean. The thesis' layouts take them at the step's start.
    #[inline(always)]
    fn linearise_over_step<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
        spool: &SpoolStep,
        f: &mut SVector<f64, N>,
        a: &mut SMatrix<f64, N, N>,
    ) {
        if N < 10 {
            self.linearise_into(s, u_v, f, a);
            return;
        }
        let psi = spool.psi;
        let rest = self.spool_rest_m(s, u_v);
        let mut at = *s;
        at[0] = rest + psi[0] * (s[0] - rest) + psi[1] * s[5];
        self.linearise_into(&at, u_v, f, a);
        // (rows 0 and 5, the spool's own, are replaced by its exact step)
        for r in (0..N).filter(|&r| r != 0 && r != 5) {
            let c = a[(r, 0)];
            a[(r, 0)] = c * psi[0];
            a[(r, 5)] += c * psi[1];
            if N >= 11 {
                a[(r, I_BIAS)] += c * (1.0 - psi[0]);
            }
        }
    }

    /// The spool's exact step (`spool`, over its step length) from `s` under the command `u_v`
    /// (V), held: its dynamics are linear, so x(k+1) = Φ·(x(k) − x_r) + x_r,
    /// with Φ = exp(A_sp·h) and x_r = (b + k_sp·u, 0) where it comes to rest.
    /// Overwrites the spool's rows 0 and 5 of `x` and of `jac` (F, the
    /// identity added). Euler turns a spool of ω_n·h = 0.7 by 0.78 rad a
    /// step where it turns 0.50, and overshoots a command step by a third.
    #[inline(always)]
    fn exact_spool_step<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
        spool: &SpoolStep,
        x: &mut SVector<f64, N>,
        jac: &mut SMatrix<f64, N, N>,
    ) {
        let phi = spool.phi;
        let rest = self.spool_rest_m(s, u_v);
        let (dx, v) = (s[0] - rest, s[5]);
        x[0] = rest + phi[0][0] * dx + phi[0][1] * v;
        x[5] = phi[1][0] * dx + phi[1][1] * v;
        for c in 0..N {
            jac[(0, c)] = 0.0;
            jac[(5, c)] = 0.0;
        }
        jac[(0, 0)] = phi[0][0];
        jac[(0, 5)] = phi[0][1];
        jac[(5, 0)] = phi[1][0];
        jac[(5, 5)] = phi[1][1];
        if N >= 11 {
            jac[(0, I_BIAS)] = 1.0 - phi[0][0];
            jac[(5, I_BIAS)] = -phi[1][0];
        }
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

/// The spool's exact step over one (sub-)step of length h: its transition
/// matrix Φ ([`spool_transition`]) and the first row of its mean Ψ
/// ([`spool_mean`]), with the natural frequency (rad/s), damping ratio (1)
/// and h (s) they are for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SpoolStep {
    /// ω_n (rad/s), ζ (1), h (s).
    key: [f64; 3],
    /// Φ = exp(A_sp·h) (rows: position m, velocity m/s).
    phi: [[f64; 2]; 2],
    /// Ψ₀₀ (1) and Ψ₀₁ (s).
    psi: [f64; 2],
}

impl SpoolStep {
    /// Stands in where no spool is stepped exactly (the thesis' layouts).
    const UNUSED: SpoolStep = SpoolStep {
        key: [f64::NAN; 3],
        phi: [[f64::NAN; 2]; 2],
        psi: [f64::NAN; 2],
    };

    /// The step of a spool of natural frequency `wn` (rad/s) and damping
    /// ratio `zeta` (1) over `h` (s).
    pub(crate) fn of(wn: f64, zeta: f64, h: f64) -> SpoolStep {
        SpoolStep {
            key: [wn, zeta, h],
            phi: spool_transition(wn, zeta, h),
            psi: spool_mean(wn, zeta, h),
        }
    }

    /// The steps of `params`' spool over a free step and over an end stop's
    /// sub-step at sample period `dt_s` (s) with `substeps` sub-steps.
    pub(crate) fn for_steps(
        params: &crate::params::ActuatorParams,
        dt_s: f64,
        substeps: u32,
    ) -> [SpoolStep; 2] {
        let (wn, zeta) = (params.spool_natural_freq_rad_s, params.spool_damping_ratio);
        [substeps.max(1), substeps.max(STOP_SUBSTEPS)].map(|n| SpoolStep::of(wn, zeta, dt_s / f64::from(n)))
    }
}

impl ProcessModel {
    /// The spool's step over `h` (s) for the model's parameters: the one
    /// kept ([`ProcessModel::params_changed`]) where it is for them and `h`,
    /// else computed afresh (a sub-step in an end stop, parameters changed in place).
    #[inline(always)]
    fn spool_step_for(&self, h: f64) -> SpoolStep {
        let p = &self.params;
        let key = [p.spool_natural_freq_rad_s, p.spool_damping_ratio, h];
        match self.spool_steps.iter().find(|s| s.key == key) {
            Some(s) => *s,
            None => SpoolStep::of(key[0], key[1], key[2]),
        }
    }
}

/// The transition matrix exp(A·h) of a second-order spool (position m,
/// velocity m/s) of natural frequency `wn` (rad/s) and damping ratio `zeta`
/// (1) over `h` (s), A = [[0, 1], [−ω_n², −2ζω_n]]:
/// e^{σh}·(c·I + s·(A − σI)), σ = −ζω_n, with c = cos(μh) and s = sin(μh)/μ,
/// μ = ω_n·√(1 − ζ²) (cosh and sinh past ζ = 1; c = 1, s = h at ζ = 1).
pub fn spool_transition(wn: f64, zeta: f64, h: f64) -> [[f64; 2]; 2] {
    let sigma = -zeta * wn;
    let mu2 = wn * wn * (1.0 - zeta * zeta);
    let (c, s) = if mu2 > 1e-12 * wn * wn {
        let mu = mu2.sqrt();
        ((mu * h).cos(), (mu * h).sin() / mu)
    } else if mu2 < -1e-12 * wn * wn {
        let mu = (-mu2).sqrt();
        ((mu * h).cosh(), (mu * h).sinh() / mu)
    } else {
        (1.0, h)
    };
    let e = (sigma * h).exp();
    // A − σI = [[−σ, 1], [−ω_n², −2ζω_n − σ]]
    [
        [e * (c - s * sigma), e * s],
        [-e * s * wn * wn, e * (c + s * (-2.0 * zeta * wn - sigma))],
    ]
}

/// The spool's mean position over a step of `h` (s) as a function of its
/// start, for natural frequency `wn` (rad/s) and damping ratio `zeta` (1):
/// x̄ − x_r = Ψ₀₀·(x − x_r) + Ψ₀₁·v, the first row of
/// Ψ = (1/h)·∫₀ʰ exp(A·τ) dτ = A⁻¹·(Φ − I)/h ([`spool_transition`]); Ψ₀₀ in 1, Ψ₀₁ in s.
pub fn spool_mean(wn: f64, zeta: f64, h: f64) -> [f64; 2] {
    let phi = spool_transition(wn, zeta, h);
    let (m00, m01, m10, m11) = (phi[0][0] - 1.0, phi[0][1], phi[1][0], phi[1][1] - 1.0);
    // A⁻¹ = [[−2ζω_n, −1], [ω_n², 0]] / ω_n²
    let scale = 1.0 / (wn * wn * h);
    [
        (-2.0 * zeta * wn * m00 - m10) * scale,
        (-2.0 * zeta * wn * m01 - m11) * scale,
    ]
}
