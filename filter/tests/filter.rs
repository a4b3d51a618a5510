//! The estimator against the simulated rig and against textbook properties.

use filter::{Ekf, Estimator, Tuning, END_STOP_MARGIN_M, FLAG_END_STOP, FLAG_RESET};
use model::rng::Rng;
use model::{ActuatorParams, FaultSchedule, FrictionPreset, Scenario, Simulator};
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

struct RunFigures {
    /// Time from the first sample after which both estimated pressures stay within
    /// [`P_TOL_PA`] of the truth, s (0: never outside, not even at the first sample).
    converged_p_s: f64,
    /// Same for the estimated position within `pos_tol_m`, s.
    converged_x_s: f64,
    /// RMS of the position error over the whole run, m.
    x_rms_m: f64,
    /// Largest position error over the whole run, m.
    x_max_m: f64,
    p_rms_pa: [f64; 2],
    fe_rms_n: f64,
    resets: u64,
}

/// Pressure tolerance of the convergence criterion, Pa (the thesis friction's
/// stick-slip makes the pressures chatter by about ±1.5 MPa).
const P_TOL_PA: f64 = 3e5;

/// Runs a healthy scenario; convergence = the time after which the estimated
/// position stays within `pos_tol_m` and both pressures within [`P_TOL_PA`] of
/// the truth. Residual RMS from 2 s on.
fn healthy_run(scenario: &str, tuning: Tuning, smooth: bool, seconds: f64, pos_tol_m: f64) -> RunFigures {
    let mut rig = ActuatorParams::default();
    let mut model = ActuatorParams::default();
    if smooth {
        rig = rig.with_friction_preset(FrictionPreset::Smooth);
        model = model.with_friction_preset(FrictionPreset::Smooth);
    }
    let sc = Scenario::by_name(scenario, 3, seconds).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, sc, FaultSchedule::default(), 3).unwrap();
    let mut est = Estimator::new(model, tuning).unwrap();
    let (mut converged_p_s, mut converged_x_s) = (0.0, 0.0);
    let (mut sq, mut fe_sq, mut n) = ([0.0; 2], 0.0, 0.0);
    let (mut x_sq, mut x_max_m) = (0.0, 0.0f64);
    let mut resets = 0;
    let samples = (seconds * 1000.0) as usize;
    for k in 0..samples {
        let s = sim.step();
        let tr = *sim.truth();
        let e = est.on_sample(&s);
        if e.flags & FLAG_RESET != 0 {
            resets += 1;
        }
        // Within tolerance from the next sample on, if this one is out (NaN is out).
        let within = |err: f64, tol: f64| err.abs() < tol;
        let next_s = (k + 1) as f64 * 1e-3;
        if !(within(e.state[1] - tr.state[1], P_TOL_PA) && within(e.state[2] - tr.state[2], P_TOL_PA)) {
            converged_p_s = next_s;
        }
        let ex = (e.state[3] - tr.state[3]).abs();
        if !within(ex, pos_tol_m) {
            converged_x_s = next_s;
        }
        x_sq += ex * ex;
        x_max_m = x_max_m.max(ex);
        if s.t_s > 2.0 {
            sq[0] += e.residual[1].powi(2);
            sq[1] += e.residual[2].powi(2);
            if e.n_states >= 7 {
                let fe_true = tr.forces.friction_n + tr.forces.load_n - tr.forces.end_stop_n;
                fe_sq += (e.state[6] - fe_true).powi(2);
            }
            n += 1.0;
        }
    }
    RunFigures {
        converged_p_s,
        converged_x_s,
        x_rms_m: (x_sq / samples as f64).sqrt(),
        x_max_m,
        p_rms_pa: [(sq[0] / n).sqrt(), (sq[1] / n).sqrt()],
        fe_rms_n: (fe_sq / n).sqrt(),
        resets,
    }
}

