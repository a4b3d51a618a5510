//! The measured-data CSV format (ARCHITECTURE.md, "Data formats").
//!
//! A header line names the columns; `t,u,x,p1,p2` (s, V, m, Pa, Pa) are
//! required, `x_sp` (m), `f_load` (N), `ref` (m), `q_leak` (L/min) and
//! `temp_c` (the oil's temperature, °C) are optional, in any order. Floats are written with Rust's shortest
//! round-trip formatting, so a file reads back bit for bit. A header name or
//! cell may be wrapped in one pair of double quotes (`"p1"`, `"0.0"`, as
//! spreadsheets and pandas write with quoting on; `""` is an empty cell);
//! nothing else of CSV quoting is read (no commas or `""` inside quotes).
//! Messages quoting input text escape its control characters ([`shown`]).
//!
//! Reading streams rows one at a time. A row that cannot be used (a
//! non-numeric cell, a NaN or infinite required value, an infinite optional
//! value, time going backwards or advancing by less than half a sample
//! period, any value outside its physical range: see [`Limits`]) is skipped
//! and reported as an [`Issue`] naming the line and column; nothing is
//! silently filled. An empty or NaN optional cell means "absent" (counted in
//! [`CsvReader::absent`]). A gap in time is reported but the row is kept, so
//! the consumer can bridge it. [`check_bad_fraction`] decides whether a file
//! with many unusable rows is usable at all.

#![forbid(unsafe_code)]

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub use model::Sample;

mod limits;
pub mod output;
pub mod parquet;
mod reader;
mod samples;
mod units;

pub use limits::{check_bad_fraction, Limits, DEFAULT_MAX_BAD_FRACTION};
pub use reader::{open_text, CsvReader, FileSource, Row};
pub use samples::{RowSource, SampleChecks, SampleRows};
pub use units::{PressureReach, LEAST_PRESSURE_SHARE};

/// Longest piece of input text a message quotes, in characters (longer text is cut, `…`).
pub const SHOWN_MAX_CHARS: usize = 80;

/// Input text as a message may quote it: [`escaped`], cut after
/// [`SHOWN_MAX_CHARS`] characters (`…`).
pub fn shown(text: &str) -> String {
    match text.char_indices().nth(SHOWN_MAX_CHARS) {
        Some((end, _)) => escaped(&text[..end]) + "…",
        None => escaped(text),
    }
}

/// `text` with every control or other non-printable character escaped as Rust
/// writes it (`\u{1b}`, `\0`, `\t`, `\u{202e}`), so that nothing read from a
/// file can move the cursor or recolour a terminal when a message quotes it.
/// Quotes and backslashes stay as they are.
pub fn escaped(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '"' | '\'' | '\\' => out.push(c),
            c => out.extend(c.escape_debug()),
        }
    }
    out
}

/// The column names, in the order they are written.
pub const COLUMNS: [&str; 10] = [
    "t", "u", "x", "p1", "p2", "x_sp", "f_load", "ref", "q_leak", "temp_c",
];
/// Number of optional columns (x_sp, f_load, ref, q_leak, temp_c).
pub const N_OPTIONAL: usize = COLUMNS.len() - REQUIRED.len();
/// The columns every file must have.
pub const REQUIRED: [&str; 5] = ["t", "u", "x", "p1", "p2"];

/// A fatal problem: the file cannot be read as this format at all.
#[derive(Debug)]
pub enum DatasetError {
    /// The file could not be opened, read or written.
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The header is missing a required column (or the file is empty).
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column that is missing.
        column: &'static str,
        /// The header as found.
        header: String,
    },
    /// A column appears twice in the header.
    DuplicateColumn {
        /// The file.
        path: PathBuf,
        /// The repeated name.
        column: String,
    },
    /// No row of the file could be used.
    NoUsableSamples {
        /// The file.
        path: PathBuf,
        /// How many rows were skipped, and the first reason.
        detail: String,
    },
}

impl std::fmt::Display for DatasetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DatasetError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            DatasetError::MissingColumn { path, column, header } => write!(
                f,
                "{}: line 1: required column `{column}` is missing (header: `{header}`; required: {})",
                path.display(),
                REQUIRED.join(",")
            ),
            DatasetError::DuplicateColumn { path, column } => {
                write!(f, "{}: line 1: column `{column}` appears twice", path.display())
            }
            DatasetError::NoUsableSamples { path, detail } => {
                write!(f, "{}: no usable samples ({detail})", path.display())
            }
        }
    }
}

impl std::error::Error for DatasetError {}

