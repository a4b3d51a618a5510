//! The estimates file of a replay: estimates.csv (text, shortest round-trip
//! floats) or estimates.parquet (columnar, for pandas, polars, pyarrow),
//! with the same columns and the same values bit for bit.

use std::fs::File;
use std::io::{BufWriter, Write};

use dataset::parquet::{Column, ParquetWriter};
use estimator::StageEstimate;

/// The format of the estimates file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum EstimatesFormat {
    /// estimates.csv: one text row per sample.
    #[default]
    Csv,
    /// estimates.parquet: one typed column per field (f64; the two flag columns i32).
    Parquet,
}

impl EstimatesFormat {
    /// The file name in the output directory.
    pub fn file_name(self) -> &'static str {
        match self {
            EstimatesFormat::Csv => "estimates.csv",
            EstimatesFormat::Parquet => "estimates.parquet",
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

/// Calls `cell` with each value of the row of `s`, in [`ESTIMATES_HEADER`]'s order.
fn for_each_cell(s: &StageEstimate, mut cell: impl FnMut(Cell)) {
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

/// The columns of estimates.parquet: [`ESTIMATES_HEADER`]'s names, `flags`
/// and `th_flags` as i32, the rest f64.
pub fn parquet_columns() -> Vec<Column> {
    ESTIMATES_HEADER
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

/// An open estimates file of either format.
pub enum EstimatesWriter {
    /// Text rows.
    Csv(BufWriter<File>),
    /// Columns, a row group of 65,536 rows at a time.
    Parquet(Box<ParquetWriter<BufWriter<File>>>),
}

impl EstimatesWriter {
    /// Starts the file (the CSV header, or the Parquet magic).
    pub fn new(file: File, format: EstimatesFormat) -> std::io::Result<Self> {
        let out = BufWriter::with_capacity(1 << 20, file);
        Ok(match format {
            EstimatesFormat::Csv => {
                let mut out = out;
                writeln!(out, "{ESTIMATES_HEADER}")?;
                EstimatesWriter::Csv(out)
            }
            EstimatesFormat::Parquet => {
                EstimatesWriter::Parquet(Box::new(ParquetWriter::new(out, &parquet_columns())?))
            }
        })
    }

    /// Writes the row of one sample.
    pub fn write(&mut self, s: &StageEstimate) -> std::io::Result<()> {
        match self {
            EstimatesWriter::Csv(out) => write_estimate_row(out, s),
            EstimatesWriter::Parquet(pq) => {
                let mut col = 0;
                for_each_cell(s, |c| {
                    match c {
                        Cell::F64(v) => pq.push_f64(col, v),
                        Cell::Flags(v) => pq.push_i32(col, v as i32),
                    }
                    col += 1;
                });
                pq.end_row()
            }
        }
    }

    /// Writes what is buffered (and the Parquet footer) and flushes.
    pub fn finish(self) -> std::io::Result<()> {
        match self {
            EstimatesWriter::Csv(mut out) => out.flush(),
            EstimatesWriter::Parquet(pq) => pq.finish().map(|_| ()),
        }
    }
}

/// Header of estimates.csv.
pub const ESTIMATES_HEADER: &str =
    "t,u,x_meas,p1_meas,p2_meas,x_sp,p1,p2,x,v,v_sp,f_e,q_e1_lpm,q_e2_lpm,q_i_lpm,\
spool_bias,bulk_scale,r_x,r_p1,r_p2,nu_x,nu_p1,nu_p2,nis,flags,th_x,th_p1,th_p2,th_v,th_f_e,th_r_x,th_r_p1,th_r_p2,\
th_nu_p1,th_nu_p2,th_mae_p1,th_mae_p2,th_nis,th_flags";

/// One CSV row being assembled: floats in shortest round-trip form, by `zmij`
/// (parsing a cell gives back the exact f64; NaN is `NaN`, infinities `inf`/`-inf`).
struct CsvLine {
    floats: zmij::Buffer,
    bytes: [u8; 1024],
    len: usize,
}

impl CsvLine {
    fn new() -> Self {
        CsvLine {
            floats: zmij::Buffer::new(),
            bytes: [0; 1024],
            len: 0,
        }
    }

    /// Appends `v` (after a comma unless it is the first cell).
    fn float(&mut self, v: f64) {
        let text = self.floats.format(v).as_bytes();
        if self.len > 0 {
            self.bytes[self.len] = b',';
            self.len += 1;
        }
        self.bytes[self.len..self.len + text.len()].copy_from_slice(text);
        self.len += text.len();
    }

    /// Appends an integer cell.
    fn int(&mut self, v: u32) {
        let mut digits = itoa::Buffer::new();
        let text = digits.format(v).as_bytes();
        self.bytes[self.len] = b',';
        self.bytes[self.len + 1..self.len + 1 + text.len()].copy_from_slice(text);
        self.len += 1 + text.len();
    }
}

/// Writes one estimates.csv row (floats in shortest round-trip form: parsing a
/// cell gives back the exact f64).
pub fn write_estimate_row<W: Write>(w: &mut W, s: &StageEstimate) -> std::io::Result<()> {
    // 37 floats of at most 24 bytes and two flags: well inside the row's 1024 bytes
    let mut row = CsvLine::new();
    for_each_cell(s, |c| match c {
        Cell::F64(v) => row.float(v),
        Cell::Flags(v) => row.int(v),
    });
    row.bytes[row.len] = b'\n';
    w.write_all(&row.bytes[..row.len + 1])
}
