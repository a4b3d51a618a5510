//! Closed-loop runs: tracking the sine, the step size's effect, the loaded scenario's spring.

use model::dynamics::{I_P1, I_P2, I_X};
use model::params::{ActuatorParams, FrictionPreset};
use model::sensors::SensorParams;
use model::sim::SimSettings;

use crate::{run_truth, sim};

#[test]
fn closed_loop_sine_tracks_the_reference() {
    let mut s = sim(
        "closed-loop-sine",
        ActuatorParams::default(),
        vec![],
        SensorParams::default(),
        SimSettings::default(),
    );
    let samples = s.run(10.0);
    let tail = &samples[2000..];
    let rms = (tail.iter().map(|s| (s.ref_m - s.x_m).powi(2)).sum::<f64>() / tail.len() as f64).sqrt();
    let max = tail.iter().map(|s| (s.ref_m - s.x_m).abs()).fold(0.0, f64::max);
    // The loop is first order with gain K = K_p·k_v, k_v = C_d·w·k_sp·sqrt((p_s/2)/ρ)/A
    // ≈ 0.0495 m/s/V, so K ≈ 2.48 1/s: a 0.5 Hz reference (ω = π) is tracked with an
    // error amplitude of 0.2·ω/sqrt(ω² + K²) ≈ 0.157 m, i.e. an RMS of ≈ 0.111 m.
    let p = ActuatorParams::default();
    let kv = p.discharge_coefficient
        * p.area_gradient_m2_per_m
        * p.spool_gain_m_per_v
        * (0.5 * p.supply_pressure_pa / p.oil_density_kg_m3).sqrt()
        / p.piston_area_m2;
    let k = 50.0 * kv;
    let w = std::f64::consts::PI;
    let predicted_rms = 0.2 * w / (w * w + k * k).sqrt() / 2f64.sqrt();
    assert!((predicted_rms - 0.111).abs() < 0.005, "{predicted_rms}");
    assert!(
        (rms - predicted_rms).abs() < 0.2 * predicted_rms,
        "tracking error rms {rms} m vs first-order prediction {predicted_rms} m (max {max} m)"
    );
}

#[test]
fn halving_the_step_changes_a_10s_run_little() {
    for preset in [FrictionPreset::Smooth, FrictionPreset::Thesis] {
        let rig = ActuatorParams::default().with_friction_preset(preset);
        let run = |n| {
            let settings = SimSettings {
                substeps_per_sample: n,
                ..SimSettings::default()
            };
            let mut s = sim(
                "closed-loop-sine",
                rig.clone(),
                vec![],
                SensorParams::ideal(),
                settings,
            );
            run_truth(&mut s, 10.0)
        };
        let a = run(40);
        let b = run(80);
        let dx = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a[I_X] - b[I_X]).abs())
            .fold(0.0, f64::max);
        let dp = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a[I_P1] - b[I_P1]).abs().max((a[I_P2] - b[I_P2]).abs()))
            .fold(0.0, f64::max);
        eprintln!("{preset:?}: max |Δx| {dx:e} m, max |Δp| {dp:e} Pa");
        let (tol_x, tol_p) = match preset {
            FrictionPreset::Smooth => (1e-8, 20.0),
            FrictionPreset::Thesis => (1e-4, 1e5),
        };
        assert!(dx < tol_x && dp < tol_p, "{preset:?}: Δx {dx} m, Δp {dp} Pa");
    }
}

#[test]
fn loaded_scenario_engages_the_spring_and_reports_its_force() {
    let mut s = sim(
        "loaded-sine",
        ActuatorParams::default(),
        vec![],
        SensorParams::default(),
        SimSettings::default(),
    );
    let samples = s.run(6.0);
    let engaged: Vec<_> = samples.iter().filter(|s| s.x_m > 0.23).collect();
    assert!(!engaged.is_empty());
    for smp in engaged {
        let expect = 2e4 * (smp.x_m - 0.22);
        assert!(
            (smp.f_load_n - expect).abs() < 40.0,
            "{} vs {expect}",
            smp.f_load_n
        );
    }
}
