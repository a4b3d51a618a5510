//! Scoring calibration on a directory of measured cases with known truth
//! (`leakwatch bench calibration --data DIR`): every `DIR/case_*/` holding
//! `measured.csv` (or `measured.csv.gz`) and `truth.json`, the layout of the
//! independent development set (`effect`, `effect_params`, `input`).
//!
//! Truth effect names map onto the library: `friction_asymmetry` →
//! `friction-asymmetry`, `spool_bias` → `spool-bias`, `spring_contact` →
//! `spring-load`, `entrained_air` → `bulk-modulus`, `supply_sag` →
//! `supply-sag`, `slow_valve` → `valve-bandwidth`, `external_leak` →
//! `leak-ext1` / `leak-ext2`, `none` → nothing.

use std::path::{Path, PathBuf};
use std::time::Instant;

use model::params::ActuatorParams;
use serde_json::Value;

use crate::suite::{summarise, BenchReport, CaseResult, ParamError};
use crate::{load_measured, run, CalibrateError, CalibrateOptions, Calibration};

/// Pressure at which an effective bulk modulus is compared, Pa (6.9 MPa, the
/// mean chamber pressure of the thesis rig).
pub const BULK_MODULUS_REFERENCE_PA: f64 = 6.9e6;

/// One true parameter of a case: the library's name for it and its value (SI).
#[derive(Debug, Clone, PartialEq)]
pub struct TrueParam {
    /// Dotted parameter name (as in [`crate::Effect::parameter_names`]), or
    /// `effective_bulk_modulus_pa_at_6.9MPa` for entrained air / bulk modulus.
    pub name: String,
    /// Value, SI.
    pub value: f64,
}

/// The truth of one case in the library's terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// Library effect names (empty: a clean control).
    pub effects: Vec<String>,
    /// True parameters of those effects.
    pub params: Vec<TrueParam>,
    /// The input (`sine_ol`, `chirp_ol`, `prbs_cl`, ...).
    pub input: String,
}

fn num(v: &Value, k: &str) -> Option<f64> {
    v.get(k).and_then(Value::as_f64)
}

/// Reads the truth of a case from its `truth.json` text.
pub fn parse_truth(text: &str) -> Result<Truth, String> {
    let v: Value = serde_json::from_str(text).map_err(|e| format!("truth.json: {e}"))?;
    let effect = v
        .get("effect")
        .and_then(Value::as_str)
        .ok_or("truth.json: no `effect`")?
        .to_string();
    let ep = v.get("effect_params").cloned().unwrap_or(Value::Null);
    let input = v.get("input").and_then(Value::as_str).unwrap_or("?").to_string();
    let p = |name: &str, value: Option<f64>| -> Vec<TrueParam> {
        value
            .map(|value| {
                vec![TrueParam {
                    name: name.to_string(),
                    value,
                }]
            })
            .unwrap_or_default()
    };
    let (effects, params): (Vec<&str>, Vec<TrueParam>) = match effect.as_str() {
        "none" => (vec![], vec![]),
        "friction_asymmetry" => (
            vec!["friction-asymmetry"],
            [
                p("friction.retract.slip_n", num(&ep, "f_sl_ret")),
                p("friction.retract.viscous_n_s_per_m", num(&ep, "d_ret")),
            ]
            .concat(),
        ),
        "spool_bias" => (
            vec!["spool-bias"],
            p("spool_null_bias_m", num(&ep, "spool_bias_m")),
        ),
        "spring_contact" => (
            vec!["spring-load"],
            [
                p("load.stiffness_n_per_m", num(&ep, "K_env_N_per_m")),
                p("load.contact_m", num(&ep, "x_contact_m")),
            ]
            .concat(),
        ),
        "entrained_air" => (
            vec!["bulk-modulus"],
            p(
                "effective_bulk_modulus_pa_at_6.9MPa",
                num(&ep, "beta_eff_at_6.9MPa_Pa").or_else(|| num(&ep, "beta_eff_Pa")),
            ),
        ),
        "supply_sag" => (
            vec!["supply-sag"],
            p("supply_sag_pa_per_m3_s", num(&ep, "sag_Pa_per_m3s")),
        ),
        "slow_valve" => (
            vec!["valve-bandwidth"],
            p("spool_natural_freq_rad_s", num(&ep, "omega_n_rad_s")),
        ),
        "external_leak" => {
            let kind = ep.get("kind").and_then(Value::as_str).unwrap_or("");
            let (name, param) = match kind {
                "ext1" => ("leak-ext1", "leaks.ext1.sqrt_m3_s_sqrt_pa"),
                "ext2" => ("leak-ext2", "leaks.ext2.sqrt_m3_s_sqrt_pa"),
                "int" => ("leak-int", "leaks.int.sqrt_m3_s_sqrt_pa"),
                other => return Err(format!("truth.json: unknown leak kind `{other}`")),
            };
            (vec![name], p(param, num(&ep, "coef_m3_s_sqrtPa")))
        }
        other => return Err(format!("truth.json: unknown effect `{other}`")),
    };
    Ok(Truth {
        effects: effects.into_iter().map(str::to_string).collect(),
        params,
        input,
    })
}

