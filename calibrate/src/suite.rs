//! The hidden-effect suite (BENCHMARKS.md §3): rigs simulated with one or
//! two effects the nominal model lacks (sensor noise on, inputs from the
//! thesis' scenarios), plus clean controls; and the benchmark over it.

use std::time::Instant;

use model::params::{ActuatorParams, FrictionPreset};
use model::{FaultSchedule, Sample, Scenario, SensorParams, SimSettings, Simulator};
use serde::{Deserialize, Serialize};

use crate::effects::Effect;
use crate::{run, CalibrateOptions};

/// One case of the suite.
#[derive(Debug, Clone, PartialEq)]
pub struct SuiteCase {
    /// Case name.
    pub name: String,
    /// Scenario driving the rig (one of `model::scenario::SCENARIO_NAMES`).
    pub scenario: &'static str,
    /// Seconds of data.
    pub seconds: f64,
    /// Noise and scenario seed.
    pub seed: u64,
    /// The hidden effects and their true parameters (SI, in the order of
    /// [`Effect::parameter_names`]). Empty for a clean control.
    pub hidden: Vec<(Effect, Vec<f64>)>,
    /// Friction of the rig and of the nominal model: `Smooth` (no
    /// stick-slip) or `Thesis` (as published: the rod stick-slips, MODEL.md §8).
    pub friction: FrictionPreset,
}

/// The nominal model of the suite: the thesis' parameters with the smooth
/// friction preset (no stick-slip chatter, MODEL.md §8).
pub fn nominal_model() -> ActuatorParams {
    nominal_model_for(FrictionPreset::Smooth)
}

/// The nominal model with a friction preset (`Thesis`: the stick-slip rig).
pub fn nominal_model_for(friction: FrictionPreset) -> ActuatorParams {
    ActuatorParams::default().with_friction_preset(friction)
}

/// The suite's cases on the stick-slip rig (thesis friction as published,
/// rig and nominal model alike): the single-effect cases of [`cases`] under
/// each of [`MATRIX_SCENARIOS`] (the spring under the loaded sine and the
/// closed-loop steps), plus three clean controls; 15 s each. Names end in
/// ` [thesis]`.
pub fn thesis_cases() -> Vec<SuiteCase> {
    let mut out = Vec::new();
    let mut seed = 300;
    for base in cases().into_iter().filter(|c| c.hidden.len() == 1) {
        let scenarios: Vec<&'static str> = if base.hidden[0].0 == Effect::SpringLoad {
            vec!["loaded-sine", "closed-loop-random"]
        } else {
            MATRIX_SCENARIOS.to_vec()
        };
        for sc in scenarios {
            seed += 1;
            out.push(SuiteCase {
                name: format!("{} / {sc} [thesis]", base.name),
                scenario: sc,
                seconds: THESIS_CASE_SECONDS,
                seed,
                hidden: base.hidden.clone(),
                friction: FrictionPreset::Thesis,
            });
        }
    }
    for sc in MATRIX_SCENARIOS {
        seed += 1;
        out.push(SuiteCase {
            name: format!("clean {sc} [thesis]"),
            scenario: sc,
            seconds: THESIS_CASE_SECONDS,
            seed,
            hidden: Vec::new(),
            friction: FrictionPreset::Thesis,
        });
    }
    out
}

/// Seconds of data per case of [`thesis_cases`].
pub const THESIS_CASE_SECONDS: f64 = 15.0;

/// Seconds of data per case.
pub const CASE_SECONDS: f64 = 12.0;

