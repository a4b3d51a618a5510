//! The measured-data CSV format (ARCHITECTURE.md, "Data formats").
//!
//! A header line names the columns; `t,u,x,p1,p2` (s, V, m, Pa, Pa) are
//! required, `x_sp` (m), `f_load` (N), `ref` (m) and `q_leak` (L/min) are
//! optional, in any order. Floats are written with Rust's shortest
//! round-trip formatting, so a file reads back bit for bit.
//!
//! Reading streams rows one at a time. A row that cannot be used (a
//! non-numeric cell, a NaN or infinite required value, time going backwards,
//! a pressure outside the physical range) is skipped and reported as an
//! [`Issue`] naming the line and column; nothing is silently filled. A gap in
//! time is reported but the row is kept, so the consumer can bridge it.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

pub use model::Sample;

/// The column names, in the order they are written.
pub const COLUMNS: [&str; 9] = ["t", "u", "x", "p1", "p2", "x_sp", "f_load", "ref", "q_leak"];
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
    /// A required value is NaN or infinite; the row is skipped.
    NonFinite,
    /// The row has fewer or more cells than the header; the row is skipped.
    WrongCellCount,
    /// Time does not increase; the row is skipped.
    TimeNotIncreasing,
    /// Time jumps by more than 1.5 sample periods; the row is kept.
    Gap {
        /// Number of missing samples.
        missing: u64,
    },
    /// A pressure is outside the accepted range; the row is skipped.
    OutOfRange,
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

/// Limits that decide which rows are usable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Lowest accepted pressure, Pa.
    pub min_pressure_pa: f64,
    /// Highest accepted pressure, Pa (MODEL: 1.5 p_s).
    pub max_pressure_pa: f64,
    /// Nominal sample period, s, used to detect gaps (None: learned from the first two rows).
    pub sample_period_s: Option<f64>,
}

impl Limits {
    /// Accepts pressures in [0, 1.5 p_s] for supply pressure `supply_pa`, 1 kHz.
    pub fn for_supply(supply_pa: f64) -> Limits {
        Limits {
            min_pressure_pa: 0.0,
            max_pressure_pa: 1.5 * supply_pa,
            sample_period_s: Some(1.0e-3),
        }
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::for_supply(13.8e6)
    }
}

/// A streaming reader of samples from a CSV file.
pub struct CsvReader<R: BufRead> {
    lines: std::io::Lines<R>,
    path: PathBuf,
    map: [Option<usize>; 9],
    n_cols: usize,
    limits: Limits,
    line_no: u64,
    last_t: Option<f64>,
    period: Option<f64>,
    cells: Vec<f64>,
    /// Rows read (excluding the header).
    pub rows: u64,
    /// Rows skipped.
    pub skipped: u64,
}

/// A buffered byte source: a plain file, or a gzip-compressed one decoded on the fly.
pub type FileSource = Box<dyn BufRead + Send>;

impl CsvReader<FileSource> {
    /// Opens `path` and reads its header; a name ending in `.gz` is decompressed
    /// on the fly (gzip), anything else is read as plain text.
    pub fn open(path: &Path, limits: Limits) -> Result<Self, DatasetError> {
        let file = File::open(path).map_err(|source| DatasetError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let gz = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("gz"));
        let source: FileSource = if gz {
            Box::new(BufReader::new(flate2::read::MultiGzDecoder::new(file)))
        } else {
            Box::new(BufReader::new(file))
        };
        CsvReader::new(source, path, limits)
    }
}

impl<R: BufRead> CsvReader<R> {
    /// Reads the header from `reader`; `path` is used in messages.
    pub fn new(reader: R, path: &Path, limits: Limits) -> Result<Self, DatasetError> {
        let mut lines = reader.lines();
        let header = match lines.next() {
            Some(Ok(h)) => h,
            Some(Err(source)) => {
                return Err(DatasetError::Io {
                    path: path.to_path_buf(),
                    source,
                })
            }
            None => String::new(),
        };
        let header = header.trim_start_matches('\u{feff}').trim().to_string();
        let names: Vec<&str> = header.split(',').map(|s| s.trim()).collect();
        let mut map = [None; 9];
        for (i, name) in names.iter().enumerate() {
            if let Some(j) = COLUMNS.iter().position(|c| c == name) {
                if map[j].is_some() {
                    return Err(DatasetError::DuplicateColumn {
                        path: path.to_path_buf(),
                        column: name.to_string(),
                    });
                }
                map[j] = Some(i);
            }
        }
        for (j, col) in COLUMNS.iter().enumerate().take(REQUIRED.len()) {
            if map[j].is_none() {
                return Err(DatasetError::MissingColumn {
                    path: path.to_path_buf(),
                    column: col,
                    header: header.clone(),
                });
            }
        }
        Ok(CsvReader {
            lines,
            path: path.to_path_buf(),
            map,
            n_cols: names.len(),
            limits,
            line_no: 1,
            last_t: None,
            period: limits.sample_period_s,
            cells: Vec::with_capacity(names.len()),
            rows: 0,
            skipped: 0,
        })
    }

    /// Which optional columns the file has, in [`COLUMNS`] order (x_sp, f_load, ref, q_leak).
    pub fn has_optional(&self) -> [bool; 4] {
        [
            self.map[5].is_some(),
            self.map[6].is_some(),
            self.map[7].is_some(),
            self.map[8].is_some(),
        ]
    }

