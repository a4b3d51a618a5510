//! The continuous dynamics of the actuator (docs/model.md): spool, orifice
//! flows, compressible oil in two chambers, rod with friction, load and end
//! stops, and leaks.
//!
//! The state order is the estimator's, `[x_sp, p1, p2, x, v, v_sp]`
//! (docs/model.md#layouts), so rig and filter states compare index by index.

use crate::friction::friction_force_n;
use crate::leakage::{LeakFlows, LeakLaw, LeakPath};
use crate::params::ActuatorParams;
use crate::units::signed_sqrt;

/// Number of physical states.
pub const N_STATES: usize = 6;
/// Index of the spool position x_sp (m).
pub const I_XSP: usize = 0;
/// Index of the chamber-1 pressure p1 (Pa).
pub const I_P1: usize = 1;
/// Index of the chamber-2 pressure p2 (Pa).
pub const I_P2: usize = 2;
/// Index of the rod position x (m).
pub const I_X: usize = 3;
/// Index of the rod velocity v (m/s).
pub const I_V: usize = 4;
/// Index of the spool velocity v_sp (m/s).
pub const I_VSP: usize = 5;

/// The physical state `[x_sp (m), p1 (Pa), p2 (Pa), x (m), v (m/s), v_sp (m/s)]`.
pub type State = [f64; N_STATES];

/// A state at rest at rod position `x_m` with both chambers at `pressure_pa`.
pub fn state_at_rest(x_m: f64, pressure_pa: f64) -> State {
    [0.0, pressure_pa, pressure_pa, x_m, 0.0, 0.0]
}

/// Leak coefficients in force at one instant, summed per path and law.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LeakSet {
    /// Linear-law coefficients for [ext1, ext2, int], m³/(s·Pa).
    pub linear_m3_s_pa: [f64; 3],
    /// Square-root-law coefficients for [ext1, ext2, int], m³/(s·√Pa).
    pub sqrt_m3_s_sqrt_pa: [f64; 3],
}

impl LeakSet {
    /// No leaks.
    pub const NONE: LeakSet = LeakSet {
        linear_m3_s_pa: [0.0; 3],
        sqrt_m3_s_sqrt_pa: [0.0; 3],
    };

    /// The built-in leaks of a parameter set.
    pub fn from_params(p: &ActuatorParams) -> LeakSet {
        let mut s = LeakSet::NONE;
        for l in &p.leaks {
            s.add(l.path, l.law, l.coefficient);
        }
        s
    }

    /// Adds a coefficient on one path.
    #[inline]
    pub fn add(&mut self, path: LeakPath, law: LeakLaw, coefficient: f64) {
        let i = path_index(path);
        match law {
            LeakLaw::Linear => self.linear_m3_s_pa[i] += coefficient,
            LeakLaw::SquareRoot => self.sqrt_m3_s_sqrt_pa[i] += coefficient,
        }
    }

    /// The leak flows at chamber pressures `p1_pa`, `p2_pa` and return pressure `pr_pa`, m³/s.
    #[inline]
    pub fn flows(&self, p1_pa: f64, p2_pa: f64, pr_pa: f64) -> LeakFlows {
        let mut q = LeakFlows::default();
        for path in LeakPath::ALL {
            let i = path_index(path);
            let (kl, ks) = (self.linear_m3_s_pa[i], self.sqrt_m3_s_sqrt_pa[i]);
            if kl == 0.0 && ks == 0.0 {
                continue;
            }
            let dp = path.pressure_drop_pa(p1_pa, p2_pa, pr_pa);
            q.add(path, kl * dp + ks * signed_sqrt(dp));
        }
        q
    }
}

/// Position of a path in per-path arrays: ext1 0, ext2 1, int 2.
#[inline]
pub fn path_index(path: LeakPath) -> usize {
    match path {
        LeakPath::External1 => 0,
        LeakPath::External2 => 1,
        LeakPath::Internal => 2,
    }
}

/// Valve flows at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ValveFlows {
    /// Flow into chamber 1, m³/s.
    pub q1_m3_s: f64,
    /// Flow out of chamber 2, m³/s.
    pub q2_m3_s: f64,
    /// Supply pressure at the valve after any sag, Pa.
    pub supply_pa: f64,
}

