//! Speed: EKF step time and replay throughput (BENCHMARKS.md §1).

use std::time::Instant;

use classifier::{Classifier, ClassifierConfig};
use estimator::{Estimator, EstimatorStage, Tuning};
use model::{ActuatorParams, FaultSchedule, Sample, Scenario, SensorParams, SimSettings, Simulator};
use serde::Serialize;

/// Step-time figures of one filter layout.
#[derive(Debug, Clone, Serialize)]
pub struct StepTime {
    /// Filter description.
    pub filter: String,
    /// Number of states.
    pub states: u32,
    /// Steps timed.
    pub steps: u64,
    /// Median time per predict + update, ns.
    pub median_ns: f64,
    /// 99th percentile, ns (over blocks of 64 steps, so the clock's own cost is amortised).
    pub p99_ns: f64,
    /// Mean, ns.
    pub mean_ns: f64,
}

/// Throughput of the in-process chain.
#[derive(Debug, Clone, Serialize)]
pub struct Throughput {
    /// What ran.
    pub chain: String,
    /// Samples processed.
    pub samples: u64,
    /// Wall time, s.
    pub wall_s: f64,
    /// Samples per second on one core.
    pub samples_per_s: f64,
}

/// A recorded scenario: `seconds` of the loaded sine with a leak at half time.
pub fn recorded_samples(seconds: f64) -> Vec<Sample> {
    let rig = ActuatorParams::default();
    let mut faults = FaultSchedule::default();
    if let Ok(f) = model::Fault::parse(&format!("ext1:0.5lpm@{}s", seconds / 2.0), &rig) {
        faults.faults.push(f);
    }
    let sc = match Scenario::by_name("loaded-sine", 1, seconds) {
        Ok(s) => s,
        Err(_) => return Vec::new(),
    };
    match Simulator::new(
        rig,
        SensorParams::default(),
        SimSettings::default(),
        sc,
        faults,
        1,
    ) {
        Ok(mut sim) => sim.run(seconds),
        Err(_) => Vec::new(),
    }
}

/// Times predict + update of a filter over at least `min_steps` steps of `samples`.
pub fn step_time(name: &str, tuning: &Tuning, samples: &[Sample], min_steps: u64) -> StepTime {
    const BLOCK: usize = 64;
    let mut blocks: Vec<f64> = Vec::new();
    let mut steps = 0u64;
    let mut sink = 0.0;
    while steps < min_steps {
        let mut est = match Estimator::new(ActuatorParams::default(), tuning.clone()) {
            Ok(e) => e,
            Err(_) => break,
        };
        for chunk in samples.chunks(BLOCK) {
            let t0 = Instant::now();
            for s in chunk {
                sink += est.on_sample(s).nis;
            }
            blocks.push(t0.elapsed().as_nanos() as f64 / chunk.len() as f64);
            steps += chunk.len() as u64;
        }
    }
    std::hint::black_box(sink);
    let mean = blocks.iter().sum::<f64>() / blocks.len().max(1) as f64;
    blocks.sort_by(f64::total_cmp);
    let q = |p: f64| {
        blocks
            .get(((blocks.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    StepTime {
        filter: name.to_string(),
        states: tuning.states,
        steps,
        median_ns: q(0.5),
        p99_ns: q(0.99),
        mean_ns: mean,
    }
}

/// Samples per second through the estimator stage (both filters) and the classifier, one core, in memory.
pub fn chain_throughput(samples: &[Sample], repeat: u32) -> Throughput {
    let mut n = 0u64;
    let mut events = 0usize;
    let t0 = Instant::now();
    for _ in 0..repeat.max(1) {
        let mut stage = match EstimatorStage::new(
            ActuatorParams::default(),
            Tuning::sensor_derived(),
            Tuning::thesis(),
        ) {
            Ok(s) => s,
            Err(_) => break,
        };
        let mut cls = match Classifier::new(ClassifierConfig::default()) {
            Ok(c) => c,
            Err(_) => break,
        };
        for s in samples {
            let e = stage.on_sample(s);
            cls.on_stage(&e, |_| events += 1);
            n += 1;
        }
    }
    std::hint::black_box(events);
    let wall = t0.elapsed().as_secs_f64();
    Throughput {
        chain: "estimator stage (11-state leak filter + 7-state thesis filter) + classifier".into(),
        samples: n,
        wall_s: wall,
        samples_per_s: n as f64 / wall.max(1e-12),
    }
}
