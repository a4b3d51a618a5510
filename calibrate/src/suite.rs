//! The hidden-effect suite (docs/calibration/README.md#results): rigs simulated with one or
//! two effects the nominal model lacks (sensor noise on, inputs from the
//! thesis' scenarios), plus clean controls; and the benchmark over it.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::{run, CalibrateOptions};

mod cases;
mod report;

pub use cases::{
    cases, generate, matrix_cases, nominal_model, nominal_model_for, nuisance, rig_of, thesis_cases,
    SuiteCase, CASE_SECONDS, MATRIX_SCENARIOS, THESIS_CASE_SECONDS,
};

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
    bench_cases_with_progress(list, opts, threads, &|_, _| {})
}

/// [`bench_cases`], calling `progress(done, total)` as each case finishes (from the worker threads).
pub fn bench_cases_with_progress(
    list: &[SuiteCase],
    opts: &CalibrateOptions,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> BenchReport {
    let t0 = Instant::now();
    let done = std::sync::atomic::AtomicUsize::new(0);
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
                        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                        progress(d, list.len());
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