/// Orifice flow through one land with opening `opening_m` (≥ 0), from
/// `p_up_pa` to `p_down_pa`, with supply sag `sag` Pa/(m³/s) applied when the
/// upstream side is the supply. m³/s, signed by the pressure drop.
#[inline]
fn land_flow(
    p: &ActuatorParams,
    gradient_m2_per_m: f64,
    opening_m: f64,
    p_up_pa: f64,
    p_down_pa: f64,
    sag: f64,
) -> f64 {
    let c = p.discharge_coefficient * gradient_m2_per_m * opening_m * (2.0 / p.oil_density_kg_m3).sqrt();
    let dp = p_up_pa - p_down_pa;
    if sag > 0.0 && dp > 0.0 && c > 0.0 {
        // Q = c·sqrt(dp − sag·Q)  ⇒  Q² + c²·sag·Q − c²·dp = 0
        let b = c * c * sag;
        0.5 * (-b + (b * b + 4.0 * c * c * dp).sqrt())
    } else {
        c * signed_sqrt(dp)
    }
}

/// The null leakage of an underlapped valve (docs/plant.md, "Valve null
/// leakage"): each metering land passes C_L·λ·Δp (laminar), with λ = 1 while the
/// land is open and fading linearly to 0 as the land closes over the underlap
/// x_u. The port-B lands pass C_L·w_B/w_A (a matched valve's narrower
/// lands). Returns (flow into chamber 1, flow out of chamber 2), m³/s, and their
/// partials with respect to (x_sp, p1, p2), in m³/s per m, per Pa, per Pa.
#[inline]
pub fn null_leakage_flows(p: &ActuatorParams, x_sp_m: f64, p1_pa: f64, p2_pa: f64) -> NullLeakage {
    let c = p.valve_null_leakage_m3_s_pa;
    // The port-B lands of a matched valve are narrower: their conductance is
    // C_L·w_B/w_A (the same land geometry over a shorter width).
    let (wa, wb) = p.area_gradients_m2_per_m();
    let cb = if wb == wa { c } else { c * wb / wa };
    let (ps, pr, xu) = (p.supply_pressure_pa, p.return_pressure_pa, p.valve_underlap_m);
    // P→A and B→T open with x_sp > 0; A→T and P→B close.
    let z = x_sp_m / xu;
    let (open, d_open) = if z <= -1.0 {
        (0.0, 0.0)
    } else if z < 0.0 {
        (1.0 + z, 1.0 / xu)
    } else {
        (1.0, 0.0)
    };
    let (close, d_close) = if z >= 1.0 {
        (0.0, 0.0)
    } else if z > 0.0 {
        (1.0 - z, -1.0 / xu)
    } else {
        (1.0, 0.0)
    };
    NullLeakage {
        q1_m3_s: c * (open * (ps - p1_pa) - close * (p1_pa - pr)),
        q2_m3_s: cb * (open * (p2_pa - pr) - close * (ps - p2_pa)),
        dq1: [
            c * (d_open * (ps - p1_pa) - d_close * (p1_pa - pr)),
            -c * (open + close),
            0.0,
        ],
        dq2: [
            cb * (d_open * (p2_pa - pr) - d_close * (ps - p2_pa)),
            0.0,
            cb * (open + close),
        ],
    }
}

/// The valve's null leakage at one instant ([`null_leakage_flows`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NullLeakage {
    /// Flow into chamber 1, m³/s.
    pub q1_m3_s: f64,
    /// Flow out of chamber 2, m³/s.
    pub q2_m3_s: f64,
    /// ∂q1/∂(x_sp, p1, p2): m³/s per m, per Pa, per Pa.
    pub dq1: [f64; 3],
    /// ∂q2/∂(x_sp, p1, p2): m³/s per m, per Pa, per Pa.
    pub dq2: [f64; 3],
}

/// Valve flows for spool position `x_sp_m` and chamber pressures (docs/model.md#orifice-flows,
/// critical centre, signed square root), plus the null leakage of an
/// underlapped valve when the parameters have one ([`null_leakage_flows`]).
#[inline]
pub fn valve_flows(p: &ActuatorParams, x_sp_m: f64, p1_pa: f64, p2_pa: f64) -> ValveFlows {
    let mut f = orifice_flows(p, x_sp_m, p1_pa, p2_pa);
    if p.valve_null_leakage_m3_s_pa > 0.0 {
        let n = null_leakage_flows(p, x_sp_m, p1_pa, p2_pa);
        f.q1_m3_s += n.q1_m3_s;
        f.q2_m3_s += n.q2_m3_s;
    }
    f
}

