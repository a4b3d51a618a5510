//! The estimates file of a replay: estimates.csv (text, shortest round-trip
//! floats) or estimates.parquet (columnar, for pandas, polars, pyarrow),
//! with the same columns and the same values bit for bit.

use std::fs::File;
use std::io::{BufWriter, Write};

use dataset::parquet::{Column, ParquetWriter};
use filter::StageEstimate;

/// The format of the estimates file (`--estimates`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum EstimatesFormat {
    /// Parquet for a batch and for an input of 16 MiB or more (2 MiB
    /// compressed: `.csv.gz`, `.mcap`), CSV for a shorter single file (decided
    /// before the replay starts; the sizes: `LONG_INPUT_BYTES`,
    /// `LONG_COMPRESSED_INPUT_BYTES`).
    #[default]
    Auto,
    /// estimates.csv: one text row per sample.
    Csv,
    /// estimates.parquet: one typed column per field (f64; the two flag columns
    /// i32), with each column chunk's minimum and maximum.
    Parquet,
    /// No estimates file (events.json and summary.json only): the fastest replay.
    None,
}

/// The input size from which [`EstimatesFormat::Auto`] writes Parquet, bytes
/// (16 MiB: about 2 minutes of a 1 kHz CSV with every column, whose
/// estimates.csv would be about 3 times larger).
pub const LONG_INPUT_BYTES: u64 = 16 << 20;

/// [`LONG_INPUT_BYTES`] for a compressed input (`.csv.gz`, a log `.mcap`), bytes
/// (2 MiB: a log holds a 1 kHz sample in about 20 bytes, 7.5 times fewer than its CSV).
pub const LONG_COMPRESSED_INPUT_BYTES: u64 = 2 << 20;

impl EstimatesFormat {
    /// The file name in the output directory (none for [`EstimatesFormat::None`];
    /// [`EstimatesFormat::Auto`] is resolved first, by [`Self::for_input`] or
    /// [`Self::for_batch`]: none either).
    pub fn file_name(self) -> Option<&'static str> {
        match self {
            EstimatesFormat::Csv => Some("estimates.csv"),
            EstimatesFormat::Parquet => Some("estimates.parquet"),
            EstimatesFormat::None | EstimatesFormat::Auto => None,
        }
    }

    /// The format for one file of a batch: [`EstimatesFormat::Auto`] is Parquet.
    pub fn for_batch(self) -> EstimatesFormat {
        match self {
            EstimatesFormat::Auto => EstimatesFormat::Parquet,
            other => other,
        }
    }

    /// The input size from which [`EstimatesFormat::Auto`] writes Parquet for
    /// the input `path`, bytes: [`LONG_COMPRESSED_INPUT_BYTES`] for a name
    /// ending in `.gz` or `.mcap` (any case), else [`LONG_INPUT_BYTES`].
    pub fn long_input_bytes(path: &std::path::Path) -> u64 {
        let compressed = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gz") || e.eq_ignore_ascii_case("mcap"));
        if compressed {
            LONG_COMPRESSED_INPUT_BYTES
        } else {
            LONG_INPUT_BYTES
        }
    }

    /// The format for a single input of `input_bytes` bytes, long from
    /// `long_bytes` on ([`Self::long_input_bytes`]): [`EstimatesFormat::Auto`]
    /// is Parquet for a long input, else CSV.
    pub fn for_input(self, input_bytes: u64, long_bytes: u64) -> EstimatesFormat {
        match self {
            EstimatesFormat::Auto if input_bytes >= long_bytes => EstimatesFormat::Parquet,
            EstimatesFormat::Auto => EstimatesFormat::Csv,
            other => other,
        }
    }

    /// Its name as `--estimates` takes it (`auto`, `csv`, `parquet`, `none`).
    pub fn name(self) -> &'static str {
        match self {
            EstimatesFormat::Auto => "auto",
            EstimatesFormat::Csv => "csv",
            EstimatesFormat::Parquet => "parquet",
            EstimatesFormat::None => "none",
        }
    }
}

/// One value of an estimates row, in column order.
#[derive(Debug, Clone, Copy)]
enum Cell {
    /// A float column (SI, leak sizes in L/min).
    F64(f64),
    /// A flags column (bit set).
    Flags(u32),
}

