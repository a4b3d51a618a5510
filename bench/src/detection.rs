//! The seeded detection suite of BENCHMARKS.md §2: both detectors side by
//! side on the same simulated runs, in parallel over the cores.
//!
//! Each run draws (from its own seed) a scenario, a rig that differs from the
//! model (friction ±20 % and asymmetric, bulk modulus −30..0 %, spool null bias
//! up to 10 % of the spool amplitude), and a fault: a leak of a given kind and
//! size (L/min at the nominal drop p_s/2), as a step or a ramp of up to 5 s, at
//! a random time in [15, 25] s. Healthy runs measure false alarms per hour.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use classifier::{Classifier, ClassifierConfig, EventKind, LeakEvent};
use estimator::{EstimatorStage, Tuning};
use model::rng::Rng;
use model::{ActuatorParams, Fault, FaultSchedule, LeakPath, Scenario, SensorParams, SimSettings, Simulator};
use serde::Serialize;

/// Leak sizes of the suite, L/min at the nominal drop.
pub const SIZES_LPM: [f64; 6] = [0.05, 0.1, 0.15, 0.25, 0.5, 1.0];
/// Scenarios drawn by the suite.
pub const SCENARIOS: [&str; 6] = [
    "open-loop-sine",
    "open-loop-chirp",
    "closed-loop-sine",
    "closed-loop-random",
    "loaded-sine",
    "loaded-random",
];
/// Variant of a leak run: the leak opens mid-run after the warm-up.
pub const MID_RUN: &str = "";
/// Variant of a leak run: the leak is there from t = 0, with a commissioning learned
/// on a healthy run of the same rig.
pub const FROM_START: &str = "from-start";
/// Variant of a healthy run: samples lost in gaps of 1 to 2000 samples every 10-30 s.
pub const GAPS: &str = "gaps";
/// The two detectors, as named in events.
pub const DETECTORS: [&str; 2] = ["leak-size", "thesis-mae"];
/// Seconds simulated after the onset of a leak.
pub const AFTER_ONSET_S: f64 = 10.0;
/// Length of one healthy run, s.
pub const HEALTHY_RUN_S: f64 = 300.0;

/// One simulated run of the suite.
#[derive(Debug, Clone, Serialize)]
pub struct Case {
    /// Seed of everything random in the run.
    pub seed: u64,
    /// Scenario name.
    pub scenario: String,
    /// Leak kind (`ext1`, `ext2`, `int`) or `none`.
    pub kind: String,
    /// Leak size at nominal drop, L/min (0 when healthy).
    pub size_lpm: f64,
    /// Onset, s (NaN when healthy).
    pub onset_s: f64,
    /// Ramp duration, s (0 = step).
    pub ramp_s: f64,
    /// Simulated length, s.
    pub seconds: f64,
    /// [`MID_RUN`], [`FROM_START`] or [`GAPS`].
    pub variant: String,
}

/// What one detector did in one run.
#[derive(Debug, Clone, Serialize)]
pub struct Outcome {
    /// Detector name.
    pub detector: String,
    /// A leak event was raised at or after the onset.
    pub detected: bool,
    /// That event named the right kind at its first alarm.
    pub isolated: bool,
    /// Detection delay from onset, s (NaN if not detected).
    pub delay_s: f64,
    /// Last reported size, L/min (NaN if none).
    pub size_lpm: f64,
    /// Leak events raised before the onset (or at all, in a healthy run): false alarms.
    pub false_alarms: u32,
    /// Mean |leak flow| the rig lost after the ramp, L/min (the size reference; 0 when healthy).
    pub real_flow_lpm: f64,
}

/// A run and both detectors' outcomes.
#[derive(Debug, Clone, Serialize)]
pub struct RunResult {
    /// The run.
    pub case: Case,
    /// One outcome per detector, in [`DETECTORS`] order.
    pub outcomes: Vec<Outcome>,
}

