use dataset::*;
use std::path::Path;

fn read_str(text: &str) -> Result<Dataset, DatasetError> {
    // one folder per call: tests run in parallel
    let d = scratch::ScratchDir::new("dataset");
    let p = d.join("t.csv");
    std::fs::write(&p, text).unwrap();
    read_csv(&p, Limits::default())
}

#[test]
fn round_trip_is_bit_exact() {
    let mut rng = model::rng::Rng::new(9);
    let samples: Vec<Sample> = (0..2000)
        .map(|k| Sample {
            t_s: k as f64 * 1e-3,
            u_v: 3.0 * rng.normal(),
            x_m: 0.3 + 1e-3 * rng.normal(),
            p1_pa: 6.9e6 + 1e5 * rng.normal(),
            p2_pa: 6.9e6 * rng.uniform(),
            x_sp_m: 1e-5 * rng.normal(),
            f_load_n: if k % 3 == 0 { f64::NAN } else { 1e3 * rng.normal() },
            ref_m: 1.0 / 3.0,
            q_leak_lpm: 1e-300 * rng.uniform(),
            temp_c: if k % 5 == 0 {
                f64::NAN
            } else {
                30.0 + 25.0 * rng.uniform()
            },
        })
        .collect();
    let d = scratch::ScratchDir::new("dataset");
    let p = d.join("round.csv");
    write_csv(&p, &samples, true).unwrap();
    let back = read_csv(&p, Limits::default()).unwrap();
    assert!(back.issues.is_empty(), "{:?}", back.issues.first());
    assert_eq!(back.samples.len(), samples.len());
    for (a, b) in samples.iter().zip(&back.samples) {
        for (x, y) in [
            (a.t_s, b.t_s),
            (a.u_v, b.u_v),
            (a.x_m, b.x_m),
            (a.p1_pa, b.p1_pa),
            (a.p2_pa, b.p2_pa),
            (a.x_sp_m, b.x_sp_m),
            (a.f_load_n, b.f_load_n),
            (a.ref_m, b.ref_m),
            (a.q_leak_lpm, b.q_leak_lpm),
            (a.temp_c, b.temp_c),
        ] {
            assert_eq!(x.to_bits(), y.to_bits());
        }
    }
}

#[test]
fn missing_column_is_fatal_and_named() {
    let e = read_str("t,u,x,p1\n0,0,0,1\n").unwrap_err();
    let m = e.to_string();
    assert!(m.contains("`p2`") && m.contains("line 1"), "{m}");
    let e = read_str("").unwrap_err();
    assert!(e.to_string().contains("`t`"));
    let e = read_str("t,u,x,p1,p2,x\n").unwrap_err();
    assert!(e.to_string().contains("appears twice"));
}

#[test]
fn bad_rows_are_skipped_and_reported_with_line_and_column() {
    let text = "t,u,x,p1,p2\n\
                0.000,0,0.3,6.9e6,6.9e6\n\
                0.001,abc,0.3,6.9e6,6.9e6\n\
                0.002,0,NaN,6.9e6,6.9e6\n\
                0.003,0,0.3,inf,6.9e6\n\
                0.004,0,0.3,6.9e6,3e7\n\
                -0.001,0,0.3,6.9e6,6.9e6\n\
                0.005,0,0.3,6.9e6\n\
                0.009,0,0.3,6.9e6,6.9e6\n\
                0.010,0,0.3,6.9e6,6.9e6\n";
    let ds = read_str(text).unwrap();
    assert_eq!(ds.samples.len(), 3);
    let got: Vec<(u64, Option<&str>, bool)> = ds
        .issues
        .iter()
        .map(|i| (i.line, i.column.as_deref(), i.skipped))
        .collect();
    assert_eq!(
        got,
        vec![
            (3, Some("u"), true),
            (4, Some("x"), true),
            (5, Some("p1"), true),
            (6, Some("p2"), true),
            (7, Some("t"), true),
            (8, None, true),
            (9, Some("t"), false),
        ]
    );
    assert_eq!(ds.issues[6].kind, IssueKind::Gap { missing: 8 });
    assert_eq!(ds.skipped(), 6);
    assert!(ds.issues[0].to_string().contains("`abc` is not a number"));
}

#[test]
fn unwritable_path_names_the_path() {
    let e = write_csv(Path::new("/nonexistent-dir/x.csv"), &[], false).unwrap_err();
    assert!(e.to_string().contains("/nonexistent-dir/x.csv"));
}