/// The metering orifices' flows (critical centre, signed square root, supply
/// sag), without the null leakage: (flow into chamber 1, out of chamber 2), m³/s.
#[inline]
pub fn orifice_flows(p: &ActuatorParams, x_sp_m: f64, p1_pa: f64, p2_pa: f64) -> ValveFlows {
    let ps = p.supply_pressure_pa;
    let pr = p.return_pressure_pa;
    let sag = p.supply_sag_pa_per_m3_s;
    let (wa, wb) = p.area_gradients_m2_per_m();
    if x_sp_m >= 0.0 {
        let q1 = land_flow(p, wa, x_sp_m, ps, p1_pa, sag);
        let q2 = land_flow(p, wb, x_sp_m, p2_pa, pr, 0.0);
        ValveFlows {
            q1_m3_s: q1,
            q2_m3_s: q2,
            supply_pa: ps - sag * q1.max(0.0),
        }
    } else {
        let q1 = -land_flow(p, wa, -x_sp_m, p1_pa, pr, 0.0);
        let q2 = -land_flow(p, wb, -x_sp_m, ps, p2_pa, sag);
        ValveFlows {
            q1_m3_s: q1,
            q2_m3_s: q2,
            supply_pa: ps - sag * (-q2).max(0.0),
        }
    }
}

/// Effective bulk modulus at gauge pressure `p_pa`, Pa: the oil's β lowered by
/// entrained air (isothermal), 1/β_eff = 1/β + ε₀·p_atm/p_abs².
#[inline]
pub fn effective_bulk_modulus_pa(p: &ActuatorParams, p_pa: f64) -> f64 {
    if p.entrained_air_fraction == 0.0 {
        return p.bulk_modulus_pa;
    }
    const P_ATM: f64 = 101_325.0;
    let p_abs = (p_pa + P_ATM).max(0.2 * P_ATM);
    1.0 / (1.0 / p.bulk_modulus_pa + p.entrained_air_fraction * P_ATM / (p_abs * p_abs))
}

/// Everything the right-hand side computes besides the derivative, for sensors and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Forces {
    /// Valve flows.
    pub valve: ValveFlows,
    /// Leak flows along the three paths, m³/s.
    pub leaks: LeakFlows,
    /// Friction force, N (positive opposes extension).
    pub friction_n: f64,
    /// External (spring) load force, N (positive opposes extension).
    pub load_n: f64,
    /// End-stop force, N (positive pushes towards extension).
    pub end_stop_n: f64,
}

/// Time constant with which stiction pulls a residual velocity inside the
/// stick band to zero in the rig simulator, s. (The estimator's model keeps
/// the plain Karnopp form, docs/model.md#friction.)
pub const STICK_VELOCITY_DECAY_S: f64 = 5.0e-4;

/// Force of the end stops on the rod at position `x` m and velocity `v` m/s, N
/// (a stiff spring-damper beyond each end of the stroke, 0 inside it).
pub fn end_stop_force_n(p: &ActuatorParams, x: f64, v: f64) -> f64 {
    if x < p.x_min_m {
        p.end_stop_stiffness_n_per_m * (p.x_min_m - x) - p.end_stop_damping_n_s_per_m * v.min(0.0)
    } else if x > p.x_max_m {
        -p.end_stop_stiffness_n_per_m * (x - p.x_max_m) - p.end_stop_damping_n_s_per_m * v.max(0.0)
    } else {
        0.0
    }
}

/// The slopes of [`end_stop_force_n`]: (∂F/∂x N/m, ∂F/∂v N·s/m); zero inside the stroke.
pub fn end_stop_slopes(p: &ActuatorParams, x: f64, v: f64) -> (f64, f64) {
    let (k, c) = (p.end_stop_stiffness_n_per_m, p.end_stop_damping_n_s_per_m);
    if x < p.x_min_m {
        (-k, if v < 0.0 { -c } else { 0.0 })
    } else if x > p.x_max_m {
        (-k, if v > 0.0 { -c } else { 0.0 })
    } else {
        (0.0, 0.0)
    }
}

