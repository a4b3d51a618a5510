//! The estimator against the simulated rig and against textbook properties.

use estimator::{Ekf, Estimator, Tuning, FLAG_RESET};
use model::rng::Rng;
use model::{ActuatorParams, FaultSchedule, FrictionPreset, Scenario, SensorParams, SimSettings, Simulator};
use nalgebra::{SMatrix, SVector};

/// The covariance factor keeps P symmetric positive definite over 1e6 steps of
/// random commands and random measurements, from the thesis' P0 = 1e4·I (the
/// case that breaks a Joseph-form update, MODEL.md §8).
#[test]
fn covariance_stays_positive_definite_over_a_million_random_steps() {
    let mut rng = Rng::new(99);
    for (tuning, steps) in [
        (Tuning::thesis(), 600_000u64),
        (Tuning::sensor_derived(), 400_000),
    ] {
        let mut est = Estimator::new(ActuatorParams::default(), tuning.clone()).unwrap();
        let mut u = 0.0;
        let mut min_eig = f64::INFINITY;
        for k in 0..steps {
            if k % 200 == 0 {
                u = rng.uniform_in(-10.0, 10.0);
            }
            let mut s = model::Sample::new(
                k as f64 * 1e-3,
                u,
                0.3 + 0.05 * rng.normal(),
                6.9e6 + 2e6 * rng.normal(),
                6.9e6 + 2e6 * rng.normal(),
            );
            s.p1_pa = s.p1_pa.clamp(0.0, 20e6);
            s.p2_pa = s.p2_pa.clamp(0.0, 20e6);
            let e = est.on_sample(&s);
            assert!(
                e.state.iter().take(tuning.states as usize).all(|v| v.is_finite()),
                "step {k}"
            );
            if k % 997 == 0 || k < 10 {
                let ev = est.min_scaled_eigenvalue();
                min_eig = min_eig.min(ev);
                assert!(
                    ev > 0.0,
                    "{} states, step {k}: smallest eigenvalue {ev:e}",
                    tuning.states
                );
                let mut p = [0.0; 121];
                let n = est.covariance_into(&mut p);
                for i in 0..n {
                    for j in 0..n {
                        let (a, b) = (p[i * n + j], p[j * n + i]);
                        assert!(
                            (a - b).abs() <= 1e-9 * (a.abs() + b.abs()) + 1e-300,
                            "asymmetric at {i},{j}"
                        );
                    }
                }
            }
        }
        assert!(min_eig > 0.0);
    }
}

/// With a system that matches the filter exactly (linear, Gaussian), the mean
/// NIS is the number of measurements: the filter is consistent.
#[test]
fn nis_is_chi_square_on_a_matched_linear_system() {
    let f = SMatrix::<f64, 3, 3>::new(1.0, 1e-3, 0.0, 0.0, 0.99, 1e-3, 0.0, 0.0, 0.98);
    let h = SMatrix::<f64, 2, 3>::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let q = SVector::<f64, 3>::new(1e-8, 1e-4, 1e2);
    let r = SVector::<f64, 2>::new(1e-6, 4e4);
    let mut ekf = Ekf::<3, 2>::new(
        SVector::zeros(),
        &SVector::<f64, 3>::new(1e-4, 1.0, 1e6),
        &q,
        r,
        SVector::<f64, 3>::new(1e-3, 1.0, 1e3),
    );
    let mut rng = Rng::new(5);
    let mut x = SVector::<f64, 3>::zeros();
    let (mut sum, mut n) = (0.0, 0.0);
    for k in 0..40_000 {
        x = f * x + SVector::from_fn(|i, _| q[i].sqrt() * rng.normal());
        let y = h * x + SVector::from_fn(|i, _| r[i].sqrt() * rng.normal());
        ekf.predict(f * ekf.state(), &f).unwrap();
        let inn = ekf.update(&y, &(h * ekf.state()), &h, [true, true]).unwrap();
        if k > 1000 {
            sum += inn.nis;
            n += 1.0;
        }
    }
    let mean = sum / n;
    assert!((mean - 2.0).abs() < 0.06, "mean NIS {mean}, expected 2");
}

struct RunFigures {
    converged_s: f64,
    p_rms_pa: [f64; 2],
    fe_rms_n: f64,
    resets: u64,
}