/// The suite: one case per effect of the library (both forms of `bulk-modulus`), three
/// two-effect cases and three clean controls.
pub fn cases() -> Vec<SuiteCase> {
    let c = |name: &str, scenario: &'static str, seed: u64, hidden: Vec<(Effect, Vec<f64>)>| SuiteCase {
        name: name.to_string(),
        scenario,
        seconds: CASE_SECONDS,
        seed,
        hidden,
        friction: FrictionPreset::Smooth,
    };
    vec![
        c(
            "friction-asymmetry",
            "open-loop-sine",
            11,
            vec![(Effect::FrictionAsymmetryViscous, vec![1600.0, 385.0])],
        ),
        c(
            "spool-bias",
            "closed-loop-random",
            12,
            vec![(Effect::SpoolBias, vec![5.0e-6])],
        ),
        c(
            "spring-load",
            "loaded-sine",
            13,
            vec![(Effect::SpringLoad, vec![2.0e4, 0.22])],
        ),
        c(
            "bulk-modulus",
            "open-loop-chirp",
            14,
            vec![(Effect::BulkModulus, vec![3.5e8])],
        ),
        c(
            "bulk-modulus (entrained air)",
            "open-loop-chirp",
            24,
            vec![(Effect::EntrainedAir, vec![0.12])],
        ),
        c(
            "supply-sag",
            "closed-loop-random",
            15,
            vec![(Effect::SupplySag, vec![8.0e9])],
        ),
        c(
            "valve-bandwidth",
            "open-loop-chirp",
            16,
            vec![(Effect::ValveBandwidth, vec![150.0])],
        ),
        c(
            "leak-ext1",
            "open-loop-sine",
            17,
            vec![(Effect::LeakExt1, vec![3.0e-9])],
        ),
        c(
            "leak-ext2",
            "closed-loop-random",
            18,
            vec![(Effect::LeakExt2, vec![3.0e-9])],
        ),
        c(
            "leak-int",
            "open-loop-chirp",
            19,
            vec![(Effect::LeakInt, vec![5.0e-9])],
        ),
        c(
            "leak-ext2+friction-asymmetry",
            "open-loop-sine",
            20,
            vec![
                (Effect::LeakExt2, vec![3.0e-9]),
                (Effect::FrictionAsymmetryViscous, vec![1600.0, 385.0]),
            ],
        ),
        c(
            "spool-bias+leak-int",
            "closed-loop-random",
            25,
            vec![(Effect::SpoolBias, vec![5.0e-6]), (Effect::LeakInt, vec![5.0e-9])],
        ),
        c(
            "supply-sag+valve-bandwidth",
            "open-loop-chirp",
            26,
            vec![
                (Effect::SupplySag, vec![8.0e9]),
                (Effect::ValveBandwidth, vec![150.0]),
            ],
        ),
        c("clean open-loop-sine", "open-loop-sine", 21, vec![]),
        c("clean open-loop-chirp", "open-loop-chirp", 22, vec![]),
        c("clean closed-loop-random", "closed-loop-random", 23, vec![]),
    ]
}

/// The small mismatch every rig of the suite has besides its hidden
/// effects (not in the library, not to be named): viscous friction 10 %
/// higher and moving mass 3 % higher than the model's.
pub fn nuisance(model: &ActuatorParams) -> ActuatorParams {
    let mut rig = model.clone();
    rig.friction.viscous_n_s_per_m *= 1.10;
    rig.mass_kg *= 1.03;
    rig
}

/// The scenarios of the input matrix: open-loop sine, chirp, closed-loop pseudorandom.
pub const MATRIX_SCENARIOS: [&str; 3] = ["open-loop-sine", "open-loop-chirp", "closed-loop-random"];

