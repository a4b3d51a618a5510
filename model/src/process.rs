//! The EKF's process models (MODEL.md §4): the healthy actuator integrated
//! with forward Euler at the sample period, with analytic Jacobians on every
//! branch (valve sign, stick band, spring contact).
//!
//! Three layouts share one right-hand side, selected by the state count `N`:
//!
//! | N | states (SI) |
//! |---|---|
//! | 6 | x_sp m, p1 Pa, p2 Pa, x m, v m/s, v_sp m/s (friction and spring from the parameters) |
//! | 7 | the 6 plus F_e N, the whole effective load (friction + environment) as a random walk |
//! | 10 | the 7 plus q_e1, q_e2, q_i m³/s: the three leak sizes (random walks) |
//! | 11 | the 10 plus b m: the spool's null bias (a random walk) |
//!
//! The 10-state "leak" layout is leakwatch's own: a leak is a flow the healthy
//! model lacks, so the filter estimates the three leaks directly, each as its
//! size at the nominal pressure drop Δp_n = p_s/2 under the square-root law:
//! q = q_n · sgn(Δp)·√(|Δp| / Δp_n), with Δp = p1 − p_r, p2 − p_r and p1 − p2.
//!
//! Measurements are y = [x, p1, p2] (m, Pa, Pa).

use nalgebra::{SMatrix, SVector};

use crate::dynamics::{effective_bulk_modulus_pa, valve_flows, LeakSet};
use crate::friction::{friction_dv, friction_force_n};
use crate::params::ActuatorParams;

/// Index of the effective load F_e (N) in the 7- and 9-state layouts.
pub const I_FE: usize = 6;
/// Index of q_e1, the chamber-1 external leak at nominal drop (m³/s), in the 10-state layout.
pub const I_QE1: usize = 7;
/// Index of q_e2, the chamber-2 external leak at nominal drop (m³/s), in the 10-state layout.
pub const I_QE2: usize = 8;
/// Index of q_i, the internal leak at nominal drop (m³/s), in the 10-state layout.
pub const I_QI: usize = 9;
/// Index of the spool null bias b (m) in the 11-state layout.
pub const I_BIAS: usize = 10;
/// Number of measurements: rod position (m) and the two chamber pressures (Pa).
pub const N_MEAS: usize = 3;

/// Smallest |Δp| used for the slope of a square-root flow law, Pa: below it the
/// slope 1/(2√|Δp|) is held at its value here, so the Jacobian stays finite
/// when a land's pressure drop crosses zero.
pub const MIN_SLOPE_DROP_PA: f64 = 1.0e3;

/// What the prediction had to do to keep the state physical.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Guard {
    /// A pressure was pulled back into [min, max] of [`PressureRange`].
    pub pressure_clamped: bool,
    /// The rod position was pulled back into the stroke (± the end-stop margin).
    pub position_clamped: bool,
}

impl Guard {
    /// Whether anything was clamped.
    pub fn any(&self) -> bool {
        self.pressure_clamped || self.position_clamped
    }
}

/// The discrete process model x(k+1) = x(k) + T·f(x(k), u(k)) of the healthy actuator.
#[derive(Debug, Clone)]
pub struct ProcessModel {
    /// Physical parameters of the model (not of the rig).
    pub params: ActuatorParams,
    /// Sample period T, s.
    pub dt_s: f64,
    /// Euler sub-steps per sample (1 = the thesis' plain forward Euler).
    pub substeps: u32,
    /// Leaks that are part of the model itself (from `params.leaks`).
    pub leaks: LeakSet,
    /// Lowest pressure a prediction may hold, Pa (vacuum, gauge).
    pub p_min_pa: f64,
    /// Highest pressure a prediction may hold, Pa.
    pub p_max_pa: f64,
}

/// The continuous right-hand side and its Jacobian at one state.
#[derive(Debug, Clone, Copy)]
pub struct Linearisation<const N: usize> {
    /// dx/dt.
    pub f: SVector<f64, N>,
    /// ∂f/∂x.
    pub a: SMatrix<f64, N, N>,
}

/// d/dΔp of sgn(Δp)·√|Δp|, held finite near zero.
#[inline]
fn sqrt_slope(dp_pa: f64) -> f64 {
    0.5 / dp_pa.abs().max(MIN_SLOPE_DROP_PA).sqrt()
}

impl ProcessModel {
    /// The model for parameters `params` at sample period `dt_s` (s).
    pub fn new(params: ActuatorParams, dt_s: f64) -> Self {
        let leaks = LeakSet::from_params(&params);
        let p_max_pa = 1.5 * params.supply_pressure_pa;
        ProcessModel {
            params,
            dt_s,
            substeps: 1,
            leaks,
            p_min_pa: -1.0e5,
            p_max_pa,
        }
    }

