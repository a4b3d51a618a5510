//! Seeded detection tests: simulated rig (off-nominal), 10-state estimator,
//! classifier. Leaks of 0.5 L/min are found, isolated and sized; healthy runs
//! and a spring engaging mid-run raise nothing.

use detect::{Classifier, ClassifierConfig, EventKind, LeakEvent, Phase};
use filter::{Estimator, Tuning};
use model::{ActuatorParams, Fault, FaultSchedule, Scenario, Simulator};

/// A rig that differs from the model: friction +15 % extending, −10 % retracting,
/// bulk modulus −20 %, a spool null bias of 4 % of the spool amplitude.
fn off_nominal_rig() -> ActuatorParams {
    ActuatorParams::default().off_nominal(0.8, 0.04)
}

fn run(scenario: &str, seconds: f64, fault: Option<&str>, seed: u64, rig: ActuatorParams) -> Vec<LeakEvent> {
    run_flow(scenario, seconds, fault, seed, rig, ClassifierConfig::default()).0
}

/// Runs a scenario; returns the events and the |leak flow| the rig lost at each
/// sample, L/min (the reference a reported size is scored against).
fn run_flow(
    scenario: &str,
    seconds: f64,
    fault: Option<&str>,
    seed: u64,
    rig: ActuatorParams,
    cfg: ClassifierConfig,
) -> (Vec<LeakEvent>, Vec<f64>) {
    let scenario = Scenario::by_name(scenario, seed, seconds).unwrap();
    let mut sched = FaultSchedule::default();
    if let Some(f) = fault {
        sched.faults.push(Fault::parse(f, &rig).unwrap());
    }
    let mut sim = Simulator::with_default_sensors(rig, scenario, sched, seed).unwrap();
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let mut cls = Classifier::new(cfg).unwrap();
    let mut events = Vec::new();
    let n = (seconds * 1000.0).round() as usize;
    let mut t = 0.0;
    let mut flow = Vec::with_capacity(n);
    for _ in 0..n {
        let s = sim.step();
        t = s.t_s;
        flow.push(s.q_leak_lpm.abs());
        let e = est.on_sample(&s);
        cls.on_estimate(&e, |ev| events.push(ev));
    }
    cls.finish(t, |ev| events.push(ev));
    (events, flow)
}

/// Mean of a 1 kHz flow trace (sample k at (k + 1) ms) over [from_s, to_s], L/min.
fn mean_flow(trace: &[f64], from_s: f64, to_s: f64) -> f64 {
    let index = |t_s: f64| ((t_s * 1000.0).round() as usize).clamp(1, trace.len()) - 1;
    let part = &trace[index(from_s)..=index(to_s)];
    part.iter().sum::<f64>() / part.len() as f64
}

/// The built-in rig's estimator stage (sensor-derived leak filter, thesis
/// filter) and the default classifier.
fn default_stage() -> (filter::EstimatorStage, Classifier) {
    let stage = filter::EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .unwrap();
    (stage, Classifier::new(ClassifierConfig::default()).unwrap())
}

fn raised(events: &[LeakEvent], detector: &str) -> Vec<LeakEvent> {
    events
        .iter()
        .filter(|e| e.phase == Phase::Raised && e.detector == detector && e.kind.is_leak())
        .cloned()
        .collect()
}

/// The first leak alarm of a detector, kind pending or named.
fn first_alarm(events: &[LeakEvent], detector: &str) -> Option<LeakEvent> {
    events
        .iter()
        .find(|e| e.phase == Phase::Raised && e.detector == detector && e.kind.is_leak_alarm())
        .cloned()
}

