//! Leaks found, isolated and sized: closed loop, loaded, slow growth, small, at start, at a stop.

use detect::{ClassifierConfig, EventKind, LeakEvent};
use filter::Tuning;
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

use crate::{first_alarm, healthy_samples, mean_flow, off_nominal_rig, raised, run, run_flow};

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