/// Calls `cell` with each value of the row of `s`, in [`LEAK_COLUMNS`]'s order,
/// then, when `thesis`, in [`THESIS_COLUMNS`]'s.
fn for_each_cell(s: &StageEstimate, thesis: bool, mut cell: impl FnMut(Cell)) {
    let e = &s.leak;
    let t = &s.thesis;
    let lpm = |v: f64| v * 6.0e4;
    for v in [e.t_s, e.u_v, e.measured[0], e.measured[1], e.measured[2]] {
        cell(Cell::F64(v));
    }
    for v in &e.state[..7] {
        cell(Cell::F64(*v));
    }
    for v in [
        lpm(e.state[7]),
        lpm(e.state[8]),
        lpm(e.state[9]),
        e.state[10],
        e.bulk_scale,
    ] {
        cell(Cell::F64(v));
    }
    for v in e.residual.iter().chain(e.innovation.iter()) {
        cell(Cell::F64(*v));
    }
    cell(Cell::F64(e.nis));
    cell(Cell::Flags(e.flags));
    if !thesis {
        return;
    }
    for v in [t.state[3], t.state[1], t.state[2], t.state[4], t.state[6]] {
        cell(Cell::F64(v));
    }
    for v in t.residual.iter() {
        cell(Cell::F64(*v));
    }
    for v in [t.innovation[1], t.innovation[2], t.mae_pa[0], t.mae_pa[1], t.nis] {
        cell(Cell::F64(v));
    }
    cell(Cell::Flags(t.flags));
}

/// The column names of an estimates file, comma-separated: [`LEAK_COLUMNS`],
/// then [`THESIS_COLUMNS`] when the thesis filter ran (`thesis`).
pub fn header(thesis: bool) -> String {
    if thesis {
        format!("{LEAK_COLUMNS},{THESIS_COLUMNS}")
    } else {
        LEAK_COLUMNS.to_string()
    }
}

/// The columns of estimates.parquet: [`header`]'s names, `flags` and
/// `th_flags` as i32, the rest f64.
pub fn parquet_columns(thesis: bool) -> Vec<Column> {
    header(thesis)
        .split(',')
        .map(|name| {
            if name.ends_with("flags") {
                Column::i32(name)
            } else {
                Column::f64(name)
            }
        })
        .collect()
}

/// An open estimates file of either format, or none.
pub enum EstimatesWriter {
    /// Text rows.
    Csv(Box<CsvOut>),
    /// Columns, a row group of 65,536 rows at a time; with the thesis
    /// filter's columns or not.
    Parquet(Box<ParquetWriter<BufWriter<File>>>, bool),
    /// No file: the estimates are not written.
    None,
}

impl EstimatesWriter {
    /// Starts the file (the CSV header, or the Parquet magic), with the thesis
    /// filter's columns when `thesis`; `file` is ignored (and may be none) for
    /// [`EstimatesFormat::None`]; [`EstimatesFormat::Auto`] is an error (resolve it first).
    pub fn new(file: Option<File>, format: EstimatesFormat, thesis: bool) -> std::io::Result<Self> {
        if format == EstimatesFormat::Auto {
            return Err(std::io::Error::other(
                "the estimates' format `auto` was not resolved to csv or parquet",
            ));
        }
        let Some(file) = file.filter(|_| format != EstimatesFormat::None) else {
            if format == EstimatesFormat::None {
                return Ok(EstimatesWriter::None);
            }
            return Err(std::io::Error::other("no file to write the estimates to"));
        };
        Ok(match format {
            EstimatesFormat::None | EstimatesFormat::Auto => EstimatesWriter::None,
            EstimatesFormat::Csv => {
                let mut out = Box::new(CsvOut::new(file, thesis));
                out.buf.extend_from_slice(header(thesis).as_bytes());
                out.buf.push(b'\n');
                EstimatesWriter::Csv(out)
            }
            EstimatesFormat::Parquet => {
                // the writer holds a row group's columns itself: the buffer
                // takes the small writes (page headers, the footer), and a
                // column's values, larger than it, go straight to the file
                let out = BufWriter::with_capacity(PARQUET_SMALL_WRITES_BYTES, file);
                EstimatesWriter::Parquet(
                    Box::new(ParquetWriter::new(out, &parquet_columns(thesis))?),
                    thesis,
                )
            }
        })
    }

    /// Writes the row of one sample.
    pub fn write(&mut self, s: &StageEstimate) -> std::io::Result<()> {
        match self {
            EstimatesWriter::Csv(out) => out.row(s),
            EstimatesWriter::Parquet(pq, thesis) => {
                let mut col = 0;
                for_each_cell(s, *thesis, |c| {
                    match c {
                        Cell::F64(v) => pq.push_f64(col, v),
                        Cell::Flags(v) => pq.push_i32(col, v as i32),
                    }
                    col += 1;
                });
                pq.end_row()
            }
            EstimatesWriter::None => Ok(()),
        }
    }