fn check_leak(scenario: &str, kind: &str, expect: EventKind, seed: u64) {
    let onset = 20.0;
    let spec = format!("{kind}:0.5lpm@{onset}s");
    let (events, flow) = run_flow(
        scenario,
        32.0,
        Some(&spec),
        seed,
        off_nominal_rig(),
        ClassifierConfig::default(),
    );
    let r = raised(&events, "leak-size");
    assert_eq!(
        r.len(),
        1,
        "{scenario} {spec}: one event expected, got {events:#?}"
    );
    let ev = &r[0];
    assert_eq!(ev.kind, expect, "{scenario} {spec}: {ev:?}");
    // The first alarm (kind pending, or already named) within 2 s; the kind named on
    // the same event id.
    let first = first_alarm(&events, "leak-size").unwrap();
    assert_eq!(first.event_id, ev.event_id, "{events:#?}");
    let delay = first.t_detect_s - onset;
    assert!((0.0..2.0).contains(&delay), "{scenario} {spec}: delay {delay} s");
    assert!(
        ev.t_detect_s - first.t_detect_s < 4.0,
        "{scenario} {spec}: named at {} s",
        ev.t_detect_s
    );
    assert!(
        (ev.t_onset_s - onset).abs() < 1.0,
        "{scenario} {spec}: onset {}",
        ev.t_onset_s
    );
    // The size is the flow the rig really lost (at the chamber pressures, over the
    // 2 s before the event says it, since the onset if that is later), not the
    // nominal 0.5 L/min at p_s/2: an internal leak across a small drop loses less.
    let last = events
        .iter()
        .rev()
        .find(|e| e.event_id == ev.event_id && e.detector == "leak-size")
        .unwrap();
    let real_flow = mean_flow(&flow, (last.t_detect_s - 2.0).max(onset), last.t_detect_s);
    let size = last.size_lpm;
    assert!(
        (size - real_flow).abs() <= 0.25 * real_flow,
        "{scenario} {spec}: size {size} L/min at {} s against {real_flow} L/min lost",
        last.t_detect_s
    );
    assert!(ev.size_lpm_sigma > 0.0 && ev.size_lpm_sigma < 0.15, "{ev:?}");
    assert!(ev.statistic > ev.threshold && ev.threshold >= 4.0, "{ev:?}");
    // Beside the real flow: the size at p_s/2 (the 0.5 L/min the fault was given at).
    assert!((last.size_nominal_lpm - 0.5).abs() < 0.2, "{last:?}");
}

#[test]
fn leaks_are_found_isolated_and_sized_closed_loop() {
    check_leak("closed-loop-sine", "ext1", EventKind::Ext1, 11);
    check_leak("closed-loop-sine", "ext2", EventKind::Ext2, 12);
    check_leak("closed-loop-sine", "int", EventKind::Int, 13);
}

#[test]
fn leaks_are_found_isolated_and_sized_loaded() {
    check_leak("loaded-sine", "ext1", EventKind::Ext1, 21);
    check_leak("loaded-sine", "ext2", EventKind::Ext2, 22);
    check_leak("loaded-sine", "int", EventKind::Int, 23);
}

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

#[test]
fn too_short_a_warm_up_is_reported_not_guessed() {
    let events = run("closed-loop-sine", 6.0, None, 5, ActuatorParams::default());
    let na: Vec<_> = events.iter().filter(|e| e.kind == EventKind::NotArmed).collect();
    assert_eq!(na.len(), 1, "{events:#?}");
    assert!(na[0].detail.contains("warm-up too short"), "{:?}", na[0]);
}