/// Figures of one detector for one leak kind and size.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    /// Detector name.
    pub detector: String,
    /// Leak kind.
    pub kind: String,
    /// Leak size, L/min.
    pub size_lpm: f64,
    /// [`MID_RUN`] or [`FROM_START`].
    pub variant: String,
    /// Runs.
    pub runs: usize,
    /// Fraction of runs with a detection.
    pub p_detect: f64,
    /// Fraction of runs whose detection (after its updates) named the right kind.
    pub p_isolate: f64,
    /// Median delay, s.
    pub delay_median_s: f64,
    /// 95th-percentile delay, s.
    pub delay_p95_s: f64,
    /// Median of |size − real flow| / real flow over correctly isolated runs (NaN if the detector does not size).
    pub size_error_median: f64,
    /// 95th percentile of |size error| / size.
    pub size_error_p95: f64,
}

/// The whole suite's result.
#[derive(Debug, Clone, Serialize)]
pub struct SuiteResult {
    /// Per detector, kind and size.
    pub cells: Vec<Cell>,
    /// Healthy hours simulated.
    pub healthy_hours: f64,
    /// False alarms per hour over the healthy runs, per detector.
    pub false_alarms_per_hour: Vec<(String, f64)>,
    /// False alarms counted over the healthy runs, per detector.
    pub false_alarm_counts: Vec<(String, u32)>,
    /// One-sided 95 % upper bound of the false-alarm rate per hour (Poisson), per detector.
    pub false_alarms_per_hour_upper95: Vec<(String, f64)>,
    /// Healthy hours of the runs that lost samples in gaps.
    pub gap_hours: f64,
    /// Every run.
    pub runs: Vec<RunResult>,
    /// Wall time of the suite, s.
    pub wall_s: f64,
}

/// Draws the rig of a run: the model with friction ±20 % and asymmetric,
/// bulk modulus −30..0 %, spool null bias up to ±10 % of the spool amplitude.
pub fn draw_rig(rng: &mut Rng) -> ActuatorParams {
    let mut rig = ActuatorParams::default();
    let mut ext = rig.friction.extend();
    let mut ret = ext;
    let fe = rng.uniform_in(0.8, 1.2);
    let fr = rng.uniform_in(0.8, 1.2);
    ext.static_n *= fe;
    ext.slip_n *= fe;
    ext.viscous_n_s_per_m *= fe;
    ret.static_n *= fr;
    ret.slip_n *= fr;
    ret.viscous_n_s_per_m *= fr;
    rig.friction.set_extend(ext);
    rig.friction.retract = Some(ret);
    rig.bulk_modulus_pa *= rng.uniform_in(0.7, 1.0);
    let spool_amplitude_m = rig.spool_gain_m_per_v * 3.0;
    rig.spool_null_bias_m = rng.uniform_in(-0.1, 0.1) * spool_amplitude_m;
    rig
}

/// The cases of a suite: `runs` per kind and size, and enough healthy runs for `hours`.
pub fn cases(runs: usize, hours: f64, seed: u64) -> Vec<Case> {
    let mut out = Vec::new();
    let mut rng = Rng::new(seed);
    for kind in ["ext1", "ext2", "int"] {
        for size in SIZES_LPM {
            for _ in 0..runs {
                let scenario = SCENARIOS[(rng.uniform() * SCENARIOS.len() as f64) as usize % SCENARIOS.len()];
                let onset = rng.uniform_in(15.0, 25.0);
                let ramp = if rng.uniform() < 0.5 {
                    0.0
                } else {
                    rng.uniform_in(0.5, 5.0)
                };
                out.push(Case {
                    seed: rng.next_u64(),
                    scenario: scenario.into(),
                    kind: kind.into(),
                    size_lpm: size,
                    onset_s: onset,
                    ramp_s: ramp,
                    seconds: onset + ramp + AFTER_ONSET_S,
                    variant: MID_RUN.into(),
                });
            }
            // The same leak present from t = 0, seen against a commissioning.
            for _ in 0..runs.div_ceil(2) {
                let scenario = SCENARIOS[(rng.uniform() * SCENARIOS.len() as f64) as usize % SCENARIOS.len()];
                out.push(Case {
                    seed: rng.next_u64(),
                    scenario: scenario.into(),
                    kind: kind.into(),
                    size_lpm: size,
                    onset_s: 0.0,
                    ramp_s: 0.0,
                    seconds: AFTER_ONSET_S,
                    variant: FROM_START.into(),
                });
            }
        }
    }
    let healthy = (hours * 3600.0 / HEALTHY_RUN_S).ceil() as usize;
    for i in 0..healthy {
        out.push(Case {
            seed: rng.next_u64(),
            scenario: SCENARIOS[i % SCENARIOS.len()].into(),
            kind: "none".into(),
            size_lpm: 0.0,
            onset_s: f64::NAN,
            ramp_s: 0.0,
            seconds: HEALTHY_RUN_S,
            // Every fourth healthy run loses samples in gaps.
            variant: if i % 4 == 3 { GAPS.into() } else { MID_RUN.into() },
        });
    }
    out
}

