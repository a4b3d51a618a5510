//! The classifier process decides on the estimate frames it receives. Those
//! carry all the detector reads (the oil's band, the offset and delay
//! responses), so a run's events are a replay's: a drifting transducer is
//! named, and no leak raised, through the wire as in one process.

use detect::{Classifier, ClassifierConfig, EventKind, LeakEvent, Phase};
use estimator::wire::EstimateWire;
use filter::{EstimatorStage, StageEstimate, Tuning};
use model::sensor_fault::SensorFaultSchedule;
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

/// The events of 240 s of the loaded random run (seed 11) with p2 drifting
/// 200 kPa/min from 20 s, decided in process and from each estimate's frame.
fn both_ways() -> (Vec<LeakEvent>, Vec<LeakEvent>) {
    let rig = ActuatorParams::default();
    let scenario = Scenario::by_name("loaded-random", 11, 240.0).expect("scenario");
    let faults = SensorFaultSchedule::parse_all(&["p2:drift=200kPa/min,max=500kPa@20s"]).expect("spec");
    let mut sim = Simulator::with_default_sensors(rig.clone(), scenario, FaultSchedule::default(), 11)
        .and_then(|s| s.with_sensor_faults(faults))
        .expect("rig");
    let mut stage = EstimatorStage::new(rig, Tuning::sensor_derived(), Tuning::thesis())
        .expect("stage")
        .with_thesis(false);
    let mut in_process = Classifier::new(ClassifierConfig::default()).expect("classifier");
    let mut over_wire = Classifier::new(ClassifierConfig::default()).expect("classifier");
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..240_000 {
        let e = stage.on_sample(&sim.step());
        in_process.on_stage(&e, |ev| a.push(ev));
        let received = StageEstimate::from_frame(&e.to_frame(), 0);
        // the delay's response, which widens a commissioned detector's thresholds, goes over too
        assert_eq!(
            received.leak.delay_response_lpm_per_ms, e.leak.delay_response_lpm_per_ms,
            "at {} s",
            e.leak.t_s
        );
        over_wire.on_stage(&received, |ev| b.push(ev));
    }
    (a, b)
}

#[test]
fn a_drift_is_named_over_the_wire_as_in_one_process() {
    let (in_process, over_wire) = both_ways();
    // (the same events, NaN sizes included: compared as printed)
    assert_eq!(format!("{in_process:?}"), format!("{over_wire:?}"));
    let named = over_wire
        .iter()
        .find(|e| e.kind == EventKind::SensorOffset && e.phase == Phase::Raised)
        .unwrap_or_else(|| panic!("not named: {over_wire:?}"));
    assert_eq!(named.channel, "p2");
    let leaks: Vec<_> = over_wire
        .iter()
        .filter(|e| e.kind.is_leak_alarm() && e.t_detect_s >= named.t_detect_s)
        .collect();
    assert!(leaks.is_empty(), "{leaks:?}");
}