/// Gaps, NaN samples and a restarted estimator on a healthy run: no leak event,
/// the restart reported as such.
#[test]
fn gaps_nan_and_a_restart_raise_no_false_leak() {
    let scenario = Scenario::by_name("closed-loop-sine", 51, 40.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(off_nominal_rig(), scenario, FaultSchedule::default(), 51).unwrap();
    let (mut stage, mut cls) = default_stage();
    let mut events = Vec::new();
    for k in 0..40_000 {
        let mut s = sim.step();
        match k {
            // NaN pressures for 50 samples
            15_000..=15_049 => s.p1_pa = f64::NAN,
            // an infinite position
            16_000 => s.x_m = f64::INFINITY,
            // a gap of 30 samples (bridged) and one of 600 (restart)
            18_000..=18_029 | 25_000..=25_599 => continue,
            _ => {}
        }
        let e = stage.on_sample(&s);
        cls.on_stage(&e, |ev| events.push(ev));
    }
    assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
    let resets: Vec<_> = events
        .iter()
        .filter(|e| e.kind == EventKind::EstimatorReset)
        .collect();
    // Gaps no longer reset the filter: the fast states re-anchor, the leak sizes stay.
    assert!(resets.is_empty(), "{resets:#?}");
    assert_eq!(stage.missing_samples(), 630);
}

/// A pressure channel that goes dead (NaN) and one that freezes are reported,
/// and cleared when they come back; neither raises a leak.
#[test]
fn dead_and_stuck_sensors_are_reported() {
    let scenario = Scenario::by_name("closed-loop-sine", 61, 30.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), scenario, FaultSchedule::default(), 61)
            .unwrap();
    let (mut stage, mut cls) = default_stage();
    let mut events = Vec::new();
    let mut frozen = 0.0;
    for k in 0..30_000 {
        let mut s = sim.step();
        if (14_000..14_500).contains(&k) {
            s.p2_pa = f64::NAN;
        }
        if k == 20_000 {
            frozen = s.p1_pa;
        }
        if (20_000..23_000).contains(&k) {
            s.p1_pa = frozen;
        }
        let e = stage.on_sample(&s);
        cls.on_stage(&e, |ev| events.push(ev));
    }
    let find = |kind: EventKind, phase: Phase| events.iter().find(|e| e.kind == kind && e.phase == phase);
    let dead = find(EventKind::SensorDead, Phase::Raised).expect("dead p2 reported");
    assert_eq!(dead.channel, "p2");
    assert!((14.19..14.21).contains(&dead.t_detect_s), "{dead:?}");
    assert!(find(EventKind::SensorDead, Phase::Cleared).is_some());
    let stuck = find(EventKind::SensorStuck, Phase::Raised).expect("stuck p1 reported");
    assert_eq!(stuck.channel, "p1");
    assert!(find(EventKind::SensorStuck, Phase::Cleared).is_some());
    assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
}

/// The classifier's events on scenario `scenario` (the default rig, seed 62)
/// with the position reading frozen over samples `frozen` (at 1 kHz).
fn with_frozen_position(
    scenario: Scenario,
    frozen: std::ops::Range<usize>,
    samples: usize,
) -> Vec<LeakEvent> {
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), scenario, FaultSchedule::default(), 62)
            .unwrap();
    let (mut stage, mut cls) = default_stage();
    let (mut events, mut held) = (Vec::new(), 0.0);
    for k in 0..samples {
        let mut s = sim.step();
        if k == frozen.start {
            held = s.x_m;
        }
        if frozen.contains(&k) {
            s.x_m = held;
        }
        let e = stage.on_sample(&s);
        cls.on_stage(&e, |ev| events.push(ev));
    }
    events
}

