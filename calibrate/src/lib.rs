//! The calibration workflow (issues 6 and 10): find where the simulated
//! actuator and the measured one disagree, name the physical effect the model
//! lacks, fit it, add it, and show the gap shrink on held-out data; on a
//! smooth rig and on one whose rod stick-slips (the thesis friction).
//!
//! # API
//!
//! ```text
//! calibrate::run(measured: &[Sample], model: &ActuatorParams, opts: &CalibrateOptions)
//!     -> Result<Calibration, CalibrateError>
//! calibrate::run_with_progress(measured, model, opts, &|line: &str| ...)   // same, with progress lines
//! calibrate::write_outputs(cal: &Calibration, out_dir: &Path, overwrite: bool, inputs: &[&Path]) -> Result<OutputFiles, CalibrateError>
//!     // DIR/calibration.json, DIR/model.toml (a leakwatch config: `--config model.toml`),
//!     // DIR/report.md + DIR/*.png
//! calibrate::fit_effect(measured, model, effect_name: &str, opts) -> Result<EffectFit, CalibrateError>
//!     // one named effect; Err(NotIdentifiable) when the data does not excite it
//! calibrate::load_measured(path: &Path) -> Result<Vec<Sample>, CalibrateError>   // dataset CSV, .csv.gz
//! calibrate::load_model(path: &Path) -> Result<ActuatorParams, CalibrateError>    // [model] of a config TOML
//! calibrate::model_toml(params: &ActuatorParams) -> Result<String, CalibrateError>
//! calibrate::suite::bench(opts) -> BenchReport           // BENCHMARKS.md §3, smooth rig, 16 cases
//! calibrate::suite::bench_thesis(opts) -> BenchReport    // the stick-slip rig, 32 cases
//! calibrate::suite::bench_matrix(opts) -> BenchReport    // smooth rig, every effect under every input, 44 cases
//!     // BenchReport::markdown(), ::to_json(), ::write(dir) -> [calibration_bench.md, .json];
//!     // suite::cases(), thesis_cases(), matrix_cases(), run_case(), bench_cases(list, opts, threads)
//! calibrate::external::bench_dir(dir, model, opts, threads, &progress) -> BenchReport
//!     // any directory of cases DIR/case_*/measured.csv[.gz] + truth.json (the hidden_dev layout)
//! ```
//!
//! `leakwatch calibrate MEASURED.{csv,csv.gz,mcap} [--config FILE] --out DIR` is
//! `load_measured` + (`load_model` or the default model) + `run_with_progress` +
//! `write_outputs`; `leakwatch bench calibration [--data DIR] [--json] [--out DIR]`
//! prints the smooth and stick-slip suites (or scores DIR).
//!
//! # Method
//!
//! 1. **Compare** ([`Method`]). The default, **equation error**
//!    ([`equation`]): the whole record is cut into windows of
//!    [`CalibrateOptions::window_s`] (50 ms); in each, every equation of the
//!    model is checked on the measured signals from the measured state at the
//!    window's start: the pressure change each chamber's continuity predicts
//!    (valve flows from the measured spool, or the model's spool when the log
//!    has none; the piston's measured displacement; leaks) against the
//!    measured one; the mean force balance A(p1 − p2) − friction − load − m·Δv/T;
//!    and the model's spool against the measured spool. Nothing is simulated
//!    freely, so the chaos of a stick-slipping rod (MODEL.md §8), which makes
//!    a free simulation diverge within tens of ms whatever the effect, does
//!    not enter. A chamber at tank or supply pressure is left out of that
//!    window (the orifice law is too stiff there). Velocity from a central
//!    difference ([`CalibrateOptions::velocity_half_width`] = 1: wider fits
//!    smear the stick-slip phases). The alternative, **multiple shooting**
//!    ([`CalibrateOptions::shooting`]: 0.25 s windows each simulated from its
//!    measured start with RK4 sub-steps of `model::dynamics`), works on a
//!    smooth rig only. In every block of 10 windows the first 70 % fit and the
//!    rest validate ([`CalibrateOptions::split_block_windows`],
//!    `fit_fraction`), so both parts see every regime of the record; windows
//!    straddling a gap in time (missing or NaN rows) are left out. Residuals
//!    (model − measured) are normalised by `scale_p_pa`, `scale_f_n`,
//!    `scale_sp_m` (`scale_x_m` for shooting); the gap is their RMS (also
//!    given per channel in SI).
//! 2. **Localise**: the validation residuals broken down by direction of
//!    motion, spool sign, stroke position, velocity, pressure level,
//!    frequency band and time ([`RegimeBin`]), from windows simulated from
//!    their measured start (a diagnostic for the report; on a stick-slipping
//!    rod it shows the chatter more than the effect).
//! 3. **Name**: every candidate of the library ([`Effect`]) is fitted on the
//!    fitting windows by Levenberg–Marquardt (finite-difference Jacobian in
//!    resolution-scaled units); after one screening iteration only the best
//!    `screen_keep` go on to a full fit. Candidates are ranked by the
//!    reduction of the validation gap. One is accepted only if it is
//!    identifiable (each parameter moves the residuals by at least
//!    `min_sensitivity` per resolution step), reduces the validation gap by at
//!    least `min_gap_reduction` (relative) and `min_gap_reduction_normalised`
//!    (absolute), moves some parameter by at least
//!    `min_size_steps` resolution steps, and lowers the BIC on the fitting part.
//!    For `bulk-modulus`, whose two forms (lower constant β, entrained air)
//!    look alike when the chamber pressures stay near one level, the chosen
//!    form must also beat the other over every window (paired t ≥
//!    `min_form_t`, or `min_form_gap_ratio` times less residual); otherwise
//!    the effect is still named and added, with the caveat "form not
//!    identifiable from this data" ([`FoundEffect::caveat`]).
//!    `friction-asymmetry` also has two forms: the retracting static and
//!    Coulomb friction scaled together, and the same with its own viscous
//!    term; the richer is kept only if it lowers the validation gap by
//!    [`MIN_RICHER_FORM_GAIN`] more and beats the simpler over every window,
//!    else the viscous term is stated not identifiable
//!    ([`FoundEffect::not_identifiable`]; on a stick-slipping rod the velocity
//!    while sliding is too poorly resolved for it).
//!    Each effect is restated in engineering units ([`units::describe`]).
//! 4. **Add and repeat** (greedy forward selection) while something is
//!    accepted, up to `max_effects`.
//!
//! All quantities are SI (m, s, Pa, m³/s, N, V).