    /// Writes what is buffered (and the Parquet footer) and flushes.
    pub fn finish(self) -> std::io::Result<()> {
        match self {
            EstimatesWriter::Csv(out) => out.finish(),
            EstimatesWriter::Parquet(pq, _) => pq.finish().map(|_| ()),
            EstimatesWriter::None => Ok(()),
        }
    }
}

/// The buffer of estimates.parquet's small writes, bytes (64 KiB, below a
/// column chunk's values: [`dataset::parquet::ROWS_PER_GROUP`] × 4 bytes).
const PARQUET_SMALL_WRITES_BYTES: usize = 64 << 10;

/// The leak filter's columns of an estimates file (every replay writes them).
pub const LEAK_COLUMNS: &str =
    "t,u,x_meas,p1_meas,p2_meas,x_sp,p1,p2,x,v,v_sp,f_e,q_e1_lpm,q_e2_lpm,q_i_lpm,\
spool_bias,bulk_scale,r_x,r_p1,r_p2,nu_x,nu_p1,nu_p2,nis,flags";

/// The thesis filter's columns, after [`LEAK_COLUMNS`] when it ran (the
/// thesis baseline or `--model` asked for it).
pub const THESIS_COLUMNS: &str = "th_x,th_p1,th_p2,th_v,th_f_e,th_r_x,th_r_p1,th_r_p2,\
th_nu_p1,th_nu_p2,th_mae_p1,th_mae_p2,th_nis,th_flags";

/// The text writer of estimates.csv: rows formatted straight into one reused
/// buffer (no per-row allocation or copy), written to the file a MiB at a time.
pub struct CsvOut {
    file: File,
    thesis: bool,
    buf: Vec<u8>,
    floats: zmij::Buffer,
    digits: itoa::Buffer,
}

/// Bytes buffered before a write to the file.
const CSV_CHUNK: usize = 1 << 20;

impl CsvOut {
    fn new(file: File, thesis: bool) -> Self {
        CsvOut {
            file,
            thesis,
            buf: Vec::with_capacity(CSV_CHUNK + 4096),
            floats: zmij::Buffer::new(),
            digits: itoa::Buffer::new(),
        }
    }

    /// Appends one row (floats in shortest round-trip form, by `zmij`: parsing
    /// a cell gives back the exact f64; NaN is `NaN`, infinities `inf`/`-inf`).
    fn row(&mut self, s: &StageEstimate) -> std::io::Result<()> {
        let (buf, floats, digits) = (&mut self.buf, &mut self.floats, &mut self.digits);
        for_each_cell(s, self.thesis, |c| {
            match c {
                Cell::F64(v) => buf.extend_from_slice(floats.format(v).as_bytes()),
                Cell::Flags(v) => buf.extend_from_slice(digits.format(v).as_bytes()),
            }
            buf.push(b',');
        });
        // the last cell's comma ends the line
        if let Some(last) = buf.last_mut() {
            *last = b'\n';
        }
        if buf.len() >= CSV_CHUNK {
            self.file.write_all(buf)?;
            buf.clear();
        }
        Ok(())
    }

    fn finish(mut self) -> std::io::Result<()> {
        self.file.write_all(&self.buf)?;
        self.file.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_is_parquet_for_a_batch_and_a_long_input_and_csv_below() {
        use EstimatesFormat::*;
        assert_eq!(LONG_INPUT_BYTES, 16 * 1024 * 1024);
        assert_eq!(Auto.for_batch(), Parquet);
        assert_eq!(Auto.for_input(LONG_INPUT_BYTES, LONG_INPUT_BYTES), Parquet);
        assert_eq!(Auto.for_input(LONG_INPUT_BYTES - 1, LONG_INPUT_BYTES), Csv);
        let long = |name: &str| EstimatesFormat::long_input_bytes(std::path::Path::new(name));
        assert_eq!(
            [long("a.csv"), long("a.csv.gz"), long("run.MCAP"), long("a")],
            [16 << 20, 2 << 20, 2 << 20, 16 << 20]
        );
        // a format asked for is kept
        for f in [Csv, Parquet, None] {
            assert_eq!(
                (f.for_batch(), f.for_input(u64::MAX, 1), f.for_input(0, 1)),
                (f, f, f)
            );
        }
        assert_eq!(Auto.file_name(), Option::None);
        assert_eq!(
            [Auto, Csv, Parquet, None].map(EstimatesFormat::name),
            ["auto", "csv", "parquet", "none"]
        );
        // an unresolved `auto` writes nothing and says so
        let err = EstimatesWriter::new(Option::None, Auto, false)
            .err()
            .expect("refused");
        assert!(err.to_string().contains("`auto` was not resolved"), "{err}");
    }
}