/// Runs a healthy scenario; convergence = the time after which the estimated
/// position stays within `pos_tol_m` and both pressures within 0.3 MPa of the truth
/// (the thesis friction's stick-slip makes the pressures chatter by about ±1.5 MPa).
fn healthy_run(scenario: &str, tuning: Tuning, smooth: bool, seconds: f64, pos_tol_m: f64) -> RunFigures {
    let mut rig = ActuatorParams::default();
    let mut model = ActuatorParams::default();
    if smooth {
        rig = rig.with_friction_preset(FrictionPreset::Smooth);
        model = model.with_friction_preset(FrictionPreset::Smooth);
    }
    let sc = Scenario::by_name(scenario, 3, seconds).unwrap();
    let mut sim = Simulator::new(
        rig,
        SensorParams::default(),
        SimSettings::default(),
        sc,
        FaultSchedule::default(),
        3,
    )
    .unwrap();
    let mut est = Estimator::new(model, tuning).unwrap();
    let mut converged_s = 0.0;
    let (mut sq, mut fe_sq, mut n) = ([0.0; 2], 0.0, 0.0);
    let mut resets = 0;
    for _ in 0..(seconds * 1000.0) as usize {
        let s = sim.step();
        let tr = *sim.truth();
        let e = est.on_sample(&s);
        if e.flags & FLAG_RESET != 0 {
            resets += 1;
        }
        let ok = (e.state[3] - tr.state[3]).abs() < pos_tol_m
            && (e.state[1] - tr.state[1]).abs() < 3e5
            && (e.state[2] - tr.state[2]).abs() < 3e5;
        if !ok {
            converged_s = s.t_s;
        }
        if s.t_s > 2.0 {
            sq[0] += e.residual[1].powi(2);
            sq[1] += e.residual[2].powi(2);
            let fe_true = tr.forces.friction_n + tr.forces.load_n - tr.forces.end_stop_n;
            fe_sq += (e.state[6] - fe_true).powi(2);
            n += 1.0;
        }
    }
    RunFigures {
        converged_s,
        p_rms_pa: [(sq[0] / n).sqrt(), (sq[1] / n).sqrt()],
        fe_rms_n: (fe_sq / n).sqrt(),
        resets,
    }
}

#[test]
fn converges_from_the_thesis_start_in_every_scenario() {
    for sc in model::scenario::SCENARIO_NAMES {
        // Both tunings start from the thesis' x0 (rod at 0, pressures 6.8 MPa) and P0 = 1e4·I.
        let thesis_start = Tuning {
            init: estimator::Init::Thesis,
            p0_x_sp_m2: 1e4,
            p0_p_pa2: 1e4,
            p0_x_m2: 1e4,
            p0_v_m2_s2: 1e4,
            p0_v_sp_m2_s2: 1e4,
            p0_f_e_n2: 1e4,
            ..Tuning::sensor_derived()
        };
        for (name, tuning) in [("thesis", Tuning::thesis()), ("sensor", thesis_start)] {
            // The thesis' R_x = 1e-4 m² trusts the encoder to 1 cm only: its position
            // estimate wanders by centimetres (4 cm RMS open loop, a finding); judge it
            // on the pressures only, as the thesis used it.
            let pos_tol = if name == "thesis" { f64::INFINITY } else { 1e-3 };
            let f = healthy_run(sc, tuning, false, 5.0, pos_tol);
            println!(
                "{sc:20} {name:6} converged after {:.3} s, residual RMS p1 {:.0} Pa p2 {:.0} Pa, F_e RMS error {:.0} N",
                f.converged_s, f.p_rms_pa[0], f.p_rms_pa[1], f.fe_rms_n
            );
            assert_eq!(f.resets, 0, "{sc} {name}");
            let limit = if name == "thesis" { 5.0 } else { 0.5 };
            assert!(
                f.converged_s < limit,
                "{sc} {name}: still converging at {} s",
                f.converged_s
            );
            assert!(
                f.p_rms_pa[0] < 2e4 && f.p_rms_pa[1] < 2e4,
                "{sc} {name}: {:?}",
                f.p_rms_pa
            );
        }
    }
}

/// Loaded, the estimated effective load F_e follows friction plus spring force;
/// unloaded it is the friction (an online friction estimator). Smooth rig.
#[test]
fn effective_load_follows_friction_plus_spring() {
    let loaded = healthy_run("loaded-sine", Tuning::sensor_derived(), true, 30.0, 1e-3);
    let unloaded = healthy_run("closed-loop-sine", Tuning::sensor_derived(), true, 20.0, 1e-3);
    println!(
        "F_e RMS error: loaded {:.1} N, unloaded {:.1} N",
        loaded.fe_rms_n, unloaded.fe_rms_n
    );
    assert!(loaded.fe_rms_n < 150.0, "loaded: {}", loaded.fe_rms_n);
    assert!(unloaded.fe_rms_n < 150.0, "unloaded: {}", unloaded.fe_rms_n);
}
