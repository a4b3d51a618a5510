//! The right-hand side at chosen states: equilibrium, the leak states' flows, the guard.

use super::*;

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
