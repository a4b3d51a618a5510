//! The checks every sample of a recording passes, whatever it was read from
//! ([`SampleChecks`]: physical ranges, time going forward, gaps), and the rows
//! of samples already decoded (a recorded log's frames: [`SampleRows`]), so a
//! replay reads a CSV and a log through one interface ([`RowSource`]).

use crate::{Issue, IssueKind, Limits, Row, Sample, COLUMNS, N_OPTIONAL, REQUIRED};

/// The rows of a recording, one at a time, with what was absent: what a replay reads.
pub trait RowSource {
    /// The next row, or `None` at the end.
    fn next_row(&mut self) -> Option<Row>;
    /// Which optional columns the recording has, in [`COLUMNS`] order (x_sp, f_load, ref, q_leak, temp_c).
    fn has_optional(&self) -> [bool; N_OPTIONAL];
    /// Usable rows so far whose optional value was absent (NaN), per optional column.
    fn absent(&self) -> [u64; N_OPTIONAL];
}

/// The checks of one sample against its predecessors: the physical ranges of
/// [`Limits`], time increasing by at least `(1 - step_tolerance)` sample
/// periods (the period from the limits, else learned from the first step),
/// and gaps of more than 1.5 periods reported (the row kept).
#[derive(Debug, Clone)]
pub struct SampleChecks {
    limits: Limits,
    last_t: Option<f64>,
    period: Option<f64>,
}

impl SampleChecks {
    /// Checks against `limits`, nothing seen yet.
    pub fn new(limits: Limits) -> SampleChecks {
        SampleChecks {
            limits,
            last_t: None,
            period: limits.sample_period_s,
        }
    }

    /// Checks `s`, the row at `line` (1-based; the header is line 1): the
    /// sample (with the issue of a gap before it), or the issue that skips it.
    pub fn check(&mut self, s: Sample, line: u64) -> Result<(Sample, Option<Issue>), Issue> {
        let issue = |column: Option<usize>, kind: IssueKind, message: String, skipped: bool| Issue {
            line,
            column: column.map(|j| COLUMNS[j].to_string()),
            kind,
            message,
            skipped,
        };
        if let Some((j, kind, msg)) = self.limits.check(&s) {
            return Err(issue(Some(j), kind, msg, true));
        }
        let Some(last) = self.last_t else {
            self.last_t = Some(s.t_s);
            return Ok((s, None));
        };
        if s.t_s <= last {
            let msg = format!("time {} s does not increase (previous {} s)", s.t_s, last);
            return Err(issue(Some(0), IssueKind::TimeNotIncreasing, msg, true));
        }
        let dt = s.t_s - last;
        let period = *self.period.get_or_insert(dt);
        if dt < (1.0 - self.limits.step_tolerance) * period {
            let msg = format!(
                "time step {dt:?} s (from {last:?} s) is shorter than {} of the sample period {period:?} s",
                1.0 - self.limits.step_tolerance
            );
            return Err(issue(Some(0), IssueKind::StepTooShort, msg, true));
        }
        self.last_t = Some(s.t_s);
        if dt > 1.5 * period {
            let missing = (dt / period).round() as u64 - 1;
            let msg = format!("gap of {dt} s ({missing} missing samples) before this row");
            return Ok((s, Some(issue(Some(0), IssueKind::Gap { missing }, msg, false))));
        }
        Ok((s, None))
    }
}

/// Rows of samples already decoded (a recorded log's frames), checked as a CSV's
/// are: sample `k` is line `k + 2`, its line in the CSV export of the same
/// samples (`leakwatch export`'s dataset.csv, every column present), so the
/// issues read the same as that file's.
pub struct SampleRows<I: Iterator<Item = Sample>> {
    samples: I,
    checks: SampleChecks,
    line_no: u64,
    /// Rows read.
    pub rows: u64,
    /// Rows skipped.
    pub skipped: u64,
    /// Usable rows whose optional value was NaN, per optional column.
    pub absent: [u64; N_OPTIONAL],
}

