//! Why calibration could not run ([`CalibrateError`]).

use std::path::PathBuf;

use crate::{Effect, NOT_IDENTIFIABLE};

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
    /// The recording's readings are not in SI units (pressures in bar, MPa or psi).
    Units(String),
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
            CalibrateError::Units(m) => write!(f, "units: {m}"),
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