    /// The nominal pressure drop at which the 10-state layout's leak sizes are given, Pa (p_s/2).
    pub fn nominal_drop_pa(&self) -> f64 {
        0.5 * (self.params.supply_pressure_pa - self.params.return_pressure_pa)
    }

    /// The continuous dynamics f(x, u) and ∂f/∂x for a layout of `N` states
    /// (6, 7, 10 or 11), command `u_v` in V.
    pub fn linearise<const N: usize>(&self, s: &SVector<f64, N>, u_v: f64) -> Linearisation<N> {
        assert!(
            N == 6 || N == 7 || N == 10 || N == 11,
            "process layouts have 6, 7, 10 or 11 states"
        );
        let p = &self.params;
        let (x_sp, p1, p2, x, v, v_sp) = (s[0], s[1], s[2], s[3], s[4], s[5]);
        let mut f = SVector::<f64, N>::zeros();
        let mut a = SMatrix::<f64, N, N>::zeros();

        // Spool: second order.
        let wn = p.spool_natural_freq_rad_s;
        f[0] = v_sp;
        a[(0, 5)] = 1.0;
        let bias = p.spool_null_bias_m + if N == 11 { s[I_BIAS] } else { 0.0 };
        f[5] = -2.0 * p.spool_damping_ratio * wn * v_sp - wn * wn * (x_sp - bias)
            + p.spool_gain_m_per_v * wn * wn * u_v;
        if N == 11 {
            a[(5, I_BIAS)] = wn * wn;
        }
        a[(5, 0)] = -wn * wn;
        a[(5, 5)] = -2.0 * p.spool_damping_ratio * wn;

        // Valve flows and their slopes.
        let flows = valve_flows(p, x_sp, p1, p2);
        let (dq1, dq2) = self.valve_partials(x_sp, p1, p2);
        // Leaks built into the model.
        let lq = self.leaks.flows(p1, p2, p.return_pressure_pa);
        let dl = self.leak_partials(p1, p2);

        // Chambers.
        let area = p.piston_area_m2;
        let (v1, v2) = p.chamber_volumes_m3(x);
        let b1 = effective_bulk_modulus_pa(p, p1);
        let b2 = effective_bulk_modulus_pa(p, p2);
        let db1 = bulk_slope(p, p1, b1);
        let db2 = bulk_slope(p, p2, b2);
        // Estimated leaks (10 states): q = q_n·ssqrt(Δp)/√Δp_n.
        let pr = p.return_pressure_pa;
        let inv_sqrt_n = 1.0 / self.nominal_drop_pa().sqrt();
        let ss = crate::units::signed_sqrt;
        let (g1, g2, gi) = (
            ss(p1 - pr) * inv_sqrt_n,
            ss(p2 - pr) * inv_sqrt_n,
            ss(p1 - p2) * inv_sqrt_n,
        );
        let (qe1, qe2, qi) = if N >= 10 {
            (s[I_QE1], s[I_QE2], s[I_QI])
        } else {
            (0.0, 0.0, 0.0)
        };
        let net1 = flows.q1_m3_s - area * v - lq.int_m3_s - lq.ext1_m3_s - qe1 * g1 - qi * gi;
        let net2 = area * v - flows.q2_m3_s + lq.int_m3_s - lq.ext2_m3_s - qe2 * g2 + qi * gi;
        f[1] = b1 / v1 * net1;
        f[2] = b2 / v2 * net2;
        // ∂/∂x_sp, ∂/∂p1, ∂/∂p2
        a[(1, 0)] = b1 / v1 * dq1[0];
        a[(1, 1)] = b1 / v1 * (dq1[1] - dl.int[0] - dl.ext1) + db1 / v1 * net1;
        a[(1, 2)] = b1 / v1 * (dq1[2] - dl.int[1]);
        a[(2, 0)] = -b2 / v2 * dq2[0];
        a[(2, 1)] = b2 / v2 * (-dq2[1] + dl.int[0]);
        a[(2, 2)] = b2 / v2 * (-dq2[2] + dl.int[1] - dl.ext2) + db2 / v2 * net2;
        // ∂/∂x through the volumes: V1 = V10 + A(x − x_min), V2 = V20 + A(x_max − x).
        a[(1, 3)] = -b1 * net1 * area / (v1 * v1);
        a[(2, 3)] = b2 * net2 * area / (v2 * v2);
        // ∂/∂v
        a[(1, 4)] = -b1 / v1 * area;
        a[(2, 4)] = b2 / v2 * area;
        if N >= 10 {
            a[(1, I_QE1)] = -b1 / v1 * g1;
            a[(1, I_QI)] = -b1 / v1 * gi;
            a[(2, I_QE2)] = -b2 / v2 * g2;
            a[(2, I_QI)] = b2 / v2 * gi;
            let (s1, s2, si) = (
                sqrt_slope(p1 - pr) * inv_sqrt_n,
                sqrt_slope(p2 - pr) * inv_sqrt_n,
                sqrt_slope(p1 - p2) * inv_sqrt_n,
            );
            a[(1, 1)] -= b1 / v1 * (qe1 * s1 + qi * si);
            a[(1, 2)] += b1 / v1 * qi * si;
            a[(2, 1)] += b2 / v2 * qi * si;
            a[(2, 2)] -= b2 / v2 * (qe2 * s2 + qi * si);
        }

        // Rod.
        f[3] = v;
        a[(3, 4)] = 1.0;
        let m = p.mass_kg;
        if N >= 7 {
            f[4] = (area * (p1 - p2) - s[I_FE]) / m;
            a[(4, 1)] = area / m;
            a[(4, 2)] = -area / m;
            a[(4, I_FE)] = -1.0 / m;
        } else {
            let load = p.load.force_n(x, v);
            let (dload_dx, dload_dv) = if p.load.stiffness_n_per_m != 0.0 || p.load.preload_n != 0.0 {
                if x > p.load.contact_m {
                    (p.load.stiffness_n_per_m, p.load.damping_n_s_per_m)
                } else {
                    (0.0, 0.0)
                }
            } else {
                (0.0, 0.0)
            };
            let drive = area * (p1 - p2) - load;
            let friction = friction_force_n(&p.friction, v, drive);
            f[4] = (drive - friction) / m;
            if v.abs() > p.friction.zero_velocity_m_s {
                // sliding: Stribeck + viscous
                a[(4, 1)] = area / m;
                a[(4, 2)] = -area / m;
                a[(4, 3)] = -dload_dx / m;
                a[(4, 4)] = (-dload_dv - friction_dv(&p.friction, v)) / m;
            } else if friction != drive {
                // breaking away: friction saturated at ±f_st
                a[(4, 1)] = area / m;
                a[(4, 2)] = -area / m;
                a[(4, 3)] = -dload_dx / m;
                a[(4, 4)] = -dload_dv / m;
            }
            // stuck: friction balances the drive, dv/dt = 0 and its row is zero
        }
        Linearisation { f, a }
    }