/// The fitted value of a true parameter in a calibration (NaN when the effect was not named).
fn fitted(cal: &Calibration, name: &str) -> f64 {
    if name == "effective_bulk_modulus_pa_at_6.9MPa" {
        if !cal.effects.iter().any(|e| e.name == "bulk-modulus") {
            return f64::NAN;
        }
        return model::dynamics::effective_bulk_modulus_pa(&cal.model_after, BULK_MODULUS_REFERENCE_PA);
    }
    cal.effects
        .iter()
        .find_map(|e| e.parameters.get(name).copied())
        .unwrap_or(f64::NAN)
}

/// The cases of `dir`: sub-directories holding `truth.json`, sorted by name.
pub fn case_dirs(dir: &Path) -> Result<Vec<PathBuf>, CalibrateError> {
    let io = |source| CalibrateError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("truth.json").is_file())
        .collect();
    out.sort();
    Ok(out)
}

/// The measured file of a case directory (`measured.csv` or `measured.csv.gz`).
pub fn measured_file(case: &Path) -> Option<PathBuf> {
    ["measured.csv", "measured.csv.gz"]
        .iter()
        .map(|f| case.join(f))
        .find(|p| p.is_file())
}

/// Calibrates and scores one case directory against its truth.
pub fn run_dir_case(case: &Path, model: &ActuatorParams, opts: &CalibrateOptions) -> CaseResult {
    let name = case
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut res = CaseResult {
        case: name,
        scenario: String::new(),
        hidden: Vec::new(),
        named: Vec::new(),
        right_first: false,
        all_found: false,
        false_claims: 0,
        parameters: Vec::new(),
        max_parameter_error: f64::NAN,
        gap_shrink: f64::NAN,
        gap_before: f64::NAN,
        gap_after: f64::NAN,
        simulate_s: 0.0,
        calibrate_s: 0.0,
        error: None,
        caveats: Vec::new(),
        effective_bulk_modulus_error: None,
        not_identifiable: Vec::new(),
    };
    let truth = match std::fs::read_to_string(case.join("truth.json"))
        .map_err(|e| e.to_string())
        .and_then(|t| parse_truth(&t))
    {
        Ok(t) => t,
        Err(e) => {
            res.error = Some(e);
            return res;
        }
    };
    res.scenario = truth.input.clone();
    res.hidden = truth.effects.clone();
    let t0 = Instant::now();
    let Some(file) = measured_file(case) else {
        res.error = Some("no measured.csv(.gz)".into());
        return res;
    };
    let data = match load_measured(&file) {
        Ok(d) => d,
        Err(e) => {
            res.error = Some(e.to_string());
            return res;
        }
    };
    res.simulate_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let cal = match run(&data, model, opts) {
        Ok(c) => c,
        Err(e) => {
            res.error = Some(e.to_string());
            res.calibrate_s = t1.elapsed().as_secs_f64();
            return res;
        }
    };
    res.calibrate_s = t1.elapsed().as_secs_f64();
    score(&mut res, &truth, &cal);
    res
}

/// Fills the verdicts of `res` from a calibration against the truth.
pub fn score(res: &mut CaseResult, truth: &Truth, cal: &Calibration) {
    let hidden = &truth.effects;
    res.verdicts(hidden, cal);
    let mut max_err: f64 = 0.0;
    for tp in &truth.params {
        if res.not_identifiable.iter().any(|n| n.starts_with(&tp.name)) {
            continue;
        }
        let f = fitted(cal, &tp.name);
        let rel = ((f - tp.value) / tp.value).abs();
        let rel = if rel.is_nan() { f64::INFINITY } else { rel };
        max_err = max_err.max(rel);
        res.parameters.push(ParamError {
            effect: hidden.first().cloned().unwrap_or_default(),
            parameter: tp.name.clone(),
            truth: tp.value,
            fitted: f,
            relative_error: rel,
        });
    }
    res.max_parameter_error = max_err;
    res.gap_before = cal.gap_before.normalised;
    res.gap_after = cal.gap_after.normalised;
    res.gap_shrink = cal.gap_reduction;
}

/// Scores every case of `dir` with `model` as the starting model, on
/// `threads` threads; `progress(done, total)` after each case.
pub fn bench_dir(
    dir: &Path,
    model: &ActuatorParams,
    opts: &CalibrateOptions,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<BenchReport, CalibrateError> {
    let t0 = Instant::now();
    let cases = case_dirs(dir)?;
    if cases.is_empty() {
        return Err(CalibrateError::Io {
            path: dir.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no case directories with a truth.json",
            ),
        });
    }
    let threads = threads.clamp(1, cases.len());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut rows: Vec<(usize, CaseResult)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(c) = cases.get(i) else { break };
                        out.push((i, run_dir_case(c, model, opts)));
                        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                        progress(n, cases.len());
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
    Ok(summarise(
        rows.into_iter().map(|(_, r)| r).collect(),
        t0.elapsed().as_secs_f64(),
    ))
}
