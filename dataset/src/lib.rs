//! The measured-data CSV format (ARCHITECTURE.md, "Data formats").
//!
//! A header line names the columns; `t,u,x,p1,p2` (s, V, m, Pa, Pa) are
//! required, `x_sp` (m), `f_load` (N), `ref` (m) and `q_leak` (L/min) are
//! optional, in any order. Floats are written with Rust's shortest
//! round-trip formatting, so a file reads back bit for bit.
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

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

pub use model::Sample;

pub mod output;

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

/// The default largest fraction of a file's rows that may be unusable (1 %);
/// beyond it replay reports the file as bad (non-zero exit).
pub const DEFAULT_MAX_BAD_FRACTION: f64 = 0.01;

/// Limits that decide which rows are usable: the physical range of every
/// column, from the actuator's parameters (see [`Limits::for_model`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Lowest accepted pressure, Pa.
    pub min_pressure_pa: f64,
    /// Highest accepted pressure, Pa (MODEL: 1.5 p_s).
    pub max_pressure_pa: f64,
    /// Nominal sample period, s, used to detect gaps and too short steps
    /// (None: learned from the first two rows).
    pub sample_period_s: Option<f64>,
    /// A time step shorter than `(1 - step_tolerance)` sample periods is refused
    /// (a duplicated or jittered time stamp), dimensionless in [0, 1).
    pub step_tolerance: f64,
    /// Largest accepted |t|, s (1e10 s: Unix time stamps pass, 1e308 does not).
    pub max_abs_time_s: f64,
    /// Lowest accepted rod position (and position reference `ref`), m.
    pub min_position_m: f64,
    /// Highest accepted rod position (and position reference `ref`), m.
    pub max_position_m: f64,
    /// Largest accepted |u|, V.
    pub max_command_v: f64,
    /// Largest accepted |x_sp|, m.
    pub max_spool_m: f64,
    /// Largest accepted |f_load|, N.
    pub max_force_n: f64,
    /// Largest accepted |q_leak|, L/min.
    pub max_leak_lpm: f64,
}

impl Limits {
    /// The physical ranges of an actuator with parameters `p`, sampled every
    /// `sample_period_s` seconds:
    /// - position x and reference within the stroke [x_min, x_max] plus 10 % of
    ///   the stroke on each side, m;
    /// - command |u| within 1.5 × the valve's ±10 V range, V;
    /// - pressures in [0, 1.5 p_s] inclusive, Pa;
    /// - spool |x_sp| within 2 × the opening at 10 V, m;
    /// - load |f_load| within 10 × the force of 1.5 p_s on the piston, N;
    /// - leak |q_leak| within 10 × the valve's flow at full opening and 1.5 p_s, L/min;
    /// - time steps no shorter than half a sample period, |t| ≤ 1e10 s.
    pub fn for_model(p: &model::ActuatorParams, sample_period_s: f64) -> Limits {
        let u_max = model::scenario::U_MAX_V;
        let stroke = p.x_max_m - p.x_min_m;
        let p_max = 1.5 * p.supply_pressure_pa;
        let spool_open = u_max * p.spool_gain_m_per_v;
        let q_valve_m3_s = p.discharge_coefficient
            * p.area_gradient_m2_per_m
            * spool_open
            * (2.0 * p_max / p.oil_density_kg_m3).sqrt();
        Limits {
            min_pressure_pa: 0.0,
            max_pressure_pa: p_max,
            sample_period_s: Some(sample_period_s),
            step_tolerance: 0.5,
            max_abs_time_s: 1.0e10,
            min_position_m: p.x_min_m - 0.1 * stroke,
            max_position_m: p.x_max_m + 0.1 * stroke,
            max_command_v: 1.5 * u_max,
            max_spool_m: 2.0 * spool_open,
            max_force_n: 10.0 * p_max * p.piston_area_m2,
            max_leak_lpm: 10.0 * model::units::m3_s_to_lpm(q_valve_m3_s),
        }
    }

    /// The default actuator's ranges with supply pressure `supply_pa` (pressures
    /// in [0, 1.5 p_s], Pa), 1 kHz.
    pub fn for_supply(supply_pa: f64) -> Limits {
        let p = model::ActuatorParams {
            supply_pressure_pa: supply_pa,
            ..model::ActuatorParams::default()
        };
        Limits::for_model(&p, 1.0e-3)
    }

    /// The first value of `s` outside its range, as (column index in
    /// [`COLUMNS`], kind, message); `None` if every value is usable. NaN in an
    /// optional column means "absent" and passes.
    pub fn check(&self, s: &Sample) -> Option<(usize, IssueKind, String)> {
        let values = s.columns();
        for (j, v) in values.into_iter().enumerate() {
            let optional = j >= REQUIRED.len();
            if optional && v.is_nan() {
                continue;
            }
            if !v.is_finite() {
                let what = if optional { "value" } else { "required value" };
                return Some((j, IssueKind::NonFinite, format!("{what} is {v:?} (not finite)")));
            }
            let (lo, hi, unit) = match j {
                0 => (-self.max_abs_time_s, self.max_abs_time_s, "s"),
                1 => (-self.max_command_v, self.max_command_v, "V"),
                2 | 7 => (self.min_position_m, self.max_position_m, "m"),
                3 | 4 => (self.min_pressure_pa, self.max_pressure_pa, "Pa"),
                5 => (-self.max_spool_m, self.max_spool_m, "m"),
                6 => (-self.max_force_n, self.max_force_n, "N"),
                _ => (-self.max_leak_lpm, self.max_leak_lpm, "L/min"),
            };
            if !(lo..=hi).contains(&v) {
                let what = match j {
                    0 => "time",
                    1 => "command",
                    2 => "position",
                    3 | 4 => "pressure",
                    5 => "spool position",
                    6 => "load",
                    7 => "position reference",
                    _ => "leak flow",
                };
                let msg = format!("{what} {v:?} {unit} is outside [{lo:?}, {hi:?}] {unit}");
                return Some((j, IssueKind::OutOfRange, msg));
            }
        }
        None
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits::for_model(&model::ActuatorParams::default(), 1.0e-3)
    }
}

