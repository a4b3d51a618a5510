//! Speed: EKF step time and replay throughput (docs/performance.md#estimation).

use std::time::Instant;

use detect::ClassifierConfig;
use filter::{Estimator, Tuning};
use model::{ActuatorParams, FaultSchedule, Sample, Scenario, Simulator};
use pipeline::{Chain, ChainSettings};
use serde::Serialize;

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
    recorded_samples_on(&ActuatorParams::default(), "loaded-sine", seconds)
}

/// The plant model the second chain runs: the in-repo vertical lift (single-rod,
/// gravity, a matched valve) with a valve null leakage of 0.1 L/min at supply
/// and a supply that sags 0.3 MPa per L/s, so every term of the model is live.
pub fn plant_model() -> ActuatorParams {
    let lift = ActuatorParams::vertical_lift();
    ActuatorParams {
        valve_null_leakage_m3_s_pa: 0.1 / 60_000.0 / lift.supply_pressure_pa,
        supply_sag_pa_per_m3_s: 3.0e8,
        ..lift
    }
}

/// `seconds` of `scenario` on `rig` with a 0.5 L/min chamber-1 leak from half time (seed 1).
pub fn recorded_samples_on(rig: &ActuatorParams, scenario: &str, seconds: f64) -> Vec<Sample> {
    let rig = rig.clone();
    let mut faults = FaultSchedule::default();
    if let Ok(f) = model::Fault::parse(&format!("ext1:0.5lpm@{}s", seconds / 2.0), &rig) {
        faults.faults.push(f);
    }
    let sc = match Scenario::by_name(scenario, 1, seconds) {
        Ok(s) => s,
        Err(_) => return Vec::new(),
    };
    match Simulator::with_default_sensors(rig, sc, faults, 1) {
        Ok(mut sim) => sim.run(seconds),
        Err(_) => Vec::new(),
    }
}

/// Step-time figures of one filter layout, every predict + update timed on its own.
#[derive(Debug, Clone, Serialize)]
pub struct StepTime {
    /// Filter description.
    pub filter: String,
    /// Number of states.
    pub states: u32,
    /// Steps timed (each one individually).
    pub steps: u64,
    /// Median time of one predict + update (one `Estimator::on_sample`), ns,
    /// including the clock's own cost (`timer_overhead_ns`).
    pub median_ns: f64,
    /// 99th percentile of the per-step times, ns (including the clock's cost).
    pub p99_ns: f64,
    /// 99.9th percentile of the per-step times, ns (including the clock's cost).
    pub p999_ns: f64,
    /// Largest per-step time, ns (including the clock's cost; preemption shows here).
    pub max_ns: f64,
    /// Mean of the per-step times, ns (including the clock's cost).
    pub mean_ns: f64,
    /// Median time of an empty timed region (two back-to-back `Instant::now()`), ns:
    /// the overhead included in every figure above.
    pub timer_overhead_ns: f64,
}

/// Value at quantile `q` (0..=1) of sorted `v`, nearest rank; NaN if empty.
fn quantile(v: &[u64], q: f64) -> f64 {
    v.get(((v.len() as f64 - 1.0) * q).round() as usize)
        .map(|x| *x as f64)
        .unwrap_or(f64::NAN)
}

/// Median cost of timing an empty region with `Instant` over `n` tries, ns.
pub fn timer_overhead_ns(n: usize) -> f64 {
    let mut d: Vec<u64> = (0..n)
        .map(|_| {
            let t0 = Instant::now();
            std::hint::black_box(());
            t0.elapsed().as_nanos() as u64
        })
        .collect();
    d.sort_unstable();
    quantile(&d, 0.5)
}