/// The continuous right-hand side dx/dt for state `s`, command `u_v` (V) and
/// leaks `leaks`; returns the derivative and the forces and flows behind it.
#[inline]
pub fn derivative(p: &ActuatorParams, s: &State, u_v: f64, leaks: &LeakSet) -> (State, Forces) {
    let [x_sp, p1, p2, x, v, v_sp] = *s;
    let wn = p.spool_natural_freq_rad_s;
    let a_sp = -2.0 * p.spool_damping_ratio * wn * v_sp - wn * wn * (x_sp - p.spool_null_bias_m)
        + p.spool_gain_m_per_v * wn * wn * u_v;

    let valve = valve_flows(p, x_sp, p1, p2);
    let lq = leaks.flows(p1, p2, p.return_pressure_pa);
    let (v1, v2) = p.chamber_volumes_m3(x);
    let (a1, a2) = p.areas_m2();
    let dp1 = effective_bulk_modulus_pa(p, p1) / v1 * (valve.q1_m3_s - a1 * v - lq.int_m3_s - lq.ext1_m3_s);
    let dp2 = effective_bulk_modulus_pa(p, p2) / v2 * (a2 * v - valve.q2_m3_s + lq.int_m3_s - lq.ext2_m3_s);

    let load = p.load.force_n(x, v);
    let end_stop = end_stop_force_n(p, x, v);
    let drive = p.pressure_force_n(p1, p2) - p.gravity_force_n() - load + end_stop;
    let mut friction = friction_force_n(&p.friction, v, drive);
    if v.abs() <= p.friction.zero_velocity_m_s && friction == drive {
        // stuck: stiction also removes the residual creep velocity, within f_st
        let hold = drive + p.mass_kg * v / STICK_VELOCITY_DECAY_S;
        let limit = p.friction.for_direction(drive).static_n;
        friction = hold.clamp(-limit, limit);
    }
    let a = (drive - friction) / p.mass_kg;

    (
        [v_sp, dp1, dp2, v, a, a_sp],
        Forces {
            valve,
            leaks: lq,
            friction_n: friction,
            load_n: load,
            end_stop_n: end_stop,
        },
    )
}

