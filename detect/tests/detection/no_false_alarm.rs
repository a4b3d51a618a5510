//! Healthy runs that raise no leak: off-nominal rigs, a spring, end-stop drifts, a fast chirp.

use detect::{Classifier, ClassifierConfig, EventKind};
use filter::{Estimator, Tuning};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

use crate::{off_nominal_rig, raised, run, run_flow};

#[test]
fn healthy_off_nominal_runs_raise_no_leak() {
    for (sc, seed) in [
        ("closed-loop-sine", 31),
        ("loaded-sine", 32),
        ("closed-loop-random", 33),
    ] {
        let events = run(sc, 40.0, None, seed, off_nominal_rig());
        let r = raised(&events, "leak-size");
        assert!(r.is_empty(), "{sc}: false alarm {r:#?}");
    }
}

#[test]
fn a_spring_engaging_mid_run_raises_no_leak() {
    // Closed-loop sine around 0.3 m touches a spring at 0.35 m only after t = 20 s,
    // when the spring is moved into reach.
    let mut rig = off_nominal_rig();
    rig.load = model::params::SpringLoad {
        stiffness_n_per_m: 2e4,
        contact_m: 0.45,
        ..Default::default()
    };
    let scenario = Scenario::by_name("closed-loop-sine", 41, 40.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, FaultSchedule::default(), 41).unwrap();
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let mut cls = Classifier::new(ClassifierConfig::default()).unwrap();
    let mut events = Vec::new();
    for _ in 0..40_000 {
        let s = sim.step();
        if (s.t_s - 20.0).abs() < 0.5e-3 {
            sim.rig_mut().load.contact_m = 0.2;
        }
        let e = est.on_sample(&s);
        cls.on_estimate(&e, |ev| events.push(ev));
    }
    assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
}

/// The rig of detection-suite seed 3176593409338201021: friction −6 % extending and
/// −17 % retracting, bulk modulus −28 %, a spool null bias of 25 % of the spool
/// amplitude at 3 V. Under the open-loop sine it drifts into the extended end stop
/// within 18 s and then hits it once a cycle (chamber 2 empties to tank).
fn drifting_rig() -> ActuatorParams {
    let mut rig = ActuatorParams::default();
    let mut ext = rig.friction.extend();
    let mut ret = ext;
    for (side, f) in [(&mut ext, 0.9406), (&mut ret, 0.8334)] {
        side.static_n *= f;
        side.slip_n *= f;
        side.viscous_n_s_per_m *= f;
    }
    rig.friction.set_extend(ext);
    rig.friction.retract = Some(ret);
    rig.bulk_modulus_pa = 4.932e8;
    rig.spool_null_bias_m = 6.199e-6;
    rig
}

#[test]
fn an_open_loop_drift_into_the_end_stop_raises_no_leak() {
    // With thresholds on the offset learned in the warm-up, this run raised a false
    // internal leak at 18.9 s: the healthy model's error while the rod is pressed
    // into its stop moves the leak estimates. Excursions to tank or supply pressure
    // hold the baseline and gather no evidence.
    let events = run("open-loop-sine", 60.0, None, 7, drifting_rig());
    let armed = events.iter().all(|e| e.kind != EventKind::NotArmed);
    assert!(armed, "{events:#?}");
    assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
}

/// The open-loop chirp sweeps to 10.5 Hz. With the command one sample early in
/// the filters (before 2026-11-25), past about 4 Hz the leak estimates wandered
/// by a tenth of a L/min and this run raised a leak unless a command-rate gate
/// (`max_command_hz`) and the NIS-ratio gate took the evidence away. With the
/// command held as the rig holds it, neither gate is needed: the run raises
/// nothing with both off.
#[test]
fn a_fast_chirp_raises_no_leak() {
    for cfg in [
        ClassifierConfig::default(),
        ClassifierConfig {
            max_command_hz: 0.0,
            nis_ratio_gate: 0.0,
            ..ClassifierConfig::default()
        },
    ] {
        let (events, _) = run_flow("open-loop-chirp", 80.0, None, 93, ActuatorParams::default(), cfg);
        assert!(
            events.iter().all(|e| e.kind != EventKind::NotArmed),
            "{events:#?}"
        );
        assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
    }
}

#[test]
fn a_rod_drifting_into_its_end_stop_raises_no_leak() {
    // Open loop, a spool null bias walks the rod into the end of its stroke, where it
    // then knocks against the stop once per cycle of the sine: a contact far stiffer
    // than the 1 kHz model follows. The leak estimates move while it lasts; the
    // estimator flags those samples and they are no evidence.
    // (bulk modulus −30 %, friction off-nominal, a bias of 4 % of the spool amplitude:
    // without the flag this run raises an internal leak at the stop)
    let mut rig = ActuatorParams::default().off_nominal(0.7, 0.0);
    rig.spool_null_bias_m = 3.5e-6;
    let scenario = Scenario::by_name("open-loop-sine", 51, 70.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, FaultSchedule::default(), 51).unwrap();
    let params = ActuatorParams::default();
    let mut est = Estimator::new(params.clone(), Tuning::sensor_derived()).unwrap();
    let mut cls = Classifier::new(ClassifierConfig::default()).unwrap();
    let (mut events, mut at_stop, mut x_max_seen) = (Vec::new(), 0, 0.0f64);
    for _ in 0..70_000 {
        let s = sim.step();
        x_max_seen = x_max_seen.max(s.x_m);
        let e = est.on_sample(&s);
        if e.flags & filter::FLAG_END_STOP != 0 {
            at_stop += 1;
        }
        cls.on_estimate(&e, |ev| events.push(ev));
    }
    assert!(
        x_max_seen > params.x_max_m - 1e-3 && at_stop > 1000,
        "the rod must reach the stop: x max {x_max_seen} m, {at_stop} samples flagged"
    );
    assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
}
