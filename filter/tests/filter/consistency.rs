//! Textbook properties: P stays positive definite, the NIS is chi-square on a matched system.

use filter::{Ekf, Estimator, Tuning};
use model::rng::Rng;
use model::ActuatorParams;
use nalgebra::{SMatrix, SVector};

/// The covariance factor keeps P symmetric positive definite over 1e6 steps of
/// random commands and random measurements, from the thesis' P0 = 1e4·I (the
/// case that breaks a Joseph-form update, docs/model.md#covariance-at-the-thesis-start).
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
                e.state.iter().take(e.n_states as usize).all(|v| v.is_finite())
                    && (tuning.states < 12 || e.bulk_scale.is_finite()),
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
                let mut p = [0.0; 144];
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