pub mod effects;
pub mod equation;
pub mod external;
pub mod fit;
pub mod output;
pub mod regime;
pub mod shoot;
pub mod suite;
pub mod units;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use model::params::ActuatorParams;
use model::Sample;
use serde::{Deserialize, Serialize};

pub use effects::Effect;
pub use output::{model_toml, write_outputs, OutputFiles};
pub use regime::RegimeBin;
pub use suite::{bench, BenchReport};

use fit::Problem;
pub use shoot::Method;
use shoot::{gap_of, residuals, Prepared, ShootSettings};

/// Message given when the data does not excite an effect.
pub const NOT_IDENTIFIABLE: &str = "not identifiable from this data";

/// Options of the workflow; every field has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CalibrateOptions {
    /// How model and measurement are compared: `equation-error` (default;
    /// short windows started from the measured state, not defeated by
    /// stick-slip) or `shooting` (windows simulated freely; smooth rigs only).
    pub method: Method,
    /// Length of one comparison window, s.
    pub window_s: f64,
    /// Fraction of the windows used for fitting; the rest validate.
    pub fit_fraction: f64,
    /// Split in blocks of this many windows: in each, the first
    /// `fit_fraction` fit and the rest validate, so both parts see every
    /// regime of the record. 0: the first `fit_fraction` of the record fits,
    /// the tail validates.
    pub split_block_windows: usize,
    /// RK4 sub-steps per sample period in the shooting simulations.
    pub substeps_per_sample: u32,
    /// Compare every n-th sample of a window.
    pub compare_stride: usize,
    /// Position error that counts as much as `scale_p_pa` of pressure error, m.
    pub scale_x_m: f64,
    /// Pressure error scale, Pa.
    pub scale_p_pa: f64,
    /// Force error scale of the equation-error comparison, N.
    pub scale_f_n: f64,
    /// Spool position error scale of the equation-error comparison, m.
    pub scale_sp_m: f64,
    /// Use at most this much of the record (from its start), s; 0: the whole record.
    pub max_seconds: f64,
    /// Least record length accepted, s.
    pub min_seconds: f64,
    /// Compare at most about this many windows (whole blocks spread evenly
    /// over the record; 0: all). 6000 windows of 50 ms = 5 min of data.
    pub max_windows: usize,
    /// Effect names to consider (empty: the whole library).
    pub candidates: Vec<String>,
    /// At most this many effects are added.
    pub max_effects: usize,
    /// Least relative reduction of the validation gap for an effect to be accepted.
    pub min_gap_reduction: f64,
    /// Least RMS change of the normalised residuals per resolution step of
    /// each parameter for the effect to count as identifiable.
    pub min_sensitivity: f64,
    /// Least absolute reduction of the normalised validation gap for an
    /// effect to be accepted (0.03 ≈ 3 kPa of pressure or 30 µm of position
    /// RMS at the default scales): what is left near the sensor-noise floor is
    /// not claimed.
    pub min_gap_reduction_normalised: f64,
    /// Least change of some parameter from the current model, in resolution
    /// steps ([`Effect::resolution`], about 10 % of a typical value), for an
    /// effect to be claimed: smaller ones are below what the method resolves
    /// and are usually other small mismatches (e.g. mass) in disguise.
    pub min_size_steps: f64,
    /// Levenberg–Marquardt iterations of a full fit.
    pub max_iterations: usize,
    /// Candidates kept for a full fit after the screening iteration.
    pub screen_keep: usize,
    /// Keep the re-anchored traces in the result for plots.
    pub keep_traces: bool,
    /// Half-width of the local quadratic fit of positions that estimates the
    /// velocity at each window start, samples.
    pub velocity_half_width: usize,
    /// For an effect with two forms (`bulk-modulus`): least paired t statistic,
    /// over every window of the record, of the per-window mean squared
    /// residual of the other form minus the chosen one, for the chosen form
    /// to be claimed (see [`FoundEffect::caveat`]).
    pub min_form_t: f64,
    /// ... or least ratio of the other form's RMS residual over every window
    /// to the chosen one's.
    pub min_form_gap_ratio: f64,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            method: Method::EquationError,
            window_s: 0.05,
            fit_fraction: 0.7,
            split_block_windows: 10,
            substeps_per_sample: 4,
            compare_stride: 5,
            scale_x_m: 1.0e-3,
            scale_p_pa: 1.0e5,
            scale_f_n: 100.0,
            scale_sp_m: 1.0e-6,
            max_seconds: 0.0,
            max_windows: 6000,
            min_seconds: 3.0,
            candidates: Vec::new(),
            max_effects: 3,
            min_gap_reduction: 0.2,
            min_sensitivity: 0.01,
            min_size_steps: 0.5,
            min_gap_reduction_normalised: 0.03,
            max_iterations: 10,
            screen_keep: 3,
            keep_traces: true,
            velocity_half_width: 1,
            min_form_t: 3.0,
            min_form_gap_ratio: 2.0,
        }
    }
}

impl CalibrateOptions {
    /// The multiple-shooting comparison with its own defaults (0.25 s
    /// windows, velocity from ±3 samples): for a smooth rig, where freely
    /// simulated windows stay close to the measurement.
    pub fn shooting() -> Self {
        CalibrateOptions {
            method: Method::Shooting,
            window_s: 0.25,
            velocity_half_width: 3,
            min_size_steps: 1.0,
            ..CalibrateOptions::default()
        }
    }
}

/// Why calibration could not run.
#[derive(Debug)]
pub enum CalibrateError {
    /// The record is too short to fit and validate.
    TooLittleData {
        /// Usable samples found.
        samples: usize,
        /// Their time span, s.
        seconds: f64,
        /// Least span needed, s.
        needed_seconds: f64,
    },
    /// A required value is not finite.
    NonFinite {
        /// Index of the sample.
        index: usize,
        /// The column.
        column: &'static str,
    },
    /// Time does not increase steadily (no sample period can be found).
    BadSampling(String),
    /// The measured file could not be read (missing columns, no usable rows, I/O).
    Dataset(dataset::DatasetError),
    /// The model file could not be loaded or is not a valid actuator.
    ModelFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The model (given directly) is not a valid actuator.
    InvalidModel(model::params::InvalidParam),
    /// A channel never changes over the record (a disconnected transducer?).
    FlatChannel {
        /// The column.
        column: &'static str,
        /// Its constant value, SI.
        value: f64,
    },
    /// The effect name is not in the library.
    UnknownEffect(String),
    /// The data does not excite the effect enough to fit it.
    NotIdentifiable {
        /// The effect.
        effect: String,
        /// Which parameter and how weakly the data sees it.
        reason: String,
    },
    /// Outputs could not be written.
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A plot could not be drawn or written.
    Plot(String),
    /// Serialising an output failed.
    Serialize(String),
}

