//! The continuous Jacobian A against central differences, on every branch and rig.

use super::*;
use crate::leakage::{LeakLaw, LeakPath};
use crate::params::BuiltInLeak;

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
