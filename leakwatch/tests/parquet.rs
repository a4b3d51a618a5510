//! `leakwatch replay --estimates parquet`: the columnar estimates file holds
//! the same values as estimates.csv, bit for bit, and pyarrow (what pandas
//! and polars use) reads it with its column names and types; the events do
//! not depend on the format.
//!
//! DuckDB reads it too, with its statistics.
//!
//! Needs python3 with `pyarrow` and `duckdb` (.ci/setup installs them). CI sets
//! LEAKWATCH_REQUIRE_PYTHON=1, so the tests must run there; elsewhere they say
//! they were skipped.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::*;

/// Reads the Parquet file with pyarrow, compares every cell with the CSV
/// (parsed as f64; NaN equals NaN) and every column chunk's statistics with
/// its values (min and max without NaN, null count), and prints a JSON summary.
const SCRIPT: &str = r#"
import csv, json, math, sys
import pyarrow.parquet as pq
f = pq.ParquetFile(sys.argv[1])
table = f.read()
cols = {n: table.column(n).to_pylist() for n in table.column_names}
with open(sys.argv[2]) as fh:
    rows = csv.reader(fh)
    header = next(rows)
    mismatches = 0
    n = 0
    for i, row in enumerate(rows):
        n += 1
        for j, name in enumerate(header):
            a, b = float(row[j]), cols[name][i]
            if not (a == b or (math.isnan(a) and math.isnan(b))):
                mismatches += 1
meta = f.metadata
stats_checked = 0
stats_mismatches = []
start = 0
for g in range(meta.num_row_groups):
    rg = meta.row_group(g)
    for c in range(rg.num_columns):
        name = table.column_names[c]
        values = [x for x in cols[name][start:start + rg.num_rows] if not (isinstance(x, float) and math.isnan(x))]
        st = rg.column(c).statistics
        if st is None or not st.has_min_max or st.null_count != 0:
            stats_mismatches.append([g, name, "no statistics"])
            continue
        if st.min != min(values) or st.max != max(values):
            stats_mismatches.append([g, name, st.min, st.max, min(values), max(values)])
        stats_checked += 1
    start += rg.num_rows
# a filter on t reads only the row group that holds it (the statistics skip the first)
late = pq.read_table(sys.argv[1], filters=[("t", ">=", 66.0)])
print(json.dumps({
    "created_by": meta.created_by,
    "stats_checked": stats_checked,
    "stats_mismatches": stats_mismatches,
    "t_min_group_1": meta.row_group(1).column(0).statistics.min if meta.num_row_groups > 1 else None,
    "filtered_rows": late.num_rows,
    "names": table.column_names,
    "csv_header": header,
    "rows": table.num_rows,
    "csv_rows": n,
    "row_groups": f.num_row_groups,
    "types": {n: str(table.schema.field(n).type) for n in ("t", "p1", "q_e1_lpm", "flags", "th_flags") if n in cols},
    "mismatches": mismatches,
    "t_last": cols["t"][-1],
}))
"#;

/// Reads the Parquet file with DuckDB: every cell against the CSV (parsed as
/// f64 by Python; NaN equals NaN), the column types, and each column chunk's
/// statistics as DuckDB's `parquet_metadata` gives them against the chunk's
/// values as DuckDB reads them (min and max without NaN); prints a JSON summary.
const DUCKDB_SCRIPT: &str = r#"
import csv, json, math, sys
import duckdb
pq_file, csv_file = sys.argv[1], sys.argv[2]
con = duckdb.connect()
cur = con.execute(
    "SELECT * EXCLUDE (file_row_number) FROM read_parquet(?, file_row_number = true) ORDER BY file_row_number",
    [pq_file],
)
names = [d[0] for d in cur.description]
table = cur.fetchall()
types = dict(con.execute("SELECT column_name, column_type FROM (DESCRIBE SELECT * FROM read_parquet(?))", [pq_file]).fetchall())
with open(csv_file) as fh:
    rows = csv.reader(fh)
    header = next(rows)
    mismatches = 0
    n = 0
    for i, row in enumerate(rows):
        n += 1
        for j, name in enumerate(header):
            a, b = float(row[j]), table[i][names.index(name)]
            if not (a == b or (math.isnan(a) and math.isnan(b))):
                mismatches += 1
