//! Sensor trouble: gaps, NaN and a restart, dead and stuck sensors, a frozen position.

use detect::{Classifier, ClassifierConfig, EventKind, LeakEvent, Phase};
use model::{ActuatorParams, FaultSchedule, Scenario, SensorParams, SimSettings, Simulator};

use crate::{default_stage, off_nominal_rig, raised};

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
    // each says since when: its first missing, or frozen, reading
    assert!((13.99..14.01).contains(&dead.t_onset_s), "{dead:?}");
    assert!(find(EventKind::SensorDead, Phase::Cleared).is_some());
    let stuck = find(EventKind::SensorStuck, Phase::Raised).expect("stuck p1 reported");
    assert_eq!(stuck.channel, "p1");
    assert!((19.99..20.01).contains(&stuck.t_onset_s), "{stuck:?}");
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
    with_frozen_reading(scenario, SensorParams::default(), frozen, samples)
}

/// [`with_frozen_position`] read through `sensors`, the classifier told their
/// full scale and position noise as the config loader does.
fn with_frozen_reading(
    scenario: Scenario,
    sensors: SensorParams,
    frozen: std::ops::Range<usize>,
    samples: usize,
) -> Vec<LeakEvent> {
    let mut sim = Simulator::new(
        ActuatorParams::default(),
        sensors,
        SimSettings::default(),
        scenario,
        FaultSchedule::default(),
        62,
    )
    .unwrap();
    let (mut stage, _) = default_stage();
    let mut cls = Classifier::new(ClassifierConfig {
        pressure_full_scale_pa: sensors.pressure_full_scale_pa,
        position_noise_counts: sensors.position_noise_m / sensors.encoder_resolution_m,
        ..ClassifierConfig::default()
    })
    .unwrap();
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

/// A position sensor whose noise spans counts (the plant rigs': 3 µm on 2 µm)
/// does not repeat a reading while healthy, resting rod or not: frozen on a
/// resting rod, where the pressures fit the rest and say nothing, it is
/// `sensor-stuck` on x after `stuck_samples`, and no leak is raised.
#[test]
fn a_noisy_position_frozen_on_a_resting_rod_is_stuck() {
    let mut resting = Scenario::by_name("closed-loop-random", 62, 30.0).unwrap();
    resting.drive = model::scenario::Drive::ClosedLoopSteps {
        levels: vec![(0.0, 0.3), (3.0, 0.25)],
    };
    let events = with_frozen_reading(resting, SensorParams::plant(), 15_000..25_000, 30_000);
    let stuck = events
        .iter()
        .find(|e| e.kind == EventKind::SensorStuck && e.phase == Phase::Raised)
        .unwrap_or_else(|| panic!("a frozen noisy x is stuck: {events:#?}"));
    assert_eq!(stuck.channel, "x");
    assert!((14.99..15.01).contains(&stuck.t_onset_s), "{stuck:?}");
    assert!((16.99..17.01).contains(&stuck.t_detect_s), "{stuck:?}");
    assert!(stuck.detail.contains("noise spans 1.5 counts"), "{stuck:?}");
    assert!(
        stuck.detail.contains(
            "no leak is decided while it stands; once it clears, the healthy state is learned again over 8 s"
        ),
        "{stuck:?}"
    );
    assert!(
        events.iter().any(|e| e.kind == EventKind::SensorStuck
            && e.phase == Phase::Cleared
            && e.t_detect_s >= 24.99
            && e.detail
                .starts_with("the channel is back; leaks are decided again")),
        "{events:#?}"
    );
    assert!(events.iter().all(|e| !e.kind.is_leak()), "{events:#?}");
}
