//! The calibration workflow: find where the simulated
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
//! calibrate::write_outputs(cal: &Calibration, out_dir: &Path, overwrite: bool, inputs: &[&Path], model_file: &str)
//!     -> Result<OutputFiles, CalibrateError>
//!     // DIR/calibration.json, DIR/model.toml (`model_file`, the caller's text: leakwatch
//!     // writes a config, `--config model.toml`), DIR/report.md + DIR/*.png
//! calibrate::fit_effect(measured, model, effect_name: &str, opts) -> Result<EffectFit, CalibrateError>
//!     // one named effect; Err(NotIdentifiable) when the data does not excite it
//! calibrate::load_measured(path: &Path) -> Result<Vec<Sample>, CalibrateError>   // dataset CSV, .csv.gz
//! calibrate::suite::bench(opts) -> BenchReport           // smooth rig, 16 cases
//! calibrate::suite::bench_thesis(opts) -> BenchReport    // the stick-slip rig, 32 cases
//! calibrate::suite::bench_matrix(opts) -> BenchReport    // smooth rig, every effect under every input, 44 cases
//!     // the suites and their results: docs/calibration/README.md
//!     // BenchReport::markdown(), ::to_json(), ::write(dir) -> [calibration_bench.md, .json];
//!     // suite::cases(), thesis_cases(), matrix_cases(), run_case(), bench_cases(list, opts, threads)
//! calibrate::external::bench_dir(dir, model, opts, threads, &progress) -> BenchReport
//!     // any directory of cases DIR/case_*/measured.csv[.gz] + truth.json (the hidden_dev layout)
//! ```
//!
//! `leakwatch calibrate MEASURED.{csv,csv.gz,mcap} [--config FILE] --out DIR` is
//! `load_measured` + (the `[model]` of the config or the default model) +
//! `run_with_progress` + `write_outputs` (with the model as TOML; this crate is
//! pure and reads and writes no TOML, leakwatch does); `leakwatch bench calibration [--data DIR] [--json] [--out DIR]`
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
//!    freely, so the chaos of a stick-slipping rod (docs/model.md#stick-slip), which makes
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

#![forbid(unsafe_code)]

pub mod effects;
pub mod equation;
pub mod external;
pub mod fit;
pub mod output;
pub mod regime;
pub mod shoot;
pub mod suite;
pub mod units;

mod error;
mod input;
mod options;
mod pipeline;
mod result;
mod select;

pub use effects::Effect;
pub use error::CalibrateError;
pub use input::{load_measured, FLAT_PRESSURE_PA, MIN_STROKE_M};
pub use options::CalibrateOptions;
pub use output::{write_outputs, OutputFiles};
pub use pipeline::{fit_effect, run, run_with_progress};
pub use regime::RegimeBin;
pub use result::{Calibration, CandidateScore, DataSummary, EffectFit, FoundEffect, Gap, Round, Traces};
pub use select::MIN_RICHER_FORM_GAIN;
pub use shoot::Method;
pub use suite::{bench, BenchReport};

/// Message given when the data does not excite an effect.
pub const NOT_IDENTIFIABLE: &str = "not identifiable from this data";
