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

/// The constants of the right-hand side that depend on the parameters alone
/// (each computed as [`ProcessModel::linearise`] computed it inline, so the
/// results are the same bit for bit), with the parameters they came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Derived {
    /// The parameters these were derived from: C_d, w_A, w_B, ρ, p_s, p_r, m,
    /// mounting angle, A1, A2 (a model whose `params` were changed in place
    /// derives them afresh in every call instead of using stale ones).
    key: [f64; 10],
    /// √(2/ρ), √(m³/kg).
    root: f64,
    /// C_d·w_A·√(2/ρ) and C_d·w_B·√(2/ρ), the orifice gains per m of opening.
    ga: f64,
    gb: f64,
    /// 1/√Δp_n, 1/√Pa.
    inv_sqrt_n: f64,
    /// √[`MIN_SLOPE_DROP_PA`], √Pa.
    root_min_slope: f64,
    /// The weight along the stroke, N.
    gravity: f64,
    /// A1/m, A2/m (m²/kg) and −1/m (1/kg).
    a1_m: f64,
    a2_m: f64,
    neg_inv_m: f64,
}

impl Derived {
    fn key(p: &ActuatorParams) -> [f64; 10] {
        let (wa, wb) = p.area_gradients_m2_per_m();
        let (a1, a2) = p.areas_m2();
        [
            p.discharge_coefficient,
            wa,
            wb,
            p.oil_density_kg_m3,
            p.supply_pressure_pa,
            p.return_pressure_pa,
            p.mass_kg,
            p.mounting_angle_rad,
            a1,
            a2,
        ]
    }

    /// The constants of parameters `p`.
    pub(crate) fn of(p: &ActuatorParams) -> Derived {
        let (wa, wb) = p.area_gradients_m2_per_m();
        let (a1, a2) = p.areas_m2();
        let root = (2.0 / p.oil_density_kg_m3).sqrt();
        let m = p.mass_kg;
        Derived {
            key: Self::key(p),
            root,
            ga: p.discharge_coefficient * wa * root,
            gb: p.discharge_coefficient * wb * root,
            inv_sqrt_n: 1.0 / (0.5 * (p.supply_pressure_pa - p.return_pressure_pa)).sqrt(),
            root_min_slope: MIN_SLOPE_DROP_PA.sqrt(),
            gravity: p.gravity_force_n(),
            a1_m: a1 / m,
            a2_m: a2 / m,
            neg_inv_m: -1.0 / m,
        }
    }
}

impl Derived {
    /// The flow law's slope d√|Δp|/dΔp = 1/(2√max(|Δp|, [`MIN_SLOPE_DROP_PA`])), 1/√Pa, from `r` = √|Δp|.
    #[inline(always)]
    fn slope(&self, r: f64) -> f64 {
        0.5 / r.max(self.root_min_slope)
    }
}

/// √|Δp|, √Pa, of a pressure drop `dp` in Pa.
#[inline(always)]
fn root(dp: f64) -> f64 {
    dp.abs().sqrt()
}

/// The pressure drops of the flow laws and their square roots.
#[derive(Clone, Copy)]
struct DropRoots {
    /// p1 − p_r, p2 − p_r and p1 − p2, Pa.
    dp1r: f64,
    dp2r: f64,
    dp12: f64,
    /// √|Δp| of each, √Pa (0 where no law of the layout needs it).
    r1r: f64,
    r2r: f64,
    r12: f64,
}

/// The valve's flows (Q1, Q2), m³/s, and the partials of Q1 and Q2 w.r.t. (x_sp, p1, p2).
struct ValveSlopes {
    q: (f64, f64),
    dq1: [f64; 3],
    dq2: [f64; 3],
}

/// The estimated leaks' flows per unit of their states (10+ states), q = q_n·ssqrt(Δp)/√Δp_n:
/// ssqrt(Δp)/√Δp_n for ext1, ext2 and int (dimensionless); zeros for fewer states.
#[inline(always)]
fn estimated_leak_gains<const N: usize>(d: &Derived, r: &DropRoots) -> (f64, f64, f64) {
    let inv_sqrt_n = d.inv_sqrt_n;
    if N >= 10 {
        (
            signed(r.dp1r, r.r1r) * inv_sqrt_n,
            signed(r.dp2r, r.r2r) * inv_sqrt_n,
            signed(r.dp12, r.r12) * inv_sqrt_n,
        )
    } else {
        (0.0, 0.0, 0.0)
    }
}

