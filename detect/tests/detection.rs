//! Seeded detection tests: simulated rig (off-nominal), 10-state estimator,
//! classifier. Leaks of 0.5 L/min are found, isolated and sized; healthy runs
//! and a spring engaging mid-run raise nothing.

use detect::{Classifier, ClassifierConfig, LeakEvent, Phase};
use filter::{Estimator, Tuning};
use model::{ActuatorParams, Fault, FaultSchedule, Scenario, Simulator};

#[path = "detection/found.rs"]
mod found;
#[path = "detection/lost_samples.rs"]
mod lost_samples;
#[path = "detection/no_false_alarm.rs"]
mod no_false_alarm;
#[path = "detection/sensor_trouble.rs"]
mod sensor_trouble;
#[path = "detection/setup.rs"]
mod setup;

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

/// Healthy closed-loop samples of an off-nominal rig (seeded), `seconds` long.
fn healthy_samples(scenario: &str, seconds: f64, seed: u64) -> Vec<model::Sample> {
    let scenario = Scenario::by_name(scenario, seed, seconds).unwrap();
    let mut sim =
        Simulator::with_default_sensors(off_nominal_rig(), scenario, FaultSchedule::default(), seed).unwrap();
    (0..(seconds * 1000.0) as usize).map(|_| sim.step()).collect()
}