/// The simulated rig of a case: the rig drawn from its seed ([`draw_rig`]), its
/// fault (if any) and its scenario over `case.seconds`.
pub fn simulator_for(case: &Case) -> Result<Simulator, String> {
    let mut rng = Rng::new(case.seed);
    let rig = draw_rig(&mut rng);
    let mut faults = FaultSchedule::default();
    if let Some(path) = LeakPath::from_name(&case.kind) {
        let spec = format!(
            "{}:{}lpm@{}s,ramp={}",
            path.name(),
            case.size_lpm,
            case.onset_s,
            case.ramp_s
        );
        faults
            .faults
            .push(Fault::parse(&spec, &rig).map_err(|e| e.to_string())?);
    }
    let scenario = Scenario::by_name(&case.scenario, case.seed, case.seconds).map_err(|e| e.to_string())?;
    Simulator::new(
        rig,
        SensorParams::default(),
        SimSettings::default(),
        scenario,
        faults,
        case.seed,
    )
    .map_err(|e| e.to_string())
}

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
    let mut stage = EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )?;
    let mut cls = Classifier::new(cfg)?;
    let mut events: Vec<LeakEvent> = Vec::new();
    let n = (case.seconds / sim.sample_period_s()).round() as u64;
    let (mut flow, mut flow_n) = (0.0f64, 0.0f64);
    let mut gaps = Rng::new(case.seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut next_gap_s = gaps.uniform_in(10.0, 30.0);
    let mut skip = 0u64;
    for _ in 0..n {
        let s = sim.step();
        if s.t_s >= case.onset_s + case.ramp_s {
            flow += s.q_leak_lpm.abs();
            flow_n += 1.0;
        }
        if case.variant == GAPS {
            if s.t_s >= next_gap_s {
                skip = 1 + (gaps.uniform() * 2000.0) as u64;
                next_gap_s = s.t_s + skip as f64 * 1e-3 + gaps.uniform_in(10.0, 30.0);
            }
            if skip > 0 {
                skip -= 1;
                continue;
            }
        }
        let e = stage.on_sample(&s);
        cls.on_stage(&e, |ev| {
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
pub fn commission_rig(case: &Case) -> Result<classifier::Commissioning, String> {
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
    let mut sim = Simulator::new(
        rig,
        SensorParams::default(),
        SimSettings::default(),
        scenario,
        FaultSchedule::default(),
        case.seed ^ 1,
    )
    .map_err(|e| e.to_string())?;
    let mut stage = EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )?;
    let mut learner = classifier::CommissioningLearner::new(ClassifierConfig::default().settle_s);
    for _ in 0..40_000 {
        learner.on_estimate(&stage.on_sample(&sim.step()).leak);
    }
    learner.finish(10.0, "40 s healthy run of the same rig")
}

fn score(case: &Case, detector: &str, events: &[LeakEvent]) -> Outcome {
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

fn quantile(v: &mut [f64], p: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() as f64 - 1.0) * p).round() as usize]
}

/// Runs the suite on `threads` threads; `progress` is called after each run with (done, total).
pub fn run_suite(cases: &[Case], threads: usize, progress: impl Fn(usize, usize) + Sync) -> SuiteResult {
    let t0 = std::time::Instant::now();
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<RunResult>>> = Mutex::new(vec![None; cases.len()]);
    let done = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= cases.len() {
                    break;
                }
                let r = run_case(&cases[i]).ok();
                if let Ok(mut all) = results.lock() {
                    all[i] = r;
                }
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, cases.len());
            });
        }
    });
    let runs: Vec<RunResult> = results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect();
    summarise(runs, t0.elapsed().as_secs_f64())
}

