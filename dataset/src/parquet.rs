//! A small Parquet writer for tables of numbers (estimates.parquet).
//!
//! Parquet is the columnar format that pandas (`pd.read_parquet`), polars,
//! pyarrow, DuckDB and Spark open directly, with each column's name and type
//! in the file; a column of one float reads as one contiguous array. This
//! writer covers what leakwatch writes and nothing more: flat schemas of
//! required `DOUBLE` (f64) and `INT32` columns, PLAIN encoding, no
//! compression, one data page per column per row group (Parquet format 2.x,
//! data page v1; the footer in Thrift's compact protocol). Values are stored
//! bit for bit (NaN and infinities included), so reading a column gives back
//! the exact f64s that were written. Each column chunk has its statistics
//! (min and max without NaN, null count 0; the columns' type order declared),
//! so a reader can skip row groups by a filter; `created_by` is [`CREATED_BY`].
//!
//! ```text
//! let mut w = ParquetWriter::new(file, &[Column::f64("t"), Column::i32("flags")])?;
//! w.push_f64(0, 0.001); w.push_i32(1, 0); w.end_row()?;
//! w.finish()?;
//! ```

use std::io::{self, Write};

/// The type of one column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnType {
    /// IEEE 754 double (Parquet `DOUBLE`).
    F64,
    /// Signed 32-bit integer (Parquet `INT32`), e.g. bit flags.
    I32,
}

/// One column of the schema: its name and type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// Column name as data tools show it.
    pub name: String,
    /// Value type.
    pub kind: ColumnType,
}

impl Column {
    /// A column of f64 values.
    pub fn f64(name: &str) -> Column {
        Column {
            name: name.to_string(),
            kind: ColumnType::F64,
        }
    }

    /// A column of i32 values.
    pub fn i32(name: &str) -> Column {
        Column {
            name: name.to_string(),
            kind: ColumnType::I32,
        }
    }
}

/// Rows per row group: 65,536 rows (about 64 s at 1 kHz, 0.5 MiB per f64 column).
pub const ROWS_PER_GROUP: usize = 1 << 16;

/// Parquet physical type codes (parquet.thrift `Type`).
const TYPE_INT32: i32 = 1;
const TYPE_DOUBLE: i32 = 5;
/// `FieldRepetitionType.REQUIRED`.
const REQUIRED: i32 = 0;
/// `Encoding.PLAIN` and `Encoding.RLE`.
const PLAIN: i32 = 0;
const RLE: i32 = 3;
/// `CompressionCodec.UNCOMPRESSED`.
const UNCOMPRESSED: i32 = 0;
/// `PageType.DATA_PAGE`.
const DATA_PAGE: i32 = 0;
const MAGIC: &[u8; 4] = b"PAR1";

/// What the footer says a file was written by (`created_by`: application,
/// `version`, its version, as Parquet readers parse it).
pub const CREATED_BY: &str = concat!("leakwatch version ", env!("CARGO_PKG_VERSION"));

/// Where one written column chunk is, and its statistics, for the footer.
struct ChunkMeta {
    /// File offset of its page header, bytes.
    offset: u64,
    /// Page header plus values, bytes.
    size: u64,
    /// Its smallest and largest value, PLAIN-encoded (little-endian), NaN left
    /// out (a zero is −0.0 as the minimum, +0.0 as the maximum, as the Parquet
    /// spec asks); `None` if every value is NaN.
    min_max: Option<(Vec<u8>, Vec<u8>)>,
}

