//! A position sensor with white noise (a magnetostrictive one's 3 µm) makes
//! the central-difference velocity of a rod at rest ±2 mm/s, beyond the
//! model's stick band of 1 mm/s. The force balance then reads the rod as
//! sliding, its friction flipping sign from sample to sample. With the
//! sensor's noise given, the band widens to three σ of the velocity's noise
//! and a model equal to the rig leaves a force gap near the noiseless one.

use calibrate::suite::nominal_model;
use calibrate::{run, CalibrateOptions};
use model::{FaultSchedule, Scenario, SensorParams, SimSettings, Simulator};

/// 20 s of the closed-loop pseudorandom steps on the nominal rig, read by a
/// position sensor with `noise_m` of white noise over its 30 µm count.
fn record(noise_m: f64) -> Vec<model::Sample> {
    let sc = Scenario::by_name("closed-loop-random", 1, 20.0).expect("a built-in scenario");
    let sensors = SensorParams {
        position_noise_m: noise_m,
        encoder_resolution_m: 1.0e-6,
        ..SensorParams::default()
    };
    let mut sim = Simulator::new(
        nominal_model(),
        sensors,
        SimSettings::default(),
        sc,
        FaultSchedule::default(),
        7,
    )
    .expect("valid rig");
    sim.run(20.0)
}

/// The force gap (validation RMS, N) of the rig's own model on `data`,
/// calibrated with the position noise `noise_m` given.
fn force_gap_n(data: &[model::Sample], noise_m: f64) -> f64 {
    let opts = CalibrateOptions {
        position_noise_m: noise_m,
        candidates: vec!["spool-bias".to_string()],
        ..CalibrateOptions::default()
    };
    run(data, &nominal_model(), &opts)
        .expect("calibrates")
        .gap_before
        .force_n
}

#[test]
fn a_noisy_position_sensor_widens_the_band_of_rest() {
    let noisy = record(3.0e-6);
    let blind = force_gap_n(&noisy, 0.0);
    let told = force_gap_n(&noisy, 3.0e-6);
    eprintln!(
        "force gap with 3 µm of position noise: {blind:.1} N read as sliding, {told:.1} N with the band"
    );
    assert!(
        told < 0.5 * blind,
        "the band leaves {told} N against {blind} N without it"
    );

    // the same rig read without noise: the band brings the noisy record near it
    let a = force_gap_n(&record(0.0), 0.0);
    eprintln!("without position noise: {a:.1} N");
    assert!(told < 3.0 * a, "with the band {told} N, a noiseless sensor {a} N");
}

#[test]
fn the_velocitys_noise_follows_the_estimator() {
    // central difference: σ_x / (dt·√2)
    let s = calibrate::shoot::velocity_noise_m_s(3.0e-6, 1.0e-3, 1);
    assert!((s - 3.0e-6 / (1.0e-3 * 2f64.sqrt())).abs() < 1e-15, "{s}");
    // ±2 samples: Σ 2k² = 10
    let s2 = calibrate::shoot::velocity_noise_m_s(3.0e-6, 1.0e-3, 2);
    assert!((s2 - 3.0e-6 / (1.0e-3 * 10f64.sqrt())).abs() < 1e-15, "{s2}");
    // measured on the estimator itself: white noise on a rod at rest
    let mut rng = model::rng::Rng::new(3);
    let samples: Vec<model::Sample> = (0..20_000)
        .map(|k| model::Sample::new(k as f64 * 1e-3, 0.0, 0.1 + 3.0e-6 * rng.normal(), 1e6, 1e6))
        .collect();
    let d = calibrate::shoot::Prepared::new(&samples, 1e-3, 50, 0.7, 10, 1);
    let n = d.v_m_s.len() as f64;
    let rms = (d.v_m_s.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
    assert!((rms / s - 1.0).abs() < 0.05, "estimated {rms} m/s against {s}");
}