/// One good row at time `k` ms, with `edit` applied to its cells (t,u,x,p1,p2,x_sp,f_load,ref,q_leak).
fn row(k: usize, edit: &[(usize, &str)]) -> String {
    let t = format!("{:?}", k as f64 * 1e-3);
    let mut cells = vec![
        t.as_str(),
        "1.5",
        "0.3",
        "6.9e6",
        "6.8e6",
        "1e-5",
        "1500",
        "0.31",
        "0.0",
    ];
    for (j, v) in edit {
        cells[*j] = v;
    }
    cells.join(",")
}

const HEADER: &str = "t,u,x,p1,p2,x_sp,f_load,ref,q_leak";

#[test]
fn values_outside_their_physical_range_are_skipped_by_column() {
    // (column index, bad value, column name, kind)
    let cases: [(usize, &str, &str, IssueKind); 22] = [
        (5, "inf", "x_sp", IssueKind::NonFinite),
        (5, "-inf", "x_sp", IssueKind::NonFinite),
        (5, "1e308", "x_sp", IssueKind::OutOfRange),
        (6, "-1e308", "f_load", IssueKind::OutOfRange),
        (6, "inf", "f_load", IssueKind::NonFinite),
        (7, "1e308", "ref", IssueKind::OutOfRange),
        (7, "-inf", "ref", IssueKind::NonFinite),
        (8, "1e308", "q_leak", IssueKind::OutOfRange),
        (8, "inf", "q_leak", IssueKind::NonFinite),
        (1, "1e308", "u", IssueKind::OutOfRange),
        (1, "-1e308", "u", IssueKind::OutOfRange),
        (1, "1000", "u", IssueKind::OutOfRange),
        (1, "1e300", "u", IssueKind::OutOfRange),
        (2, "1e308", "x", IssueKind::OutOfRange),
        (2, "-10", "x", IssueKind::OutOfRange),
        (2, "-1e308", "x", IssueKind::OutOfRange),
        (3, "-276001", "p1", IssueKind::OutOfRange),
        (4, "-1e6", "p2", IssueKind::OutOfRange),
        (4, "20700001", "p2", IssueKind::OutOfRange),
        (3, "NaN", "p1", IssueKind::NonFinite),
        (0, "1e308", "t", IssueKind::OutOfRange),
        (0, "inf", "t", IssueKind::NonFinite),
    ];
    for (j, v, col, kind) in cases {
        let text = format!(
            "{HEADER}\n{}\n{}\n{}\n",
            row(0, &[]),
            row(1, &[(j, v)]),
            row(2, &[])
        );
        let ds = read_str(&text).unwrap();
        assert_eq!(ds.samples.len(), 2, "{v} in {col}");
        assert_eq!(ds.skipped(), 1, "{v} in {col}");
        let i = &ds.issues[0];
        assert_eq!(
            (i.line, i.column.as_deref(), &i.kind),
            (3, Some(col), &kind),
            "{v} in {col}: {i}"
        );
        // the gap the skipped row leaves is reported, the next row kept
        assert_eq!(ds.issues[1].kind, IssueKind::Gap { missing: 1 });
    }
    // the boundaries are inclusive: p = 0 and p = 1.5 p_s pass, as do u = ±15 V
    let text = format!(
        "{HEADER}\n{}\n{}\n{}\n",
        row(0, &[(3, "0"), (4, "20700000")]),
        row(1, &[(1, "-15")]),
        row(2, &[(1, "15")])
    );
    let ds = read_str(&text).unwrap();
    assert_eq!((ds.samples.len(), ds.issues.len()), (3, 0), "{:?}", ds.issues);
    // NaN or empty in an optional column means absent: kept, and counted
    let d = scratch::ScratchDir::new("dataset");
    let p = d.join("absent.csv");
    let text = format!(
        "{HEADER}\n{}\n{}\n{}\n",
        row(0, &[(7, "NaN")]),
        row(1, &[(7, "")]),
        row(2, &[])
    );
    std::fs::write(&p, text).unwrap();
    let mut r = CsvReader::open(&p, Limits::default()).unwrap();
    let mut n = 0;
    while let Some(Row::Sample(_)) = r.next_row() {
        n += 1;
    }
    assert_eq!((n, r.skipped, r.absent), (3, 0, [0, 0, 2, 0, 0]));
}