    /// Partials of (Q1, Q2) with respect to (x_sp, p1, p2); no supply sag
    /// (with sag, central differences of [`valve_flows`]).
    fn valve_partials(&self, x_sp: f64, p1: f64, p2: f64) -> ([f64; 3], [f64; 3]) {
        let p = &self.params;
        if p.supply_sag_pa_per_m3_s != 0.0 {
            let q = |xs: f64, a: f64, b: f64| {
                let f = valve_flows(p, xs, a, b);
                (f.q1_m3_s, f.q2_m3_s)
            };
            let (hx, hp) = (
                1e-9_f64.max(1e-6 * x_sp.abs()),
                1.0_f64.max(1e-6 * p1.abs().max(p2.abs())),
            );
            let d = |plus: (f64, f64), minus: (f64, f64), h: f64| {
                ((plus.0 - minus.0) / (2.0 * h), (plus.1 - minus.1) / (2.0 * h))
            };
            let dx = d(q(x_sp + hx, p1, p2), q(x_sp - hx, p1, p2), hx);
            let d1 = d(q(x_sp, p1 + hp, p2), q(x_sp, p1 - hp, p2), hp);
            let d2 = d(q(x_sp, p1, p2 + hp), q(x_sp, p1, p2 - hp), hp);
            return ([dx.0, d1.0, d2.0], [dx.1, d1.1, d2.1]);
        }
        let g = p.discharge_coefficient * p.area_gradient_m2_per_m * (2.0 / p.oil_density_kg_m3).sqrt();
        let (ps, pr) = (p.supply_pressure_pa, p.return_pressure_pa);
        let ss = crate::units::signed_sqrt;
        if x_sp >= 0.0 {
            // Q1 = g x_sp ssqrt(ps − p1), Q2 = g x_sp ssqrt(p2 − pr)
            (
                [g * ss(ps - p1), -g * x_sp * sqrt_slope(ps - p1), 0.0],
                [g * ss(p2 - pr), 0.0, g * x_sp * sqrt_slope(p2 - pr)],
            )
        } else {
            // Q1 = g x_sp ssqrt(p1 − pr), Q2 = g x_sp ssqrt(ps − p2)
            (
                [g * ss(p1 - pr), g * x_sp * sqrt_slope(p1 - pr), 0.0],
                [g * ss(ps - p2), 0.0, -g * x_sp * sqrt_slope(ps - p2)],
            )
        }
    }

