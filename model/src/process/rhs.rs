//! The continuous right-hand side f(x, u) of every layout and its analytic
//! Jacobian ∂f/∂x ([`ProcessModel::linearise`]), with the slopes of the valve,
//! leak and bulk-modulus laws it is built from.

use nalgebra::{SMatrix, SVector};

use super::{Linearisation, ProcessModel, I_BIAS, I_BULK, I_FE, I_QE1, I_QE2, I_QI, MIN_SLOPE_DROP_PA};
use crate::dynamics::{
    effective_bulk_modulus_pa, end_stop_force_n, end_stop_slopes, null_leakage_flows, valve_flows,
};
use crate::friction::{friction_dv, friction_force_n};
use crate::params::ActuatorParams;

/// d/dΔp of sgn(Δp)·√|Δp|, held finite near zero.
#[inline]
fn sqrt_slope(dp_pa: f64) -> f64 {
    0.5 / dp_pa.abs().max(MIN_SLOPE_DROP_PA).sqrt()
}

impl ProcessModel {
    /// The continuous dynamics f(x, u) and ∂f/∂x for a layout of `N` states
    /// (6, 7, 10, 11 or 12), command `u_v` in V.
    pub fn linearise<const N: usize>(&self, s: &SVector<f64, N>, u_v: f64) -> Linearisation<N> {
        assert!(
            N == 6 || N == 7 || N == 10 || N == 11 || N == 12,
            "process layouts have 6, 7, 10, 11 or 12 states"
        );
        let p = &self.params;
        let (x_sp, p1, p2, x, v, v_sp) = (s[0], s[1], s[2], s[3], s[4], s[5]);
        let mut f = SVector::<f64, N>::zeros();
        let mut a = SMatrix::<f64, N, N>::zeros();

        // Spool: second order.
        let wn = p.spool_natural_freq_rad_s;
        f[0] = v_sp;
        a[(0, 5)] = 1.0;
        let bias = p.spool_null_bias_m + if N >= 11 { s[I_BIAS] } else { 0.0 };
        f[5] = -2.0 * p.spool_damping_ratio * wn * v_sp - wn * wn * (x_sp - bias)
            + p.spool_gain_m_per_v * wn * wn * u_v;
        if N >= 11 {
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
        let (a1, a2) = p.areas_m2();
        let (v1, v2) = p.chamber_volumes_m3(x);
        // The 12-state layout scales the oil's stiffness by its estimate θ.
        let theta = if N == 12 { s[I_BULK] } else { 1.0 };
        let (b1_model, b2_model) = (effective_bulk_modulus_pa(p, p1), effective_bulk_modulus_pa(p, p2));
        let (b1, b2) = (theta * b1_model, theta * b2_model);
        let db1 = theta * bulk_slope(p, p1, b1_model);
        let db2 = theta * bulk_slope(p, p2, b2_model);
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
        let net1 = flows.q1_m3_s - a1 * v - lq.int_m3_s - lq.ext1_m3_s - qe1 * g1 - qi * gi;
        let net2 = a2 * v - flows.q2_m3_s + lq.int_m3_s - lq.ext2_m3_s - qe2 * g2 + qi * gi;
        f[1] = b1 / v1 * net1;
        f[2] = b2 / v2 * net2;
        if N == 12 {
            a[(1, I_BULK)] = b1_model / v1 * net1;
            a[(2, I_BULK)] = b2_model / v2 * net2;
        }
        // ∂/∂x_sp, ∂/∂p1, ∂/∂p2
        a[(1, 0)] = b1 / v1 * dq1[0];
        a[(1, 1)] = b1 / v1 * (dq1[1] - dl.int[0] - dl.ext1) + db1 / v1 * net1;
        a[(1, 2)] = b1 / v1 * (dq1[2] - dl.int[1]);
        a[(2, 0)] = -b2 / v2 * dq2[0];
        a[(2, 1)] = b2 / v2 * (-dq2[1] + dl.int[0]);
        a[(2, 2)] = b2 / v2 * (-dq2[2] + dl.int[1] - dl.ext2) + db2 / v2 * net2;
        // ∂/∂x through the volumes: V1 = V10 + A1(x − x_min), V2 = V20 + A2(x_max − x).
        a[(1, 3)] = -b1 * net1 * a1 / (v1 * v1);
        a[(2, 3)] = b2 * net2 * a2 / (v2 * v2);
        // ∂/∂v
        a[(1, 4)] = -b1 / v1 * a1;
        a[(2, 4)] = b2 / v2 * a2;
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
        let gravity = p.gravity_force_n();
        // The end stops, as the rig has them, in leakwatch's own layouts (10 states
        // and more): a stiff spring-damper beyond each end of the stroke
        // ([`ProcessModel::step`] sub-steps while the rod is in one). The thesis'
        // layouts (6, 7) keep the thesis' model, which has none: their start from the
        // thesis' P0 (1e4 m² on the rod position) would throw the rod deep into a stop.
        let (stop, (dstop_dx, dstop_dv)) = if N >= 10 {
            (end_stop_force_n(p, x, v), end_stop_slopes(p, x, v))
        } else {
            (0.0, (0.0, 0.0))
        };
        if N >= 7 {
            f[4] = (p.pressure_force_n(p1, p2) - gravity - s[I_FE] + stop) / m;
            a[(4, 1)] = a1 / m;
            a[(4, 2)] = -a2 / m;
            a[(4, 3)] = dstop_dx / m;
            a[(4, 4)] = dstop_dv / m;
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
            let drive = p.pressure_force_n(p1, p2) - gravity - load;
            let friction = friction_force_n(&p.friction, v, drive);
            f[4] = (drive - friction) / m;
            if v.abs() > p.friction.zero_velocity_m_s {
                // sliding: Stribeck + viscous
                a[(4, 1)] = a1 / m;
                a[(4, 2)] = -a2 / m;
                a[(4, 3)] = -dload_dx / m;
                a[(4, 4)] = (-dload_dv - friction_dv(&p.friction, v)) / m;
            } else if friction != drive {
                // breaking away: friction saturated at ±f_st
                a[(4, 1)] = a1 / m;
                a[(4, 2)] = -a2 / m;
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
        let (mut dq1, mut dq2) = self.orifice_partials(x_sp, p1, p2);
        if p.valve_null_leakage_m3_s_pa > 0.0 {
            let n = null_leakage_flows(p, x_sp, p1, p2);
            for i in 0..3 {
                dq1[i] += n.dq1[i];
                dq2[i] += n.dq2[i];
            }
        }
        (dq1, dq2)
    }

    /// Partials of the metering orifices' (Q1, Q2) with respect to (x_sp, p1, p2), no sag.
    fn orifice_partials(&self, x_sp: f64, p1: f64, p2: f64) -> ([f64; 3], [f64; 3]) {
        let p = &self.params;
        let (wa, wb) = p.area_gradients_m2_per_m();
        let root = (2.0 / p.oil_density_kg_m3).sqrt();
        let (ga, gb) = (
            p.discharge_coefficient * wa * root,
            p.discharge_coefficient * wb * root,
        );
        let (ps, pr) = (p.supply_pressure_pa, p.return_pressure_pa);
        let ss = crate::units::signed_sqrt;
        if x_sp >= 0.0 {
            // Q1 = g_A x_sp ssqrt(ps − p1), Q2 = g_B x_sp ssqrt(p2 − pr)
            (
                [ga * ss(ps - p1), -ga * x_sp * sqrt_slope(ps - p1), 0.0],
                [gb * ss(p2 - pr), 0.0, gb * x_sp * sqrt_slope(p2 - pr)],
            )
        } else {
            // Q1 = g_A x_sp ssqrt(p1 − pr), Q2 = g_B x_sp ssqrt(ps − p2)
            (
                [ga * ss(p1 - pr), ga * x_sp * sqrt_slope(p1 - pr), 0.0],
                [gb * ss(ps - p2), 0.0, -gb * x_sp * sqrt_slope(ps - p2)],
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