/// Checks that at most `max_fraction` of `rows` were unusable; the error says
/// how many were and the limit (a message for the user).
pub fn check_bad_fraction(rows: u64, skipped: u64, max_fraction: f64) -> Result<(), String> {
    if rows > 0 && skipped as f64 > max_fraction * rows as f64 {
        return Err(format!(
            "{skipped} of {rows} rows ({:.2} %) are unusable, more than the {:.2} % accepted",
            100.0 * skipped as f64 / rows as f64,
            100.0 * max_fraction
        ));
    }
    Ok(())
}

/// A streaming reader of samples from a CSV file.
pub struct CsvReader<R: BufRead> {
    reader: R,
    line: Vec<u8>,
    ended: bool,
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
    /// Usable rows whose optional column was absent (empty or NaN), per column
    /// in [`COLUMNS`] order (x_sp, f_load, ref, q_leak); only columns in the header count.
    pub absent: [u64; 4],
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
    pub fn new(mut reader: R, path: &Path, limits: Limits) -> Result<Self, DatasetError> {
        let mut line = Vec::new();
        reader
            .read_until(b'\n', &mut line)
            .map_err(|source| DatasetError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        // a header that is not UTF-8 names no known column: MissingColumn shows it
        let header = String::from_utf8_lossy(&line);
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
            reader,
            line,
            ended: false,
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
            absent: [0; 4],
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

    /// The next row, or `None` at the end of the file. A read error (an I/O
    /// error, a damaged gzip stream) is reported once as a skipped row of kind
    /// [`IssueKind::ReadError`] and ends the file.
    pub fn next_row(&mut self) -> Option<Row> {
        loop {
            if self.ended {
                return None;
            }
            let mut buf = std::mem::take(&mut self.line);
            buf.clear();
            let read = self.reader.read_until(b'\n', &mut buf);
            let row = match read {
                Ok(0) => {
                    self.ended = true;
                    None
                }
                Ok(_) => {
                    self.line_no += 1;
                    self.row(&buf)
                }
                Err(e) => {
                    // the reader cannot go on: report it once, at the line it broke
                    // (a reader that fails again and again would never end otherwise)
                    self.ended = true;
                    self.line_no += 1;
                    self.rows += 1;
                    let msg = format!("read error, the rest of the file is not read: {e}");
                    Some(Row::Skipped(self.issue(None, IssueKind::ReadError, msg, true)))
                }
            };
            self.line = buf;
            if row.is_some() {
                return row;
            }
        }
    }

    /// The row of one line (with its end of line); `None` for an empty line.
    fn row(&mut self, bytes: &[u8]) -> Option<Row> {
        let line = match std::str::from_utf8(bytes) {
            Ok(l) => l.trim(),
            Err(e) => {
                self.rows += 1;
                let msg = format!("not UTF-8 text (byte {} of the line)", e.valid_up_to() + 1);
                return Some(Row::Skipped(self.issue(None, IssueKind::NotText, msg, true)));
            }
        };
        if line.is_empty() {
            return None;
        }
        self.rows += 1;
        let parsed = self.parse_row(line);
        if let Ok((s, _)) = &parsed {
            for (k, v) in [s.x_sp_m, s.f_load_n, s.ref_m, s.q_leak_lpm]
                .into_iter()
                .enumerate()
            {
                if v.is_nan() && self.map[5 + k].is_some() {
                    self.absent[k] += 1;
                }
            }
        }
        Some(match parsed {
            Ok((sample, None)) => Row::Sample(sample),
            Ok((sample, Some(issue))) => Row::AfterGap(sample, issue),
            Err(issue) => Row::Skipped(issue),
        })
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
        if let Some((j, kind, msg)) = self.limits.check(&s) {
            return Err(self.issue(Some(j), kind, msg, true));
        }
        if let Some(last) = self.last_t {
            if s.t_s <= last {
                let msg = format!("time {} s does not increase (previous {} s)", s.t_s, last);
                return Err(self.issue(Some(0), IssueKind::TimeNotIncreasing, msg, true));
            }
            let dt = s.t_s - last;
            let period = *self.period.get_or_insert(dt);
            if dt < (1.0 - self.limits.step_tolerance) * period {
                let msg = format!(
                    "time step {dt:?} s (from {last:?} s) is shorter than {} of the sample period {period:?} s",
                    1.0 - self.limits.step_tolerance
                );
                return Err(self.issue(Some(0), IssueKind::StepTooShort, msg, true));
            }
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
        "{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
        s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa, s.x_sp_m, s.f_load_n, s.ref_m, s.q_leak_lpm
    )
}