/// A position reading frozen while the rod moves is `sensor-stuck` on x, and
/// no leak; frozen while the rod rests (a fine encoder at rest reads the same)
/// it is not: the pressures fit a resting rod.
#[test]
fn a_frozen_position_is_stuck_only_while_the_pressures_say_the_rod_moves() {
    let moving = Scenario::by_name("closed-loop-sine", 62, 30.0).unwrap();
    let events = with_frozen_position(moving, 20_000..26_000, 30_000);
    let stuck = events
        .iter()
        .find(|e| e.kind == EventKind::SensorStuck && e.phase == Phase::Raised)
        .expect("a frozen x on a moving rod is stuck");
    assert_eq!(stuck.channel, "x");
    assert!((22.0..22.1).contains(&stuck.t_detect_s), "{stuck:?}");
    assert!(
        events
            .iter()
            .any(|e| e.kind == EventKind::SensorStuck && e.phase == Phase::Cleared),
        "{events:#?}"
    );
    assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");

    let mut resting = Scenario::by_name("closed-loop-random", 62, 30.0).unwrap();
    resting.drive = model::scenario::Drive::ClosedLoopSteps {
        levels: vec![(0.0, 0.3), (3.0, 0.25)],
    };
    let events = with_frozen_position(resting, 15_000..25_000, 30_000);
    assert!(
        events.iter().all(|e| e.kind != EventKind::SensorStuck),
        "{events:#?}"
    );
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

#[test]
fn a_leak_growing_over_minutes_is_caught_by_the_held_baseline() {
    // 0.6 L/min reached over 300 s. The adapting baseline (τ = 15 s) would lag such a
    // slow ramp by only 0.03 L/min; each time the rise passes half its threshold
    // the baseline holds (up to 5 s at a time), so the leak is raised as an ordinary
    // rise while it is still small (here before it reaches 0.15 L/min), not only
    // when the baseline's drift since the warm-up passes `slow_leak_lpm` (0.5 L/min).
    let (onset, ramp, size) = (20.0, 300.0, 0.6);
    let spec = format!("ext1:{size}lpm@{onset}s,ramp={ramp}");
    let events = run("closed-loop-sine", 330.0, Some(&spec), 31, off_nominal_rig());
    let r = raised(&events, "leak-size");
    assert_eq!(r.len(), 1, "{events:#?}");
    let ev = &r[0];
    assert_eq!(ev.kind, EventKind::Ext1, "{ev:?}");
    let scheduled = size * ((ev.t_detect_s - onset) / ramp).min(1.0);
    assert!(
        scheduled < 0.15,
        "raised at {} s, when {scheduled} L/min leaked",
        ev.t_detect_s
    );
    // The size is the rise above the baseline: what the baseline took up of the ramp
    // before it held (a few hundredths of a L/min) is missing from it, so the
    // first size is checked to that lag, and the last update, near 0.6 L/min, to 10 %.
    assert!(
        (ev.size_nominal_lpm - scheduled).abs() <= 0.15 * scheduled + 0.035,
        "nominal size {} L/min against {scheduled} scheduled at {} s",
        ev.size_nominal_lpm,
        ev.t_detect_s
    );
    let last = events
        .iter()
        .rev()
        .find(|e| e.event_id == ev.event_id && e.detector == "leak-size")
        .unwrap();
    let scheduled_last = size * ((last.t_detect_s - onset) / ramp).min(1.0);
    assert!(
        scheduled_last > 0.8 * size && (last.size_nominal_lpm - scheduled_last).abs() <= 0.1 * scheduled_last,
        "last size {} L/min at {} s against {scheduled_last} scheduled",
        last.size_nominal_lpm,
        last.t_detect_s
    );
}

/// Healthy closed-loop samples of an off-nominal rig (seeded), `seconds` long.
fn healthy_samples(scenario: &str, seconds: f64, seed: u64) -> Vec<model::Sample> {
    let scenario = Scenario::by_name(scenario, seed, seconds).unwrap();
    let mut sim =
        Simulator::with_default_sensors(off_nominal_rig(), scenario, FaultSchedule::default(), seed).unwrap();
    (0..(seconds * 1000.0) as usize).map(|_| sim.step()).collect()
}

/// 40 s of the off-nominal rig under the loaded sine with a 0.5 L/min ext1 leak at 20 s.
fn ext1_leak_samples(seed: u64) -> Vec<model::Sample> {
    let seconds = 40.0;
    let rig = off_nominal_rig();
    let scenario = Scenario::by_name("loaded-sine", seed, seconds).unwrap();
    let mut sched = FaultSchedule::default();
    sched.faults.push(Fault::parse("ext1:0.5lpm@20s", &rig).unwrap());
    let mut sim = Simulator::with_default_sensors(rig, scenario, sched, seed).unwrap();
    (0..(seconds * 1000.0) as usize).map(|_| sim.step()).collect()
}

fn replay_events(samples: &[model::Sample], cfg: ClassifierConfig) -> Vec<LeakEvent> {
    let mut stage = filter::EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .unwrap();
    let mut cls = Classifier::new(cfg).unwrap();
    let mut events = Vec::new();
    for s in samples {
        let e = stage.on_sample(s);
        cls.on_stage(&e, |ev| events.push(ev));
    }
    events
}

/// Gaps of 1 to 2000 missing samples at positions all over a healthy run raise no
/// leak (the thesis-free reproduction of a 30-sample gap that raised 120 L/min).
#[test]
fn gaps_of_any_length_at_any_position_raise_no_leak() {
    for (scenario, seed) in [("loaded-sine", 71), ("closed-loop-random", 72)] {
        let all = healthy_samples(scenario, 30.0, seed);
        for len in [1usize, 2, 5, 6, 25, 30, 50, 51, 200, 2000] {
            for start in [11_000usize, 13_240, 17_777, 22_500] {
                let cut: Vec<model::Sample> = all
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i < start || *i >= start + len)
                    .map(|(_, s)| *s)
                    .collect();
                let events = replay_events(&cut, ClassifierConfig::default());
                let r = raised(&events, "leak-size");
                assert!(r.is_empty(), "{scenario}: gap of {len} at sample {start}: {r:#?}");
            }
        }
    }
}