/// The wider suite: every single-effect case of [`cases`] (with its true
/// parameters) under each of [`MATRIX_SCENARIOS`], plus the two-effect
/// cases and the clean controls. Used by [`bench_matrix`] and asserted by
/// `tests/matrix.rs`.
///
/// Every effect is excited by every one of the three inputs: the rod starts
/// at 0.30 m, so a spring touching at 0.22 m is compressed from the start and
/// the rod crosses the contact in the sine and the closed-loop record. The
/// spring is also run under the two loaded scenarios (whose own spring is
/// then the hidden one, [`Simulator`] puts the scenario's spring on the rig).
/// The loaded scenarios are not paired with the other effects: their spring
/// would be a second hidden effect. Seeds: the original 41 cases keep theirs
/// (101..=135); the spring under the three inputs uses 141..=143.
pub fn matrix_cases() -> Vec<SuiteCase> {
    let mut out = Vec::new();
    let mut seed = 100;
    let mut extra_seed = 140;
    for base in cases().into_iter().filter(|c| c.hidden.len() == 1) {
        let mut scenarios: Vec<(&'static str, u64)> = Vec::new();
        if base.hidden[0].0 == Effect::SpringLoad {
            for sc in ["loaded-sine", "loaded-random"] {
                seed += 1;
                scenarios.push((sc, seed));
            }
            for sc in MATRIX_SCENARIOS {
                extra_seed += 1;
                scenarios.push((sc, extra_seed));
            }
        } else {
            for sc in MATRIX_SCENARIOS {
                seed += 1;
                scenarios.push((sc, seed));
            }
        }
        for (sc, seed) in scenarios {
            out.push(SuiteCase {
                name: format!("{} / {sc}", base.name),
                scenario: sc,
                seconds: CASE_SECONDS,
                seed,
                hidden: base.hidden.clone(),
                friction: FrictionPreset::Smooth,
            });
        }
    }
    out.extend(cases().into_iter().filter(|c| c.hidden.len() != 1));
    // more clean controls: other noise seeds and reference levels
    for sc in MATRIX_SCENARIOS {
        for _ in 0..2 {
            seed += 1;
            out.push(SuiteCase {
                name: format!("clean {sc} (seed {seed})"),
                scenario: sc,
                seconds: CASE_SECONDS,
                seed,
                hidden: Vec::new(),
                friction: FrictionPreset::Smooth,
            });
        }
    }
    out
}

/// The rig of a case: the nominal model with the small [`nuisance`]
/// mismatch and its hidden effects.
pub fn rig_of(case: &SuiteCase) -> ActuatorParams {
    let mut rig = nuisance(&nominal_model_for(case.friction));
    for (e, theta) in &case.hidden {
        rig = e.apply(&rig, theta);
    }
    rig
}

/// Simulates a case's measured data (default sensors, noise on). A loaded
/// scenario puts its spring on the rig; the model used for calibration is
/// always [`nominal_model`] (no spring).
pub fn generate(case: &SuiteCase) -> Vec<Sample> {
    let rig = rig_of(case);
    let sc = match Scenario::by_name(case.scenario, case.seed, case.seconds) {
        Ok(s) => s,
        Err(_) => return Vec::new(),
    };
    match Simulator::new(
        rig,
        SensorParams::default(),
        SimSettings::default(),
        sc,
        FaultSchedule::default(),
        case.seed,
    ) {
        Ok(mut sim) => sim.run(case.seconds),
        Err(_) => Vec::new(),
    }
}

/// One fitted parameter against its truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamError {
    /// Effect name.
    pub effect: String,
    /// Dotted parameter name.
    pub parameter: String,
    /// True value, SI.
    pub truth: f64,
    /// Fitted value, SI (NaN if the effect was not found).
    pub fitted: f64,
    /// |fitted − truth| / |truth|.
    pub relative_error: f64,
}

/// The outcome of one case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// Case name.
    pub case: String,
    /// Scenario.
    pub scenario: String,
    /// Hidden effect names.
    pub hidden: Vec<String>,
    /// Effects named, in order.
    pub named: Vec<String>,
    /// Whether the first effect named is a hidden one (clean: nothing named).
    pub right_first: bool,
    /// Whether every hidden effect was named and nothing else.
    pub all_found: bool,
    /// Effects named that are not hidden.
    pub false_claims: usize,
    /// Fitted parameters against truth.
    pub parameters: Vec<ParamError>,
    /// Largest relative parameter error (0 for a clean case).
    pub max_parameter_error: f64,
    /// Relative shrink of the normalised validation gap.
    pub gap_shrink: f64,
    /// Normalised validation gap before and after.
    pub gap_before: f64,
    /// Normalised validation gap after.
    pub gap_after: f64,
    /// Seconds spent simulating the data.
    pub simulate_s: f64,
    /// Seconds spent calibrating.
    pub calibrate_s: f64,
    /// Error message, if calibration failed.
    pub error: Option<String>,
    /// What the workflow said the data cannot tell about the effects it
    /// named ([`crate::FoundEffect::caveat`]), as `effect: caveat`.
    #[serde(default)]
    pub caveats: Vec<String>,
    /// For a hidden `bulk-modulus` (either form) that was named: relative
    /// error of the calibrated model's effective bulk modulus at the record's
    /// mean chamber pressure against the rig's, whichever form was fitted
    /// (what the data pin down when its pressure dependence is not identifiable).
    #[serde(default)]
    pub effective_bulk_modulus_error: Option<f64>,
    /// Parameters the workflow stated as not identifiable from the data
    /// (left out of the parameter errors), with why.
    #[serde(default)]
    pub not_identifiable: Vec<String>,
}