#[test]
fn the_ranges_come_from_the_model() {
    let l = Limits::default();
    assert_eq!(l.max_pressure_pa, 20.7e6);
    assert_eq!(l.max_command_v, 15.0);
    assert!((l.min_position_m + 0.06069).abs() < 1e-12, "{}", l.min_position_m);
    assert!((l.max_position_m - 0.66759).abs() < 1e-12, "{}", l.max_position_m);
    assert!((l.max_spool_m - 5.588e-4).abs() < 1e-12, "{}", l.max_spool_m);
    assert!((l.max_force_n - 131_031.0).abs() < 1e-6, "{}", l.max_force_n);
    assert!((l.max_leak_lpm - 461.5).abs() < 0.5, "{}", l.max_leak_lpm);
    let l = Limits::for_supply(21.0e6);
    assert_eq!(l.max_pressure_pa, 31.5e6);
    assert_eq!(l.sample_period_s, Some(1e-3));
}

#[test]
fn time_reversed_duplicated_or_too_short_steps_are_skipped() {
    let text = format!(
        "{HEADER}\n{}\n{}\n{}\n{}\n{}\n{}\n",
        row(0, &[]),
        row(1, &[]),
        row(1, &[]),                // duplicated time
        row(1, &[(0, "0.001001")]), // a 1 µs step
        row(1, &[(0, "0.0005")]),   // reversed
        row(2, &[(0, "0.0019")]),   // 0.9 ms: within tolerance, kept
    );
    let ds = read_str(&text).unwrap();
    let got: Vec<(u64, &IssueKind)> = ds.issues.iter().map(|i| (i.line, &i.kind)).collect();
    assert_eq!(
        got,
        vec![
            (4, &IssueKind::TimeNotIncreasing),
            (5, &IssueKind::StepTooShort),
            (6, &IssueKind::TimeNotIncreasing),
        ]
    );
    assert_eq!(ds.samples.len(), 3);
    assert_eq!(ds.rows, 6);
    assert_eq!(ds.issues[1].kind.name(), "step_too_short");
}

#[test]
fn a_file_reversed_in_time_fails_the_bad_fraction() {
    // 3000 rows, time reversed: only the first is usable
    let mut text = format!("{HEADER}\n");
    for k in (0..3000).rev() {
        text += &row(k, &[]);
        text += "\n";
    }
    let ds = read_str(&text).unwrap();
    assert_eq!((ds.samples.len(), ds.skipped(), ds.rows), (1, 2999, 3000));
    let e = check_bad_fraction(ds.rows, ds.skipped() as u64, DEFAULT_MAX_BAD_FRACTION).unwrap_err();
    assert!(
        e.contains("2999 of 3000 rows (99.97 %)") && e.contains("1.00 %"),
        "{e}"
    );
    // 1 % is accepted, one more row is not
    assert_eq!(check_bad_fraction(1000, 10, 0.01), Ok(()));
    assert!(check_bad_fraction(1000, 11, 0.01).is_err());
    assert_eq!(check_bad_fraction(0, 0, 0.01), Ok(()));
}

#[test]
fn u_of_1e300_in_every_row_gives_no_usable_sample() {
    let mut text = format!("{HEADER}\n");
    for k in 0..1000 {
        text += &row(k, &[(1, "1e300")]);
        text += "\n";
    }
    let e = read_str(&text).unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("1000 rows skipped")
            && m.contains("line 2, column `u`: command 1e300 V is outside [-15.0, 15.0] V"),
        "{m}"
    );
}

/// A source that gives `text` and then fails on every read, as a damaged disk
/// or gzip stream does.
struct FailsAfter {
    text: std::io::Cursor<Vec<u8>>,
}

impl std::io::Read for FailsAfter {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.text.read(buf)?;
        if n > 0 {
            return Ok(n);
        }
        Err(std::io::Error::other("disk on fire"))
    }
}

#[test]
fn a_read_error_is_reported_once_and_ends_the_file() {
    // (the reader used to report a persistent read error as one skipped row
    // after another, forever)
    let text = b"t,u,x,p1,p2\n0.0,0.5,0.3,6.9e6,6.8e6\n0.001,0.5,0.3,6.9e6,6.8e6\n0.002,0.5".to_vec();
    let src = std::io::BufReader::new(FailsAfter {
        text: std::io::Cursor::new(text),
    });
    let mut r = CsvReader::new(src, Path::new("fire.csv"), Limits::default()).unwrap();
    let mut rows = Vec::new();
    while let Some(row) = r.next_row() {
        rows.push(row);
        assert!(rows.len() < 10, "does not end: {rows:?}");
    }
    assert_eq!(rows.len(), 3, "{rows:?}");
    assert!(matches!(rows[0], Row::Sample(_)) && matches!(rows[1], Row::Sample(_)));
    let Row::Skipped(issue) = &rows[2] else {
        panic!("{:?}", rows[2])
    };
    assert_eq!((issue.line, issue.kind.clone()), (4, IssueKind::ReadError));
    assert!(issue.message.contains("disk on fire"), "{}", issue.message);
    assert_eq!((r.rows, r.skipped), (3, 1));
}

