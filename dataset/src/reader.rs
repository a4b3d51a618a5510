//! The streaming reader ([`CsvReader`]): the header, then one [`Row`] at a
//! time, every unusable row reported with its line and column.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

use crate::{DatasetError, Issue, IssueKind, Limits, Sample, COLUMNS, N_OPTIONAL, REQUIRED};

/// A streaming reader of samples from a CSV file.
pub struct CsvReader<R: BufRead> {
    reader: R,
    line: Vec<u8>,
    ended: bool,
    path: PathBuf,
    map: [Option<usize>; COLUMNS.len()],
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
    /// in [`COLUMNS`] order (x_sp, f_load, ref, q_leak, temp_c); only columns in the header count.
    pub absent: [u64; N_OPTIONAL],
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
        let names: Vec<&str> = header.split(',').map(|s| unquote(s.trim())).collect();
        let mut map = [None; COLUMNS.len()];
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
                    header: crate::shown(&header),
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
            absent: [0; N_OPTIONAL],
        })
    }

    /// Which optional columns the file has, in [`COLUMNS`] order (x_sp, f_load, ref, q_leak, temp_c).
    pub fn has_optional(&self) -> [bool; N_OPTIONAL] {
        std::array::from_fn(|k| self.map[REQUIRED.len() + k].is_some())
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
            for (k, v) in [s.x_sp_m, s.f_load_n, s.ref_m, s.q_leak_lpm, s.temp_c]
                .into_iter()
                .enumerate()
            {
                if v.is_nan() && self.map[REQUIRED.len() + k].is_some() {
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
            let cell = unquote(cell.trim());
            let v = if cell.is_empty() {
                f64::NAN
            } else {
                match cell.parse::<f64>() {
                    Ok(v) => v,
                    Err(_) => {
                        if bad.is_none() {
                            bad = Some((count - 1, crate::shown(cell)));
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
            temp_c: get(9),
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

/// `text` without one pair of surrounding double quotes (standard CSV quoting,
/// `"0.0"`), if it has them; anything else as it is. Nothing inside is undone
/// (no `""` escapes, no commas within quotes: those fields stay invalid).
fn unquote(text: &str) -> &str {
    match text.strip_prefix('"').and_then(|t| t.strip_suffix('"')) {
        Some(inner) => inner,
        None => text,
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