/// Convergence in every scenario (5 s runs, thesis friction, seed 3) with both
/// tunings, from two starts, each with the thesis' x0 (rod at 0 m although it sits
/// near 0.3 m, pressures at `init_pressure_pa`):
///
/// - the thesis start, P0 = 1e4·I: its mixed units make the first update adopt the
///   measurements, so both pressures are within 0.3 MPa, and (sensor tuning) the
///   position within 1 mm, from the first sample on (measured: 0 ms in every
///   scenario); asserted within 2 samples. The sensor tuning takes 11 states
///   from this start: the first update leaves the rod at 7 m/s, and in the
///   press scenario the oil's stiffness θ of the 12-state layout then runs to
///   its clamp (0.2) and the filter does not recover (the leak filter starts
///   from the measured state: the `confident` start and every replay);
/// - a confident wrong start, P0 = 1e-12·I and pressures at 3.8 MPa (3 MPa low):
///   the sensor tuning needs 32–34 ms to bring the pressures within 0.3 MPa and
///   43–45 ms for the position within 1 mm (asserted within 70 ms and 100 ms); the
///   thesis tuning has its pressures within 0.3 MPa from the second sample on.
///
/// The thesis tuning's position estimate does not converge (R_x = 1e-4 m² trusts the
/// encoder to 1 cm only, and the forward-Euler bursts of docs/model.md#forward-euler-bursts
/// run it into the stroke clamp): measured RMS error 1.8–4.7 cm over 5 s, asserted below 10 cm.
/// The figures are printed (`--nocapture`) and tabulated in docs/estimator.md.
#[test]
fn converges_from_the_thesis_start_in_every_scenario() {
    const SECONDS: f64 = 5.0;
    let thesis_p0 = |t: Tuning| Tuning {
        init: filter::Init::Thesis,
        p0_x_sp_m2: 1e4,
        p0_p_pa2: 1e4,
        p0_x_m2: 1e4,
        p0_v_m2_s2: 1e4,
        p0_v_sp_m2_s2: 1e4,
        p0_f_e_n2: 1e4,
        ..t
    };
    let confident = |t: Tuning| Tuning {
        init: filter::Init::Thesis,
        init_pressure_pa: 3.8e6,
        p0_x_sp_m2: 1e-12,
        p0_p_pa2: 1e-12,
        p0_x_m2: 1e-12,
        p0_v_m2_s2: 1e-12,
        p0_v_sp_m2_s2: 1e-12,
        p0_f_e_n2: 1e-12,
        p0_leak_m6_s2: 1e-24,
        p0_bias_m2: 1e-24,
        ..t
    };
    for sc in model::scenario::SCENARIO_NAMES {
        for (start, name, tuning) in [
            ("thesis P0", "thesis", thesis_p0(Tuning::thesis())),
            (
                "thesis P0",
                "sensor",
                thesis_p0(Tuning {
                    states: 11,
                    ..Tuning::sensor_derived()
                }),
            ),
            ("confident", "thesis", confident(Tuning::thesis())),
            ("confident", "sensor", confident(Tuning::sensor_derived())),
        ] {
            let pos_tol = if name == "thesis" { 5e-2 } else { 1e-3 };
            let f = healthy_run(sc, tuning, false, SECONDS, pos_tol);
            eprintln!(
                "{sc:18} {name:6} {start:9}: pressures within 0.3 MPa after {:5.3} s, position within \
                 {:2} mm after {:5.3} s (RMS error {:.4} m, max {:.4} m); residual RMS p1 {:.0} Pa \
                 p2 {:.0} Pa, F_e RMS error {:.0} N",
                f.converged_p_s,
                pos_tol * 1e3,
                f.converged_x_s,
                f.x_rms_m,
                f.x_max_m,
                f.p_rms_pa[0],
                f.p_rms_pa[1],
                f.fe_rms_n
            );
            assert_eq!(f.resets, 0, "{sc} {name} {start}");
            let (p_limit, x_limit) = match (start, name) {
                ("thesis P0", _) => (0.002, 0.002),
                (_, "sensor") => (0.07, 0.1),
                _ => (0.002, f64::NAN),
            };
            assert!(
                f.converged_p_s <= p_limit,
                "{sc} {name} {start}: pressures converged after {} s (limit {p_limit} s)",
                f.converged_p_s
            );
            if name == "sensor" {
                assert!(
                    f.converged_x_s <= x_limit,
                    "{sc} {name} {start}: position converged after {} s (limit {x_limit} s)",
                    f.converged_x_s
                );
            } else {
                assert!(
                    f.x_rms_m < 0.1,
                    "{sc} {name} {start}: position RMS error {} m",
                    f.x_rms_m
                );
            }
            assert!(
                f.p_rms_pa[0] < 2e4 && f.p_rms_pa[1] < 2e4,
                "{sc} {name} {start}: {:?}",
                f.p_rms_pa
            );
        }
    }
}