/// Turns runs into the per-cell figures.
pub fn summarise(runs: Vec<RunResult>, wall_s: f64) -> SuiteResult {
    let mut cells = Vec::new();
    for (di, det) in DETECTORS.iter().enumerate() {
        for kind in ["ext1", "ext2", "int"] {
            for size in SIZES_LPM {
                for variant in [MID_RUN, FROM_START] {
                    let these: Vec<&RunResult> = runs
                        .iter()
                        .filter(|r| {
                            r.case.kind == kind && r.case.size_lpm == size && r.case.variant == variant
                        })
                        .collect();
                    if these.is_empty() {
                        continue;
                    }
                    let n = these.len();
                    let det_runs: Vec<&Outcome> = these.iter().map(|r| &r.outcomes[di]).collect();
                    let mut delays: Vec<f64> = det_runs
                        .iter()
                        .filter(|o| o.detected)
                        .map(|o| o.delay_s)
                        .collect();
                    let mut errs: Vec<f64> = det_runs
                        .iter()
                        .filter(|o| o.isolated && o.size_lpm.is_finite() && o.real_flow_lpm > 0.0)
                        .map(|o| (o.size_lpm - o.real_flow_lpm).abs() / o.real_flow_lpm)
                        .collect();
                    cells.push(Cell {
                        detector: det.to_string(),
                        kind: kind.into(),
                        size_lpm: size,
                        variant: variant.into(),
                        runs: n,
                        p_detect: det_runs.iter().filter(|o| o.detected).count() as f64 / n as f64,
                        p_isolate: det_runs.iter().filter(|o| o.isolated).count() as f64 / n as f64,
                        delay_median_s: quantile(&mut delays, 0.5),
                        delay_p95_s: quantile(&mut delays, 0.95),
                        size_error_median: quantile(&mut errs, 0.5),
                        size_error_p95: quantile(&mut errs, 0.95),
                    });
                }
            }
        }
    }
    let healthy: Vec<&RunResult> = runs.iter().filter(|r| r.case.kind == "none").collect();
    let hours = healthy.iter().map(|r| r.case.seconds).sum::<f64>() / 3600.0;
    let false_alarms_per_hour = DETECTORS
        .iter()
        .enumerate()
        .map(|(di, d)| {
            let n: u32 = healthy.iter().map(|r| r.outcomes[di].false_alarms).sum();
            (
                d.to_string(),
                if hours > 0.0 { n as f64 / hours } else { f64::NAN },
            )
        })
        .collect();
    let counts: Vec<(String, u32)> = DETECTORS
        .iter()
        .enumerate()
        .map(|(di, d)| {
            (
                d.to_string(),
                healthy.iter().map(|r| r.outcomes[di].false_alarms).sum(),
            )
        })
        .collect();
    let upper = counts
        .iter()
        .map(|(d, n)| (d.clone(), poisson_upper95(*n) / hours.max(1e-9)))
        .collect();
    let gap_hours = healthy
        .iter()
        .filter(|r| r.case.variant == GAPS)
        .map(|r| r.case.seconds)
        .sum::<f64>()
        / 3600.0;
    SuiteResult {
        cells,
        healthy_hours: hours,
        false_alarms_per_hour,
        false_alarm_counts: counts,
        false_alarms_per_hour_upper95: upper,
        gap_hours,
        runs,
        wall_s,
    }
}

/// One-sided 95 % upper confidence bound of a Poisson mean after `n` events
/// (exact for n ≤ 5, the Wilson–Hilferty approximation beyond).
pub fn poisson_upper95(n: u32) -> f64 {
    const EXACT: [f64; 6] = [2.996, 4.744, 6.296, 7.754, 9.154, 10.513];
    match EXACT.get(n as usize) {
        Some(v) => *v,
        None => {
            let k = n as f64 + 1.0;
            k * (1.0 - 1.0 / (9.0 * k) + 1.645 / (3.0 * k.sqrt())).powi(3)
        }
    }
}

