//! At rest and in balance: the centred valve, friction's stiction and break-away, mass balance.

use model::dynamics::{derivative, rk4_step, state_at_rest, LeakSet, I_P1, I_P2, I_X};
use model::leakage::{LeakLaw, LeakPath};
use model::params::{ActuatorParams, FrictionPreset};
use model::sim::advance;

#[test]
fn centred_valve_holds_pressures_and_position() {
    let p = ActuatorParams::default();
    let mut s = state_at_rest(0.25, 6.9e6);
    for _ in 0..2000 {
        s = advance(&p, &s, 0.0, &LeakSet::NONE, 1e-3, 40);
    }
    assert_eq!(s, state_at_rest(0.25, 6.9e6));
    // unequal pressures whose force is below stiction: sealed chambers, rod held
    let mut s = [0.0, 8.4e6, 5.4e6, 0.25, 0.0, 0.0]; // A·Δp = 1899 N < 2400 N
    for _ in 0..1000 {
        s = advance(&p, &s, 0.0, &LeakSet::NONE, 1e-3, 40);
    }
    assert!((s[I_X] - 0.25).abs() < 1e-9, "rod moved {} m", s[I_X] - 0.25);
    assert!((s[I_P1] - 8.4e6).abs() < 1.0 && (s[I_P2] - 5.4e6).abs() < 1.0);
}

#[test]
fn friction_holds_below_stiction_and_breaks_away_above() {
    let p = ActuatorParams::default();
    // valve open a little: drive ramps slowly; rod stays put until A·Δp reaches f_st
    let mut s = state_at_rest(0.3, 6.9e6);
    let mut moved_at_force = None;
    for k in 0..3000 {
        s = advance(&p, &s, 0.02, &LeakSet::NONE, 1e-3, 40);
        let force = p.piston_area_m2 * (s[I_P1] - s[I_P2]);
        if (s[I_X] - 0.3).abs() > 1e-6 && moved_at_force.is_none() {
            moved_at_force = Some((k, force));
        }
        if moved_at_force.is_none() {
            assert!(force < 2400.0 + 50.0, "held at {force} N");
        }
    }
    let (_, f) = moved_at_force.expect("the rod never broke away");
    assert!(
        (f - 2400.0).abs() < 150.0,
        "broke away at {f} N, expected about f_st = 2400 N"
    );
}

#[test]
fn mass_balance_over_a_run() {
    mass_balance(ActuatorParams::default().with_friction_preset(FrictionPreset::Smooth));
    // a vertical single-rod lift: the two chambers change volume at A1·v and A2·v
    mass_balance(ActuatorParams::vertical_lift());
}

fn mass_balance(mut p: ActuatorParams) {
    // Integrate, alongside the state, the reference-density oil volume that flowed
    // into each chamber: d/dt(V·e^{(p−p0)/β}) = e^{(p−p0)/β}·Q_net exactly for this model.
    p.leaks.push(model::params::BuiltInLeak {
        path: LeakPath::Internal,
        law: LeakLaw::SquareRoot,
        coefficient: 3e-9,
    });
    p.leaks.push(model::params::BuiltInLeak {
        path: LeakPath::External1,
        law: LeakLaw::Linear,
        coefficient: 1e-12,
    });
    let leaks = LeakSet::from_params(&p);
    let beta = p.bulk_modulus_pa;
    let p0 = 6.9e6;
    let mass = |s: &[f64; 8]| {
        let (v1, v2) = p.chamber_volumes_m3(s[I_X]);
        (
            v1 * ((s[I_P1] - p0) / beta).exp(),
            v2 * ((s[I_P2] - p0) / beta).exp(),
        )
    };
    let mut y = [0.0; 8];
    y[..6].copy_from_slice(&state_at_rest(0.3, p0));
    let (m1_0, m2_0) = mass(&y);
    let h = 25e-6;
    let mut inflow = (0.0f64, 0.0f64);
    for k in 0..(2.0 / h) as usize {
        let u = 3.0 * (2.0 * std::f64::consts::PI * (k as f64 * h) + 0.1).sin();
        y = rk4_step(&y, h, |z| {
            let s: [f64; 6] = z[..6].try_into().unwrap();
            let (d, f) = derivative(&p, &s, u, &leaks);
            let q1 = f.valve.q1_m3_s - f.leaks.int_m3_s - f.leaks.ext1_m3_s;
            let q2 = -f.valve.q2_m3_s + f.leaks.int_m3_s - f.leaks.ext2_m3_s;
            let mut out = [0.0; 8];
            out[..6].copy_from_slice(&d);
            out[6] = ((z[I_P1] - p0) / beta).exp() * q1;
            out[7] = ((z[I_P2] - p0) / beta).exp() * q2;
            out
        });
        inflow.0 = inflow.0.max(y[6].abs());
        inflow.1 = inflow.1.max(y[7].abs());
    }
    let (m1, m2) = mass(&y);
    // relative to the largest volume that flowed in or out during the run
    let e1 = ((m1 - m1_0) - y[6]).abs() / inflow.0;
    let e2 = ((m2 - m2_0) - y[7]).abs() / inflow.1;
    assert!(inflow.0 > 1e-5, "the run moved oil: {} m³", inflow.0);
    assert!(e1 < 1e-6 && e2 < 1e-6, "mass balance errors {e1:e}, {e2:e}");
}