impl CaseResult {
    /// Fills what was named, the caveats, the verdicts against the `hidden` effect
    /// names and what was stated not identifiable, from calibration `cal`.
    pub fn verdicts(&mut self, hidden: &[String], cal: &crate::Calibration) {
        self.named = cal.names();
        self.caveats = cal
            .effects
            .iter()
            .filter_map(|e| e.caveat.as_ref().map(|c| format!("{}: {c}", e.name)))
            .collect();
        self.right_first = match self.named.first() {
            Some(n) => hidden.contains(n),
            None => hidden.is_empty(),
        };
        self.false_claims = self.named.iter().filter(|n| !hidden.contains(n)).count();
        self.all_found = self.false_claims == 0 && hidden.iter().all(|h| self.named.contains(h));
        self.not_identifiable = cal
            .effects
            .iter()
            .flat_map(|e| e.not_identifiable.iter().cloned())
            .collect();
    }
}

/// Runs one case: simulate, calibrate, score.
pub fn run_case(case: &SuiteCase, opts: &CalibrateOptions) -> CaseResult {
    let t0 = Instant::now();
    let data = generate(case);
    let simulate_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let hidden: Vec<String> = case.hidden.iter().map(|(e, _)| e.name().to_string()).collect();
    let mut res = CaseResult {
        case: case.name.clone(),
        scenario: case.scenario.to_string(),
        hidden: hidden.clone(),
        named: Vec::new(),
        right_first: false,
        all_found: false,
        false_claims: 0,
        parameters: Vec::new(),
        max_parameter_error: f64::NAN,
        gap_shrink: f64::NAN,
        gap_before: f64::NAN,
        gap_after: f64::NAN,
        simulate_s,
        calibrate_s: 0.0,
        error: None,
        caveats: Vec::new(),
        effective_bulk_modulus_error: None,
        not_identifiable: Vec::new(),
    };
    let cal = match run(&data, &nominal_model_for(case.friction), opts) {
        Ok(c) => c,
        Err(e) => {
            res.error = Some(e.to_string());
            res.calibrate_s = t1.elapsed().as_secs_f64();
            return res;
        }
    };
    res.calibrate_s = t1.elapsed().as_secs_f64();
    res.verdicts(&hidden, &cal);
    let mut max_err: f64 = 0.0;
    for (e, truth) in &case.hidden {
        let found = cal.effects.iter().find(|f| f.name == e.name());
        for (k, pname) in e.parameter_names().iter().enumerate() {
            if res.not_identifiable.iter().any(|n| n.starts_with(pname)) {
                continue;
            }
            let t = truth.get(k).copied().unwrap_or(f64::NAN);
            let fitted = found
                .and_then(|f| f.parameters.get(*pname).copied())
                .unwrap_or(f64::NAN);
            let rel = ((fitted - t) / t).abs();
            max_err = if rel.is_nan() {
                f64::INFINITY
            } else {
                max_err.max(rel)
            };
            res.parameters.push(ParamError {
                effect: e.name().to_string(),
                parameter: pname.to_string(),
                truth: t,
                fitted,
                relative_error: if rel.is_nan() { f64::INFINITY } else { rel },
            });
        }
    }
    res.max_parameter_error = max_err;
    if hidden.iter().any(|h| h == "bulk-modulus") && res.named.iter().any(|n| n == "bulk-modulus") {
        let n = data.len().max(1) as f64;
        let p_mean = data.iter().map(|s| 0.5 * (s.p1_pa + s.p2_pa)).sum::<f64>() / n;
        let truth = model::dynamics::effective_bulk_modulus_pa(&rig_of(case), p_mean);
        let fitted = model::dynamics::effective_bulk_modulus_pa(&cal.model_after, p_mean);
        res.effective_bulk_modulus_error = Some(((fitted - truth) / truth).abs());
    }
    res.gap_before = cal.gap_before.normalised;
    res.gap_after = cal.gap_after.normalised;
    res.gap_shrink = cal.gap_reduction;
    res
}