impl<I: Iterator<Item = Sample>> SampleRows<I> {
    /// The rows of `samples`, checked against `limits`.
    pub fn new(samples: I, limits: Limits) -> SampleRows<I> {
        SampleRows {
            samples,
            checks: SampleChecks::new(limits),
            line_no: 1,
            rows: 0,
            skipped: 0,
            absent: [0; N_OPTIONAL],
        }
    }
}

/// Counts the optional values of `s` that are absent (NaN) into `absent`,
/// those of the columns in `present` only.
pub(crate) fn count_absent(s: &Sample, present: impl Fn(usize) -> bool, absent: &mut [u64; N_OPTIONAL]) {
    for (k, v) in [s.x_sp_m, s.f_load_n, s.ref_m, s.q_leak_lpm, s.temp_c]
        .into_iter()
        .enumerate()
    {
        if v.is_nan() && present(REQUIRED.len() + k) {
            absent[k] += 1;
        }
    }
}

impl<I: Iterator<Item = Sample>> RowSource for SampleRows<I> {
    fn next_row(&mut self) -> Option<Row> {
        let s = self.samples.next()?;
        self.line_no += 1;
        self.rows += 1;
        Some(match self.checks.check(s, self.line_no) {
            Ok((s, issue)) => {
                count_absent(&s, |_| true, &mut self.absent);
                match issue {
                    None => Row::Sample(s),
                    Some(issue) => Row::AfterGap(s, issue),
                }
            }
            Err(issue) => {
                self.skipped += 1;
                Row::Skipped(issue)
            }
        })
    }

    fn has_optional(&self) -> [bool; N_OPTIONAL] {
        [true; N_OPTIONAL]
    }

    fn absent(&self) -> [u64; N_OPTIONAL] {
        self.absent
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t_s: f64) -> Sample {
        Sample {
            t_s,
            u_v: 0.0,
            x_m: 0.0,
            p1_pa: 1e6,
            p2_pa: 1e6,
            x_sp_m: f64::NAN,
            f_load_n: f64::NAN,
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
            temp_c: 40.0,
        }
    }

    #[test]
    fn decoded_samples_are_checked_as_a_csv_export_of_them_is() {
        let p = model::ActuatorParams::default();
        let limits = Limits::for_model(&p, 0.001);
        let ts = [0.0, 0.001, 0.001, 0.005, 0.0055, 0.006];
        let mut rows = SampleRows::new(ts.iter().map(|&t| sample(t)), limits);
        // the same samples as a CSV, through the CSV reader
        let mut text = String::from("t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c\n");
        for &t in &ts {
            let mut line = Vec::new();
            crate::write_row(&mut line, &sample(t)).unwrap();
            text.push_str(std::str::from_utf8(&line).unwrap());
        }
        let mut csv = crate::CsvReader::new(text.as_bytes(), std::path::Path::new("x.csv"), limits).unwrap();
        let mut kinds = Vec::new();
        while let Some(row) = rows.next_row() {
            // (NaN is no value equal to itself: the rows compared as printed)
            assert_eq!(
                format!("{row:?}"),
                format!("{:?}", csv.next_row().expect("a row"))
            );
            kinds.push(match row {
                Row::Sample(s) => format!("ok {}", s.t_s),
                Row::AfterGap(_, i) => format!("{} line {}", i.kind.name(), i.line),
                Row::Skipped(i) => format!("{} line {}", i.kind.name(), i.line),
            });
        }
        assert_eq!(csv.next_row(), None);
        assert_eq!(
            kinds,
            [
                "ok 0",
                "ok 0.001",
                "time_not_increasing line 4",
                "gap line 5",
                "step_too_short line 6",
                "ok 0.006"
            ]
        );
        assert_eq!((rows.rows, rows.skipped), (6, 2));
        assert_eq!((csv.rows, csv.skipped), (6, 2));
        assert_eq!(rows.absent, [4, 4, 4, 4, 0]);
        assert_eq!(rows.absent, csv.absent);
    }
}