/// The statistics of one chunk's PLAIN values (see [`ChunkMeta::min_max`]).
fn min_max(kind: ColumnType, values: &[u8]) -> Option<(Vec<u8>, Vec<u8>)> {
    match kind {
        ColumnType::F64 => {
            // f64::min and f64::max keep the other value over a NaN, so NaN
            // is left out without a test per value; four lanes apart, so the
            // loop runs in vector registers
            let (mut lo, mut hi) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4]);
            let quads = values.chunks_exact(32);
            let rest = quads.remainder();
            for quad in quads {
                for (k, v) in quad.chunks_exact(8).enumerate() {
                    let x = f64::from_le_bytes([v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]]);
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                }
            }
            for v in rest.chunks_exact(8) {
                let x = f64::from_le_bytes([v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]]);
                lo[0] = lo[0].min(x);
                hi[0] = hi[0].max(x);
            }
            let lo = lo[0].min(lo[1]).min(lo[2].min(lo[3]));
            let hi = hi[0].max(hi[1]).max(hi[2].max(hi[3]));
            // a value that is not NaN lies in [lo, hi]; none: lo = ∞ > hi = −∞
            if lo > hi {
                return None;
            }
            let lo = if lo == 0.0 { -0.0 } else { lo };
            let hi = if hi == 0.0 { 0.0 } else { hi };
            Some((lo.to_le_bytes().to_vec(), hi.to_le_bytes().to_vec()))
        }
        ColumnType::I32 => {
            let mut it = values
                .chunks_exact(4)
                .map(|v| i32::from_le_bytes([v[0], v[1], v[2], v[3]]));
            let first = it.next()?;
            let (lo, hi) = it.fold((first, first), |(lo, hi), x| (lo.min(x), hi.max(x)));
            Some((lo.to_le_bytes().to_vec(), hi.to_le_bytes().to_vec()))
        }
    }
}

/// Writes rows of numbers into a Parquet file, a row group at a time.
///
/// Values are pushed per column into a buffer of [`ROWS_PER_GROUP`] rows;
/// [`ParquetWriter::end_row`] closes a row and writes a full group; a row
/// group's buffers are reused, so steady-state writing does not allocate.
pub struct ParquetWriter<W: Write> {
    out: W,
    columns: Vec<Column>,
    /// Little-endian values of the current row group, one buffer per column.
    buffers: Vec<Vec<u8>>,
    rows_in_group: usize,
    rows_total: u64,
    /// Bytes written so far (the next offset).
    offset: u64,
    groups: Vec<(u64, Vec<ChunkMeta>)>,
}