/// The benchmark table over the whole suite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    /// One row per case.
    pub cases: Vec<CaseResult>,
    /// Cases with hidden effects whose first named effect is right, fraction (NaN without such cases).
    pub right_named_rate: f64,
    /// Hidden-effect cases whose every parameter is within 10 %, fraction.
    pub params_within_10pct_rate: f64,
    /// Hidden-effect cases whose gap shrank by at least 70 %, fraction.
    pub gap_shrink_70pct_rate: f64,
    /// Effects claimed on the clean controls (target 0).
    pub clean_false_claims: usize,
    /// Median relative shrink of the validation gap over the hidden-effect cases.
    #[serde(default)]
    pub median_gap_shrink: f64,
    /// Hidden-effect cases whose first named effect is right, and their number.
    #[serde(default)]
    pub right_first: [usize; 2],
    /// Clean controls on which nothing was named, and their number.
    #[serde(default)]
    pub controls_quiet: [usize; 2],
    /// Total wall time, s.
    pub total_s: f64,
}

/// Runs every case of [`cases`] on two threads and collects the table.
pub fn bench(opts: &CalibrateOptions) -> BenchReport {
    bench_cases(&cases(), opts, 2)
}

/// Runs every case of [`thesis_cases`] (the stick-slip rig) on two threads and collects the table.
pub fn bench_thesis(opts: &CalibrateOptions) -> BenchReport {
    bench_cases(&thesis_cases(), opts, 2)
}

/// Runs `list` on `threads` threads (at least one) and collects the table, rows in the order of `list`.
pub fn bench_cases(list: &[SuiteCase], opts: &CalibrateOptions, threads: usize) -> BenchReport {
    let t0 = Instant::now();
    let threads = threads.clamp(1, list.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut rows: Vec<(usize, CaseResult)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(c) = list.get(i) else { break };
                        out.push((i, run_case(c, opts)));
                    }
                    out
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    rows.sort_by_key(|(i, _)| *i);
    summarise(
        rows.into_iter().map(|(_, r)| r).collect(),
        t0.elapsed().as_secs_f64(),
    )
}

/// Runs every case of [`matrix_cases`] (each effect under every input) on two threads and collects the table.
pub fn bench_matrix(opts: &CalibrateOptions) -> BenchReport {
    bench_cases(&matrix_cases(), opts, 2)
}

/// Builds the report from case results.
pub fn summarise(rows: Vec<CaseResult>, total_s: f64) -> BenchReport {
    let effect_rows: Vec<&CaseResult> = rows.iter().filter(|r| !r.hidden.is_empty()).collect();
    let n = if effect_rows.is_empty() {
        f64::NAN
    } else {
        effect_rows.len() as f64
    };
    let frac = |f: &dyn Fn(&CaseResult) -> bool| effect_rows.iter().filter(|r| f(r)).count() as f64 / n;
    let mut shrinks: Vec<f64> = effect_rows
        .iter()
        .map(|r| if r.gap_shrink.is_nan() { 0.0 } else { r.gap_shrink })
        .collect();
    shrinks.sort_by(f64::total_cmp);
    let median_gap_shrink = match shrinks.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => shrinks[n / 2],
        n => 0.5 * (shrinks[n / 2 - 1] + shrinks[n / 2]),
    };
    let controls: Vec<&CaseResult> = rows.iter().filter(|r| r.hidden.is_empty()).collect();
    BenchReport {
        median_gap_shrink,
        right_first: [
            effect_rows.iter().filter(|r| r.right_first).count(),
            effect_rows.len(),
        ],
        controls_quiet: [
            controls
                .iter()
                .filter(|r| r.named.is_empty() && r.error.is_none())
                .count(),
            controls.len(),
        ],
        right_named_rate: frac(&|r| r.right_first),
        params_within_10pct_rate: frac(&|r| r.max_parameter_error <= 0.10),
        gap_shrink_70pct_rate: frac(&|r| r.gap_shrink >= 0.70),
        clean_false_claims: rows
            .iter()
            .filter(|r| r.hidden.is_empty())
            .map(|r| r.named.len())
            .sum(),
        cases: rows,
        total_s,
    }
}