/// The suite's tables in Markdown: one per leak kind, both detectors side by side.
pub fn markdown(r: &SuiteResult) -> String {
    let mut s = String::new();
    let f = |v: f64, digits: usize| {
        if v.is_finite() {
            format!("{v:.digits$}")
        } else {
            "–".into()
        }
    };
    for kind in ["ext1", "ext2", "int"] {
        s.push_str(&format!("\n### {kind}\n\n"));
        s.push_str(
            "| size L/min | leak | detector | runs | P(detect) | P(right kind at first alarm) | delay median s | delay p95 s | size error median (real flow) | size error p95 |\n",
        );
        s.push_str("|---|---|---|---|---|---|---|---|---|---|\n");
        for size in SIZES_LPM {
            for variant in [MID_RUN, FROM_START] {
                for det in DETECTORS {
                    if let Some(c) = r.cells.iter().find(|c| {
                        c.kind == kind && c.size_lpm == size && c.detector == det && c.variant == variant
                    }) {
                        let when = if variant == FROM_START {
                            "from t = 0, commissioned"
                        } else {
                            "mid-run"
                        };
                        s.push_str(&format!(
                            "| {size} | {when} | {det} | {} | {:.2} | {:.2} | {} | {} | {} | {} |\n",
                            c.runs,
                            c.p_detect,
                            c.p_isolate,
                            f(c.delay_median_s, 2),
                            f(c.delay_p95_s, 2),
                            f(c.size_error_median * 100.0, 0)
                                + if c.size_error_median.is_finite() { " %" } else { "" },
                            f(c.size_error_p95 * 100.0, 0)
                                + if c.size_error_p95.is_finite() { " %" } else { "" },
                        ));
                    }
                }
            }
        }
    }
    s.push_str(&format!(
        "\nHealthy runs: {:.2} simulated hours (all six scenarios; {:.2} h of them losing samples in gaps of 1-2000 \
         samples every 10-30 s).\n\n| detector | false alarms | per hour | 95 % upper bound per hour |\n|---|---|---|---|\n",
        r.healthy_hours, r.gap_hours
    ));
    for (i, (d, fa)) in r.false_alarms_per_hour.iter().enumerate() {
        s.push_str(&format!(
            "| {d} | {} | {} | {} |\n",
            r.false_alarm_counts.get(i).map_or(0, |c| c.1),
            f(*fa, 3),
            f(
                r.false_alarms_per_hour_upper95.get(i).map_or(f64::NAN, |c| c.1),
                3
            )
        ));
    }
    s
}

/// Plots of detection probability against leak size, both detectors, one panel per kind.
pub fn probability_figure(r: &SuiteResult) -> plot::Figure {
    let mut fig = plot::Figure::new(
        "Detection probability against leak size",
        "leak size [L/min at p_s/2]",
    );
    for kind in ["ext1", "ext2", "int"] {
        let mut panel = plot::Panel::new(&format!("{kind}: P(detect) and P(isolate)"), "probability [-]");
        for det in DETECTORS {
            let cells: Vec<&Cell> = r
                .cells
                .iter()
                .filter(|c| c.kind == kind && c.detector == det && c.variant == MID_RUN)
                .collect();
            let x: Vec<f64> = cells.iter().map(|c| c.size_lpm).collect();
            let pd: Vec<f64> = cells.iter().map(|c| c.p_detect).collect();
            let pi: Vec<f64> = cells.iter().map(|c| c.p_isolate).collect();
            panel = panel
                .with_series(plot::Series::line(&format!("{det} detect"), &x, &pd))
                .with_series(
                    plot::Series::line(&format!("{det} isolate"), &x, &pi).styled(plot::Style::Dashed),
                );
        }
        fig.panels.push(panel);
    }
    fig
}

/// The event kinds a leak run may raise, for documentation.
pub fn leak_kinds() -> [EventKind; 3] {
    EventKind::LEAKS
}