    fn issue(&mut self, column: Option<usize>, kind: IssueKind, message: String, skipped: bool) -> Issue {
        if skipped {
            self.skipped += 1;
        }
        Issue {
            line: self.line_no,
            column: column.map(|j| COLUMNS[j].to_string()),
            kind,
            message,
            skipped,
        }
    }

    /// The next row, or `None` at the end of the file.
    pub fn next_row(&mut self) -> Option<Row> {
        loop {
            let line = match self.lines.next()? {
                Ok(l) => l,
                Err(e) => {
                    self.line_no += 1;
                    let issue = self.issue(None, IssueKind::NotANumber, format!("read error: {e}"), true);
                    return Some(Row::Skipped(issue));
                }
            };
            self.line_no += 1;
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            self.rows += 1;
            return Some(match self.parse_row(line) {
                Ok((sample, None)) => Row::Sample(sample),
                Ok((sample, Some(issue))) => Row::AfterGap(sample, issue),
                Err(issue) => Row::Skipped(issue),
            });
        }
    }

    fn parse_row(&mut self, line: &str) -> Result<(Sample, Option<Issue>), Issue> {
        self.cells.clear();
        let mut count = 0;
        let mut bad: Option<(usize, String)> = None;
        for cell in line.split(',') {
            count += 1;
            let cell = cell.trim();
            let v = if cell.is_empty() {
                f64::NAN
            } else {
                match cell.parse::<f64>() {
                    Ok(v) => v,
                    Err(_) => {
                        if bad.is_none() {
                            bad = Some((count - 1, cell.to_string()));
                        }
                        f64::NAN
                    }
                }
            };
            self.cells.push(v);
        }
        if count != self.n_cols {
            let msg = format!("{count} cells, but the header has {}", self.n_cols);
            return Err(self.issue(None, IssueKind::WrongCellCount, msg, true));
        }
        if let Some((i, text)) = bad {
            if let Some(j) = self.map.iter().position(|m| *m == Some(i)) {
                let msg = format!("`{text}` is not a number");
                return Err(self.issue(Some(j), IssueKind::NotANumber, msg, true));
            }
        }
        let get = |j: usize| self.map[j].map(|i| self.cells[i]).unwrap_or(f64::NAN);
        let s = Sample {
            t_s: get(0),
            u_v: get(1),
            x_m: get(2),
            p1_pa: get(3),
            p2_pa: get(4),
            x_sp_m: get(5),
            f_load_n: get(6),
            ref_m: get(7),
            q_leak_lpm: get(8),
        };
        for (j, v) in [s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa].into_iter().enumerate() {
            if !v.is_finite() {
                let msg = format!("required value is {v} (not finite)");
                return Err(self.issue(Some(j), IssueKind::NonFinite, msg, true));
            }
        }
        for (j, v) in [(3, s.p1_pa), (4, s.p2_pa)] {
            if v < self.limits.min_pressure_pa || v > self.limits.max_pressure_pa {
                let msg = format!(
                    "pressure {v} Pa is outside [{}, {}] Pa",
                    self.limits.min_pressure_pa, self.limits.max_pressure_pa
                );
                return Err(self.issue(Some(j), IssueKind::OutOfRange, msg, true));
            }
        }
        if let Some(last) = self.last_t {
            if s.t_s <= last {
                let msg = format!("time {} s does not increase (previous {} s)", s.t_s, last);
                return Err(self.issue(Some(0), IssueKind::TimeNotIncreasing, msg, true));
            }
            let dt = s.t_s - last;
            let period = *self.period.get_or_insert(dt);
            self.last_t = Some(s.t_s);
            if dt > 1.5 * period {
                let missing = (dt / period).round() as u64 - 1;
                let msg = format!("gap of {dt} s ({missing} missing samples) before this row");
                let issue = self.issue(Some(0), IssueKind::Gap { missing }, msg, false);
                return Ok((s, Some(issue)));
            }
        } else {
            self.last_t = Some(s.t_s);
        }
        Ok((s, None))
    }

    /// The file being read.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// One row of a CSV file.
#[derive(Debug, Clone, PartialEq)]
pub enum Row {
    /// A usable sample.
    Sample(Sample),
    /// A usable sample that follows a gap in time (reported, kept).
    AfterGap(Sample, Issue),
    /// A row that cannot be used; skipped.
    Skipped(Issue),
}

/// A whole file read into memory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dataset {
    /// The usable samples, in file order.
    pub samples: Vec<Sample>,
    /// Every problem found (skipped rows and gaps), in file order.
    pub issues: Vec<Issue>,
    /// Which optional columns the file has (x_sp, f_load, ref, q_leak).
    pub has_optional: [bool; 4],
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
    Ok(ds)
}

/// Writes samples to a CSV file with every column of [`COLUMNS`], floats at
/// full round-trip precision.
pub fn write_csv(path: &Path, samples: &[Sample]) -> Result<(), DatasetError> {
    let io = |source| DatasetError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = File::create(path).map_err(io)?;
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
        "{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
        s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa, s.x_sp_m, s.f_load_n, s.ref_m, s.q_leak_lpm
    )
}