/// One classical fourth-order Runge–Kutta step of size `dt_s` for any
/// right-hand side over `N` states.
#[inline]
pub fn rk4_step<const N: usize>(
    y: &[f64; N],
    dt_s: f64,
    mut f: impl FnMut(&[f64; N]) -> [f64; N],
) -> [f64; N] {
    let add = |a: &[f64; N], b: &[f64; N], h: f64| -> [f64; N] {
        let mut r = *a;
        for i in 0..N {
            r[i] += h * b[i];
        }
        r
    };
    let k1 = f(y);
    let k2 = f(&add(y, &k1, 0.5 * dt_s));
    let k3 = f(&add(y, &k2, 0.5 * dt_s));
    let k4 = f(&add(y, &k3, dt_s));
    let mut r = *y;
    for i in 0..N {
        r[i] += dt_s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An underlapped valve at null with its ports blocked passes the catalogue's
    /// internal leakage C_L·p_s from supply to tank, and no flow into either
    /// chamber at p_s/2; beyond the underlap only the open lands leak.
    #[test]
    fn null_leakage_is_a_laminar_bridge_that_closes_with_the_spool() {
        let p = ActuatorParams {
            valve_null_leakage_m3_s_pa: 1e-13,
            valve_underlap_m: 5e-6,
            supply_pressure_pa: 21e6,
            ..ActuatorParams::default()
        };
        let half = 10.5e6;
        let n = null_leakage_flows(&p, 0.0, half, half);
        assert_eq!((n.q1_m3_s, n.q2_m3_s), (0.0, 0.0));
        // Chamber 1 above p_s/2 at null: it drains (A→T passes more than P→A).
        let n = null_leakage_flows(&p, 0.0, 15e6, half);
        assert!((n.q1_m3_s - 1e-13 * ((21e6 - 15e6) - 15e6)).abs() < 1e-20);
        // Past the underlap the closing lands (A→T, P→B) pass nothing.
        let n = null_leakage_flows(&p, 6e-6, 15e6, 5e6);
        assert!((n.q1_m3_s - 1e-13 * (21e6 - 15e6)).abs() < 1e-20);
        assert!((n.q2_m3_s - 1e-13 * 5e6).abs() < 1e-20);
        // Half-way: the closing lands pass half.
        let n = null_leakage_flows(&p, 2.5e-6, 15e6, 5e6);
        assert!((n.q1_m3_s - 1e-13 * ((21e6 - 15e6) - 0.5 * 15e6)).abs() < 1e-20);
        // valve_flows adds it to the orifices' flows; without it nothing changes.
        let plain = ActuatorParams {
            valve_null_leakage_m3_s_pa: 0.0,
            ..p.clone()
        };
        let (a, b) = (
            valve_flows(&p, 2e-6, 15e6, 5e6),
            valve_flows(&plain, 2e-6, 15e6, 5e6),
        );
        let n = null_leakage_flows(&p, 2e-6, 15e6, 5e6);
        assert_eq!(a.q1_m3_s, b.q1_m3_s + n.q1_m3_s);
        assert_eq!(a.q2_m3_s, b.q2_m3_s + n.q2_m3_s);
    }

    use crate::units::m3_s_to_lpm;

    #[test]
    fn rated_flow_at_full_command() {
        // docs/model.md#parameters: 10 V at a 10.35 MPa drop per land gives about 33 L/min.
        let p = ActuatorParams::default();
        let x_sp = 10.0 * p.spool_gain_m_per_v;
        let ps = p.supply_pressure_pa;
        let p1 = ps - 10.35e6;
        let f = valve_flows(&p, x_sp, p1, 10.35e6);
        let q1 = m3_s_to_lpm(f.q1_m3_s);
        assert!((q1 - 33.0).abs() < 1.0, "{q1} L/min");
        assert!((f.q1_m3_s - f.q2_m3_s).abs() < 1e-12);
        // negative spool reverses both flows
        let r = valve_flows(&p, -x_sp, 10.35e6, p1);
        assert!((r.q1_m3_s + f.q1_m3_s).abs() < 1e-12);
        assert!((r.q2_m3_s + f.q2_m3_s).abs() < 1e-12);
    }

    #[test]
    fn pressure_above_supply_flows_back() {
        let p = ActuatorParams::default();
        let f = valve_flows(&p, 1e-4, p.supply_pressure_pa + 1e6, 1e6);
        assert!(f.q1_m3_s < 0.0 && f.q1_m3_s.is_finite());
    }

    #[test]
    fn supply_sag_solves_the_implicit_flow() {
        let p = ActuatorParams {
            supply_sag_pa_per_m3_s: 2e10,
            ..ActuatorParams::default()
        };
        let f = valve_flows(&p, 2e-4, 5e6, 5e6);
        let c = 0.6 * 2.075e-2 * 2e-4 * (2.0f64 / 847.15).sqrt();
        let implied = c * (p.supply_pressure_pa - 2e10 * f.q1_m3_s - 5e6).sqrt();
        assert!((implied - f.q1_m3_s).abs() < 1e-12 * f.q1_m3_s.abs().max(1e-9));
        assert!(f.supply_pa < p.supply_pressure_pa);
    }

    #[test]
    fn centred_valve_at_rest_is_an_equilibrium() {
        let p = ActuatorParams::default();
        let s = state_at_rest(0.3, 6.9e6);
        let (d, _) = derivative(&p, &s, 0.0, &LeakSet::NONE);
        assert!(d.iter().all(|v| *v == 0.0), "{d:?}");
    }

    #[test]
    fn air_lowers_bulk_modulus_most_at_low_pressure() {
        let p = ActuatorParams {
            entrained_air_fraction: 0.01,
            ..ActuatorParams::default()
        };
        let lo = effective_bulk_modulus_pa(&p, 1e6);
        let hi = effective_bulk_modulus_pa(&p, 10e6);
        assert!(lo < hi && hi < p.bulk_modulus_pa);
        assert_eq!(effective_bulk_modulus_pa(&ActuatorParams::default(), 1e6), 6.89e8);
    }

    #[test]
    fn rk4_is_fourth_order_on_exponential() {
        let exact = (-1.0f64).exp();
        let run = |n: usize| {
            let mut y = [1.0];
            for _ in 0..n {
                y = rk4_step(&y, 1.0 / n as f64, |y| [-y[0]]);
            }
            (y[0] - exact).abs()
        };
        let ratio = run(10) / run(20);
        assert!(ratio > 14.0 && ratio < 18.0, "{ratio}");
    }
}