meta = con.execute(
    "SELECT row_group_id, row_group_num_rows, column_id, path_in_schema, stats_min_value, stats_max_value, "
    "stats_null_count FROM parquet_metadata(?) ORDER BY row_group_id, column_id",
    [pq_file],
).fetchall()
starts = {}
start = 0
for g, rows_in_group, *_ in meta:
    if g not in starts:
        starts[g] = start
        start += rows_in_group
stats_checked = 0
stats_mismatches = []
for g, rows_in_group, c, name, lo, hi, nulls in meta:
    values = [r[c] for r in table[starts[g]:starts[g] + rows_in_group]]
    values = [v for v in values if not (isinstance(v, float) and math.isnan(v))]
    if lo is None or hi is None or nulls != 0:
        stats_mismatches.append([g, name, "no statistics", lo, hi, nulls])
        continue
    cast = float if isinstance(values[0], float) else int
    if cast(lo) != min(values) or cast(hi) != max(values):
        stats_mismatches.append([g, name, lo, hi, min(values), max(values)])
    stats_checked += 1
late = con.execute("SELECT count(*) FROM read_parquet(?) WHERE t >= 66.0", [pq_file]).fetchone()[0]
print(json.dumps({
    "version": duckdb.__version__,
    "names": names,
    "csv_header": header,
    "rows": len(table),
    "csv_rows": n,
    "row_groups": len(starts),
    "types": {k: types[k] for k in ("t", "p1", "q_e1_lpm", "flags", "th_flags")},
    "mismatches": mismatches,
    "stats_checked": stats_checked,
    "stats_mismatches": stats_mismatches,
    "filtered_rows": late,
}))
"#;

fn pyarrow() -> bool {
    python_with("pyarrow.parquet")
}