impl std::fmt::Display for CalibrateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CalibrateError::TooLittleData {
                samples,
                seconds,
                needed_seconds,
            } => write!(
                f,
                "too little data: {samples} samples over {seconds:.3} s; calibration needs at least \
                 {needed_seconds} s (a fitting and a validation part), 10-20 s recommended"
            ),
            CalibrateError::NonFinite { index, column } => {
                write!(f, "sample {index}: column `{column}` is not a finite number")
            }
            CalibrateError::BadSampling(m) => write!(f, "bad sampling: {m}"),
            CalibrateError::Dataset(e) => write!(f, "measured data: {e}"),
            CalibrateError::ModelFile { path, message } => {
                write!(f, "model file {}: {message}", path.display())
            }
            CalibrateError::InvalidModel(e) => write!(f, "model: {e}"),
            CalibrateError::FlatChannel { column, value } => write!(
                f,
                "column `{column}` is flat ({value:.6e} throughout): a disconnected or broken channel; \
                 nothing can be identified from it"
            ),
            CalibrateError::UnknownEffect(n) => write!(
                f,
                "unknown effect `{n}`: expected one of {}",
                Effect::NAMES.join(", ")
            ),
            CalibrateError::NotIdentifiable { effect, reason } => {
                write!(f, "{effect}: {NOT_IDENTIFIABLE} ({reason})")
            }
            CalibrateError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            CalibrateError::Plot(m) => write!(f, "plot: {m}"),
            CalibrateError::Serialize(m) => write!(f, "serialise: {m}"),
        }
    }
}

impl std::error::Error for CalibrateError {}

impl From<dataset::DatasetError> for CalibrateError {
    fn from(e: dataset::DatasetError) -> Self {
        CalibrateError::Dataset(e)
    }
}

/// RMS simulation-vs-measurement error on the validation windows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Gap {
    /// Rod position, m.
    pub x_m: f64,
    /// Chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Every channel normalised by its scale, combined RMS (dimensionless).
    pub normalised: f64,
    /// Force balance error (equation-error comparison), N.
    #[serde(default)]
    pub force_n: f64,
    /// Spool position error (equation-error comparison with a measured spool), m.
    #[serde(default)]
    pub spool_m: f64,
}

/// One effect added to the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoundEffect {
    /// Effect name (`friction-asymmetry`, `spool-bias`, ...).
    pub name: String,
    /// Which form of it was fitted.
    pub form: String,
    /// Fitted parameters by dotted field name, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Approximate standard deviation of each parameter, SI.
    pub parameter_std: BTreeMap<String, f64>,
    /// Relative reduction of the normalised validation gap when this effect was added
    /// (1 − gap after / gap before this step).
    pub gap_reduction: f64,
    /// Relative reduction of the validation gap of the nominal model, up to and including this effect.
    pub cumulative_gap_reduction: f64,
    /// The validation gap after adding it.
    pub gap_after: Gap,
    /// The residual signature of this effect.
    pub signature: String,
    /// What this data cannot tell about the effect, if anything (contains
    /// [`NOT_IDENTIFIABLE`]): for `bulk-modulus`, whether β depends on
    /// pressure, when the other form explains the record about as well (the
    /// chamber pressures visited do not separate them). The fitted value then
    /// holds near the pressures visited, not beyond.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caveat: Option<String>,
    /// Parameters of the effect this data cannot pin down, each with why
    /// (contains [`NOT_IDENTIFIABLE`]); they keep the model's value.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_identifiable: Vec<String>,
    /// The effect in engineering units (N, µm, kN/m, MPa, L/min, Hz, ...), one line per quantity.
    #[serde(default)]
    pub engineering: Vec<String>,
}

/// How one candidate fared in one round of the selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    /// Effect name.
    pub name: String,
    /// Its form.
    pub form: String,
    /// Fitted parameters, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Relative reduction of the validation gap (negative: worse).
    pub gap_reduction: f64,
    /// Change of the BIC on the fitting part (negative favours the effect).
    pub delta_bic: f64,
    /// Whether every parameter is seen by the data.
    pub identifiable: bool,
    /// Verdict: `added`, `explains too little`, `not identifiable from this data`, `screened out`, ...
    pub status: String,
}

/// One round of the greedy forward selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Round {
    /// Normalised validation gap at the start of the round.
    pub gap_before: f64,
    /// Every candidate, best first.
    pub candidates: Vec<CandidateScore>,
}

/// Facts about the data used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataSummary {
    /// Samples used.
    pub samples: usize,
    /// Span used, s.
    pub seconds: f64,
    /// Sample period, s.
    pub sample_period_s: f64,
    /// Shooting window length, s.
    pub window_s: f64,
    /// Windows in the fitting part.
    pub fit_windows: usize,
    /// Windows in the validation part.
    pub validation_windows: usize,
    /// Time at which validation starts, s.
    pub validation_start_s: f64,
    /// How the windows were split into fitting and validation.
    pub split: String,
}

/// Re-anchored traces over the validation part, for plots.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Traces {
    /// Time, s (NaN between windows to break lines).
    pub t_s: Vec<f64>,
    /// Measured [x m, p1 Pa, p2 Pa].
    pub measured: Vec<[f64; 3]>,
    /// Nominal model.
    pub before: Vec<[f64; 3]>,
    /// Calibrated model.
    pub after: Vec<[f64; 3]>,
}