impl BenchReport {
    /// The table of BENCHMARKS.md §3 as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = self.effect_by_input();
        s.push_str("| case | scenario | hidden | named | right | max param error | gap shrink | time |\n");
        s.push_str("|---|---|---|---|---|---|---|---|\n");
        for r in &self.cases {
            let hidden = if r.hidden.is_empty() {
                "—".to_string()
            } else {
                r.hidden.join(" + ")
            };
            let named = if r.named.is_empty() {
                "nothing".to_string()
            } else {
                r.named.join(", ")
            };
            let right = if r.hidden.is_empty() {
                if r.named.is_empty() {
                    "yes (quiet)"
                } else {
                    "NO (false claim)"
                }
            } else if r.all_found && !r.caveats.is_empty() {
                "yes (form not identifiable)"
            } else if r.all_found {
                "yes"
            } else if r.right_first {
                "first only"
            } else {
                "NO"
            };
            let perr = if r.hidden.is_empty() {
                "—".to_string()
            } else {
                format!("{:.1} %", 100.0 * r.max_parameter_error)
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {:.0} % ({:.3} → {:.3}) | {:.2} s (+{:.2} s sim) |\n",
                r.case,
                r.scenario,
                hidden,
                named,
                right,
                perr,
                100.0 * r.gap_shrink,
                r.gap_before,
                r.gap_after,
                r.calibrate_s,
                r.simulate_s
            ));
            if let Some(e) = &r.error {
                s.push_str(&format!("|  | error: {e} |  |  |  |  |  |  |\n"));
            }
        }
        let caveated: Vec<&CaseResult> = self.cases.iter().filter(|r| !r.caveats.is_empty()).collect();
        if !caveated.is_empty() {
            s.push_str("\nWhat the workflow said it could not tell:\n\n");
            for r in caveated {
                let eff = r
                    .effective_bulk_modulus_error
                    .map(|e| {
                        format!(
                            " (effective bulk modulus at the mean chamber pressure: {:.1} % off)",
                            100.0 * e
                        )
                    })
                    .unwrap_or_default();
                s.push_str(&format!("- {}{eff}: {}\n", r.case, r.caveats.join("; ")));
            }
        }
        s.push_str("\nParameters (fitted vs truth, SI) and what was stated not identifiable:\n\n");
        for r in self.cases.iter().filter(|r| !r.hidden.is_empty()) {
            let mut parts: Vec<String> = r
                .parameters
                .iter()
                .map(|p| {
                    format!(
                        "{} {:.4e} vs {:.4e} ({:.1} %)",
                        p.parameter,
                        p.fitted,
                        p.truth,
                        100.0 * p.relative_error
                    )
                })
                .collect();
            parts.extend(r.not_identifiable.iter().cloned());
            s.push_str(&format!("- {}: {}\n", r.case, parts.join("; ")));
        }
        s.push_str(&format!(
            "\nRight effect named first: {} of {}; clean controls quiet: {} of {}; median gap shrink {:.0} %.\n",
            self.right_first[0],
            self.right_first[1],
            self.controls_quiet[0],
            self.controls_quiet[1],
            100.0 * self.median_gap_shrink
        ));
        s.push_str(&format!(
            "Right effect named first: {:.0} % (target ≥ 95 %); parameters within 10 %: {:.0} %; \
             gap shrink ≥ 70 %: {:.0} %; effects claimed on clean data: {} (target 0); total {:.1} s.\n",
            100.0 * self.right_named_rate,
            100.0 * self.params_within_10pct_rate,
            100.0 * self.gap_shrink_70pct_rate,
            self.clean_false_claims,
            self.total_s
        ));
        s
    }

    /// The effect × input grid of the matrix cases (named `EFFECT / SCENARIO`,
    /// see [`matrix_cases`]) as Markdown, one cell per case: `pass` when the
    /// hidden effect was named first and alone, its parameters are within
    /// 10 % and the gap shrank by at least 70 %, with the largest parameter
    /// error and the shrink; empty when there are no such cases.
    pub fn effect_by_input(&self) -> String {
        let cells: Vec<(&str, &str, &CaseResult)> = self
            .cases
            .iter()
            .filter_map(|r| r.case.split_once(" / ").map(|(e, sc)| (e, sc, r)))
            .collect();
        if cells.is_empty() {
            return String::new();
        }
        let mut effects: Vec<&str> = Vec::new();
        let mut scenarios: Vec<&str> = Vec::new();
        for (e, sc, _) in &cells {
            if !effects.contains(e) {
                effects.push(e);
            }
            if !scenarios.contains(sc) {
                scenarios.push(sc);
            }
        }
        let mut s = String::from("| effect | ");
        s.push_str(&scenarios.join(" | "));
        s.push_str(" |\n|---|");
        s.push_str(&"---|".repeat(scenarios.len()));
        s.push('\n');
        let (mut pass, mut total) = (0, 0);
        for e in &effects {
            s.push_str(&format!("| {e} |"));
            for sc in &scenarios {
                let Some((_, _, r)) = cells.iter().find(|(a, b, _)| a == e && b == sc) else {
                    s.push_str(" — |");
                    continue;
                };
                total += 1;
                let ok = r.error.is_none()
                    && r.right_first
                    && r.all_found
                    && r.max_parameter_error <= 0.10
                    && r.gap_shrink >= 0.70;
                let verdict = if ok && r.caveats.is_empty() {
                    pass += 1;
                    "pass".to_string()
                } else if r.right_first && r.all_found && !r.caveats.is_empty() {
                    let eff = r
                        .effective_bulk_modulus_error
                        .map(|x| format!(", effective β {:.1} %", 100.0 * x))
                        .unwrap_or_default();
                    format!("named, form not identifiable{eff}")
                } else {
                    "FAIL".to_string()
                };
                s.push_str(&format!(
                    " {verdict} ({:.1} %, {:.0} %) |",
                    100.0 * r.max_parameter_error,
                    100.0 * r.gap_shrink
                ));
            }
            s.push('\n');
        }
        s.push_str(&format!(
            "\n{pass} of {total} effect × input cases pass (in brackets: largest parameter error, gap shrink).\n\n"
        ));
        s
    }

    /// The report as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// Writes `DIR/calibration_bench.md` and `DIR/calibration_bench.json` and returns their
    /// paths; existing ones are replaced only if `overwrite` (`--force`), symbolic links never.
    pub fn write(
        &self,
        dir: &std::path::Path,
        overwrite: bool,
    ) -> Result<[std::path::PathBuf; 2], crate::CalibrateError> {
        let io = |path: &std::path::Path| {
            let path = path.to_path_buf();
            move |source| crate::CalibrateError::Io { path, source }
        };
        use dataset::output::{check_replaceable, create_dir, write_file};
        create_dir(dir).map_err(io(dir))?;
        let md = dir.join("calibration_bench.md");
        let js = dir.join("calibration_bench.json");
        for p in [&md, &js] {
            check_replaceable(p, overwrite, &[]).map_err(io(p))?;
        }
        write_file(&md, self.markdown().as_bytes(), true, &[]).map_err(io(&md))?;
        write_file(&js, self.to_json().as_bytes(), true, &[]).map_err(io(&js))?;
        Ok([md, js])
    }
}