/// Times every predict + update of a filter individually over at least
/// `min_steps` steps of `samples` (restarting the filter at the end of the samples).
pub fn step_time(
    name: &str,
    tuning: &Tuning,
    samples: &[Sample],
    min_steps: u64,
    overhead_ns: f64,
) -> StepTime {
    let mut times: Vec<u64> = Vec::with_capacity(min_steps as usize + samples.len());
    let mut sink = 0.0;
    while (times.len() as u64) < min_steps {
        let mut est = match Estimator::new(ActuatorParams::default(), tuning.clone()) {
            Ok(e) => e,
            Err(_) => break,
        };
        let mut e = filter::Estimate::default();
        for s in samples {
            let t0 = Instant::now();
            est.on_sample_into(std::hint::black_box(s), &mut e);
            let dt = t0.elapsed();
            sink += e.nis;
            times.push(dt.as_nanos() as u64);
        }
    }
    std::hint::black_box(sink);
    let mean = times.iter().sum::<u64>() as f64 / times.len().max(1) as f64;
    times.sort_unstable();
    StepTime {
        filter: name.to_string(),
        states: tuning.states,
        steps: times.len() as u64,
        median_ns: quantile(&times, 0.5),
        p99_ns: quantile(&times, 0.99),
        p999_ns: quantile(&times, 0.999),
        max_ns: times.last().map(|x| *x as f64).unwrap_or(f64::NAN),
        mean_ns: mean,
        timer_overhead_ns: overhead_ns,
    }
}

/// Samples per second through the estimator stage and the classifier as
/// `leakwatch run` runs them by default (the leak filter; the thesis filter
/// runs only with its baseline), one core, in memory.
pub fn chain_throughput(samples: &[Sample], repeat: u32) -> Throughput {
    chain_throughput_on(
        "estimator stage (12-state leak filter) + classifier",
        &ActuatorParams::default(),
        samples,
        repeat,
        false,
    )
}

/// [`chain_throughput`] with the thesis' baseline on (`--thesis-baseline`:
/// the 7-state thesis filter and its MAE detector too).
pub fn chain_throughput_with_thesis(samples: &[Sample], repeat: u32) -> Throughput {
    chain_throughput_on(
        "the same with the thesis' baseline (+ 7-state thesis filter and its MAE detector)",
        &ActuatorParams::default(),
        samples,
        repeat,
        true,
    )
}

/// The transducers' lag the plant chain's leak filter counts, s: about what
/// commissioning reads on plant_dev's rigs.
pub const PLANT_PRESSURE_LAG_S: f64 = 0.5e-3;

/// [`chain_throughput`] on the plant model ([`plant_model`]) with its
/// transducers' lag counted ([`PLANT_PRESSURE_LAG_S`]), as a commissioned
/// plant rig runs.
pub fn plant_chain_throughput(samples: &[Sample], repeat: u32) -> Throughput {
    let set = ChainSettings {
        model: plant_model(),
        leak_filter: Tuning {
            pressure_lag_s: [PLANT_PRESSURE_LAG_S; 2],
            ..Tuning::sensor_derived()
        },
        ..ChainSettings::default()
    };
    chain_throughput_with(
        "the default chain on the plant model (single-rod lift, gravity, null leakage, supply sag, transducer lag)",
        &set,
        samples,
        repeat,
    )
}

/// [`chain_throughput`] with `model` in both filters, labelled `chain`, with
/// the thesis' baseline on or off (`thesis_baseline`).
pub fn chain_throughput_on(
    chain: &str,
    model: &ActuatorParams,
    samples: &[Sample],
    repeat: u32,
    thesis_baseline: bool,
) -> Throughput {
    let set = ChainSettings {
        model: model.clone(),
        classifier: ClassifierConfig {
            thesis_baseline,
            ..ClassifierConfig::default()
        },
        ..ChainSettings::default()
    };
    chain_throughput_with(chain, &set, samples, repeat)
}

/// Samples per second through the chain `set` makes, labelled `chain`.
pub fn chain_throughput_with(
    chain: &str,
    set: &ChainSettings,
    samples: &[Sample],
    repeat: u32,
) -> Throughput {
    let mut n = 0u64;
    let mut events = 0usize;
    let t0 = Instant::now();
    for _ in 0..repeat.max(1) {
        let Ok(mut chain) = Chain::new(set) else { break };
        for s in samples {
            chain.step(s, |_| events += 1);
            n += 1;
        }
    }
    std::hint::black_box(events);
    let wall = t0.elapsed().as_secs_f64();
    Throughput {
        chain: chain.into(),
        samples: n,
        wall_s: wall,
        samples_per_s: n as f64 / wall.max(1e-12),
    }
}