#[test]
fn a_line_that_is_not_utf8_is_one_skipped_row_and_counted() {
    let text =
        b"t,u,x,p1,p2\n0.0,0.5,0.3,6.9e6,6.8e6\n0.001,\xff\xfe,0.3,6.9e6,6.8e6\n0.002,0.5,0.3,6.9e6,6.8e6\n";
    let mut r = CsvReader::new(&text[..], Path::new("bytes.csv"), Limits::default()).unwrap();
    let mut kinds = Vec::new();
    while let Some(row) = r.next_row() {
        kinds.push(match row {
            Row::Sample(_) => "sample".to_string(),
            Row::AfterGap(..) => "gap".to_string(),
            Row::Skipped(i) => format!("{} at {}: {}", i.kind.name(), i.line, i.message),
        });
    }
    assert_eq!(
        kinds,
        [
            "sample",
            "not_text at 3: not UTF-8 text (byte 7 of the line)",
            "gap"
        ]
    );
    // rows and skipped agree (a read error used to be skipped without being a row)
    assert_eq!((r.rows, r.skipped), (3, 1));
}

#[test]
fn pressures_slightly_below_zero_within_2_percent_of_supply_are_usable() {
    // ±10 Pa sensor noise around tank pressure (0 Pa) in both chambers
    let mut text = format!("{HEADER}\n");
    let noise = ["-5.7", "3.2", "-9.9", "0", "-0.001", "9.8"];
    for k in 0..600 {
        let (a, b) = (noise[k % 6], noise[(k + 3) % 6]);
        text += &row(k, &[(3, a), (4, b)]);
        text += "\n";
    }
    let ds = read_str(&text).unwrap();
    assert_eq!(
        (ds.samples.len(), ds.issues.len()),
        (600, 0),
        "{:?}",
        ds.issues.first()
    );
    assert_eq!(ds.samples[0].p1_pa, -5.7);
    // the margin is 2 % of the supply pressure (13.8 MPa): -276 kPa is usable, below is not
    let l = Limits::default();
    assert_eq!((l.min_pressure_pa, l.max_pressure_pa), (-276_000.0, 20.7e6));
    assert_eq!(Limits::for_supply(21.0e6).min_pressure_pa, -420_000.0);
    // and the supply they were made from reads back
    assert_eq!(
        (l.supply_pa(), Limits::for_supply(21.0e6).supply_pa()),
        (13.8e6, 21.0e6)
    );
    let text = format!(
        "{HEADER}\n{}\n{}\n{}\n",
        row(0, &[(3, "-276000")]),
        row(1, &[(4, "-276000.5")]),
        row(2, &[])
    );
    let ds = read_str(&text).unwrap();
    assert_eq!(ds.samples.len(), 2);
    assert_eq!(ds.samples[0].p1_pa, -276_000.0);
    assert_eq!(
        ds.issues[0].to_string(),
        "line 3, column `p2`: pressure -276000.5 Pa is outside [-276000.0, 20700000.0] Pa \
         (from 2 % of the supply pressure below 0 to 1.5 × the supply pressure)"
    );
}