/// The 6-state thesis filter (thesis tuning; friction and load from the model, no
/// F_e state) on the healthy open-loop sine with the thesis friction, 10 s: both
/// pressures within 0.3 MPa from the first sample on, and an a-posteriori pressure
/// residual RMS (from 2 s on) of 1.9 / 1.7 kPa measured, asserted below 4 kPa
/// (the sensor noise is 5.2 kPa RMS: like the 7-state thesis filter it over-fits);
/// position RMS error 0.86 cm over the run (max 19 cm in a burst), asserted below 2 cm.
#[test]
fn six_state_thesis_filter_tracks_the_open_loop_sine() {
    let tuning = Tuning {
        states: 6,
        ..Tuning::thesis()
    };
    let f = healthy_run("open-loop-sine", tuning, false, 10.0, 5e-2);
    eprintln!(
        "6 states, open-loop-sine: pressures within 0.3 MPa after {:.3} s, position within 5 cm after \
         {:.3} s (RMS error {:.4} m, max {:.4} m), residual RMS p1 {:.0} Pa p2 {:.0} Pa",
        f.converged_p_s, f.converged_x_s, f.x_rms_m, f.x_max_m, f.p_rms_pa[0], f.p_rms_pa[1]
    );
    assert_eq!(f.resets, 0);
    assert!(
        f.converged_p_s <= 0.002,
        "pressures converged after {} s",
        f.converged_p_s
    );
    for (k, r) in f.p_rms_pa.iter().enumerate() {
        assert!(*r > 500.0 && *r < 4000.0, "p{} residual RMS {r} Pa", k + 1);
    }
    assert!(f.x_rms_m < 0.02, "position RMS error {} m", f.x_rms_m);
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

/// After a gap too long to bridge, the fast states restart from the next sample while
/// the leak sizes keep their estimate and joint covariance; the covariance stays
/// positive definite and the filter tracks again at once.
#[test]
fn a_long_gap_reanchors_the_fast_states_and_keeps_the_leak_sizes() {
    use model::Fault;
    let rig = ActuatorParams::default();
    let mut faults = FaultSchedule::default();
    faults.faults.push(Fault::parse("ext1:0.5lpm@0s", &rig).unwrap());
    let scenario = Scenario::by_name("closed-loop-sine", 5, 12.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, faults, 5).unwrap();
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let mut before = [0.0; 3];
    let mut cov_before = [0.0; 144];
    let mut cov_after = [0.0; 144];
    let mut max_leak_after = 0.0f64;
    for k in 0..12_000 {
        let s = sim.step();
        if (6_000..6_300).contains(&k) {
            continue; // 300 samples lost
        }
        if k == 6_300 {
            est.covariance_into(&mut cov_before);
            est.on_gap(300);
        }
        let e = est.on_sample(&s);
        if k == 5_999 {
            before = [e.state[7], e.state[8], e.state[9]];
        }
        if k == 6_300 {
            est.covariance_into(&mut cov_after);
            assert_eq!(e.flags & FLAG_RESET, 0, "a gap is not a reset");
            for i in 0..3 {
                // One update moves the kept leak sizes only a little.
                assert!(
                    (e.state[7 + i] - before[i]).abs() < 0.05 / 60_000.0,
                    "{:?} vs {before:?}",
                    e.state
                );
            }
        }
        if k > 6_300 {
            max_leak_after = max_leak_after.max(e.state[7].abs() * 60_000.0);
            assert!(e.nis < 1e4, "NIS {} at sample {k}", e.nis);
        }
    }
    // The kept block (leak sizes, bias) survives the re-anchoring; the fast block restarts.
    let n = Tuning::sensor_derived().states as usize;
    assert_eq!(n * n, cov_before.len());
    let (kept_before, kept_after) = (cov_before[7 * n + 7], cov_after[7 * n + 7]);
    assert!(kept_before > 0.0 && kept_after <= kept_before * 1.01 && kept_after > 0.5 * kept_before);
    assert!(est.min_scaled_eigenvalue() > 0.0);
    assert!(
        max_leak_after < 1.0,
        "ext1 estimate went to {max_leak_after} L/min after the gap"
    );
}

/// A measured pressure slightly below 0 Pa (noise near tank pressure) within
/// 2 % of the supply pressure is used as measured, as a CSV row with it is; one
/// further below is left out (the channel dropped, counted), and the estimate
/// stays finite either way.
#[test]
fn pressures_within_the_negative_margin_are_used_and_beyond_it_dropped() {
    let rig = ActuatorParams::default();
    let (lo, hi) = rig.measured_pressure_range_pa();
    assert_eq!((lo, hi), (-276_000.0, 20.7e6));
    let scenario = Scenario::by_name("closed-loop-sine", 5, 2.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(rig.clone(), scenario, FaultSchedule::default(), 5).unwrap();
    let mut est = Estimator::new(rig, Tuning::sensor_derived()).unwrap();
    for _ in 0..500 {
        est.on_sample(&sim.step());
    }
    let dropped = est.counters().channels_dropped;
    // (p2 value, channel used)
    for (p2, used) in [
        (-5.7, true),
        (-0.2e6, true),
        (lo, true),
        (-276_001.0, false),
        (-1e6, false),
    ] {
        let mut s = sim.step();
        s.p2_pa = p2;
        let before = est.counters().channels_dropped;
        let e = est.on_sample(&s);
        assert_eq!(e.residual[2].is_finite(), used, "p2 = {p2} Pa: {e:?}");
        assert_eq!(
            est.counters().channels_dropped - before,
            u64::from(!used),
            "p2 = {p2} Pa"
        );
        assert!(e.state[..11].iter().all(|v| v.is_finite()), "p2 = {p2} Pa: {e:?}");
        assert_eq!(e.measured[2], p2);
    }
    assert_eq!(est.counters().channels_dropped - dropped, 2);
    assert_eq!(est.counters().skipped, 0);
}

/// An open-loop sine whose spool bias walks the rod into the far end of its stroke:
/// the estimates carry the end-stop flag while the rod is within the margin of the
/// stop (the measured rod at the stop is always flagged), and nowhere else.
#[test]
fn the_end_stop_flag_marks_the_rod_at_the_end_of_its_stroke() {
    let rig = ActuatorParams {
        spool_null_bias_m: 3.5e-6,
        ..ActuatorParams::default()
    };
    let x_max_m = rig.x_max_m;
    let scenario = Scenario::by_name("open-loop-sine", 51, 40.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(rig.clone(), scenario, FaultSchedule::default(), 51).unwrap();
    let mut est = Estimator::new(rig, Tuning::sensor_derived()).unwrap();
    let (mut flagged, mut at_stop) = (0, 0);
    for _ in 0..40_000 {
        let s = sim.step();
        let e = est.on_sample(&s);
        let flag = e.flags & FLAG_END_STOP != 0;
        assert_eq!(
            flag,
            e.state[3] > x_max_m - END_STOP_MARGIN_M,
            "t {} s: {e:?}",
            s.t_s
        );
        // (the estimate is within a few encoder counts of the measurement)
        if flag {
            assert!(
                s.x_m > x_max_m - END_STOP_MARGIN_M - 2e-4,
                "t {} s: x {} m",
                s.t_s,
                s.x_m
            );
            flagged += 1;
        }
        if s.x_m > x_max_m - 1e-4 {
            assert!(
                flag,
                "t {} s: the rod at the stop ({} m) is not flagged",
                s.t_s, s.x_m
            );
            at_stop += 1;
        }
    }
    assert!(
        at_stop > 500 && flagged > at_stop,
        "{at_stop} samples at the stop, {flagged} flagged"
    );
}

/// The warm-up step before each sample (low-latency mode) changes nothing the
/// filters estimate: a stage warmed before every sample gives the same estimates,
/// bit for bit, as one that is not, leak present, on both filters.
#[test]
fn the_warm_up_step_changes_no_estimate() {
    let rig = ActuatorParams::default();
    let mut faults = FaultSchedule::default();
    faults
        .faults
        .push(model::Fault::parse("int:0.3lpm@2s", &rig).unwrap());
    let scenario = Scenario::by_name("loaded-sine", 7, 5.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, faults, 7).unwrap();
    let new = || {
        filter::EstimatorStage::new(
            ActuatorParams::default(),
            Tuning::sensor_derived(),
            Tuning::thesis(),
        )
    };
    let (mut plain, mut warmed) = (new().unwrap(), new().unwrap());
    for k in 0..5000 {
        let s = sim.step();
        warmed.warm_up();
        let (a, b) = (plain.on_sample(&s), warmed.on_sample(&s));
        for (x, y) in [(&a.leak, &b.leak), (&a.thesis, &b.thesis)] {
            assert!(
                x.state
                    .iter()
                    .zip(&y.state)
                    .all(|(p, q)| p.to_bits() == q.to_bits()),
                "sample {k}"
            );
            assert_eq!(x.sigma.map(f64::to_bits), y.sigma.map(f64::to_bits), "sample {k}");
            assert_eq!(x.nis.to_bits(), y.nis.to_bits(), "sample {k}");
        }
    }
}

/// Healthy run of `scenario` on a rig whose oil is `bulk_factor` times as stiff as
/// the model's, through a filter of `states` states: the last θ estimate and the
/// largest 1-s mean of each leak-size estimate (L/min at nominal drop) over 10-30 s.
fn soft_rig_run(scenario: &str, bulk_factor: f64, states: u32, seed: u64) -> (f64, [f64; 3]) {
    let rig = ActuatorParams::default().off_nominal(bulk_factor, 0.0);
    let sc = Scenario::by_name(scenario, seed, 30.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, sc, FaultSchedule::default(), seed).unwrap();
    let tuning = Tuning {
        states,
        ..Tuning::sensor_derived()
    };
    let mut est = Estimator::new(ActuatorParams::default(), tuning).unwrap();
    let (mut theta, mut worst, mut sum, mut n) = (f64::NAN, [0.0f64; 3], [0.0; 3], 0);
    for k in 0..30_000 {
        let e = est.on_sample(&sim.step());
        theta = e.bulk_scale;
        if k >= 10_000 {
            for (acc, q) in sum.iter_mut().zip(&e.state[7..10]) {
                *acc += q * 60_000.0;
            }
            n += 1;
            if n == 1000 {
                for (w, acc) in worst.iter_mut().zip(&sum) {
                    *w = w.max((acc / 1000.0).abs());
                }
                (sum, n) = ([0.0; 3], 0);
            }
        }
    }
    // the stage reports the same θ as its last estimate (the estimator process prints it at exit)
    assert_eq!(est.bulk_scale().map(|b| b.0), theta.is_finite().then_some(theta));
    (theta, worst)
}

/// The 12-state filter estimates the oil's stiffness: on rigs whose oil is 25 %
/// softer than the model's (air, hoses; friction off nominal too) θ settles
/// within 0.04 of 0.75 (measured 0.747 loaded sine, 0.734 closed-loop
/// pseudorandom), and the healthy leak estimates that the stiffness error made
/// (a soft rig's pressure swings read as flow the model lacks) shrink: the
/// largest 1-s mean over 10-30 s of any of the three falls from 0.11 and
/// 0.059 L/min (11 states) to 0.008 and 0.020 L/min; asserted at half or less,
/// and below 0.03 L/min. On the nominal rig θ stays within 0.03 of 1.
#[test]
fn the_oil_stiffness_of_a_soft_rig_is_estimated_and_no_longer_reads_as_leaks() {
    for (scenario, seed) in [("loaded-sine", 11), ("closed-loop-random", 12)] {
        let (theta, worst12) = soft_rig_run(scenario, 0.75, 12, seed);
        let (theta11, worst11) = soft_rig_run(scenario, 0.75, 11, seed);
        eprintln!("{scenario}: θ {theta:.3}; largest 1-s healthy leak means, L/min: 12 states {worst12:.4?}, 11 states {worst11:.4?}");
        assert!(theta11.is_nan(), "11 states carry no θ");
        assert!((theta - 0.75).abs() < 0.04, "{scenario}: θ {theta}");
        let (w12, w11) = (
            worst12.iter().cloned().fold(0.0, f64::max),
            worst11.iter().cloned().fold(0.0, f64::max),
        );
        assert!(w12 <= 0.5 * w11 && w12 < 0.03, "{scenario}: {w12} vs {w11} L/min");
        let (theta_nominal, _) = soft_rig_run(scenario, 1.0, 12, seed);
        assert!(
            (theta_nominal - 1.0).abs() < 0.03,
            "{scenario}: θ {theta_nominal} on the nominal rig"
        );
    }
}

/// The command of a sample drives the interval after it (the rig's zero-order
/// hold, docs/model.md#discretisation: x(k+1) = x(k) + T·f(x(k), u(k))): the estimate at
/// a sample cannot depend on that sample's own command, only on the ones before. Two
/// estimators fed the same samples, except ±10 V in the last one's command,
/// agree to the bit at that sample and part at the next. (Until 2026-11-25 the
/// prediction into sample k used u(k): the valve acted 1 ms early, and on a
/// 10 Hz chirp the mean NIS tripled.)
#[test]
fn a_samples_command_drives_the_interval_after_it() {
    for states in [6, 7, 12] {
        let tuning = Tuning {
            states,
            ..Tuning::sensor_derived()
        };
        let scenario = Scenario::by_name("open-loop-sine", 3, 2.0).unwrap();
        let mut sim =
            Simulator::with_default_sensors(ActuatorParams::default(), scenario, FaultSchedule::default(), 3)
                .unwrap();
        let samples: Vec<_> = (0..1002).map(|_| sim.step()).collect();
        let mut a = Estimator::new(ActuatorParams::default(), tuning.clone()).unwrap();
        let mut b = Estimator::new(ActuatorParams::default(), tuning).unwrap();
        for s in &samples[..1000] {
            a.on_sample(s);
            b.on_sample(s);
        }
        let (mut up, mut down) = (samples[1000], samples[1000]);
        up.u_v = 10.0;
        down.u_v = -10.0;
        let (ea, eb) = (a.on_sample(&up), b.on_sample(&down));
        assert_eq!(
            ea.state.map(f64::to_bits),
            eb.state.map(f64::to_bits),
            "{states} states"
        );
        assert_eq!(ea.nis.to_bits(), eb.nis.to_bits(), "{states} states");
        let (na, nb) = (a.on_sample(&samples[1001]), b.on_sample(&samples[1001]));
        // the spool's velocity (state 5) has turned towards +10 V in one and -10 V in the other
        assert!(
            na.state[5] > nb.state[5] + 1e-4,
            "{states} states: {} vs {} m/s",
            na.state[5],
            nb.state[5]
        );
    }
}

/// On the model's own rig, the open-loop chirp is tracked as well at 8.5-10.5 Hz
/// as at 1.5-3 Hz: the mean NIS of the 12-state filter over 30-40 s of the sweep
/// is within 1.4 times that over 4-10 s (measured 14.9 and 14.2), and the leak
/// sizes hold still within each second (the largest 1-s spread of the three
/// below 0.005 L/min; measured 0.0026). With the command one sample early (the
/// filter before 2026-11-25) the NIS rose from 15 to 44 along the sweep and
/// the internal-leak estimate swung up to ±0.022 L/min within a second
/// and by ±0.1 L/min between seconds.
#[test]
fn the_fast_end_of_the_chirp_is_tracked_like_the_slow_end() {
    let scenario = Scenario::by_name("open-loop-chirp", 1, 40.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), scenario, FaultSchedule::default(), 1)
            .unwrap();
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let (mut nis_slow, mut nis_fast) = ((0.0, 0), (0.0, 0));
    let (mut sum, mut sq, mut n, mut worst_spread) = ([0.0f64; 3], [0.0f64; 3], 0, 0.0f64);
    for k in 0..40_000 {
        let e = est.on_sample(&sim.step());
        let slot = match k {
            4_000..=9_999 => Some(&mut nis_slow),
            30_000.. => Some(&mut nis_fast),
            _ => None,
        };
        if let Some((s, c)) = slot {
            *s += e.nis;
            *c += 1;
        }
        if k >= 4_000 {
            for j in 0..3 {
                let q = e.state[7 + j] * 60_000.0;
                sum[j] += q;
                sq[j] += q * q;
            }
            n += 1;
            if n == 1000 {
                for j in 0..3 {
                    let mean = sum[j] / 1000.0;
                    worst_spread = worst_spread.max((sq[j] / 1000.0 - mean * mean).max(0.0).sqrt());
                }
                (sum, sq, n) = ([0.0; 3], [0.0; 3], 0);
            }
        }
    }
    let (slow, fast) = (nis_slow.0 / nis_slow.1 as f64, nis_fast.0 / nis_fast.1 as f64);
    eprintln!("mean NIS 4-10 s {slow:.1}, 30-40 s {fast:.1}; largest 1-s spread of a leak size {worst_spread:.4} L/min");
    assert!(
        fast < 1.4 * slow,
        "NIS {fast} at the fast end against {slow} at the slow end"
    );
    assert!(
        worst_spread < 0.005,
        "leak sizes spread {worst_spread} L/min within a second"
    );
}

/// Healthy `scenario` on the thesis rig whose oil warms from 25 to 55 °C with a
/// 15-s time constant (commissioned at 25 °C), with or without the oil's
/// temperature in the samples: the last θ, the factor the rig's bulk modulus
/// fell by, and the largest 1-s mean of any leak-size estimate over 10-60 s (L/min).
fn warming_run(scenario: &str, measured: bool, seed: u64) -> (f64, f64, f64) {
    let mut rig = ActuatorParams::default();
    rig.oil_temperature.reference_c = 25.0;
    let settings = model::SimSettings {
        oil: Some(model::OilWarmUp {
            start_c: 25.0,
            end_c: 55.0,
            time_constant_s: 15.0,
            measured,
        }),
        ..model::SimSettings::default()
    };
    let sc = Scenario::by_name(scenario, seed, 60.0).unwrap();
    let sensors = model::SensorParams::default();
    let mut sim = Simulator::new(rig.clone(), sensors, settings, sc, FaultSchedule::default(), seed).unwrap();
    let mut est = Estimator::new(rig.clone(), Tuning::sensor_derived()).unwrap();
    let (mut theta, mut worst, mut sum, mut n) = (f64::NAN, 0.0f64, [0.0; 3], 0);
    for k in 0..60_000 {
        let s = sim.step();
        assert_eq!(s.temp_c.is_finite(), measured);
        let e = est.on_sample(&s);
        theta = e.bulk_scale;
        if k >= 10_000 {
            for (acc, q) in sum.iter_mut().zip(&e.state[7..10]) {
                *acc += q * 60_000.0;
            }
            n += 1;
            if n == 1000 {
                worst = sum.iter().fold(worst, |w, acc| w.max((acc / 1000.0).abs()));
                (sum, n) = ([0.0; 3], 0);
            }
        }
    }
    if measured {
        assert!((est.oil_temp_c() - sim.oil_temp_c()).abs() < 0.1);
    } else {
        assert!(est.oil_temp_c().is_nan());
    }
    (theta, sim.rig().bulk_modulus_pa / rig.bulk_modulus_pa, worst)
}

/// The oil warms by 30 K over a run (bulk modulus −13.5 %, viscosity to about
/// a third, the seals' viscous friction to 0.6): with the temperature in the
/// samples the model follows it and θ stays within 0.03 of 1; without it θ
/// follows the stiffness instead, to within 0.04 of the rig's factor. Either
/// way the healthy leak estimates stay below 0.04 L/min (1-s means; measured
/// 0.016 and 0.030-0.034 L/min, as on a rig whose oil does not warm).
#[test]
fn a_warming_oil_is_followed_with_its_temperature_and_without_it() {
    for (scenario, seed) in [("loaded-sine", 21), ("closed-loop-random", 22)] {
        let (theta_t, factor, worst_t) = warming_run(scenario, true, seed);
        let (theta, factor_again, worst) = warming_run(scenario, false, seed);
        eprintln!(
            "{scenario}: bulk modulus ×{factor:.3}; with temp_c θ {theta_t:.3}, leaks ≤ {worst_t:.4} L/min; \
             without θ {theta:.3}, leaks ≤ {worst:.4} L/min"
        );
        assert_eq!(factor, factor_again);
        assert!((factor - (1.0 - 0.0045 * 30.0)).abs() < 0.01, "{factor}");
        assert!(
            (theta_t - 1.0).abs() < 0.03,
            "{scenario}: θ {theta_t} with the temperature"
        );
        assert!(
            (theta - factor).abs() < 0.04,
            "{scenario}: θ {theta} against ×{factor}"
        );
        assert!(
            worst_t < 0.04 && worst < 0.04,
            "{scenario}: {worst_t}, {worst} L/min"
        );
    }
}

/// A healthy loaded sine on the thesis rig with a leaky valve (null leakage
/// 2e-13 m³/(s·Pa) at 25 °C, 0.08 L/min a path at p_s/2) whose oil warms from
/// 25 to 55 °C (τ 15 s), with no thermometer; the model's bulk modulus known at
/// 25 °C when `identified`. Returns the largest 1-s mean of any leak-size
/// estimate over 20-60 s (L/min), the oil temperature the filter ended at and
/// the rig's (°C), and the last null-leakage band (L/min).
fn leaky_valve_warming_run(identified: bool) -> (f64, f64, f64, f64) {
    let mut rig = ActuatorParams::default();
    rig.oil_temperature.reference_c = 25.0;
    rig.valve_null_leakage_m3_s_pa = 2e-13;
    let settings = model::SimSettings {
        oil: Some(model::OilWarmUp {
            start_c: 25.0,
            end_c: 55.0,
            time_constant_s: 15.0,
            measured: false,
        }),
        ..model::SimSettings::default()
    };
    let sc = Scenario::by_name("loaded-sine", 31, 60.0).unwrap();
    let sensors = model::SensorParams::default();
    let mut sim = Simulator::new(rig.clone(), sensors, settings, sc, FaultSchedule::default(), 31).unwrap();
    let mut model = rig.clone();
    model.oil_temperature.reference_stiffness = identified.then_some(1.0);
    let mut est = Estimator::new(model, Tuning::sensor_derived()).unwrap();
    let (mut worst, mut sum, mut n, mut band) = (0.0f64, [0.0; 3], 0, f64::NAN);
    for k in 0..60_000 {
        let e = est.on_sample(&sim.step());
        band = e.null_leakage_band_lpm;
        if k >= 20_000 {
            for (acc, q) in sum.iter_mut().zip(&e.state[7..10]) {
                *acc += q * 60_000.0;
            }
            n += 1;
            if n == 1000 {
                worst = sum.iter().fold(worst, |w, acc| w.max((acc / 1000.0).abs()));
                (sum, n) = ([0.0; 3], 0);
            }
        }
    }
    (worst, est.oil_temp_c(), sim.oil_temp_c(), band)
}

/// Without a thermometer, a model whose bulk modulus was identified at its
/// reference temperature reads the oil's temperature from θ (within 5 K of the
/// rig's 30 K rise) and moves its null leakage with it: the healthy leak
/// estimates stay at half or less of what they reach when the null leakage
/// stays at its 25 °C value, and the filter says how uncertain that null
/// leakage now is: a band of 0.05-0.3 L/min on the 0.3 L/min a path it has
/// grown to (the law's 40 % and k_β's 20 %; 0 when nothing is inferred).
#[test]
fn a_leaky_valves_null_leakage_follows_the_temperature_read_from_the_oils_stiffness() {
    let (worst_held, t_held, _, band_held) = leaky_valve_warming_run(false);
    let (worst, t_read, t_rig, band) = leaky_valve_warming_run(true);
    eprintln!(
        "held: leaks ≤ {worst_held:.4} L/min; read from θ: {t_read:.1} °C (rig {t_rig:.1} °C), \
         leaks ≤ {worst:.4} L/min, band {band:.4} L/min"
    );
    assert!(t_held.is_nan() && band_held == 0.0, "{t_held} {band_held}");
    assert!((t_read - t_rig).abs() < 5.0, "{t_read} against {t_rig}");
    assert!(worst < 0.5 * worst_held, "{worst} against {worst_held}");
    assert!((0.05..0.3).contains(&band), "{band}");
}