#[cfg(test)]
mod tests {
    use super::*;
    use classifier::Phase;

    #[test]
    fn cases_cover_every_kind_and_size_and_the_healthy_hours() {
        let c = cases(2, 0.25, 1);
        assert_eq!(
            c.iter()
                .filter(|c| c.kind != "none" && c.variant == MID_RUN)
                .count(),
            3 * 6 * 2
        );
        assert_eq!(c.iter().filter(|c| c.variant == FROM_START).count(), 3 * 6);
        for sc in SCENARIOS {
            assert!(c.iter().any(|c| c.scenario == sc), "{sc} missing");
        }
        let healthy: f64 = c.iter().filter(|c| c.kind == "none").map(|c| c.seconds).sum();
        assert!(healthy >= 0.25 * 3600.0);
        assert!(c
            .iter()
            .filter(|c| c.kind != "none" && c.variant == MID_RUN)
            .all(|c| (15.0..=25.0).contains(&c.onset_s)));
        // Seeded: the same suite twice.
        assert_eq!(format!("{:?}", cases(2, 0.25, 1)), format!("{c:?}"));
    }

    #[test]
    fn scoring_counts_false_alarms_delay_and_isolation() {
        let case = Case {
            seed: 1,
            scenario: "closed-loop-sine".into(),
            kind: "ext2".into(),
            size_lpm: 0.5,
            onset_s: 20.0,
            ramp_s: 0.0,
            seconds: 30.0,
            variant: String::new(),
        };
        let ev = |kind, phase, t: f64, id, size| {
            let mut e = LeakEvent::plain(kind, phase, "leak-size", id, t, t);
            e.size_lpm = size;
            e.size_lpm_sigma = 0.01;
            e
        };
        let events = vec![
            // a false alarm raised pending and named: one false alarm
            ev(EventKind::Leak, Phase::Raised, 11.0, 1, 0.1),
            ev(EventKind::Ext1, Phase::Raised, 12.0, 1, 0.1),
            ev(EventKind::Ext1, Phase::Cleared, 13.0, 1, 0.0),
            // the leak: detected at the pending alarm, its kind the one named
            ev(EventKind::Leak, Phase::Raised, 20.4, 2, 0.3),
            ev(EventKind::Ext2, Phase::Raised, 21.9, 2, 0.4),
            ev(EventKind::Ext2, Phase::Updated, 22.9, 2, 0.45),
        ];
        let o = score(&case, "leak-size", &events);
        assert_eq!(o.false_alarms, 1);
        assert!(o.detected && o.isolated);
        assert!((o.delay_s - 0.4).abs() < 1e-9);
        assert_eq!(o.size_lpm, 0.45);
        // named wrong first: not isolated, whatever comes later
        let mut wrong = events.clone();
        wrong[4].kind = EventKind::Ext1;
        assert!(!score(&case, "leak-size", &wrong).isolated);
        let none = score(&case, "thesis-mae", &events);
        assert!(!none.detected && none.delay_s.is_nan());
    }

    #[test]
    fn one_real_run_is_detected() {
        let case = Case {
            seed: 3,
            scenario: "closed-loop-sine".into(),
            kind: "ext1".into(),
            size_lpm: 0.5,
            onset_s: 15.0,
            ramp_s: 0.0,
            seconds: 22.0,
            variant: String::new(),
        };
        let r = run_case(&case).unwrap();
        eprintln!("{r:?}");
        // Found within a second, sized against the flow the rig really lost. This step
        // opens at a motion reversal and the filter first books it on chamber 2 for
        // half a second: the first alarm is raised with its kind pending, and ext1 is
        // named once it has led for `kind_confirm_s` (before, the first alarm said ext2).
        let o = &r.outcomes[0];
        assert!(o.detected && o.delay_s < 1.0, "{r:?}");
        assert!(o.isolated, "the kind named first: {r:?}");
        assert!(
            (o.size_lpm - o.real_flow_lpm).abs() < 0.25 * o.real_flow_lpm,
            "{r:?}"
        );
    }
}
