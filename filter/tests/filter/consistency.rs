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

/// A DAQ that reads each sample 30 µs (RMS) off its stamp puts v·δ on the
/// position. On the lift's cycle (model = rig) the position innovations at
/// speed grow by the jitter's variance, mean (v·σ_δ)², and by part of it
/// again (the estimate carries the past readings' v·δ); counted
/// ([`Tuning::sample_jitter_s`]), the filter's innovation variance grows by
/// about as much (its R by exactly that, its prior a little). Without a jitter the steps are the tuning's, bit for bit.
#[test]
fn a_counted_jitter_adds_its_variance_to_the_position_innovations() {
    let rig = ActuatorParams::vertical_lift();
    let jitter_s = 30e-6;
    let sensors = |jitter_s: f64| model::SensorParams {
        sample_jitter_s: jitter_s,
        ..model::SensorParams::plant()
    };
    let record = |jitter_s: f64| {
        let scenario = model::Scenario::by_name("lift", 3, 60.0).expect("scenario");
        let rig = rig.clone();
        let settings = model::SimSettings::default();
        let mut sim = model::Simulator::new(
            rig,
            sensors(jitter_s),
            settings,
            scenario,
            model::FaultSchedule::default(),
            7,
        )
        .expect("rig");
        sim.run(60.0)
    };
    let s = sensors(0.0);
    let tuning = Tuning {
        r_x_m2: s.position_sigma_m().powi(2),
        r_p_pa2: s.pressure_sigma_pa().powi(2),
        ..Tuning::sensor_derived()
    };
    // over the samples after 10 s where the rod moves faster than 0.1 m/s:
    // mean ν_x², mean σ_x² (the filter's innovation variance), mean v², m² and m²/s²
    let at_speed = |samples: &[model::Sample], jitter_s: f64| {
        let tuning = Tuning {
            sample_jitter_s: jitter_s,
            ..tuning.clone()
        };
        let mut est = Estimator::new(rig.clone(), tuning).unwrap();
        let (mut n, mut nu2, mut c, mut v2) = (0usize, 0.0, 0.0, 0.0);
        for s in samples {
            let e = est.on_sample(s);
            if s.t_s > 10.0 && e.state[4].abs() > 0.1 {
                nu2 += e.innovation[0].powi(2);
                c += e.innovation_sigma[0].powi(2);
                v2 += e.state[4].powi(2);
                n += 1;
            }
        }
        let n = n.max(1) as f64;
        (nu2 / n, c / n, v2 / n, n)
    };
    let (clean, jittered) = (record(0.0), record(jitter_s));
    let (nu2_clean, c_clean, _, n) = at_speed(&clean, 0.0);
    let (nu2_jittered, _, v2, _) = at_speed(&jittered, 0.0);
    let (_, c_counted, _, _) = at_speed(&jittered, jitter_s);
    assert!(n > 1000.0, "{n} samples at speed");
    let share = jitter_s * jitter_s * v2;
    let grown = nu2_jittered - nu2_clean;
    // at least the reading's own v·δ; the estimate carries part of the past ones
    assert!(
        (1.0..1.5).contains(&(grown / share)),
        "the innovations grew by {grown:e} m² against the jitter's {share:e}"
    );
    // R's part is the jitter's variance; the prior's grows a little with it
    let counted = c_counted - c_clean;
    assert!(
        (1.0..1.25).contains(&(counted / share)),
        "the innovation variance grew by {counted:e} m² against the jitter's {share:e}"
    );
    // no jitter: the same bits as a tuning that never had the field set
    let mut a = Estimator::new(rig.clone(), tuning.clone()).unwrap();
    let mut b = Estimator::new(
        rig.clone(),
        Tuning {
            sample_jitter_s: 0.0,
            ..tuning.clone()
        },
    )
    .unwrap();
    for s in &jittered[..5000] {
        let (x, y) = (a.on_sample(s), b.on_sample(s));
        assert_eq!(x.state.map(f64::to_bits), y.state.map(f64::to_bits));
    }
}

/// Transducers lagging by 0.6 ms on the lift's cycle (model = rig), replayed
/// with the lag counted ([`Tuning::pressure_lag_s`]) and without (neither
/// re-anchors): the estimates are the same bits, the mean NIS loses most of what
/// the lag added. Both pressures stuck from 30 s: a repeated reading does
/// not lag, and the NIS is the same bits as without the lag counted.
#[test]
fn a_counted_lag_widens_the_nis_of_moving_readings_only() {
    let rig = ActuatorParams::vertical_lift();
    let lag_s: f64 = 6e-4;
    let record = |lag_s: f64| {
        let scenario = model::Scenario::by_name("lift", 3, 40.0).expect("scenario");
        let sensors = model::SensorParams {
            pressure_lag_s: lag_s,
            ..model::SensorParams::plant()
        };
        let mut sim = model::Simulator::new(
            rig.clone(),
            sensors,
            model::SimSettings::default(),
            scenario,
            model::FaultSchedule::default(),
            7,
        )
        .expect("rig");
        sim.run(40.0)
    };
    let s = model::SensorParams::plant();
    let tuning = |lag_s: f64| Tuning {
        r_x_m2: s.position_sigma_m().powi(2),
        r_p_pa2: s.pressure_sigma_pa().powi(2),
        pressure_lag_s: [lag_s; 2],
        ..Tuning::sensor_derived()
    };
    let replay = |samples: &[model::Sample], lag_s: f64| {
        let mut est = Estimator::new(rig.clone(), tuning(lag_s)).unwrap();
        samples
            .iter()
            .map(|s| {
                let e = est.on_sample(s);
                (e.t_s, e.state.map(f64::to_bits), e.nis)
            })
            .collect::<Vec<_>>()
    };
    let mean_nis = |run: &[(f64, [u64; filter::MAX_STATES], f64)]| {
        let after: Vec<f64> = run
            .iter()
            .filter(|r| (10.0..30.0).contains(&r.0))
            .map(|r| r.2)
            .collect();
        after.iter().sum::<f64>() / after.len() as f64
    };
    let (clean, mut lagged) = (record(0.0), record(lag_s));
    let (nis_clean, nis_lagged) = (mean_nis(&replay(&clean, 0.0)), mean_nis(&replay(&lagged, 0.0)));
    let (uncounted, counted) = (replay(&lagged, 0.0), replay(&lagged, lag_s));
    let nis_counted = mean_nis(&counted);
    let said = format!(
        "mean NIS 10-30 s: unlagged {nis_clean:.2}, lagged {nis_lagged:.2}, lag counted {nis_counted:.2}"
    );
    // measured: 2.95, 5.35, 3.68
    assert!(nis_lagged > 1.3 * nis_clean, "{said}");
    assert!(
        nis_lagged - nis_counted > 0.6 * (nis_lagged - nis_clean),
        "{said}"
    );
    assert!(
        uncounted.iter().zip(&counted).all(|(a, b)| a.1 == b.1),
        "the lag moved the estimates"
    );
    // both transducers stuck from 30 s
    let (p1, p2) = (lagged[30_000].p1_pa, lagged[30_000].p2_pa);
    for s in lagged.iter_mut().skip(30_000) {
        (s.p1_pa, s.p2_pa) = (p1, p2);
    }
    let (uncounted, counted) = (replay(&lagged, 0.0), replay(&lagged, lag_s));
    for (a, b) in uncounted.iter().zip(&counted).skip(30_001) {
        assert_eq!(a.2.to_bits(), b.2.to_bits(), "at {} s", a.0);
    }
}