/// The result of the workflow.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Effects added, in order.
    pub effects: Vec<FoundEffect>,
    /// Validation gap of the model given.
    pub gap_before: Gap,
    /// Validation gap of the calibrated model.
    pub gap_after: Gap,
    /// Overall relative reduction of the normalised validation gap.
    pub gap_reduction: f64,
    /// Every round of the selection with every candidate's score.
    pub rounds: Vec<Round>,
    /// Residual breakdown of the model given (validation part).
    pub breakdown_before: Vec<RegimeBin>,
    /// Residual breakdown of the calibrated model (validation part).
    pub breakdown_after: Vec<RegimeBin>,
    /// RMS of measured spool minus model spool, before and after, m (when x_sp is measured).
    pub spool_rms_m: Option<[f64; 2]>,
    /// Data used.
    pub data: DataSummary,
    /// The options used.
    pub options: CalibrateOptions,
    /// The model given.
    pub model_before: ActuatorParams,
    /// The calibrated model.
    pub model_after: ActuatorParams,
    /// Traces for plots (empty unless `keep_traces`).
    #[serde(skip)]
    pub traces: Traces,
    /// What the user should know about the data used (gaps, stretch used, no motion).
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Wall time, s.
    pub elapsed_s: f64,
}

impl Calibration {
    /// Names of the effects found, in order.
    pub fn names(&self) -> Vec<String> {
        self.effects.iter().map(|e| e.name.clone()).collect()
    }
}

/// One effect fitted on its own ([`fit_effect`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectFit {
    /// The effect.
    pub name: String,
    /// Its form.
    pub form: String,
    /// Fitted parameters, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Approximate standard deviations, SI.
    pub parameter_std: BTreeMap<String, f64>,
    /// Validation gap without the effect.
    pub gap_before: Gap,
    /// Validation gap with it.
    pub gap_after: Gap,
    /// 1 − gap after / gap before (normalised).
    pub gap_reduction: f64,
}