impl<W: Write> ParquetWriter<W> {
    /// Starts a file with the given schema (writes the leading magic).
    pub fn new(mut out: W, columns: &[Column]) -> io::Result<Self> {
        if columns.is_empty() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "a Parquet file needs a column",
            ));
        }
        out.write_all(MAGIC)?;
        let buffers = columns
            .iter()
            .map(|c| Vec::with_capacity(ROWS_PER_GROUP * width(c.kind)))
            .collect();
        Ok(ParquetWriter {
            out,
            columns: columns.to_vec(),
            buffers,
            rows_in_group: 0,
            rows_total: 0,
            offset: MAGIC.len() as u64,
            groups: Vec::new(),
        })
    }

    /// The schema.
    pub fn columns(&self) -> &[Column] {
        &self.columns
    }

    /// Appends `v` to column `col` (an `F64` column) of the current row.
    #[inline]
    pub fn push_f64(&mut self, col: usize, v: f64) {
        self.buffers[col].extend_from_slice(&v.to_le_bytes());
    }

    /// Appends `v` to column `col` (an `I32` column) of the current row.
    #[inline]
    pub fn push_i32(&mut self, col: usize, v: i32) {
        self.buffers[col].extend_from_slice(&v.to_le_bytes());
    }

    /// Closes the current row (every column must have had one value pushed);
    /// writes the row group when it is full.
    pub fn end_row(&mut self) -> io::Result<()> {
        self.rows_in_group += 1;
        if self.rows_in_group == ROWS_PER_GROUP {
            self.write_group()?;
        }
        Ok(())
    }

    /// Rows closed so far.
    pub fn rows(&self) -> u64 {
        self.rows_total + self.rows_in_group as u64
    }

    fn write_group(&mut self) -> io::Result<()> {
        let rows = self.rows_in_group;
        if rows == 0 {
            return Ok(());
        }
        for (c, (col, buf)) in self.columns.iter().zip(&self.buffers).enumerate() {
            if buf.len() != rows * width(col.kind) {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!(
                        "column {c} `{}` has {} values in a group of {rows} rows",
                        col.name,
                        buf.len() / width(col.kind)
                    ),
                ));
            }
        }
        let mut chunks = Vec::with_capacity(self.columns.len());
        let mut header = Vec::with_capacity(32);
        for (col, buf) in self.columns.iter().zip(&mut self.buffers) {
            header.clear();
            page_header(&mut header, rows, buf.len());
            let start = self.offset;
            self.out.write_all(&header)?;
            self.out.write_all(buf)?;
            let size = (header.len() + buf.len()) as u64;
            self.offset += size;
            chunks.push(ChunkMeta {
                offset: start,
                size,
                min_max: min_max(col.kind, buf),
            });
            buf.clear();
        }
        self.groups.push((rows as u64, chunks));
        self.rows_total += rows as u64;
        self.rows_in_group = 0;
        Ok(())
    }

    /// Writes the last row group and the footer; returns the output.
    pub fn finish(mut self) -> io::Result<W> {
        self.write_group()?;
        let footer = self.footer();
        self.out.write_all(&footer)?;
        self.out.write_all(&(footer.len() as u32).to_le_bytes())?;
        self.out.write_all(MAGIC)?;
        self.out.flush()?;
        Ok(self.out)
    }

    /// FileMetaData in Thrift's compact protocol.
    fn footer(&self) -> Vec<u8> {
        let mut t = Thrift::default();
        t.field_i32(1, 1); // version
        t.field_list(2, STRUCT, self.columns.len() + 1); // schema
        {
            // the root: a group of the columns
            t.begin_struct();
            t.field_binary(4, b"schema");
            t.field_i32(5, self.columns.len() as i32);
            t.end_struct();
            for c in &self.columns {
                t.begin_struct();
                t.field_i32(1, physical(c.kind));
                t.field_i32(3, REQUIRED);
                t.field_binary(4, c.name.as_bytes());
                t.end_struct();
            }
        }
        t.field_i64(3, self.rows_total as i64); // num_rows
        t.field_list(4, STRUCT, self.groups.len()); // row_groups
        for (rows, chunks) in &self.groups {
            t.begin_struct();
            t.field_list(1, STRUCT, chunks.len()); // columns
            for (col, chunk) in self.columns.iter().zip(chunks) {
                t.begin_struct();
                t.field_i64(2, chunk.offset as i64); // file_offset
                t.field_struct(3); // meta_data
                t.field_i32(1, physical(col.kind));
                t.field_list(2, I32, 1); // encodings
                t.i32(PLAIN);
                t.field_list(3, BINARY, 1); // path_in_schema
                t.binary(col.name.as_bytes());
                t.field_i32(4, UNCOMPRESSED);
                t.field_i64(5, *rows as i64); // num_values
                t.field_i64(6, chunk.size as i64); // total_uncompressed_size
                t.field_i64(7, chunk.size as i64); // total_compressed_size
                t.field_i64(9, chunk.offset as i64); // data_page_offset
                t.field_struct(12); // statistics
                t.field_i64(3, 0); // null_count (the columns are required)
                if let Some((min, max)) = &chunk.min_max {
                    t.field_binary(5, max); // max_value
                    t.field_binary(6, min); // min_value
                }
                t.end_struct();
                t.end_struct();
                t.end_struct();
            }
            let bytes: u64 = chunks.iter().map(|c| c.size).sum();
            t.field_i64(2, bytes as i64); // total_byte_size
            t.field_i64(3, *rows as i64); // num_rows
            t.end_struct();
        }
        t.field_binary(6, CREATED_BY.as_bytes()); // created_by
                                                  // column_orders: each column's values ordered by their type (what lets
                                                  // readers trust min_value and max_value)
        t.field_list(7, STRUCT, self.columns.len());
        for _ in &self.columns {
            t.begin_struct(); // ColumnOrder (a union)
            t.field_struct(1); // TYPE_ORDER: TypeDefinedOrder, empty
            t.end_struct();
            t.end_struct();
        }
        t.end_struct();
        t.out
    }
}

/// Bytes per value.
fn width(kind: ColumnType) -> usize {
    match kind {
        ColumnType::F64 => 8,
        ColumnType::I32 => 4,
    }
}

