//! The process model's unit tests: the helpers they share (random states, finite
//! differences, the Jacobian comparison); the tests in the submodules.

use super::*;
use crate::dynamics::valve_flows;
use crate::rng::Rng;

mod continuous_jacobian;
mod discrete_jacobian;
mod equations;
mod stepping;

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
    // inside the stroke, clear of the stops (0.05-0.55 m on the thesis rig)
    s[3] = rng.uniform_in(p.x_min_m + 0.05, 0.55f64.min(p.x_max_m - 0.05));
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
    if N >= 11 {
        s[I_BIAS] = rng.uniform_in(-1e-5, 1e-5);
    }
    if N == 12 {
        s[I_BULK] = rng.uniform_in(0.6, 1.2);
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
const SCALE: [f64; 12] = [1e-5, 1e6, 1e6, 0.1, 0.1, 0.01, 1e3, 1e-5, 1e-5, 1e-5, 1e-6, 1.0];

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

/// Steps of [`fd_step_jacobian`], per state.
const STEP_FD_STEPS: [f64; 12] = [
    1e-9, 1.0, 1.0, 1e-7, 1e-7, 1e-7, 1e-2, 1e-10, 1e-10, 1e-10, 1e-10, 1e-7,
];

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