/// Reads a measured CSV (dataset format; `.csv.gz` is decompressed on the
/// fly); missing columns and unusable files are errors. Rows that cannot be
/// used (NaN, out of range) are skipped by the reader; a gap they leave ends
/// the stretch used.
pub fn load_measured(path: &Path) -> Result<Vec<Sample>, CalibrateError> {
    if path.extension().is_some_and(|e| e == "gz") {
        let file = std::fs::File::open(path).map_err(|source| CalibrateError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let reader = std::io::BufReader::new(flate2::read::GzDecoder::new(file));
        let mut r = dataset::CsvReader::new(reader, path, dataset::Limits::default())?;
        let mut samples = Vec::new();
        let mut first_issue = None;
        let mut skipped = 0usize;
        while let Some(row) = r.next_row() {
            match row {
                dataset::Row::Sample(s) | dataset::Row::AfterGap(s, _) => samples.push(s),
                dataset::Row::Skipped(issue) => {
                    skipped += 1;
                    first_issue.get_or_insert(issue.to_string());
                }
            }
        }
        if samples.is_empty() {
            return Err(CalibrateError::Dataset(dataset::DatasetError::NoUsableSamples {
                path: path.to_path_buf(),
                detail: match first_issue {
                    Some(f) => format!("{skipped} rows skipped; first: {f}"),
                    None => "the file has a header but no rows".to_string(),
                },
            }));
        }
        return Ok(samples);
    }
    let ds = dataset::read_csv(path, dataset::Limits::default())?;
    Ok(ds.samples)
}

/// Reads the `[model]` table of a leakwatch config file (other sections are
/// ignored here); a missing table gives the default model. The model is validated.
pub fn load_model(path: &Path) -> Result<ActuatorParams, CalibrateError> {
    let err = |message: String| CalibrateError::ModelFile {
        path: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| err(format!("not valid TOML: {e}")))?;
    let params = match table.get("model") {
        Some(v) => {
            let t = toml::to_string(v).map_err(|e| err(e.to_string()))?;
            toml::from_str::<ActuatorParams>(&t).map_err(|e| err(format!("[model]: {e}")))?
        }
        None => ActuatorParams::default(),
    };
    params.validate().map_err(|e| err(format!("[model] {e}")))?;
    Ok(params)
}

/// Prepared inputs of a calibration.
struct Setup {
    data: Prepared,
    set: ShootSettings,
    seconds: f64,
    warnings: Vec<String>,
}

/// A pressure channel whose whole range is within this is taken as flat (a
/// disconnected transducer), Pa.
pub const FLAT_PRESSURE_PA: f64 = 1.0e3;

/// Below this stroke the record is said not to excite effects that need motion, m.
pub const MIN_STROKE_M: f64 = 1.0e-3;

fn setup(
    measured: &[Sample],
    model: &ActuatorParams,
    opts: &CalibrateOptions,
) -> Result<Setup, CalibrateError> {
    model.validate().map_err(CalibrateError::InvalidModel)?;
    for (i, s) in measured.iter().enumerate() {
        for (v, c) in [
            (s.t_s, "t"),
            (s.u_v, "u"),
            (s.x_m, "x"),
            (s.p1_pa, "p1"),
            (s.p2_pa, "p2"),
        ] {
            if !v.is_finite() {
                return Err(CalibrateError::NonFinite { index: i, column: c });
            }
        }
    }
    let n = measured.len();
    let span = if n >= 2 {
        measured[n - 1].t_s - measured[0].t_s
    } else {
        0.0
    };
    if n < 10 || span < opts.min_seconds {
        return Err(CalibrateError::TooLittleData {
            samples: n,
            seconds: span.max(0.0),
            needed_seconds: opts.min_seconds,
        });
    }
    let mut diffs: Vec<f64> = measured.windows(2).map(|w| w[1].t_s - w[0].t_s).collect();
    diffs.sort_by(|a, b| a.total_cmp(b));
    let dt = diffs[diffs.len() / 2];
    if dt <= 0.0 || !dt.is_finite() {
        return Err(CalibrateError::BadSampling(
            "time does not increase from one sample to the next".into(),
        ));
    }
    let mut warnings = Vec::new();
    // Every sample (up to max_seconds); gaps in time (rows the reader skipped:
    // NaN, out of range, ...) are left out of the comparison windows.
    let mut end = n;
    if opts.max_seconds > 0.0 {
        let t_end = measured[0].t_s + opts.max_seconds;
        end = measured.iter().position(|s| s.t_s >= t_end).unwrap_or(n);
        if end < n {
            warnings.push(format!(
                "only the first {:.1} s of the record are used (max_seconds)",
                opts.max_seconds
            ));
        }
    }
    let gaps = measured[..end]
        .windows(2)
        .filter(|w| w[1].t_s - w[0].t_s >= 1.5 * dt)
        .count();
    if gaps > 0 {
        warnings.push(format!(
            "the record has {gaps} gap(s) in time (rows skipped or missing); comparison windows that \
             straddle one are left out"
        ));
    }
    let first = 0;
    let used = &measured[first..end];
    let end = end - first;
    let seconds = end as f64 * dt;
    // A channel that never changes is a disconnected or broken transducer.
    for (name, get) in [
        ("p1", (|s: &Sample| s.p1_pa) as fn(&Sample) -> f64),
        ("p2", |s: &Sample| s.p2_pa),
    ] {
        let lo = used.iter().map(get).fold(f64::INFINITY, f64::min);
        let hi = used.iter().map(get).fold(f64::NEG_INFINITY, f64::max);
        if hi - lo <= FLAT_PRESSURE_PA {
            return Err(CalibrateError::FlatChannel {
                column: name,
                value: lo,
            });
        }
    }
    let x_lo = used.iter().map(|s| s.x_m).fold(f64::INFINITY, f64::min);
    let x_hi = used.iter().map(|s| s.x_m).fold(f64::NEG_INFINITY, f64::max);
    if x_hi - x_lo < MIN_STROKE_M {
        warnings.push(format!(
            "the rod moved only {:.3} mm: friction, a spring and anything that needs motion {NOT_IDENTIFIABLE} \
             (move the rod over some centimetres, e.g. an open-loop sine of 3 V at 1 Hz)",
            (x_hi - x_lo) * 1e3
        ));
    }
    if seconds < opts.min_seconds {
        return Err(CalibrateError::TooLittleData {
            samples: end,
            seconds,
            needed_seconds: opts.min_seconds,
        });
    }
    let w = ((opts.window_s / dt).round() as usize).max(10);
    let mut data = Prepared::new(
        used,
        dt,
        w,
        opts.fit_fraction.clamp(0.1, 0.95),
        opts.split_block_windows,
        opts.velocity_half_width,
    );
    let before = data.thin(opts.max_windows, opts.split_block_windows.max(1));
    if before > 0 {
        warnings.push(format!(
            "for speed, {} of the {before} windows are compared: whole blocks of {} spread evenly \
             from the start to the end of the record (max_windows)",
            data.windows.len(),
            opts.split_block_windows.max(1)
        ));
    }
    if data.fit_windows().len() < 2 || data.val_windows().is_empty() {
        return Err(CalibrateError::TooLittleData {
            samples: end,
            seconds,
            needed_seconds: opts.min_seconds,
        });
    }
    let set = ShootSettings {
        method: opts.method,
        scale_f_n: opts.scale_f_n,
        scale_sp_m: opts.scale_sp_m,
        substeps: opts.substeps_per_sample.max(1),
        stride: opts.compare_stride.max(1),
        scale_x_m: opts.scale_x_m,
        scale_p_pa: opts.scale_p_pa,
    };
    Ok(Setup {
        data,
        set,
        seconds,
        warnings,
    })
}

fn gap_on(p: &ActuatorParams, d: &Prepared, windows: &[(usize, usize)], set: &ShootSettings) -> Gap {
    let (r, _) = residuals(p, d, windows, set);
    if set.method == Method::EquationError {
        let (ch, j) = equation::gap_of(&r, d, set);
        return Gap {
            x_m: 0.0,
            p1_pa: ch[0],
            p2_pa: ch[1],
            normalised: j,
            force_n: ch[2],
            spool_m: ch[3],
        };
    }
    let (ch, j) = gap_of(&r, set);
    Gap {
        x_m: ch[0],
        p1_pa: ch[1],
        p2_pa: ch[2],
        normalised: j,
        force_n: 0.0,
        spool_m: 0.0,
    }
}

fn mean_sq(r: &[f64]) -> f64 {
    if r.is_empty() {
        0.0
    } else {
        r.iter().map(|a| a * a).sum::<f64>() / r.len() as f64
    }
}

fn named(effect: Effect, v: &[f64]) -> BTreeMap<String, f64> {
    effect
        .parameter_names()
        .iter()
        .zip(v)
        .map(|(n, x)| (n.to_string(), *x))
        .collect()
}

/// A fitted candidate with its scores.
#[derive(Clone)]
struct Scored {
    effect: Effect,
    theta: Vec<f64>,
    std: Vec<f64>,
    fit_cost: f64,
    val: Gap,
    identifiable: bool,
    weakest: (usize, f64),
    screened_out: bool,
    /// Largest parameter change from the current model, in resolution steps.
    size_steps: f64,
}

/// Effective number of independent residuals of the fitting part for the
/// BIC: a few per window and channel (residuals inside a window are strongly
/// correlated).
fn n_eff(d: &Prepared) -> f64 {
    (d.fit_windows().len() * 3 * 5) as f64
}

fn screen_and_fit(
    effects: &[Effect],
    base: &ActuatorParams,
    s: &Setup,
    opts: &CalibrateOptions,
    keep: usize,
) -> Vec<Scored> {
    let d = &s.data;
    // Screening: a short fit (2 iterations) from each starting point.
    let mut first: Vec<(Effect, fit::FitOutcome)> = Vec::new();
    for &e in effects {
        let prob = Problem {
            base,
            data: d,
            windows: d.fit_windows(),
            set: s.set,
            effect: e,
        };
        let starts = e.starting_points(base, d.x_range_m());
        let per_start = if starts.len() > 1 { 1 } else { 2 };
        let mut best: Option<fit::FitOutcome> = None;
        for start in starts.iter() {
            let o = prob.lm(start, per_start);
            if best.as_ref().is_none_or(|b| o.cost < b.cost) {
                best = Some(o);
            }
        }
        if let Some(b) = best {
            let b = if per_start == 1 {
                let more = prob.lm(&b.theta, 1);
                if more.cost <= b.cost {
                    fit::FitOutcome {
                        evaluations: more.evaluations + b.evaluations,
                        ..more
                    }
                } else {
                    b
                }
            } else {
                b
            };
            first.push((e, b));
        }
    }
    first.sort_by(|a, b| a.1.cost.total_cmp(&b.1.cost));
    let mut out = Vec::new();
    for (rank, (e, o)) in first.into_iter().enumerate() {
        let screened_out = rank >= keep;
        let o = if screened_out {
            o
        } else {
            let prob = Problem {
                base,
                data: d,
                windows: d.fit_windows(),
                set: s.set,
                effect: e,
            };
            let full = prob.lm(&o.theta, opts.max_iterations);
            if full.cost <= o.cost {
                full
            } else {
                o
            }
        };
        let weakest = o
            .sensitivity
            .iter()
            .copied()
            .enumerate()
            .fold((0, f64::INFINITY), |a, (i, v)| if v < a.1 { (i, v) } else { a });
        let identifiable = weakest.1 >= opts.min_sensitivity;
        let p = e.apply(base, &o.theta);
        let val = gap_on(&p, d, d.val_windows(), &s.set);
        let size_steps = e
            .read(base)
            .iter()
            .zip(&o.theta)
            .zip(e.resolution(base))
            .map(|((a, b), r)| (b - a).abs() / r)
            .fold(0.0, f64::max);
        out.push(Scored {
            effect: e,
            theta: o.theta,
            std: o.std,
            fit_cost: o.cost,
            val,
            identifiable,
            weakest,
            screened_out,
            size_steps,
        });
    }
    out
}

/// Runs the whole workflow on `measured` samples with `model` as the starting model.
pub fn run(
    measured: &[Sample],
    model: &ActuatorParams,
    opts: &CalibrateOptions,
) -> Result<Calibration, CalibrateError> {
    run_with_progress(measured, model, opts, &|_| {})
}

/// [`run`], telling `progress` what it is doing (one line per step: the
/// data used, each round of the selection and its verdict).
pub fn run_with_progress(
    measured: &[Sample],
    model: &ActuatorParams,
    opts: &CalibrateOptions,
    progress: &dyn Fn(&str),
) -> Result<Calibration, CalibrateError> {
    let t0 = Instant::now();
    let s = setup(measured, model, opts)?;
    progress(&format!(
        "using {:.1} s ({} samples): {} windows fit, {} validate",
        s.seconds,
        s.data.t_s.len(),
        s.data.fit_windows().len(),
        s.data.val_windows().len()
    ));
    let d = &s.data;
    let mut pool: Vec<Effect> = if opts.candidates.is_empty() {
        Effect::ALL.to_vec()
    } else {
        let mut v = Vec::new();
        for n in &opts.candidates {
            let e = Effect::by_name(n);
            if e.is_empty() {
                return Err(CalibrateError::UnknownEffect(n.clone()));
            }
            v.extend(e);
        }
        v
    };
    let mut current = model.clone();
    let gap_before = gap_on(&current, d, d.val_windows(), &s.set);
    let breakdown_before = regime::breakdown(&current, d, d.val_windows(), &s.set);
    let mut gap_cur = gap_before;
    let mut fit_cost_cur = mean_sq(&residuals(&current, d, d.fit_windows(), &s.set).0);
    let mut effects = Vec::new();
    let mut rounds = Vec::new();
    let ne = n_eff(d);
    while effects.len() < opts.max_effects && !pool.is_empty() {
        progress(&format!(
            "round {}: fitting {} candidates (validation gap {:.3}) ... {:.1} s",
            rounds.len() + 1,
            pool.len(),
            gap_cur.normalised,
            t0.elapsed().as_secs_f64()
        ));
        let mut scored = screen_and_fit(&pool, &current, &s, opts, opts.screen_keep.max(1));
        let red = |x: &Scored| 1.0 - x.val.normalised / gap_cur.normalised.max(1e-300);
        scored.sort_by(|a, b| red(b).total_cmp(&red(a)));
        let mut chosen: Option<usize> = None;
        let mut cands = Vec::new();
        for (i, c) in scored.iter().enumerate() {
            let k = c.theta.len() as f64;
            let dbic = ne * (c.fit_cost.max(1e-300) / fit_cost_cur.max(1e-300)).ln() + k * ne.ln();
            let r = red(c);
            // an effect of the spool alone, with the spool measured: judged on
            // the spool channel, which measures it directly (the other
            // channels sit at their sensor floor and would dilute it)
            let spool_only = s.set.method == Method::EquationError
                && d.has_spool()
                && matches!(c.effect, Effect::SpoolBias | Effect::ValveBandwidth);
            let (r_judged, abs_judged) = if spool_only && gap_cur.spool_m > 0.0 {
                (
                    1.0 - c.val.spool_m / gap_cur.spool_m,
                    (gap_cur.spool_m - c.val.spool_m) / s.set.scale_sp_m,
                )
            } else {
                (r, gap_cur.normalised - c.val.normalised)
            };
            let status = if !c.identifiable {
                format!(
                    "{NOT_IDENTIFIABLE} (`{}` moves the residuals by {:.2e} per step of {:.3e})",
                    c.effect.parameter_names()[c.weakest.0],
                    c.weakest.1,
                    c.effect.resolution(&current)[c.weakest.0]
                )
            } else if c.screened_out {
                "screened out (explains less on the fitting part)".to_string()
            } else if c.size_steps < opts.min_size_steps {
                format!(
                    "too small to claim (parameters moved {:.2} resolution steps; needs {})",
                    c.size_steps, opts.min_size_steps
                )
            } else if r_judged < opts.min_gap_reduction || abs_judged < opts.min_gap_reduction_normalised {
                if spool_only {
                    format!(
                        "explains too little ({:.0} % of the spool channel's gap)",
                        100.0 * r_judged
                    )
                } else {
                    format!("explains too little ({:.0} % of the gap)", 100.0 * r)
                }
            } else if dbic >= 0.0 {
                "not significant (BIC)".to_string()
            } else if chosen.is_none() {
                chosen = Some(i);
                "added".to_string()
            } else {
                "significant, but a better candidate was added".to_string()
            };
            cands.push(CandidateScore {
                name: c.effect.name().to_string(),
                form: c.effect.form().to_string(),
                parameters: named(c.effect, &c.theta),
                gap_reduction: r,
                delta_bic: dbic,
                identifiable: c.identifiable,
                status,
            });
        }
        rounds.push(Round {
            gap_before: gap_cur.normalised,
            candidates: cands,
        });
        let Some(mut i) = chosen else {
            progress("nothing else explains a significant part of the gap");
            break;
        };
        // a richer form (more parameters) is kept only when the data tell it
        // from the simpler one; otherwise the simpler one, and the extra
        // parameters are stated as not identifiable
        let mut not_identifiable = Vec::new();
        if let Some((j, why)) = prefer_simpler(i, &scored, &current, d, &s.set, opts) {
            let extra: Vec<&str> = scored[i]
                .effect
                .parameter_names()
                .iter()
                .filter(|n| !scored[j].effect.parameter_names().contains(n))
                .copied()
                .collect();
            for n in extra {
                not_identifiable.push(format!("{n}: {NOT_IDENTIFIABLE} ({why})"));
            }
            i = j;
        } else if let Some(rich) = scored.iter().find(|o| {
            o.effect.name() == scored[i].effect.name()
                && o.effect.parameter_names().len() > scored[i].effect.parameter_names().len()
        }) {
            // the simpler form explained the record better than the richer one
            for n in rich
                .effect
                .parameter_names()
                .iter()
                .filter(|n| !scored[i].effect.parameter_names().contains(n))
            {
                not_identifiable.push(format!(
                    "{n}: {NOT_IDENTIFIABLE} (fitting it does not lower the validation gap: {:.3} with it, \
                     {:.3} without); it keeps the model's value",
                    rich.val.normalised, scored[i].val.normalised
                ));
            }
        }
        let c = &scored[i];
        let r = red(c);
        let caveat = if c.effect.name() == "friction-asymmetry" {
            None
        } else {
            form_caveat(c, &scored, &current, d, &s.set, opts)
        };
        let previous = current.clone();
        current = c.effect.apply(&current, &c.theta);
        let engineering = units::describe(c.effect.name(), &previous, &current, d.mean_pressures_pa());
        fit_cost_cur = c.fit_cost;
        gap_cur = c.val;
        effects.push(FoundEffect {
            name: c.effect.name().to_string(),
            form: c.effect.form().to_string(),
            parameters: named(c.effect, &c.theta),
            parameter_std: named(c.effect, &c.std),
            gap_reduction: r,
            cumulative_gap_reduction: 1.0 - gap_cur.normalised / gap_before.normalised.max(1e-300),
            gap_after: gap_cur,
            signature: c.effect.signature().to_string(),
            caveat,
            not_identifiable,
            engineering,
        });
        let name = c.effect.name();
        progress(&format!("added {name}: the gap shrinks by {:.0} %", 100.0 * r));
        pool.retain(|e| e.name() != name);
    }
    let breakdown_after = regime::breakdown(&current, d, d.val_windows(), &s.set);
    let traces = if opts.keep_traces {
        make_traces(model, &current, d, &s.set)
    } else {
        Traces::default()
    };
    let spool_rms_m = spool_rms(model, &current, d, &s.set);
    let vs = d.val_windows().first().map(|w| d.t_s[w.0]).unwrap_or(0.0);
    Ok(Calibration {
        effects,
        gap_before,
        gap_after: gap_cur,
        gap_reduction: 1.0 - gap_cur.normalised / gap_before.normalised.max(1e-300),
        rounds,
        breakdown_before,
        breakdown_after,
        spool_rms_m,
        data: DataSummary {
            samples: d.t_s.len(),
            seconds: s.seconds,
            sample_period_s: d.dt_s,
            window_s: (d.windows.first().map(|w| w.1 - w.0).unwrap_or(0)) as f64 * d.dt_s,
            fit_windows: d.fit_windows().len(),
            validation_windows: d.val_windows().len(),
            validation_start_s: vs,
            split: if opts.split_block_windows == 0 {
                format!("first {:.0} % fit, the tail validates", 100.0 * opts.fit_fraction)
            } else {
                format!(
                    "in every block of {} windows, the first {:.0} % fit and the rest validate",
                    opts.split_block_windows,
                    100.0 * opts.fit_fraction
                )
            },
        },
        options: opts.clone(),
        model_before: model.clone(),
        model_after: current,
        traces,
        warnings: s.warnings.clone(),
        elapsed_s: t0.elapsed().as_secs_f64(),
    })
}

/// Per-window mean squared normalised residual of model `p` over every window of the record.
fn per_window_cost(p: &ActuatorParams, d: &Prepared, set: &ShootSettings) -> Vec<f64> {
    let (r, idx) = residuals(p, d, &d.windows, set);
    if set.method == Method::EquationError {
        return r
            .chunks_exact(equation::per_window(d))
            .map(|c| c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64)
            .collect();
    }
    let mut out = vec![(0.0, 0usize); d.windows.len()];
    let mut w = 0;
    for (k, i) in idx.iter().enumerate() {
        while w + 1 < d.windows.len() && *i >= d.windows[w].1 {
            w += 1;
        }
        for v in &r[3 * k..3 * k + 3] {
            out[w].0 += v * v;
            out[w].1 += 1;
        }
    }
    out.into_iter()
        .filter(|(_, n)| *n > 0)
        .map(|(s, n)| s / n as f64)
        .collect()
}

/// Least relative reduction of the validation gap a richer form of an effect
/// must add over its simpler form to be kept.
pub const MIN_RICHER_FORM_GAIN: f64 = 0.05;

/// For a chosen candidate with a simpler form of the same effect (fewer
/// parameters, e.g. `friction-asymmetry` without its own viscous term):
/// the simpler one's index and why, unless the richer form lowers the
/// validation gap by at least [`MIN_RICHER_FORM_GAIN`] and beats it over
/// every window (paired t ≥ `min_form_t`).
fn prefer_simpler(
    i: usize,
    scored: &[Scored],
    base: &ActuatorParams,
    d: &Prepared,
    set: &ShootSettings,
    opts: &CalibrateOptions,
) -> Option<(usize, String)> {
    let c = &scored[i];
    let np = c.effect.parameter_names().len();
    let (j, simple) = scored.iter().enumerate().find(|(_, o)| {
        o.effect != c.effect
            && o.effect.name() == c.effect.name()
            && o.effect.parameter_names().len() < np
            && !o.screened_out
            && o.identifiable
    })?;
    let gain = 1.0 - c.val.normalised / simple.val.normalised.max(1e-300);
    let a = per_window_cost(&c.effect.apply(base, &c.theta), d, set);
    let b = per_window_cost(&simple.effect.apply(base, &simple.theta), d, set);
    let t = paired_t(&b, &a);
    if gain >= MIN_RICHER_FORM_GAIN && t >= opts.min_form_t {
        return None;
    }
    Some((
        j,
        format!(
            "fitting it lowers the validation gap by only {:.1} % (needs {:.0} %; paired t {t:.1} over every window); \
             it keeps the model's value",
            100.0 * gain,
            100.0 * MIN_RICHER_FORM_GAIN
        ),
    ))
}

/// Paired t statistic of `b − a` (0 when fewer than three pairs).
fn paired_t(b: &[f64], a: &[f64]) -> f64 {
    if a.len() != b.len() || a.len() < 3 {
        return 0.0;
    }
    let n = a.len() as f64;
    let diff: Vec<f64> = b.iter().zip(a).map(|(x, y)| x - y).collect();
    let mean = diff.iter().sum::<f64>() / n;
    let var = diff.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    mean / (var / n).sqrt().max(1e-300)
}

/// Whether the data tell the chosen form of a multi-form effect from its
/// other form: over every window, the other form's residual must be
/// consistently larger (paired t ≥ `min_form_t`) or clearly larger (RMS
/// ratio ≥ `min_form_gap_ratio`). Otherwise returns the caveat.
fn form_caveat(
    c: &Scored,
    scored: &[Scored],
    base: &ActuatorParams,
    d: &Prepared,
    set: &ShootSettings,
    opts: &CalibrateOptions,
) -> Option<String> {
    let other = scored
        .iter()
        .find(|o| o.effect != c.effect && o.effect.name() == c.effect.name())?;
    let a = per_window_cost(&c.effect.apply(base, &c.theta), d, set);
    let b = per_window_cost(&other.effect.apply(base, &other.theta), d, set);
    if a.len() != b.len() || a.len() < 3 {
        return None;
    }
    let n = a.len() as f64;
    let diff: Vec<f64> = b.iter().zip(&a).map(|(x, y)| x - y).collect();
    let mean = diff.iter().sum::<f64>() / n;
    let var = diff.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    let t = mean / (var / n).sqrt().max(1e-300);
    let rms = |v: &[f64]| (v.iter().sum::<f64>() / n).sqrt();
    let ratio = rms(&b) / rms(&a).max(1e-300);
    if t >= opts.min_form_t || ratio >= opts.min_form_gap_ratio {
        return None;
    }
    let pm = d.p1_pa.iter().chain(&d.p2_pa).sum::<f64>() / (2.0 * d.p1_pa.len().max(1) as f64);
    Some(format!(
        "form {NOT_IDENTIFIABLE}: `{}` explains the record about as well as `{}` (RMS residual over \
         every window {:.3} vs {:.3}, paired t {:.1}; needs t ≥ {} or a ratio ≥ {}); the fitted \
         value describes the effect near the pressures visited (mean chamber pressure {:.1} MPa), \
         not its pressure dependence",
        other.effect.form(),
        c.effect.form(),
        rms(&b),
        rms(&a),
        t,
        opts.min_form_t,
        opts.min_form_gap_ratio,
        pm * 1e-6
    ))
}

fn make_traces(before: &ActuatorParams, after: &ActuatorParams, d: &Prepared, set: &ShootSettings) -> Traces {
    let w = d.val_windows();
    let tb = regime::traces(before, d, w, set);
    let ta = regime::traces(after, d, w, set);
    let mut tr = Traces::default();
    let nan = [f64::NAN; 3];
    for (k, ((i, b), (_, a))) in tb.iter().zip(&ta).enumerate() {
        if k > 0 && *i != tb[k - 1].0 + 1 {
            tr.t_s.push(f64::NAN);
            tr.measured.push(nan);
            tr.before.push(nan);
            tr.after.push(nan);
        }
        tr.t_s.push(d.t_s[*i]);
        tr.measured.push([d.x_m[*i], d.p1_pa[*i], d.p2_pa[*i]]);
        tr.before.push(*b);
        tr.after.push(*a);
    }
    tr
}

fn spool_rms(
    before: &ActuatorParams,
    after: &ActuatorParams,
    d: &Prepared,
    set: &ShootSettings,
) -> Option<[f64; 2]> {
    if !d.x_sp_m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let f = |p: &ActuatorParams| {
        let sp = shoot::spool_trajectory(p, d, set.substeps);
        let e: Vec<f64> = sp.iter().zip(&d.x_sp_m).map(|(a, b)| a[0] - b).collect();
        shoot::rms(&e)
    };
    Some([f(before), f(after)])
}

/// Fits one named effect (both forms for `bulk-modulus`, the better kept)
/// on the fitting part and scores it on the validation part. Fails with
/// [`CalibrateError::NotIdentifiable`] when the data does not excite it.
pub fn fit_effect(
    measured: &[Sample],
    model: &ActuatorParams,
    effect_name: &str,
    opts: &CalibrateOptions,
) -> Result<EffectFit, CalibrateError> {
    let s = setup(measured, model, opts)?;
    let d = &s.data;
    let effects = Effect::by_name(effect_name);
    if effects.is_empty() {
        return Err(CalibrateError::UnknownEffect(effect_name.to_string()));
    }
    let scored = screen_and_fit(&effects, model, &s, opts, effects.len());
    let best = scored
        .iter()
        .filter(|c| c.identifiable)
        .min_by(|a, b| a.val.normalised.total_cmp(&b.val.normalised));
    let Some(c) = best else {
        let reason = scored
            .iter()
            .map(|c| {
                format!(
                    "`{}` changes the normalised residuals by only {:.2e} per step of {:.3e} (needs {:.2e})",
                    c.effect.parameter_names()[c.weakest.0],
                    c.weakest.1,
                    c.effect.resolution(model)[c.weakest.0],
                    opts.min_sensitivity
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        return Err(CalibrateError::NotIdentifiable {
            effect: effect_name.to_string(),
            reason,
        });
    };
    let gap_before = gap_on(model, d, d.val_windows(), &s.set);
    Ok(EffectFit {
        name: c.effect.name().to_string(),
        form: c.effect.form().to_string(),
        parameters: named(c.effect, &c.theta),
        parameter_std: named(c.effect, &c.std),
        gap_before,
        gap_after: c.val,
        gap_reduction: 1.0 - c.val.normalised / gap_before.normalised.max(1e-300),
    })
}