fn physical(kind: ColumnType) -> i32 {
    match kind {
        ColumnType::F64 => TYPE_DOUBLE,
        ColumnType::I32 => TYPE_INT32,
    }
}

/// A data page header for `rows` required values of `bytes` bytes.
fn page_header(out: &mut Vec<u8>, rows: usize, bytes: usize) {
    let mut t = Thrift {
        out: std::mem::take(out),
        ..Thrift::default()
    };
    t.field_i32(1, DATA_PAGE);
    t.field_i32(2, bytes as i32); // uncompressed_page_size
    t.field_i32(3, bytes as i32); // compressed_page_size
    t.field_struct(5); // data_page_header
    t.field_i32(1, rows as i32); // num_values
    t.field_i32(2, PLAIN);
    t.field_i32(3, RLE); // definition levels (none: required)
    t.field_i32(4, RLE); // repetition levels (none: flat)
    t.end_struct();
    t.end_struct();
    *out = t.out;
}

// Thrift compact protocol type codes.
const I32: u8 = 5;
const I64: u8 = 6;
const BINARY: u8 = 8;
const LIST: u8 = 9;
const STRUCT: u8 = 12;

/// A Thrift compact-protocol encoder (the subset Parquet's metadata needs):
/// field headers carry the id as a delta from the previous field of the same
/// struct, integers are zigzag varints.
#[derive(Default)]
struct Thrift {
    out: Vec<u8>,
    /// Last field id of each open struct (innermost last).
    last_ids: Vec<i16>,
    last: i16,
}