    /// Partials of the model's own leak flows: internal w.r.t. (p1, p2), ext1 w.r.t. p1, ext2 w.r.t. p2.
    fn leak_partials(&self, p1: f64, p2: f64) -> LeakPartials {
        let l = &self.leaks;
        let pr = self.params.return_pressure_pa;
        // index order of LeakSet: ext1, ext2, int
        let d_ext1 = l.linear_m3_s_pa[0] + l.sqrt_m3_s_sqrt_pa[0] * sqrt_slope(p1 - pr);
        let d_ext2 = l.linear_m3_s_pa[1] + l.sqrt_m3_s_sqrt_pa[1] * sqrt_slope(p2 - pr);
        let d_int = l.linear_m3_s_pa[2] + l.sqrt_m3_s_sqrt_pa[2] * sqrt_slope(p1 - p2);
        LeakPartials {
            ext1: d_ext1,
            ext2: d_ext2,
            int: [d_int, -d_int],
        }
    }

    /// One sample step: x(k+1) and the discrete Jacobian F = ∂x(k+1)/∂x(k)
    /// (forward Euler in `substeps` sub-steps), with the state kept physical.
    pub fn step<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
    ) -> (SVector<f64, N>, SMatrix<f64, N, N>, Guard) {
        let n = self.substeps.max(1);
        let h = self.dt_s / n as f64;
        let mut x = *s;
        let mut jac = SMatrix::<f64, N, N>::identity();
        for i in 0..n {
            let lin = self.linearise(&x, u_v);
            let step_jac = SMatrix::<f64, N, N>::identity() + lin.a * h;
            x += lin.f * h;
            jac = if i == 0 { step_jac } else { step_jac * jac };
        }
        let guard = self.keep_physical(&mut x);
        (x, jac, guard)
    }

    /// Clamps pressures into [p_min, p_max] and the rod into its stroke plus
    /// 1 cm; reports what was done.
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
        g
    }

    /// The measurement y = [x, p1, p2] of a state, m, Pa, Pa.
    #[inline]
    pub fn measure<const N: usize>(s: &SVector<f64, N>) -> SVector<f64, N_MEAS> {
        SVector::<f64, N_MEAS>::new(s[3], s[1], s[2])
    }

    /// The measurement matrix H (selects x, p1, p2).
    pub fn measurement_matrix<const N: usize>() -> SMatrix<f64, N_MEAS, N> {
        let mut h = SMatrix::<f64, N_MEAS, N>::zeros();
        h[(0, 3)] = 1.0;
        h[(1, 1)] = 1.0;
        h[(2, 2)] = 1.0;
        h
    }
}

struct LeakPartials {
    ext1: f64,
    ext2: f64,
    int: [f64; 2],
}