/// Replays `input` into `out` in `format`, with the thesis filter's columns
/// (`--model 7`: both flag columns) when `thesis`.
fn replay(input: &Path, out: &Path, format: &str, thesis: bool) {
    let mut args = vec!["replay", input.to_str().unwrap(), "--out", out.to_str().unwrap()];
    if thesis {
        args.extend(["--model", "7"]);
    }
    args.extend(["--estimates", format]);
    let o = leakwatch(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A closed-loop sine of `seconds` with a 0.5 L/min chamber-1 leak from 40 s,
/// replayed into `d/csv` and `d/parquet` (`thesis`: with `--model 7`); returns
/// the two directories.
fn replayed_both_ways(d: &Path, seconds: &str, thesis: bool) -> (PathBuf, PathBuf) {
    let input = d.join("in.csv");
    let args = ["simulate", "--scenario", "closed-loop-sine", "--seconds", seconds];
    let o = leakwatch(
        &[
            &args[..],
            &["--fault", "ext1:0.5lpm@40s", "--out", input.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (csv_dir, pq_dir) = (d.join("csv"), d.join("parquet"));
    replay(&input, &csv_dir, "csv", thesis);
    replay(&input, &pq_dir, "parquet", thesis);
    (csv_dir, pq_dir)
}

/// A 70 s leak run replayed into `d/csv` and `d/parquet` with the thesis
/// filter's columns; returns the Parquet file and the CSV file.
fn estimates_both_ways(d: &Path) -> (PathBuf, PathBuf) {
    // 70 s at 1 kHz: 70,000 rows, more than one row group of 65,536
    let (csv_dir, pq_dir) = replayed_both_ways(d, "70", true);
    assert!(!pq_dir.join("estimates.csv").exists());
    let pq_file = pq_dir.join("estimates.parquet");
    let bytes = std::fs::read(&pq_file).unwrap();
    assert_eq!(&bytes[..4], b"PAR1");
    assert_eq!(&bytes[bytes.len() - 4..], b"PAR1");
    // 37 f64 and 2 i32 columns of 70,000 values, plus headers and footer
    let values = 70_000 * (37 * 8 + 2 * 4);
    assert!(
        bytes.len() > values && bytes.len() < values + 20_000,
        "{} bytes",
        bytes.len()
    );
    // the events do not depend on the estimates' format, and the leak is found
    let events = |dir: &Path| std::fs::read_to_string(dir.join("events.json")).unwrap();
    assert_eq!(events(&csv_dir), events(&pq_dir));
    assert!(events(&pq_dir).contains("\"ext1\""), "{}", events(&pq_dir));
    (pq_file, csv_dir.join("estimates.csv"))
}

/// Runs a Python `script` on the two files; its JSON output.
fn python_json(script: &str, pq_file: &Path, csv_file: &Path) -> serde_json::Value {
    let o = Command::new("python3")
        .args(["-c", script])
        .arg(pq_file)
        .arg(csv_file)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn parquet_estimates_equal_the_csv_bit_for_bit_and_pyarrow_reads_them() {
    let d = tmpdir("roundtrip");
    let (pq_file, csv_file) = estimates_both_ways(&d);
    if !pyarrow() {
        return;
    }
    let v = python_json(SCRIPT, &pq_file, &csv_file);
    assert_eq!(v["names"], v["csv_header"]);
    assert_eq!(v["names"].as_array().unwrap().len(), 39);
    assert_eq!(v["rows"], 70_000);
    assert_eq!(v["csv_rows"], 70_000);
    assert_eq!(v["row_groups"], 2);
    assert_eq!(v["mismatches"], 0, "{v}");
    assert_eq!(v["types"]["t"], "double");
    assert_eq!(v["types"]["q_e1_lpm"], "double");
    assert_eq!(v["types"]["flags"], "int32");
    assert_eq!(v["types"]["th_flags"], "int32");
    assert!((v["t_last"].as_f64().unwrap() - 69.999).abs() < 1e-9, "{v}");
    // statistics on every column chunk: 2 row groups of 39 columns, each min
    // and max equal to its values'; created_by with the version
    assert_eq!(v["stats_checked"], 78, "{v}");
    assert_eq!(v["stats_mismatches"], serde_json::json!([]), "{v}");
    assert_eq!(
        v["created_by"],
        format!("leakwatch version {}", env!("CARGO_PKG_VERSION"))
    );
    // the second group starts at row 65,536: t = 65.536 s
    assert!(
        (v["t_min_group_1"].as_f64().unwrap() - 65.536).abs() < 1e-9,
        "{v}"
    );
    assert_eq!(v["filtered_rows"], 4_000, "{v}");
}

/// DuckDB reads estimates.parquet: the CSV's columns, types and values, bit
/// for bit, and min/max statistics on every column chunk that equal its values.
/// Without `--model` or the thesis baseline both formats hold the leak
/// filter's 25 columns (no `th_*`), the same values bit for bit.
#[test]
fn a_default_replays_estimates_are_the_leak_filters_columns_in_both_formats() {
    let d = tmpdir("default");
    // (15 s: a replay too short to arm the detector exits non-zero)
    let (csv_dir, pq_dir) = replayed_both_ways(&d, "15", false);
    if !pyarrow() {
        return;
    }
    let v = python_json(
        SCRIPT,
        &pq_dir.join("estimates.parquet"),
        &csv_dir.join("estimates.csv"),
    );
    assert_eq!(v["names"], v["csv_header"]);
    let names = v["names"].as_array().unwrap();
    assert_eq!(names.len(), 25, "{v}");
    assert!(
        names.iter().all(|n| !n.as_str().unwrap().starts_with("th_")),
        "{v}"
    );
    assert_eq!(v["csv_rows"], 15_000);
    assert_eq!(v["mismatches"], 0, "{v}");
    assert_eq!(v["types"]["flags"], "int32");
    assert_eq!(v["stats_mismatches"], serde_json::json!([]), "{v}");
}

#[test]
fn duckdb_reads_the_parquet_estimates_with_their_statistics() {
    let d = tmpdir("duckdb");
    let (pq_file, csv_file) = estimates_both_ways(&d);
    if !python_with("duckdb") {
        return;
    }
    let v = python_json(DUCKDB_SCRIPT, &pq_file, &csv_file);
    eprintln!("duckdb {}", v["version"]);
    assert_eq!(v["names"], v["csv_header"]);
    assert_eq!(v["names"].as_array().unwrap().len(), 39);
    assert_eq!(
        (v["rows"].as_u64(), v["csv_rows"].as_u64()),
        (Some(70_000), Some(70_000))
    );
    assert_eq!(v["row_groups"], 2);
    assert_eq!(v["mismatches"], 0, "{v}");
    assert_eq!(v["types"]["t"], "DOUBLE");
    assert_eq!(v["types"]["q_e1_lpm"], "DOUBLE");
    assert_eq!(v["types"]["flags"], "INTEGER");
    assert_eq!(v["types"]["th_flags"], "INTEGER");
    // 2 row groups of 39 column chunks, each with its min and max
    assert_eq!(v["stats_checked"], 78, "{v}");
    assert_eq!(v["stats_mismatches"], serde_json::json!([]), "{v}");
    assert_eq!(v["filtered_rows"], 4_000, "{v}");
}
