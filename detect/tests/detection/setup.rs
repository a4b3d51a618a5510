//! The classifier's setup: too short a warm-up, the thesis baseline, the false-alarm threshold.

use detect::{ClassifierConfig, EventKind};
use model::ActuatorParams;

use crate::{off_nominal_rig, run, run_flow};

#[test]
fn too_short_a_warm_up_is_reported_not_guessed() {
    let events = run("closed-loop-sine", 6.0, None, 5, ActuatorParams::default());
    let na: Vec<_> = events.iter().filter(|e| e.kind == EventKind::NotArmed).collect();
    assert_eq!(na.len(), 1, "{events:#?}");
    assert!(na[0].detail.contains("warm-up too short"), "{:?}", na[0]);
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
