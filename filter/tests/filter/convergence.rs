//! Healthy runs: convergence from the thesis start, the 6-state filter, the effective load.

use filter::{Estimator, Tuning, FLAG_RESET};
use model::{ActuatorParams, FaultSchedule, FrictionPreset, Scenario, Simulator};

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