/// A stream that loses one sample in a thousand (a UDP link, a DAQ dropping rows)
/// still arms and finds a 0.5 L/min leak as fast as the complete stream: the
/// filter bridges each lost sample by prediction, so the detector keeps taking
/// evidence (it used to go blind for 2 s after every gap, never armed, and said
/// nothing at all).
#[test]
fn one_lost_sample_in_a_thousand_does_not_blind_the_detector() {
    let all = ext1_leak_samples(93);
    let lossy: Vec<model::Sample> = all
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 1000 != 500)
        .map(|(_, s)| *s)
        .collect();
    assert_eq!(all.len() - lossy.len(), 40);
    let complete = first_alarm(&replay_events(&all, ClassifierConfig::default()), "leak-size")
        .expect("the complete stream finds the leak");
    let events = replay_events(&lossy, ClassifierConfig::default());
    let first = first_alarm(&events, "leak-size").expect("the lossy stream finds the leak");
    eprintln!(
        "first alarm: complete stream {:.3} s, one sample in 1000 lost {:.3} s",
        complete.t_detect_s, first.t_detect_s
    );
    assert!(
        first.t_detect_s > 20.0 && (first.t_detect_s - complete.t_detect_s).abs() < 0.5,
        "lossy {:.2} s against complete {:.2} s",
        first.t_detect_s,
        complete.t_detect_s
    );
    let before: Vec<_> = raised(&events, "leak-size")
        .into_iter()
        .filter(|e| e.t_detect_s < 20.0)
        .collect();
    assert!(before.is_empty(), "false alarms before the onset: {before:#?}");
}

/// A 0.5 L/min ext1 leak that opens inside a 2 s gap is reported after the gap, as
/// ext1 and sized against the flow it passes: the leak filter keeps its leak sizes
/// through a gap, so the baseline is held, not taken again with the leak in it.
#[test]
fn a_leak_opening_inside_a_gap_is_reported_after_it() {
    let all = ext1_leak_samples(91);
    let (gap_from_s, gap_to_s) = (19.0, 21.0);
    let kept: Vec<model::Sample> = all
        .iter()
        .filter(|s| s.t_s < gap_from_s || s.t_s >= gap_to_s)
        .copied()
        .collect();
    let events = replay_events(&kept, ClassifierConfig::default());
    let first = first_alarm(&events, "leak-size").expect("the leak opened in the gap is reported");
    assert!(
        first.t_detect_s > gap_to_s && first.t_detect_s < gap_to_s + 5.0,
        "reported at {:.2} s, the gap ends at {gap_to_s} s",
        first.t_detect_s
    );
    let named = raised(&events, "leak-size")
        .into_iter()
        .find(|e| e.kind != EventKind::Leak)
        .expect("the kind is named");
    assert_eq!(named.kind, EventKind::Ext1, "{named:#?}");
    // (the size stated last, once the estimate has settled after the gap)
    let last = events
        .iter()
        .rfind(|e| e.detector == "leak-size" && e.event_id == named.event_id && e.phase != Phase::Cleared)
        .expect("the named event");
    let flow: Vec<f64> = all.iter().map(|s| s.q_leak_lpm.abs()).collect();
    let real = mean_flow(&flow, last.t_detect_s - 2.0, last.t_detect_s);
    assert!(
        (last.size_lpm - real).abs() < 0.1 * real,
        "size {:.3} L/min at {:.1} s against a real flow of {real:.3} L/min",
        last.size_lpm,
        last.t_detect_s
    );
}