/// What is wrong with one row.
#[derive(Debug, Clone, PartialEq)]
pub enum IssueKind {
    /// A cell is not a number; the row is skipped.
    NotANumber,
    /// A value is NaN or infinite (a required column), or infinite (an optional
    /// column, where NaN or an empty cell means "absent"); the row is skipped.
    NonFinite,
    /// The row has fewer or more cells than the header; the row is skipped.
    WrongCellCount,
    /// Time does not increase; the row is skipped.
    TimeNotIncreasing,
    /// Time advances by less than `(1 - step_tolerance)` sample periods; the row is skipped.
    StepTooShort,
    /// Time jumps by more than 1.5 sample periods; the row is kept.
    Gap {
        /// Number of missing samples.
        missing: u64,
    },
    /// A value is outside its physical range ([`Limits`]); the row is skipped.
    OutOfRange,
    /// The line is not UTF-8 text; the row is skipped.
    NotText,
    /// The file could not be read further (an I/O error, a damaged gzip
    /// stream); the rest of the file is not read.
    ReadError,
}

impl IssueKind {
    /// A short name of the kind, used as a key in replay's summary.json
    /// (`not_a_number`, `non_finite`, `wrong_cell_count`, `time_not_increasing`,
    /// `step_too_short`, `gap`, `out_of_range`, `not_text`, `read_error`).
    pub fn name(&self) -> &'static str {
        match self {
            IssueKind::NotANumber => "not_a_number",
            IssueKind::NonFinite => "non_finite",
            IssueKind::WrongCellCount => "wrong_cell_count",
            IssueKind::TimeNotIncreasing => "time_not_increasing",
            IssueKind::StepTooShort => "step_too_short",
            IssueKind::Gap { .. } => "gap",
            IssueKind::OutOfRange => "out_of_range",
            IssueKind::NotText => "not_text",
            IssueKind::ReadError => "read_error",
        }
    }
}

/// A problem with one row of the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Issue {
    /// 1-based line number in the file (the header is line 1).
    pub line: u64,
    /// The column concerned, if one is.
    pub column: Option<String>,
    /// What is wrong.
    pub kind: IssueKind,
    /// A message naming the problem.
    pub message: String,
    /// Whether the row was skipped (false: kept, e.g. after a gap).
    pub skipped: bool,
}

impl std::fmt::Display for Issue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.column {
            Some(c) => write!(f, "line {}, column `{c}`: {}", self.line, self.message),
            None => write!(f, "line {}: {}", self.line, self.message),
        }
    }
}

/// A whole file read into memory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    /// The usable samples, in file order.
    pub samples: Vec<Sample>,
    /// Every problem found (skipped rows and gaps), in file order.
    pub issues: Vec<Issue>,
    /// Which optional columns the file has (x_sp, f_load, ref, q_leak, temp_c).
    pub has_optional: [bool; N_OPTIONAL],
    /// Rows read (excluding the header and empty lines).
    pub rows: u64,
}

impl Dataset {
    /// Number of rows skipped.
    pub fn skipped(&self) -> usize {
        self.issues.iter().filter(|i| i.skipped).count()
    }
}

/// Reads a whole CSV file. Fails if the header is wrong or no row is usable.
pub fn read_csv(path: &Path, limits: Limits) -> Result<Dataset, DatasetError> {
    let mut reader = CsvReader::open(path, limits)?;
    let mut ds = Dataset {
        has_optional: reader.has_optional(),
        ..Dataset::default()
    };
    while let Some(row) = reader.next_row() {
        match row {
            Row::Sample(s) => ds.samples.push(s),
            Row::AfterGap(s, issue) => {
                ds.issues.push(issue);
                ds.samples.push(s);
            }
            Row::Skipped(issue) => ds.issues.push(issue),
        }
    }
    if ds.samples.is_empty() {
        let detail = match ds.issues.first() {
            Some(first) => format!("{} rows skipped; first: {first}", ds.issues.len()),
            None => "the file has a header but no rows".to_string(),
        };
        return Err(DatasetError::NoUsableSamples {
            path: path.to_path_buf(),
            detail,
        });
    }
    ds.rows = reader.rows;
    Ok(ds)
}

/// Writes samples to a CSV file with every column of [`COLUMNS`], floats at
/// full round-trip precision. The file is created by [`output::create_file`]:
/// an existing file is replaced only if `overwrite`, a symbolic link never.
pub fn write_csv(path: &Path, samples: &[Sample], overwrite: bool) -> Result<(), DatasetError> {
    let io = |source| DatasetError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = output::create_file(path, overwrite, &[]).map_err(io)?;
    let mut w = BufWriter::new(file);
    write_header(&mut w).map_err(io)?;
    for s in samples {
        write_row(&mut w, s).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Writes the header line.
pub fn write_header<W: Write>(w: &mut W) -> std::io::Result<()> {
    writeln!(w, "{}", COLUMNS.join(","))
}

/// Writes one sample as a CSV line (shortest round-trip float formatting).
pub fn write_row<W: Write>(w: &mut W, s: &Sample) -> std::io::Result<()> {
    writeln!(
        w,
        "{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
        s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa, s.x_sp_m, s.f_load_n, s.ref_m, s.q_leak_lpm, s.temp_c
    )
}
