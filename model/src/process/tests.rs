use super::*;
use crate::dynamics::valve_flows;
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
    assert!(check_jacobian::<12>(&m, Band::Sliding, inside, 8).0 > 250);
    // Entrained air: the oil's stiffness depends on pressure, and θ scales it.
    let airy = ProcessModel::new(
        ActuatorParams {
            entrained_air_fraction: 0.01,
            ..p.clone()
        },
        1e-3,
    );
    assert!(check_jacobian::<12>(&airy, Band::Sliding, inside, 9).0 > 250);
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
        (
            12,
            check_jacobian::<12>(&m, Band::Sliding, Pressures::NearTank, 26),
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

    // A vertical single-rod lift: two areas, a port-B gradient matched to them,
    // the load's weight on the rod (and the rod chamber's smaller volume).
    let lift = ProcessModel::new(ActuatorParams::vertical_lift(), 1e-3);
    assert!(check_jacobian::<6>(&lift, Band::Sliding, inside, 61).0 > 250);
    assert!(check_jacobian::<6>(&lift, Band::Stick, inside, 62).0 > 250);
    assert!(check_jacobian::<7>(&lift, Band::Sliding, Pressures::Mixed, 63).0 > 200);
    assert!(check_jacobian::<12>(&lift, Band::Sliding, inside, 64).0 > 250);
    assert!(check_jacobian::<12>(&lift, Band::Sliding, Pressures::NearTank, 65).0 > 200);

    // An underlapped valve's null leakage: inside the underlap (x_u 1e-4 m > every
    // drawn spool position) and mostly beyond it (x_u 5 µm), at a conductance that
    // passes about the orifice's flow at a 10 µm opening.
    for (xu, seed) in [(1e-4, 51), (5e-6, 52)] {
        let lapped = ProcessModel::new(
            ActuatorParams {
                valve_null_leakage_m3_s_pa: 1e-12,
                valve_underlap_m: xu,
                ..ActuatorParams::default()
            },
            1e-3,
        );
        assert!(check_jacobian::<7>(&lapped, Band::Sliding, inside, seed).0 > 250);
        assert!(check_jacobian::<12>(&lapped, Band::Sliding, Pressures::Mixed, seed + 10).0 > 200);
    }
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
            (
                12,
                check_step_jacobian::<12>(&m, Band::Sliding, Pressures::Inside, 56),
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
            if substeps == 1 && n < 10 {
                // one forward Euler step: the product is the single linearisation
                assert_eq!(one_step_fails, 0);
            } else {
                // sub-steps, or the symplectic step of the layouts with leaks:
                // F is not I + T·A(x(k)), and the test can tell
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

/// The end stops are in the model as the rig has them (a spring-damper beyond
/// each end of the stroke): pressed δ into a stop and moving in at 1 mm/s, the
/// rod's acceleration is (A(p1 − p2) − F_e ∓ (k·δ + c·|v|))/m with its slopes
/// −k/m and −c/m in A; the step there takes [`STOP_SUBSTEPS`] sub-steps, and its
/// Jacobian matches central differences of the step to 0.1 % (10 and 12 states;
/// both stops; the stiff stop makes the differences themselves that coarse).
/// A single 1 ms Euler step could not follow the stop: its modes are near −3000 1/s.
#[test]
fn the_end_stops_are_in_the_model_and_stepped_finely() {
    fn check<const N: usize>() {
        let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
        let p = &m.params;
        let (k, c, area, mass) = (
            p.end_stop_stiffness_n_per_m,
            p.end_stop_damping_n_s_per_m,
            p.piston_area_m2,
            p.mass_kg,
        );
        // pressed in as far as the pressures push it (k·δ = A·Δp − F_e), still moving in at 1 mm/s
        let depth = (area * 6.0e6 - 500.0) / k;
        for (x, v, p1, p2, push) in [
            (p.x_max_m + depth, 1e-3, 9.0e6, 3.0e6, -1.0),
            (p.x_min_m - depth, -1e-3, 3.0e6, 9.0e6, 1.0),
        ] {
            let mut s = SVector::<f64, N>::zeros();
            s[1] = p1;
            s[2] = p2;
            s[3] = x;
            s[4] = v;
            s[I_FE] = 500.0;
            // the spool held 0.2 V open (off its sign switch at null, where the valve law has a kink)
            s[0] = 0.2 * p.spool_gain_m_per_v;
            if N == 12 {
                s[I_BULK] = 1.0;
            }
            let lin = m.linearise(&s, 0.2);
            let expected = (area * (p1 - p2) - 500.0 + push * (k * depth + c * 1e-3)) / mass;
            assert!(
                (lin.f[4] - expected).abs() < 1e-9 * expected.abs(),
                "{N}: {} vs {expected}",
                lin.f[4]
            );
            assert_eq!(lin.a[(4, 3)], -k / mass);
            assert_eq!(lin.a[(4, 4)], -c / mass);
            // The step's Jacobian, on a stop without its damper (the damper acts only
            // while the rod moves into the stop: a kink at v = 0, which the rod
            // crosses within the step as it settles)
            let undamped = ProcessModel::new(
                ActuatorParams {
                    end_stop_damping_n_s_per_m: 0.0,
                    ..p.clone()
                },
                1e-3,
            );
            let (next, an, guard) = undamped.step(&s, 0.2);
            assert!(!guard.any(), "{guard:?} {next:?}");
            let fd = fd_step_jacobian(&undamped, &s, 0.2);
            let ratio = worst_step_ratio(&an, &fd, &next, STOP_SUBSTEPS, 1e-3);
            assert!(
                ratio <= 1.0,
                "N={N} at x {x}: error {ratio} times the allowed\n{an:e}\n{fd:e}"
            );
            // one Euler step of 1 ms would put I + T·A's position-velocity block far
            // outside the unit circle (T²·k/m = 10)
            let single = SMatrix::<f64, N, N>::identity() + lin.a * m.dt_s;
            assert!(single[(4, 3)].abs() * m.dt_s > 5.0, "{single:e}");
            // and its position-velocity block (complex eigenvalues, |λ|² = det = 5) would
            // more than double an error every sample
            let block = single.fixed_view::<2, 2>(3, 3).into_owned();
            assert!(block.determinant().abs() > 4.0, "{block}");
        }
        // inside the stroke the stop adds nothing
        let mut s = SVector::<f64, N>::zeros();
        s[3] = 0.3;
        s[4] = 0.1;
        if N == 12 {
            s[I_BULK] = 1.0;
        }
        let lin = m.linearise(&s, 0.0);
        assert_eq!((lin.a[(4, 3)], lin.a[(4, 4)]), (0.0, 0.0));
    }
    check::<10>();
    check::<12>();
    // the thesis' 7-state layout keeps the thesis' model, without stops
    let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
    let mut s7 = SVector::<f64, 7>::zeros();
    s7[3] = m.params.x_max_m + 1e-3;
    s7[4] = 0.1;
    let lin = m.linearise(&s7, 0.0);
    assert_eq!((lin.f[4], lin.a[(4, 3)], lin.a[(4, 4)]), (0.0, 0.0, 0.0));
}

/// The velocity's part of θ's column is what the column loses when v is 0:
/// a step's ∂(p1, p2)/∂θ at v minus the same at v = 0 (one sub-step, in stroke).
#[test]
fn bulk_column_from_velocity_is_the_velocity_term_of_the_step_jacobian() {
    let m = ProcessModel::new(ActuatorParams::vertical_lift(), 1e-3);
    let mut s = SVector::<f64, 12>::zeros();
    s[0] = 2e-6;
    s[1] = 8.5e6;
    s[2] = 12.5e6;
    s[3] = 0.2;
    s[4] = 0.05;
    s[11] = 0.9;
    let (_, f, _) = m.step(&s, 0.5);
    let mut still = s;
    still[4] = 0.0;
    let (_, f0, _) = m.step(&still, 0.5);
    let (c1, c2) = m.bulk_column_from_velocity(&s);
    for (row, c) in [(1, c1), (2, c2)] {
        let want = f[(row, I_BULK)] - f0[(row, I_BULK)];
        assert!(
            (c - want).abs() <= 1e-9 * want.abs(),
            "row {row}: {c} against {want}"
        );
        assert!(c.abs() > 1e3, "row {row}: {c} Pa per unit θ");
    }
}

#[test]
fn the_random_walk_states_step_as_they_are() {
    // x(k+1) = x(k) and rows of the identity in F, exactly: in free travel
    // (one Euler step) and in an end stop (the product of sub-steps).
    fn check<const N: usize>(m: &ProcessModel, rng: &mut Rng) -> usize {
        let mut in_stop = 0;
        for k in 0..200 {
            let band = if k % 2 == 0 { Band::Sliding } else { Band::Stick };
            let mut s = random_state::<N>(rng, &m.params, band, Pressures::Mixed);
            if k % 4 == 3 {
                s[3] = m.params.x_max_m + 1e-4;
            } else if k % 4 == 1 {
                s[3] = m.params.x_min_m - 1e-4;
            }
            in_stop += usize::from(s[3] > m.params.x_max_m || s[3] < m.params.x_min_m);
            let u = rng.uniform_in(-10.0, 10.0);
            let (x, f, _) = m.step(&s, u);
            for r in FIRST_RANDOM_WALK..N {
                assert_eq!(x[r].to_bits(), s[r].to_bits(), "{N} states: state {r} moved");
                for c in 0..N {
                    let identity = if r == c { 1.0 } else { 0.0 };
                    assert!(f[(r, c)] == identity, "{N} states: F[{r}][{c}] = {}", f[(r, c)]);
                }
            }
            // the other rows are not the identity's (the check can tell)
            assert!(f[(4, 1)] != 0.0, "{N} states: F[4][1] = 0");
        }
        in_stop
    }
    let p = ActuatorParams::default();
    let mut rng = Rng::new(71);
    for substeps in [1, 4] {
        let mut m = ProcessModel::new(p.clone(), 1e-3);
        m.substeps = substeps;
        assert_eq!(check::<7>(&m, &mut rng), 100);
        assert_eq!(check::<10>(&m, &mut rng), 100);
        assert_eq!(check::<11>(&m, &mut rng), 100);
        assert_eq!(check::<12>(&m, &mut rng), 100);
    }
}

/// The hydraulic mode (the oil's stiffness against the moving mass) without
/// damping: the symplectic step of the layouts with leaks keeps its amplitude,
/// the forward Euler step of the thesis' layouts lets it grow by
/// √(1 + (ωT)²) per step (the lift at mid-stroke: ω ≈ 270 rad/s, ×1.036).
#[test]
fn the_symplectic_step_keeps_an_undamped_hydraulic_mode_and_forward_euler_grows_it() {
    let mut p = ActuatorParams::vertical_lift();
    p.friction.static_n = 0.0;
    p.friction.slip_n = 0.0;
    p.friction.viscous_n_s_per_m = 0.0;
    p.valve_null_leakage_m3_s_pa = 0.0;
    p.valve_underlap_m = 0.0;
    let m = ProcessModel::new(p, 1e-3);
    fn growth<const N: usize>(m: &ProcessModel) -> f64 {
        let mut s = SVector::<f64, N>::zeros();
        (s[1], s[2], s[3]) = (8.0e6, 12.0e6, 0.2);
        // the load that holds the rod at rest at these pressures, then 50 kPa more in chamber 1
        let lin = m.linearise(&s, 0.0);
        s[I_FE] -= lin.f[4] / lin.a[(4, I_FE)];
        assert!(m.linearise(&s, 0.0).f[4].abs() < 1e-9);
        s[1] += 50e3;
        let (mut first, mut last) = (0.0f64, 0.0f64);
        for k in 0..500 {
            let (next, _, guard) = m.step(&s, 0.0);
            if guard.any() {
                // grown to a clamp (a pressure at 0 or past the supply)
                return f64::INFINITY;
            }
            s = next;
            let dp = (s[1] - 8.0e6).abs();
            if k < 100 {
                first = first.max(dp);
            } else if k >= 400 {
                last = last.max(dp);
            }
        }
        last / first
    }
    let symplectic = growth::<10>(&m);
    let forward = growth::<7>(&m);
    assert!(
        (0.8..1.25).contains(&symplectic),
        "symplectic: amplitude ×{symplectic}"
    );
    assert!(forward > 100.0, "forward Euler: amplitude ×{forward}");
}