/// dβ_eff/dp at pressure `p_pa`, Pa/Pa, for the entrained-air law of [`effective_bulk_modulus_pa`].
fn bulk_slope(p: &ActuatorParams, p_pa: f64, beta_eff: f64) -> f64 {
    if p.entrained_air_fraction == 0.0 {
        return 0.0;
    }
    const P_ATM: f64 = 101_325.0;
    let p_abs = p_pa + P_ATM;
    if p_abs <= 0.2 * P_ATM {
        return 0.0;
    }
    beta_eff * beta_eff * 2.0 * p.entrained_air_fraction * P_ATM / (p_abs * p_abs * p_abs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leakage::{LeakLaw, LeakPath};
    use crate::params::BuiltInLeak;
    use crate::rng::Rng;

    /// Central-difference Jacobian of f.
    fn fd_jacobian<const N: usize>(m: &ProcessModel, s: &SVector<f64, N>, u: f64) -> SMatrix<f64, N, N> {
        let mut j = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            let h = 1e-6 * SCALE[c];
            let mut sp = *s;
            let mut sm = *s;
            sp[c] += h;
            sm[c] -= h;
            let col = (m.linearise(&sp, u).f - m.linearise(&sm, u).f) / (2.0 * h);
            j.set_column(c, &col);
        }
        j
    }

    /// Central-difference Jacobian of the discrete step x(k) -> x(k+1) of [`ProcessModel::step`].
    fn fd_step_jacobian<const N: usize>(m: &ProcessModel, s: &SVector<f64, N>, u: f64) -> SMatrix<f64, N, N> {
        let mut j = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            let h = STEP_FD_STEPS[c];
            let mut sp = *s;
            let mut sm = *s;
            sp[c] += h;
            sm[c] -= h;
            let col = (m.step(&sp, u).0 - m.step(&sm, u).0) / (2.0 * h);
            j.set_column(c, &col);
        }
        j
    }

    /// Where the chamber pressures of a random state are drawn from.
    #[derive(Clone, Copy, Debug)]
    enum Pressures {
        /// Both in 0.5–13 MPa: every land passes flow in the spool's direction.
        Inside,
        /// Both above supply (p_s + 20 kPa to 1.45 p_s): the supply land passes back-flow.
        AboveSupply,
        /// Both near or below tank (−70 kPa to 0.2 MPa gauge): the signed square
        /// root's negative branch on the tank land.
        NearTank,
        /// Each chamber independently from one of the three ranges.
        Mixed,
    }

    fn chamber_pressure(rng: &mut Rng, p: &ActuatorParams, band: Pressures) -> f64 {
        let ps = p.supply_pressure_pa;
        match band {
            Pressures::Inside => rng.uniform_in(0.5e6, 13.0e6),
            Pressures::AboveSupply => rng.uniform_in(ps + 2e4, 1.45 * ps),
            Pressures::NearTank => rng.uniform_in(-7e4, 2e5),
            Pressures::Mixed => {
                let k = rng.uniform();
                let band = if k < 1.0 / 3.0 {
                    Pressures::Inside
                } else if k < 2.0 / 3.0 {
                    Pressures::AboveSupply
                } else {
                    Pressures::NearTank
                };
                chamber_pressure(rng, p, band)
            }
        }
    }

    fn random_state<const N: usize>(
        rng: &mut Rng,
        p: &ActuatorParams,
        band: Band,
        pressures: Pressures,
    ) -> SVector<f64, N> {
        let mut s = SVector::<f64, N>::zeros();
        s[0] = rng.uniform_in(-8e-5, 8e-5);
        s[1] = chamber_pressure(rng, p, pressures);
        s[2] = chamber_pressure(rng, p, pressures);
        s[3] = rng.uniform_in(0.05, 0.55);
        s[4] = match band {
            Band::Sliding => {
                let v = rng.uniform_in(0.002, 0.5);
                if rng.uniform() < 0.5 {
                    -v
                } else {
                    v
                }
            }
            Band::Stick => rng.uniform_in(-0.0009, 0.0009),
        };
        s[5] = rng.uniform_in(-0.05, 0.05);
        if N >= 7 {
            s[I_FE] = rng.uniform_in(-3e3, 3e3);
        }
        if N >= 10 {
            for i in [I_QE1, I_QE2, I_QI] {
                s[i] = rng.uniform_in(0.0, 2e-5);
            }
        }
        if N == 11 {
            s[I_BIAS] = rng.uniform_in(-1e-5, 1e-5);
        }
        s
    }

    #[derive(Clone, Copy)]
    enum Band {
        Sliding,
        Stick,
    }

    /// Whether `s` lies within a finite-difference step (with a wide margin) of a
    /// point where the right-hand side is not differentiable: the spool through
    /// zero, any land's or leak path's pressure drop through zero (and the
    /// ±[`MIN_SLOPE_DROP_PA`] band where the square root's slope is held), and for
    /// 6 states the stick band's edge, break-away and spring contact.
    fn near_branch<const N: usize>(m: &ProcessModel, s: &SVector<f64, N>) -> bool {
        let p = &m.params;
        let (ps, pr) = (p.supply_pressure_pa, p.return_pressure_pa);
        let drops = [ps - s[1], ps - s[2], s[1] - pr, s[2] - pr, s[1] - s[2]];
        if s[0].abs() < 1e-8 || drops.iter().any(|d| d.abs() < 5.0 * MIN_SLOPE_DROP_PA) {
            return true;
        }
        if N == 6 {
            let drive = p.piston_area_m2 * (s[1] - s[2]) - p.load.force_n(s[3], s[4]);
            if (drive.abs() - p.friction.static_n).abs() < 50.0
                || (s[3] - p.load.contact_m).abs() < 1e-5
                || (s[4].abs() - p.friction.zero_velocity_m_s).abs() < 1e-6
            {
                return true;
            }
        }
        false
    }

    /// Whether a land passes flow against the spool's direction at `s` (a
    /// chamber above supply on the supply land, or below tank on the tank land).
    fn back_flow<const N: usize>(m: &ProcessModel, s: &SVector<f64, N>) -> bool {
        let f = valve_flows(&m.params, s[0], s[1], s[2]);
        f.q1_m3_s * s[0] < 0.0 || f.q2_m3_s * s[0] < 0.0
    }

    /// Typical magnitude of each state, SI: the Jacobians are compared in these units
    /// (entry (r, c) times SCALE[c]/SCALE[r]), so that a row's entries are comparable
    /// whatever their units.
    const SCALE: [f64; 11] = [1e-5, 1e6, 1e6, 0.1, 0.1, 0.01, 1e3, 1e-5, 1e-5, 1e-5, 1e-6];

    /// Worst ratio of |an − fd| to what the comparison allows, both in scaled units:
    /// `tol` relative to the entry or to 1e-3 of its row's largest entry, plus
    /// `floor(r, c)` (an absolute allowance in SI, e.g. for rounding).
    fn worst_ratio<const N: usize>(
        an: &SMatrix<f64, N, N>,
        fd: &SMatrix<f64, N, N>,
        tol: f64,
        floor: impl Fn(usize, usize) -> f64,
    ) -> f64 {
        let k = |r: usize, c: usize| SCALE[c] / SCALE[r];
        let mut worst = 0.0f64;
        for r in 0..N {
            let row_scale = (0..N)
                .map(|c| (an[(r, c)] * k(r, c)).abs() * 1e-3)
                .fold(1e-300, f64::max);
            for c in 0..N {
                let err = ((an[(r, c)] - fd[(r, c)]) * k(r, c)).abs();
                let allowed = tol * (an[(r, c)] * k(r, c)).abs().max(row_scale) + floor(r, c) * k(r, c);
                worst = worst.max(err / allowed);
            }
        }
        worst
    }

    /// Checks the continuous Jacobian at 300 random states; returns how many
    /// states were checked and at how many of them a land passed back-flow.
    fn check_jacobian<const N: usize>(
        m: &ProcessModel,
        band: Band,
        pressures: Pressures,
        seed: u64,
    ) -> (usize, usize) {
        let mut rng = Rng::new(seed);
        let (mut checked, mut reversed) = (0, 0);
        for _ in 0..300 {
            let s: SVector<f64, N> = random_state(&mut rng, &m.params, band, pressures);
            let u = rng.uniform_in(-10.0, 10.0);
            // Skip states within a finite-difference step of a branch switch.
            if near_branch(m, &s) {
                continue;
            }
            let an = m.linearise(&s, u).a;
            let fd = fd_jacobian(m, &s, u);
            let ratio = worst_ratio(&an, &fd, 1e-5, |_, _| 0.0);
            assert!(
                ratio <= 1.0,
                "N={N} {pressures:?}: error {ratio} times the allowed\nanalytic {an:e}\nfd {fd:e}\nat {s:?}, u {u}"
            );
            checked += 1;
            reversed += usize::from(back_flow(m, &s));
        }
        (checked, reversed)
    }

    #[test]
    fn jacobians_match_central_differences_on_every_branch() {
        let p = ActuatorParams {
            load: crate::params::SpringLoad::thesis_simulation(),
            ..Default::default()
        };
        let m = ProcessModel::new(p.clone(), 1e-3);
        let inside = Pressures::Inside;
        assert!(check_jacobian::<6>(&m, Band::Sliding, inside, 1).0 > 250);
        assert!(check_jacobian::<6>(&m, Band::Stick, inside, 2).0 > 250);
        assert!(check_jacobian::<7>(&m, Band::Sliding, inside, 3).0 > 250);
        assert!(check_jacobian::<10>(&m, Band::Sliding, inside, 4).0 > 250);
        assert!(check_jacobian::<11>(&m, Band::Sliding, inside, 7).0 > 250);
        // A chamber above supply: back-flow through the supply land in every state.
        for (n, (checked, reversed)) in [
            (
                6,
                check_jacobian::<6>(&m, Band::Sliding, Pressures::AboveSupply, 11),
            ),
            (
                6,
                check_jacobian::<6>(&m, Band::Stick, Pressures::AboveSupply, 12),
            ),
            (
                7,
                check_jacobian::<7>(&m, Band::Sliding, Pressures::AboveSupply, 13),
            ),
            (
                10,
                check_jacobian::<10>(&m, Band::Sliding, Pressures::AboveSupply, 14),
            ),
        ] {
            assert!(checked > 250, "{n} states above supply: {checked} checked");
            assert_eq!(reversed, checked, "{n} states above supply");
        }
        // Chambers near or below tank: the signed square root's negative branch
        // (tank land, built-in and estimated leaks) and the smallest slopes' neighbours.
        for (n, (checked, reversed)) in [
            (6, check_jacobian::<6>(&m, Band::Sliding, Pressures::NearTank, 21)),
            (6, check_jacobian::<6>(&m, Band::Stick, Pressures::NearTank, 22)),
            (7, check_jacobian::<7>(&m, Band::Sliding, Pressures::NearTank, 23)),
            (
                10,
                check_jacobian::<10>(&m, Band::Sliding, Pressures::NearTank, 24),
            ),
            (
                11,
                check_jacobian::<11>(&m, Band::Sliding, Pressures::NearTank, 25),
            ),
        ] {
            assert!(checked > 200, "{n} states near tank: {checked} checked");
            assert!(
                reversed > checked / 5,
                "{n} states near tank: back-flow in {reversed} of {checked}"
            );
        }
        // One chamber at each extreme: the largest cross-piston drops (internal leak state).
        let (checked, reversed) = check_jacobian::<10>(&m, Band::Sliding, Pressures::Mixed, 31);
        assert!(checked > 200 && reversed > checked / 5, "{checked} {reversed}");

        // With entrained air, a pressure-dependent bulk modulus, built-in leaks of both laws.
        let mut p2 = p;
        p2.entrained_air_fraction = 0.01;
        p2.leaks = vec![
            BuiltInLeak {
                path: LeakPath::External1,
                law: LeakLaw::SquareRoot,
                coefficient: 5e-9,
            },
            BuiltInLeak {
                path: LeakPath::Internal,
                law: LeakLaw::Linear,
                coefficient: 2e-12,
            },
            BuiltInLeak {
                path: LeakPath::External2,
                law: LeakLaw::SquareRoot,
                coefficient: 3e-9,
            },
        ];
        let m2 = ProcessModel::new(p2.clone(), 1e-3);
        assert!(check_jacobian::<7>(&m2, Band::Sliding, inside, 5).0 > 250);
        assert!(check_jacobian::<6>(&m2, Band::Stick, inside, 6).0 > 250);
        assert!(check_jacobian::<7>(&m2, Band::Sliding, Pressures::Mixed, 8).0 > 200);
        assert!(check_jacobian::<6>(&m2, Band::Sliding, Pressures::NearTank, 9).0 > 200);

        // Supply sag (the supply pressure at the valve drops with the supply land's flow).
        let mut p3 = p2;
        p3.supply_sag_pa_per_m3_s = 2e10;
        let m3 = ProcessModel::new(p3, 1e-3);
        assert!(check_jacobian::<6>(&m3, Band::Sliding, inside, 41).0 > 250);
        assert!(check_jacobian::<7>(&m3, Band::Sliding, inside, 42).0 > 250);
        assert!(check_jacobian::<10>(&m3, Band::Sliding, Pressures::Mixed, 43).0 > 200);
        let (checked, reversed) = check_jacobian::<7>(&m3, Band::Sliding, Pressures::AboveSupply, 44);
        assert!(checked > 250 && reversed == checked, "{checked} {reversed}");
    }

    /// Steps of [`fd_step_jacobian`], per state.
    const STEP_FD_STEPS: [f64; 11] = [1e-9, 1.0, 1.0, 1e-7, 1e-7, 1e-7, 1e-2, 1e-10, 1e-10, 1e-10, 1e-10];

    /// [`worst_ratio`] with the rounding floor of a central difference of x(k+1)
    /// taken over `substeps` sub-steps, ε·n·|x(k+1)_r|/h_c.
    fn worst_step_ratio<const N: usize>(
        an: &SMatrix<f64, N, N>,
        fd: &SMatrix<f64, N, N>,
        next: &SVector<f64, N>,
        substeps: u32,
        tol: f64,
    ) -> f64 {
        worst_ratio(an, fd, tol, |r, c| {
            f64::EPSILON * substeps as f64 * next[r].abs() / STEP_FD_STEPS[c]
        })
    }

    /// Checks the discrete Jacobian of [`ProcessModel::step`] at 300 random
    /// states against central differences of the step itself; skips states whose
    /// sub-steps pass near a branch switch or that the guard clamps. Returns how
    /// many were checked and at how many a single linearisation, I + T·A(x(k)),
    /// would have failed the same comparison.
    fn check_step_jacobian<const N: usize>(
        m: &ProcessModel,
        band: Band,
        pressures: Pressures,
        seed: u64,
    ) -> (usize, usize) {
        const TOL: f64 = 1e-5;
        let mut rng = Rng::new(seed);
        let (mut checked, mut one_step_fails) = (0, 0);
        let n = m.substeps.max(1);
        let h = m.dt_s / n as f64;
        for _ in 0..300 {
            let s: SVector<f64, N> = random_state(&mut rng, &m.params, band, pressures);
            let u = rng.uniform_in(-10.0, 10.0);
            let mut x = s;
            let mut near = false;
            for _ in 0..n {
                near |= near_branch(m, &x);
                x += m.linearise(&x, u).f * h;
            }
            let (next, an, guard) = m.step(&s, u);
            if near || guard.any() {
                continue;
            }
            let fd = fd_step_jacobian(m, &s, u);
            let ratio = worst_step_ratio(&an, &fd, &next, n, TOL);
            assert!(
                ratio <= 1.0,
                "N={N} substeps {n}: error {ratio} times the allowed\nanalytic {an:e}\nfd {fd:e}\nat {s:?}, u {u}"
            );
            let single = SMatrix::<f64, N, N>::identity() + m.linearise(&s, u).a * m.dt_s;
            one_step_fails += usize::from(worst_step_ratio(&single, &fd, &next, n, TOL) > 1.0);
            checked += 1;
        }
        (checked, one_step_fails)
    }

    #[test]
    fn discrete_step_jacobian_matches_central_differences_of_the_step() {
        let p = ActuatorParams {
            load: crate::params::SpringLoad::thesis_simulation(),
            ..Default::default()
        };
        for substeps in [1, 4, 10] {
            let mut m = ProcessModel::new(p.clone(), 1e-3);
            m.substeps = substeps;
            let runs = [
                (
                    6,
                    check_step_jacobian::<6>(&m, Band::Sliding, Pressures::Inside, 51),
                ),
                (
                    6,
                    check_step_jacobian::<6>(&m, Band::Stick, Pressures::Inside, 52),
                ),
                (
                    7,
                    check_step_jacobian::<7>(&m, Band::Sliding, Pressures::Inside, 53),
                ),
                (
                    7,
                    check_step_jacobian::<7>(&m, Band::Sliding, Pressures::Mixed, 54),
                ),
                (
                    11,
                    check_step_jacobian::<11>(&m, Band::Sliding, Pressures::Inside, 55),
                ),
            ];
            for (n, (checked, one_step_fails)) in runs {
                eprintln!(
                    "{n} states, {substeps} sub-steps: {checked} states checked, \
                     I + T·A(x) off in {one_step_fails}"
                );
                assert!(
                    checked > 150,
                    "{n} states, {substeps} sub-steps: {checked} checked"
                );
                if substeps == 1 {
                    // one Euler step: the product is the single linearisation
                    assert_eq!(one_step_fails, 0);
                } else {
                    // the product of sub-step Jacobians is not I + T·A(x(k)): the test can tell
                    assert!(
                        one_step_fails > checked / 2,
                        "{n} states, {substeps} sub-steps: {one_step_fails} of {checked}"
                    );
                }
            }
        }
        // With supply sag and entrained air.
        let mut p2 = p;
        p2.supply_sag_pa_per_m3_s = 2e10;
        p2.entrained_air_fraction = 0.01;
        let mut m2 = ProcessModel::new(p2, 1e-3);
        m2.substeps = 5;
        let (checked, _) = check_step_jacobian::<7>(&m2, Band::Sliding, Pressures::Inside, 61);
        assert!(checked > 150, "{checked}");
        let (checked, _) = check_step_jacobian::<6>(&m2, Band::Sliding, Pressures::Mixed, 62);
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn centred_valve_is_an_equilibrium_and_stick_band_rows_vanish() {
        let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
        let p0 = m.params.nominal_chamber_pressure_pa();
        let s = SVector::<f64, 6>::from([0.0, p0, p0, 0.3, 0.0, 0.0]);
        let lin = m.linearise(&s, 0.0);
        assert!(lin.f.iter().all(|d| d.abs() < 1e-12), "{:?}", lin.f);
        // stuck: the velocity row is zero
        assert!(lin.a.row(4).iter().all(|d| *d == 0.0));
        let (next, jac, guard) = m.step(&s, 0.0);
        assert_eq!(next, s);
        assert!(!guard.any());
        assert_eq!(jac, SMatrix::<f64, 6, 6>::identity() + lin.a * 1e-3);
    }

    #[test]
    fn leak_states_enter_the_continuity_equations() {
        let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
        let pn = m.nominal_drop_pa();
        let q = crate::units::lpm_to_m3_s(0.5);
        let (v1, v2) = m.params.chamber_volumes_m3(0.3);
        let beta = m.params.bulk_modulus_pa;
        // At the nominal drop an external leak of size q takes exactly q from its chamber.
        let s = SVector::<f64, 10>::from([0.0, pn, pn, 0.3, 0.0, 0.0, 0.0, q, 0.0, 0.0]);
        let f = m.linearise(&s, 0.0).f;
        assert!((f[1] + beta / v1 * q).abs() < 1e-9 * beta / v1 * q);
        assert!(f[2].abs() < 1e-9);
        // An internal leak at a drop of pn/4 carries half its nominal size from 1 to 2.
        let s = SVector::<f64, 10>::from([0.0, pn, 0.75 * pn, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0, q]);
        let f = m.linearise(&s, 0.0).f;
        let f_ref = m
            .linearise(
                &SVector::<f64, 10>::from([0.0, pn, 0.75 * pn, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
                0.0,
            )
            .f;
        assert!((f[1] - f_ref[1] + beta / v1 * 0.5 * q).abs() < 1e-6 * beta / v1 * q);
        assert!((f[2] - f_ref[2] - beta / v2 * 0.5 * q).abs() < 1e-6 * beta / v2 * q);
    }

    #[test]
    fn guard_clamps_unphysical_pressures() {
        let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
        let mut s = SVector::<f64, 7>::from([0.0, 30e6, f64::NAN, 0.7, 0.0, 0.0, 0.0]);
        let g = m.keep_physical(&mut s);
        assert!(g.pressure_clamped && g.position_clamped);
        assert_eq!(s[1], 1.5 * 13.8e6);
        assert_eq!(s[2], m.params.nominal_chamber_pressure_pa());
        assert!((s[3] - (m.params.x_max_m + 0.01)).abs() < 1e-12);
    }
}