/// sgn(Δp)·√|Δp| from √|Δp|.
#[inline]
fn signed(dp_pa: f64, root: f64) -> f64 {
    if dp_pa >= 0.0 {
        root
    } else {
        -root
    }
}

impl ProcessModel {
    /// The parameter constants, from the cache when it was derived from the
    /// parameters as they are now.
    #[inline]
    fn derived(&self) -> Derived {
        if self.derived.key == Derived::key(&self.params) {
            self.derived
        } else {
            Derived::of(&self.params)
        }
    }

    /// The continuous dynamics f(x, u) and ∂f/∂x for a layout of `N` states
    /// (6, 7, 10, 11 or 12), command `u_v` in V.
    pub fn linearise<const N: usize>(&self, s: &SVector<f64, N>, u_v: f64) -> Linearisation<N> {
        let mut lin = Linearisation {
            f: SVector::zeros(),
            a: SMatrix::zeros(),
        };
        self.linearise_into(s, u_v, &mut lin.f, &mut lin.a);
        lin
    }

    /// [`Self::linearise`] into `f` (dx/dt) and `a` (∂f/∂x), which it overwrites.
    ///
    /// Each square root of a pressure drop is taken once: the flow law's
    /// sgn(Δp)·√|Δp| and its slope 1/(2√max(|Δp|, [`MIN_SLOPE_DROP_PA`])) share it
    /// (√ is monotonic and correctly rounded, so √max(a, b) = max(√a, √b) and the
    /// results are those of computing each on its own); the parameter constants
    /// come from the model's cache.
    #[inline(always)]
    pub fn linearise_into<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
        f: &mut SVector<f64, N>,
        a: &mut SMatrix<f64, N, N>,
    ) {
        assert!(
            N == 6 || N == 7 || N == 10 || N == 11 || N == 12,
            "process layouts have 6, 7, 10, 11 or 12 states"
        );
        let d = self.derived();
        let (x_sp, p1, p2) = (s[0], s[1], s[2]);
        f.as_mut_slice().fill(0.0);
        a.as_mut_slice().fill(0.0);

        self.spool_rows(s, u_v, f, a);
        let roots = self.drop_roots::<N>(x_sp, p1, p2);
        let valve = self.valve_flows_and_slopes(&d, &roots, x_sp, p1, p2);
        self.chamber_rows(s, &d, &roots, &valve, f, a);
        self.rod_rows(s, &d, f, a);
    }

    /// Rows 0 and 5 of f and ∂f/∂x: the spool's second-order dynamics (m, m/s)
    /// driven by the command `u_v` (V), with the estimated null bias in layouts of 11+ states.
    #[inline(always)]
    fn spool_rows<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        u_v: f64,
        f: &mut SVector<f64, N>,
        a: &mut SMatrix<f64, N, N>,
    ) {
        let p = &self.params;
        let (x_sp, v_sp) = (s[0], s[5]);
        let wn = p.spool_natural_freq_rad_s;
        f[0] = v_sp;
        a[(0, 5)] = 1.0;
        let bias = self.spool_bias_m(s);
        f[5] = -2.0 * p.spool_damping_ratio * wn * v_sp - wn * wn * (x_sp - bias)
            + p.spool_gain_m_per_v * wn * wn * u_v;
        if N >= 11 {
            a[(5, I_BIAS)] = wn * wn;
        }
        a[(5, 0)] = -wn * wn;
        a[(5, 5)] = -2.0 * p.spool_damping_ratio * wn;
    }

    /// The pressure drops to return and across the piston (Pa) and the square
    /// roots (√Pa) the valve and leak laws of the layout `N` use (0 where none does).
    #[inline(always)]
    fn drop_roots<const N: usize>(&self, x_sp: f64, p1: f64, p2: f64) -> DropRoots {
        let pr = self.params.return_pressure_pa;
        let (dp1r, dp2r, dp12) = (p1 - pr, p2 - pr, p1 - p2);
        let needs_leak_roots = N >= 10;
        let r1r = if needs_leak_roots || x_sp < 0.0 || self.leaks.sqrt_m3_s_sqrt_pa[0] != 0.0 {
            root(dp1r)
        } else {
            0.0
        };
        let r2r = root(dp2r);
        let r12 = if needs_leak_roots || self.leaks.sqrt_m3_s_sqrt_pa[2] != 0.0 {
            root(dp12)
        } else {
            0.0
        };
        DropRoots {
            dp1r,
            dp2r,
            dp12,
            r1r,
            r2r,
            r12,
        }
    }

    /// The valve's flows into chambers 1 and 2 (m³/s) and their partials with
    /// respect to (x_sp, p1, p2): by differences with supply sag, else in closed
    /// form (orifice law on the open lands plus the null leakage).
    #[inline(always)]
    fn valve_flows_and_slopes(&self, d: &Derived, r: &DropRoots, x_sp: f64, p1: f64, p2: f64) -> ValveSlopes {
        let p = &self.params;
        if p.supply_sag_pa_per_m3_s != 0.0 {
            let flows = valve_flows(p, x_sp, p1, p2);
            let (dq1, dq2) = self.valve_partials(x_sp, p1, p2);
            return ValveSlopes {
                q: (flows.q1_m3_s, flows.q2_m3_s),
                dq1,
                dq2,
            };
        }
        let ps = p.supply_pressure_pa;
        let slope = |rt: f64| d.slope(rt);
        let (cd, (wa, wb)) = (p.discharge_coefficient, p.area_gradients_m2_per_m());
        let (ga, gb) = (d.ga, d.gb);
        let (mut q, mut dq1, mut dq2) = if x_sp >= 0.0 {
            // Q1 = g_A x_sp ssqrt(ps − p1), Q2 = g_B x_sp ssqrt(p2 − pr)
            let dps1 = ps - p1;
            let rs1 = root(dps1);
            let (ss1, ss2) = (signed(dps1, rs1), signed(r.dp2r, r.r2r));
            (
                (cd * wa * x_sp * d.root * ss1, cd * wb * x_sp * d.root * ss2),
                [ga * ss1, -ga * x_sp * slope(rs1), 0.0],
                [gb * ss2, 0.0, gb * x_sp * slope(r.r2r)],
            )
        } else {
            // Q1 = g_A x_sp ssqrt(p1 − pr), Q2 = g_B x_sp ssqrt(ps − p2)
            let dps2 = ps - p2;
            let rs2 = root(dps2);
            let (ss1, ss2) = (signed(r.dp1r, r.r1r), signed(dps2, rs2));
            (
                (
                    -(cd * wa * -x_sp * d.root * ss1),
                    -(cd * wb * -x_sp * d.root * ss2),
                ),
                [ga * ss1, ga * x_sp * slope(r.r1r), 0.0],
                [gb * ss2, 0.0, -gb * x_sp * slope(rs2)],
            )
        };
        if p.valve_null_leakage_m3_s_pa > 0.0 {
            let n = null_leakage_flows(p, x_sp, p1, p2);
            q.0 += n.q1_m3_s;
            q.1 += n.q2_m3_s;
            for i in 0..3 {
                dq1[i] += n.dq1[i];
                dq2[i] += n.dq2[i];
            }
        }
        ValveSlopes { q, dq1, dq2 }
    }

    /// The slopes (m³/(s·Pa)) of the leaks built into the model: internal
    /// w.r.t. (p1, p2), ext1 w.r.t. p1, ext2 w.r.t. p2 (index order of LeakSet: ext1, ext2, int).
    #[inline(always)]
    fn leak_partials(&self, d: &Derived, r: &DropRoots) -> LeakPartials {
        let l = &self.leaks;
        let leak_slope = |i: usize, rt: f64| {
            if l.sqrt_m3_s_sqrt_pa[i] == 0.0 {
                l.linear_m3_s_pa[i]
            } else {
                l.linear_m3_s_pa[i] + l.sqrt_m3_s_sqrt_pa[i] * d.slope(rt)
            }
        };
        let d_int = leak_slope(2, r.r12);
        LeakPartials {
            ext1: leak_slope(0, r.r1r),
            ext2: leak_slope(1, r.r2r),
            int: [d_int, -d_int],
        }
    }

    /// Rows 1 and 2 of f and ∂f/∂x: the chamber pressures (Pa/s), from the net
    /// inflow (valve, built-in and estimated leaks, piston displacement) times β/V.
    #[inline(always)]
    fn chamber_rows<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        d: &Derived,
        r: &DropRoots,
        valve: &ValveSlopes,
        f: &mut SVector<f64, N>,
        a: &mut SMatrix<f64, N, N>,
    ) {
        let p = &self.params;
        let (p1, p2, x, v) = (s[1], s[2], s[3], s[4]);
        let (flows, dq1, dq2) = (valve.q, valve.dq1, valve.dq2);
        let lq = self.leaks.flows(p1, p2, p.return_pressure_pa);
        let dl = self.leak_partials(d, r);
        let (a1, a2) = p.areas_m2();
        let (v1, v2) = p.chamber_volumes_m3(x);
        // The 12-state layout scales the oil's stiffness by its estimate θ.
        let theta = if N == 12 { s[I_BULK] } else { 1.0 };
        let (b1_model, b2_model) = (effective_bulk_modulus_pa(p, p1), effective_bulk_modulus_pa(p, p2));
        let (b1, b2) = (theta * b1_model, theta * b2_model);
        let db1 = theta * bulk_slope(p, p1, b1_model);
        let db2 = theta * bulk_slope(p, p2, b2_model);
        let (g1, g2, gi) = estimated_leak_gains::<N>(d, r);
        let (qe1, qe2, qi) = if N >= 10 {
            (s[I_QE1], s[I_QE2], s[I_QI])
        } else {
            (0.0, 0.0, 0.0)
        };
        let net1 = flows.0 - a1 * v - lq.int_m3_s - lq.ext1_m3_s - qe1 * g1 - qi * gi;
        let net2 = a2 * v - flows.1 + lq.int_m3_s - lq.ext2_m3_s - qe2 * g2 + qi * gi;
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
            let inv_sqrt_n = d.inv_sqrt_n;
            let (s1, s2, si) = (
                d.slope(r.r1r) * inv_sqrt_n,
                d.slope(r.r2r) * inv_sqrt_n,
                d.slope(r.r12) * inv_sqrt_n,
            );
            a[(1, 1)] -= b1 / v1 * (qe1 * s1 + qi * si);
            a[(1, 2)] += b1 / v1 * qi * si;
            a[(2, 1)] += b2 / v2 * qi * si;
            a[(2, 2)] -= b2 / v2 * (qe2 * s2 + qi * si);
        }
    }

    /// Rows 3 and 4 of f and ∂f/∂x: the rod's position (m) and its acceleration
    /// (m/s²) from the pressure force, gravity, the end stops and the estimated
    /// external force (7+ states), or the load and friction (the thesis' 6).
    #[inline(always)]
    fn rod_rows<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        d: &Derived,
        f: &mut SVector<f64, N>,
        a: &mut SMatrix<f64, N, N>,
    ) {
        let p = &self.params;
        let (p1, p2, x, v) = (s[1], s[2], s[3], s[4]);
        f[3] = v;
        a[(3, 4)] = 1.0;
        let m = p.mass_kg;
        let gravity = d.gravity;
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
            a[(4, 1)] = d.a1_m;
            a[(4, 2)] = -d.a2_m;
            if dstop_dx != 0.0 || dstop_dv != 0.0 {
                a[(4, 3)] = dstop_dx / m;
                a[(4, 4)] = dstop_dv / m;
            }
            a[(4, I_FE)] = d.neg_inv_m;
        } else {
            self.thesis_acceleration_row(s, d, f, a);
        }
    }

    /// Row 4 of the thesis' 6-state layout: the rod's acceleration (m/s²) from
    /// the pressure force, gravity, the load and friction (sliding, breaking away or stuck).
    #[inline(always)]
    fn thesis_acceleration_row<const N: usize>(
        &self,
        s: &SVector<f64, N>,
        d: &Derived,
        f: &mut SVector<f64, N>,
        a: &mut SMatrix<f64, N, N>,
    ) {
        let p = &self.params;
        let (p1, p2, x, v) = (s[1], s[2], s[3], s[4]);
        let m = p.mass_kg;
        let gravity = d.gravity;
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
            a[(4, 1)] = d.a1_m;
            a[(4, 2)] = -d.a2_m;
            a[(4, 3)] = -dload_dx / m;
            a[(4, 4)] = (-dload_dv - friction_dv(&p.friction, v)) / m;
        } else if friction != drive {
            // breaking away: friction saturated at ±f_st
            a[(4, 1)] = d.a1_m;
            a[(4, 2)] = -d.a2_m;
            a[(4, 3)] = -dload_dx / m;
            a[(4, 4)] = -dload_dv / m;
        }
        // stuck: friction balances the drive, dv/dt = 0 and its row is zero
    }

    /// Partials of the valve's (Q1, Q2) with respect to (x_sp, p1, p2) with
    /// supply sag: central differences of [`valve_flows`] (without sag,
    /// [`Self::linearise_into`] has them in closed form).
    fn valve_partials(&self, x_sp: f64, p1: f64, p2: f64) -> ([f64; 3], [f64; 3]) {
        let p = &self.params;
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
        ([dx.0, d1.0, d2.0], [dx.1, d1.1, d2.1])
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
