//! Running the cases: one case through the rig, the estimator stage and the
//! classifier, scored per detector; the whole suite on several threads.

use detect::{ClassifierConfig, LeakEvent};
use model::rng::Rng;
use model::{FaultSchedule, Scenario, Simulator};
use pipeline::{Chain, ChainSettings};

use super::{
    draw_rig, simulator_for, summarise, Case, GapSchedule, GapStep, Outcome, RunResult, SuiteResult,
    DETECTORS, FROM_START, GAPS, MID_RUN,
};

/// Runs one case through the rig, the estimator stage and the classifier.
pub fn run_case(case: &Case) -> Result<RunResult, String> {
    let mut cfg = ClassifierConfig {
        thesis_baseline: true,
        ..ClassifierConfig::default()
    };
    if case.variant == FROM_START {
        cfg.commissioning = Some(commission_rig(case)?);
    }
    let mut sim = simulator_for(case)?;
    let mut chain = Chain::new(&ChainSettings {
        classifier: cfg,
        ..ChainSettings::default()
    })?;
    let mut events: Vec<LeakEvent> = Vec::new();
    let n = (case.seconds / sim.sample_period_s()).round() as u64;
    let (mut flow, mut flow_n) = (0.0f64, 0.0f64);
    let mut gaps = GapSchedule::new(case.seed);
    for _ in 0..n {
        let s = sim.step();
        if s.t_s >= case.onset_s + case.ramp_s {
            flow += s.q_leak_lpm.abs();
            flow_n += 1.0;
        }
        if case.variant == GAPS && gaps.step(s.t_s) != GapStep::Kept {
            continue;
        }
        chain.step(&s, |ev| {
            if ev.kind.is_leak_alarm() {
                events.push(ev)
            }
        });
    }
    if std::env::var("LEAKWATCH_DEBUG_EVENTS").is_ok() {
        eprintln!(
            "{} events; first {:?}",
            events.len(),
            events.iter().take(3).collect::<Vec<_>>()
        );
    }
    let real = if case.kind == "none" {
        0.0
    } else {
        flow / flow_n.max(1.0)
    };
    let outcomes = DETECTORS
        .iter()
        .map(|d| {
            let mut o = score(case, d, &events);
            o.real_flow_lpm = real;
            o
        })
        .collect();
    Ok(RunResult {
        case: case.clone(),
        outcomes,
    })
}

/// The commissioning of a case's rig: 40 s of a healthy run of the same rig under the
/// same scenario with another seed (the rig's noise and reference differ).
pub fn commission_rig(case: &Case) -> Result<detect::Commissioning, String> {
    let healthy = Case {
        kind: "none".into(),
        size_lpm: 0.0,
        onset_s: f64::NAN,
        ramp_s: 0.0,
        seconds: 40.0,
        variant: MID_RUN.into(),
        ..case.clone()
    };
    let mut rng = Rng::new(case.seed);
    let rig = draw_rig(&mut rng);
    let scenario =
        Scenario::by_name(&healthy.scenario, case.seed ^ 1, healthy.seconds).map_err(|e| e.to_string())?;
    let mut sim = Simulator::with_default_sensors(rig, scenario, FaultSchedule::default(), case.seed ^ 1)
        .map_err(|e| e.to_string())?;
    let mut stage = ChainSettings::default().leak_stage()?;
    let mut learner = detect::CommissioningLearner::new(ClassifierConfig::default().settle_s);
    for _ in 0..40_000 {
        learner.on_estimate(&stage.on_sample(&sim.step()).leak);
    }
    learner.finish(
        &ClassifierConfig::default(),
        10.0,
        "40 s healthy run of the same rig",
    )
}

pub(super) fn score(case: &Case, detector: &str, events: &[LeakEvent]) -> Outcome {
    let mine: Vec<&LeakEvent> = events.iter().filter(|e| e.detector == detector).collect();
    let healthy = case.kind == "none";
    let alarms = crate::alarms::read(&mine, (!healthy).then_some(case.onset_s));
    // Detected at the first alarm (kind pending or named); the kind a user acts on is
    // the first one named; the size is the last word on the leak.
    let (detected, isolated, delay, size) = match alarms.first {
        Some(ev) => (
            true,
            alarms.first_named.is_some_and(|n| n.kind.name() == case.kind),
            ev.t_detect_s - case.onset_s,
            alarms.last.map(|e| e.size_lpm).unwrap_or(f64::NAN),
        ),
        None => (false, false, f64::NAN, f64::NAN),
    };
    Outcome {
        detector: detector.into(),
        detected,
        isolated,
        delay_s: delay,
        size_lpm: size,
        false_alarms: alarms.false_alarms,
        real_flow_lpm: f64::NAN,
    }
}

/// Runs the suite on `threads` threads; `progress` is called after each run with (done, total).
pub fn run_suite(cases: &[Case], threads: usize, progress: impl Fn(usize, usize) + Sync) -> SuiteResult {
    let t0 = std::time::Instant::now();
    // a case that cannot run is left out of the totals
    let all = crate::work::try_map(cases.len(), threads, |i| Ok(run_case(&cases[i]).ok()), progress);
    let runs: Vec<RunResult> = all.unwrap_or_default().into_iter().flatten().collect();
    summarise(runs, t0.elapsed().as_secs_f64())
}