#[test]
fn fields_in_double_quotes_are_read_as_without() {
    // as pandas writes with quoting=csv.QUOTE_ALL (NaN as "")
    let text = "\"t\",\"u\",\"x\",\"p1\",\"p2\",\"ref\"\n\
                \"0.0\",\"1.5\",\"0.3\",\"6.9e6\",\"6.8e6\",\"0.31\"\n\
                \"0.001\",1.5,0.3,\"6.9e6\",6.8e6,\"\"\n\
                0.002,1.5,0.3,6.9e6,6.8e6,0.31\n";
    let d = scratch::ScratchDir::new("dataset");
    let p = d.join("quoted.csv");
    std::fs::write(&p, text).unwrap();
    let mut r = CsvReader::open(&p, Limits::default()).unwrap();
    assert_eq!(r.has_optional(), [false, false, true, false, false]);
    let mut samples = Vec::new();
    while let Some(row) = r.next_row() {
        let Row::Sample(s) = row else { panic!("{row:?}") };
        samples.push(s);
    }
    assert_eq!(samples.len(), 3);
    assert_eq!(
        (samples[0].t_s, samples[0].u_v, samples[0].p1_pa),
        (0.0, 1.5, 6.9e6)
    );
    assert_eq!(samples[0].ref_m, 0.31);
    assert!(samples[1].ref_m.is_nan());
    assert_eq!(r.absent, [0, 0, 1, 0, 0]);
    // anything else stays strict: one quote, quotes inside, single quotes, a quoted comma
    for (cell, shown) in [
        ("\"1.5", "`\"1.5` is not a number"),
        ("1.5\"", "`1.5\"` is not a number"),
        ("\"\"1.5\"\"", "`\"1.5\"` is not a number"),
        ("'1.5'", "`'1.5'` is not a number"),
        ("\" 1.5\"", "` 1.5` is not a number"),
    ] {
        let text = format!("{HEADER}\n{}\n{}\n", row(0, &[(1, cell)]), row(1, &[]));
        let ds = read_str(&text).unwrap();
        assert_eq!(ds.issues.len(), 1, "{cell}");
        assert_eq!(ds.issues[0].to_string(), format!("line 2, column `u`: {shown}"));
    }
    let text = format!("{HEADER}\n{}\n{}\n", row(0, &[(1, "\"1,5\"")]), row(1, &[]));
    let ds = read_str(&text).unwrap();
    assert_eq!(ds.issues[0].kind, IssueKind::WrongCellCount);
    // a required column whose quoted cell is empty is NaN, not a number to use
    let text = format!("{HEADER}\n{}\n{}\n", row(0, &[(2, "\"\"")]), row(1, &[]));
    let ds = read_str(&text).unwrap();
    assert_eq!(ds.issues[0].kind, IssueKind::NonFinite);
    // a quoted header name counts as the name (and twice is still twice)
    let e = read_str("t,u,x,p1,p2,\"x\"\n").unwrap_err();
    assert!(e.to_string().ends_with("line 1: column `x` appears twice"), "{e}");
}

#[test]
fn control_characters_from_the_file_are_escaped_in_messages() {
    // ESC (a terminal colour sequence) and NUL inside a cell
    for (cell, shown) in [
        ("\u{1b}[31mred", "`\\u{1b}[31mred` is not a number"),
        ("1\u{0}5", "`1\\05` is not a number"),
        ("\u{7f}\u{9b}2J", "`\\u{7f}\\u{9b}2J` is not a number"),
        ("\u{202e}1.5", "`\\u{202e}1.5` is not a number"),
    ] {
        let text = format!("{HEADER}\n{}\n{}\n", row(0, &[(6, cell)]), row(1, &[]));
        let ds = read_str(&text).unwrap();
        let m = ds.issues[0].to_string();
        assert_eq!(m, format!("line 2, column `f_load`: {shown}"));
        assert!(!m.chars().any(|c| c.is_control()), "{m:?}");
    }
    // a long cell is cut
    let long = "9".repeat(100) + "x";
    let text = format!("{HEADER}\n{}\n{}\n", row(0, &[(6, &long)]), row(1, &[]));
    let ds = read_str(&text).unwrap();
    assert_eq!(
        ds.issues[0].message,
        format!("`{}…` is not a number", "9".repeat(80))
    );
    // a binary header: the message shows it escaped (bytes that are not UTF-8 as U+FFFD)
    let d = scratch::ScratchDir::new("dataset");
    let p = d.join("binary-header.csv");
    std::fs::write(&p, b"\x1b]0;owned\x07t,u\x00,\xff\x1b[2J\n0,0,0\n").unwrap();
    let m = read_csv(&p, Limits::default()).unwrap_err().to_string();
    assert!(
        m.contains("(header: `\\u{1b}]0;owned\\u{7}t,u\\0,\u{fffd}\\u{1b}[2J`; required: t,u,x,p1,p2)"),
        "{m}"
    );
    assert!(!m.chars().any(|c| c.is_control()), "{m:?}");
    assert_eq!(shown("a\tb\r\n\"q\" \\ é"), "a\\tb\\r\\n\"q\" \\ é");
}