impl Thrift {
    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.out.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.out.push(v as u8);
    }

    fn i32(&mut self, v: i32) {
        self.varint(((v << 1) ^ (v >> 31)) as u32 as u64);
    }

    fn i64(&mut self, v: i64) {
        self.varint(((v << 1) ^ (v >> 63)) as u64);
    }

    fn binary(&mut self, b: &[u8]) {
        self.varint(b.len() as u64);
        self.out.extend_from_slice(b);
    }

    fn field(&mut self, id: i16, kind: u8) {
        let delta = id - self.last;
        if (1..=15).contains(&delta) {
            self.out.push(((delta as u8) << 4) | kind);
        } else {
            self.out.push(kind);
            self.i32(i32::from(id));
        }
        self.last = id;
    }

    fn field_i32(&mut self, id: i16, v: i32) {
        self.field(id, I32);
        self.i32(v);
    }

    fn field_i64(&mut self, id: i16, v: i64) {
        self.field(id, I64);
        self.i64(v);
    }

    fn field_binary(&mut self, id: i16, b: &[u8]) {
        self.field(id, BINARY);
        self.binary(b);
    }

    fn field_list(&mut self, id: i16, elem: u8, len: usize) {
        self.field(id, LIST);
        if len < 15 {
            self.out.push(((len as u8) << 4) | elem);
        } else {
            self.out.push(0xF0 | elem);
            self.varint(len as u64);
        }
    }

    /// A struct-valued field: opens the nested struct.
    fn field_struct(&mut self, id: i16) {
        self.field(id, STRUCT);
        self.begin_struct();
    }

    /// Opens a struct (a list element, or after a struct field header).
    fn begin_struct(&mut self) {
        self.last_ids.push(self.last);
        self.last = 0;
    }

    /// Closes the innermost struct (the stop byte).
    fn end_struct(&mut self) {
        self.out.push(0);
        self.last = self.last_ids.pop().unwrap_or(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunk_statistics_leave_nan_out_and_order_zeros_as_the_spec_asks() {
        let f = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let back = |b: &[u8]| f64::from_le_bytes(b.try_into().expect("8 bytes"));
        let (lo, hi) = min_max(
            ColumnType::F64,
            &f(&[f64::NAN, 2.5, -1.0, f64::INFINITY, f64::NAN]),
        )
        .expect("a range");
        assert_eq!((back(&lo), back(&hi)), (-1.0, f64::INFINITY));
        let (lo, hi) = min_max(ColumnType::F64, &f(&[0.0, -0.0, 0.0])).expect("a range");
        assert_eq!(
            (back(&lo).to_bits(), back(&hi).to_bits()),
            ((-0.0f64).to_bits(), 0.0f64.to_bits())
        );
        assert_eq!(min_max(ColumnType::F64, &f(&[f64::NAN, f64::NAN])), None);
        let ints: Vec<u8> = [7i32, -3, 12].iter().flat_map(|x| x.to_le_bytes()).collect();
        let (lo, hi) = min_max(ColumnType::I32, &ints).expect("a range");
        assert_eq!(
            (lo, hi),
            ((-3i32).to_le_bytes().to_vec(), 12i32.to_le_bytes().to_vec())
        );
        assert_eq!(
            CREATED_BY,
            format!("leakwatch version {}", env!("CARGO_PKG_VERSION"))
        );
    }

    #[test]
    fn chunk_statistics_are_the_least_and_greatest_value_in_any_position() {
        let f = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let back = |b: &[u8]| f64::from_le_bytes(b.try_into().expect("8 bytes"));
        // each length up to past two lanes' rounds, the extremes in every position
        for n in 1..12 {
            for at_lo in 0..n {
                for at_hi in (0..n).filter(|k| *k != at_lo) {
                    let mut v: Vec<f64> = (0..n).map(|k| if k % 3 == 0 { f64::NAN } else { 0.5 }).collect();
                    v[at_lo] = -7.25;
                    v[at_hi] = 3.0e9;
                    let (lo, hi) = min_max(ColumnType::F64, &f(&v)).expect("a range");
                    assert_eq!((back(&lo), back(&hi)), (-7.25, 3.0e9), "{v:?}");
                }
            }
            let all_nan = vec![f64::NAN; n];
            assert_eq!(min_max(ColumnType::F64, &f(&all_nan)), None);
            let (lo, hi) = min_max(ColumnType::F64, &f(&vec![f64::INFINITY; n])).expect("a range");
            assert_eq!((back(&lo), back(&hi)), (f64::INFINITY, f64::INFINITY));
        }
    }

    #[test]
    fn thrift_compact_encodings_match_the_spec() {
        let mut t = Thrift::default();
        t.i32(-1);
        t.i32(1);
        t.i64(300);
        assert_eq!(t.out, [0x01, 0x02, 0xD8, 0x04]);
        let mut t = Thrift::default();
        t.field_i32(1, 3);
        t.field_i32(20, 0);
        assert_eq!(t.out, [0x15, 0x06, 0x05, 0x28, 0x00]);
    }

    #[test]
    fn the_file_has_its_magic_length_and_footer() {
        let mut w = ParquetWriter::new(Vec::new(), &[Column::f64("t"), Column::i32("flags")]).unwrap();
        for k in 0..10 {
            w.push_f64(0, k as f64 * 1e-3);
            w.push_i32(1, k);
            w.end_row().unwrap();
        }
        assert_eq!(w.rows(), 10);
        let bytes = w.finish().unwrap();
        assert_eq!(&bytes[..4], b"PAR1");
        assert_eq!(&bytes[bytes.len() - 4..], b"PAR1");
        let n = bytes.len();
        let footer_len =
            u32::from_le_bytes([bytes[n - 8], bytes[n - 7], bytes[n - 6], bytes[n - 5]]) as usize;
        // magic + two pages (header + 80 and 40 bytes of values) + footer + length + magic
        assert!(footer_len > 40 && footer_len < 400, "{footer_len}");
        let values: usize = 80 + 40;
        assert!(n > 4 + values + footer_len + 8);
        // the t column's values, bit for bit, after its page header
        let needle = (9.0f64 * 1e-3).to_le_bytes();
        assert!(bytes.windows(8).any(|w| w == needle));
    }

    #[test]
    fn a_row_with_a_missing_value_is_an_error_naming_the_column() {
        let mut w = ParquetWriter::new(Vec::new(), &[Column::f64("t"), Column::f64("x")]).unwrap();
        w.push_f64(0, 1.0);
        w.end_row().unwrap();
        let err = w.finish().expect_err("short column");
        assert!(err.to_string().contains("`x`"), "{err}");
    }
}