/// An external leak of 0.08 L/min (nominal) is declared as ext2 with the default
/// floors; its floor is `min_size_lpm`: raised to 0.1 L/min of real flow it hides
/// the leak, while the internal leak's floor raised as much does not. (The leak
/// was 0.05 L/min until q_leak went to 2e-18: the stick-slipping sine rig's
/// learned thresholds are 0.05-0.06 L/min since, above the external floor.)
#[test]
fn a_small_external_leak_is_governed_by_the_external_floor() {
    let mut found = 0;
    for seed in [101, 102, 103] {
        let run = |cfg: ClassifierConfig| {
            let (events, _) = run_flow(
                "closed-loop-sine",
                45.0,
                Some("ext2:0.08lpm@20s"),
                seed,
                off_nominal_rig(),
                cfg,
            );
            raised(&events, "leak-size")
        };
        let cfg = ClassifierConfig::default();
        let named = |r: &[LeakEvent]| r.iter().find(|e| e.kind != EventKind::Leak).map(|e| e.kind);
        let by_default = run(cfg.clone());
        if by_default.is_empty() {
            continue;
        }
        found += 1;
        assert!(by_default[0].t_detect_s > 20.0, "seed {seed}: {by_default:#?}");
        assert_eq!(
            named(&by_default),
            Some(EventKind::Ext2),
            "seed {seed}: {by_default:#?}"
        );
        let high_internal = run(ClassifierConfig {
            min_internal_size_lpm: 0.1,
            ..cfg.clone()
        });
        assert_eq!(
            named(&high_internal),
            Some(EventKind::Ext2),
            "seed {seed}: {high_internal:#?}"
        );
        let high_external = run(ClassifierConfig {
            min_size_lpm: 0.1,
            ..cfg
        });
        assert!(high_external.is_empty(), "seed {seed}: {high_external:#?}");
    }
    assert!(found >= 2, "{found} of 3 declared");
}

/// With a commissioning learned on a healthy recording of the rig, a 0.5 L/min leak
/// present from t = 0 is reported within 2 s of the start, as the right kind.
#[test]
fn a_leak_present_at_start_is_seen_with_a_commissioning() {
    let healthy = healthy_samples("closed-loop-sine", 30.0, 81);
    let mut stage = filter::EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .unwrap();
    let mut learner = detect::CommissioningLearner::new(ClassifierConfig::default().settle_s);
    for s in &healthy {
        learner.on_estimate(&stage.on_sample(s).leak);
    }
    let c = learner
        .finish(&ClassifierConfig::default(), 10.0, "healthy.csv")
        .unwrap();
    assert!(c.healthy_s > 25.0 && c.healthy_s < 29.0, "{c:?}");
    assert!(c.spreads_lpm.iter().all(|s| *s > 0.0 && *s < 0.05), "{c:?}");
    // Too little healthy data is refused, not guessed.
    assert!(detect::CommissioningLearner::new(2.0)
        .finish(&ClassifierConfig::default(), 10.0, "")
        .is_err());
    for (kind, expect) in [("ext1", EventKind::Ext1), ("int", EventKind::Int)] {
        let cfg = ClassifierConfig {
            commissioning: Some(c.clone()),
            ..ClassifierConfig::default()
        };
        let spec = format!("{kind}:0.5lpm@0s");
        let (events, _) = run_flow("closed-loop-sine", 8.0, Some(&spec), 82, off_nominal_rig(), cfg);
        let r = raised(&events, "leak-size");
        assert!(!r.is_empty(), "{spec}: nothing raised {events:#?}");
        assert_eq!(r[0].kind, expect, "{spec}: {:?}", r[0]);
        let first = first_alarm(&events, "leak-size").unwrap();
        assert!(
            first.t_detect_s <= 2.0,
            "{spec}: raised at {} s",
            first.t_detect_s
        );
        // Without it the same leak is never reported (it is learned as healthy).
        let events = run("closed-loop-sine", 16.0, Some(&spec), 82, off_nominal_rig());
        assert!(raised(&events, "leak-size").is_empty(), "{events:#?}");
    }
}

