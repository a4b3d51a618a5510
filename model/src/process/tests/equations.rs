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

/// Transducers at the manifold read the chambers plus the line's drop: with
/// the spool open to extend, p1 reads R·Q1 above chamber 1 and p2 reads R·Q2
/// below chamber 2, Q the orifice law's flows (C_d·w·x_sp·√(2Δp/ρ), worked
/// out here); with R = 0 the reading is the chambers'.
#[test]
fn manifold_transducers_read_the_lines_drop() {
    let r = 2e8;
    let p = ActuatorParams {
        line_resistance_pa_s_per_m3: r,
        ..ActuatorParams::default()
    };
    let (ps, rho, cd, w) = (
        p.supply_pressure_pa,
        p.oil_density_kg_m3,
        p.discharge_coefficient,
        p.area_gradient_m2_per_m,
    );
    let (x_sp, p1, p2) = (1e-4, 6e6, 4e6);
    let s = SVector::<f64, 10>::from([x_sp, p1, p2, 0.3, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let q1 = cd * w * x_sp * (2.0 * (ps - p1) / rho).sqrt();
    let q2 = cd * w * x_sp * (2.0 * p2 / rho).sqrt();
    let y = ProcessModel::new(p.clone(), 1e-3).read(&s);
    assert_eq!(y[0], 0.3);
    assert!(
        (y[1] - (p1 + r * q1)).abs() < 1e-6 * r * q1,
        "{} against {}",
        y[1],
        p1 + r * q1
    );
    assert!(
        (y[2] - (p2 - r * q2)).abs() < 1e-6 * r * q2,
        "{} against {}",
        y[2],
        p2 - r * q2
    );
    // tens of kPa a third of the way open (a manifold shows 0.1-0.2 MPa at full flow)
    assert!(r * q1 > 2e4 && r * q1 < 5e4, "{}", r * q1);
    let at_ports = ProcessModel::new(ActuatorParams::default(), 1e-3);
    assert_eq!(at_ports.read(&s), ProcessModel::measure(&s));
}