/// A leak that opens at 10 s of a loaded sine is reported (the warm-up is over by then).
#[test]
fn a_leak_at_ten_seconds_is_reported() {
    let events = run(
        "loaded-sine",
        20.0,
        Some("ext1:0.5lpm@10s"),
        91,
        off_nominal_rig(),
    );
    let r = raised(&events, "leak-size");
    assert_eq!(r.len(), 1, "{events:#?}");
    assert_eq!(r[0].kind, EventKind::Ext1);
    let first = first_alarm(&events, "leak-size").unwrap();
    assert!((10.0..12.0).contains(&first.t_detect_s), "{first:?}");
}

/// The thesis' MAE detector reports only when asked to, and says it is the baseline.
#[test]
fn the_thesis_baseline_is_off_unless_asked_for() {
    let spec = "ext1:1lpm@15s";
    let off = run("closed-loop-sine", 25.0, Some(spec), 92, off_nominal_rig());
    assert!(off.iter().all(|e| e.detector != "thesis-mae"), "{off:#?}");
    let cfg = ClassifierConfig {
        thesis_baseline: true,
        ..ClassifierConfig::default()
    };
    let (on, _) = run_flow("closed-loop-sine", 25.0, Some(spec), 92, off_nominal_rig(), cfg);
    let mae: Vec<_> = on.iter().filter(|e| e.detector == "thesis-mae").collect();
    assert!(!mae.is_empty(), "{on:#?}");
    assert!(mae[0].detail.contains("thesis baseline"), "{:?}", mae[0]);
}

/// Rice's formula: the threshold for a rate of false upcrossings, in spreads.
#[test]
fn threshold_from_the_false_alarm_rate() {
    // 1 upcrossing of the mean per second = 3600/h; 0.05/h asks e^(-c²/2) = 0.05/3600.
    let c = detect::rice_threshold(1.0, 0.05, 0.0);
    assert!((c - (2.0f64 * 72_000.0f64.ln()).sqrt()).abs() < 1e-12, "{c}");
    assert!((c - 4.7296).abs() < 1e-3, "{c}");
    // Ten times rarer alarms ask for a higher threshold; the floor holds.
    assert!(detect::rice_threshold(1.0, 0.005, 0.0) > c);
    assert_eq!(detect::rice_threshold(1e-9, 0.05, 4.0), 4.0);
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

/// A leak while the rod sits at its stop is seen: a spool null bias of 7.5 µm
/// walks the rod of an open-loop chirp into its extended stop within 15 s, where
/// it stays; a 1 L/min chamber-1 leak opens at 20 s. The leak filter's model has
/// the stop as the rig has it (a stiff spring-damper, stepped in 8 sub-steps), so
/// the leak estimates stay clean there: the leak is raised within 1 s and the
/// first kind it is named is ext1 (measured: 0.29 s, kind pending, then ext1).
/// Until 2026-11-25 no evidence counted at a stop, and the leak was never raised.
#[test]
fn a_leak_is_raised_while_the_rod_sits_at_its_stop() {
    let rig = ActuatorParams {
        spool_null_bias_m: 7.5e-6,
        ..ActuatorParams::default()
    };
    // the rod is at its stop from before the onset to the end of the run
    let scenario = Scenario::by_name("open-loop-chirp", 41, 30.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(rig.clone(), scenario, FaultSchedule::default(), 41).unwrap();
    let x_min_after_15_s = (0..30_000)
        .map(|_| sim.step())
        .filter(|s| s.t_s >= 15.0)
        .map(|s| s.x_m)
        .fold(f64::INFINITY, f64::min);
    assert!(x_min_after_15_s > rig.x_max_m - 0.02, "{x_min_after_15_s} m");
    let (events, _) = run_flow(
        "open-loop-chirp",
        30.0,
        Some("ext1:1lpm@20s"),
        41,
        rig,
        ClassifierConfig::default(),
    );
    let first = first_alarm(&events, "leak-size").expect("a leak alarm");
    eprintln!("first alarm {:.3} s: {:?}", first.t_detect_s, first.kind);
    assert!(
        first.t_detect_s > 20.0 && first.t_detect_s < 21.0,
        "{first:?}\n{events:#?}"
    );
    let named = raised(&events, "leak-size");
    assert!(!named.is_empty(), "{events:#?}");
    assert_eq!(named[0].kind, EventKind::Ext1, "{events:#?}");
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
