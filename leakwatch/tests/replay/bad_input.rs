//! Bad input reported: bad rows, a missing column, values out of range, a one-sample spike.

use crate::common::*;

use crate::{json, ran, replay, simulate};

#[test]
fn bad_rows_are_reported_skipped_and_do_not_poison_the_filter() {
    let d = tmpdir("bad");
    let input = simulate(&d, "closed-loop-sine", "14", "ext1:0.5lpm@100s");
    let text = std::fs::read_to_string(&input).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // line numbers are 1-based with the header at line 1: data row k is lines[k].
    let edit = |lines: &mut Vec<String>, row: usize, col: usize, value: &str| {
        let mut cells: Vec<String> = lines[row].split(',').map(String::from).collect();
        cells[col] = value.to_string();
        lines[row] = cells.join(",");
    };
    edit(&mut lines, 3000, 3, "abc"); // p1 not a number
    edit(&mut lines, 4000, 4, "NaN"); // p2 NaN
    edit(&mut lines, 5000, 2, "inf"); // x infinite
    edit(&mut lines, 6000, 3, "4e7"); // p1 above 1.5 p_s
    edit(&mut lines, 6500, 0, "1.0"); // time going backwards
    lines.drain(8000..8020); // a gap of 20 samples
    let bad = d.join("bad.csv");
    std::fs::write(&bad, lines.join("\n") + "\n").unwrap();
    let out = d.join("out");
    // with the thesis filter (--model 7): neither filter is poisoned
    let o = replay(&bad, &out, &["--model", "7"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(ran(&o), "{err}");
    let summary = json(&out.join("summary.json"));
    let issues: Vec<String> = summary["issues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let expect = [
        ("line 3001", "p1"),
        ("line 4001", "p2"),
        ("line 5001", "x"),
        ("line 6001", "p1"),
        ("line 6501", "t"),
    ];
    for (line, col) in expect {
        assert!(
            issues
                .iter()
                .any(|i| i.contains(line) && i.contains(&format!("`{col}`"))),
            "no issue at {line}, column {col}: {issues:#?}"
        );
    }
    assert!(
        issues.iter().any(|i| i.contains("line 8001") && i.contains("20")),
        "gap not reported: {issues:#?}"
    );
    assert_eq!(summary["rows_skipped"], 5, "{summary:#}");
    assert_eq!(summary["samples_missing"], 25, "{summary:#}");
    assert_eq!(summary["samples"], 14_000 - 5 - 20);
    assert_eq!(summary["leak_filter"]["resets"], 0);
    assert_eq!(summary["thesis_filter"]["resets"], 0);
    // The filter is not poisoned: no NaN states, residuals stay small after the bad rows.
    let est = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    let header: Vec<&str> = est.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (p1_col, r_x_col) = (column("p1"), column("r_x"));
    for line in est.lines().skip(9000) {
        let cells: Vec<&str> = line.split(',').collect();
        let p1: f64 = cells[p1_col].parse().unwrap();
        let r_x: f64 = cells[r_x_col].parse().unwrap();
        assert!(p1.is_finite() && r_x.abs() < 1e-3, "{line}");
    }
    // No leak event on this healthy run.
    let events = json(&out.join("events.json"));
    assert!(
        events
            .as_array()
            .unwrap()
            .iter()
            .all(|e| e["detector"] != "leak-size"),
        "{events:#}"
    );
    // Stderr names the problems too.
    assert!(err.contains("warning: line 3001"), "{err}");
}

#[test]
fn a_missing_column_is_an_error_naming_it() {
    let d = tmpdir("missing");
    let f = d.join("m.csv");
    std::fs::write(&f, "t,u,x,p1\n0,0,0.3,6.9e6\n").unwrap();
    let o = replay(&f, &d.join("out"), &[]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("`p2`") && err.trim().lines().count() == 1, "{err}");
}

#[test]
fn values_outside_physical_ranges_are_rejected_counted_and_too_many_fail_the_file() {
    let d = tmpdir("ranges");
    let input = simulate(&d, "loaded-sine", "3", "ext1:0.5lpm@100s");
    let text = std::fs::read_to_string(&input).unwrap();
    let lines: Vec<String> = text.lines().map(String::from).collect();
    let write = |name: &str, rows: &[String]| {
        let p = d.join(name);
        std::fs::write(&p, rows.join("\n") + "\n").unwrap();
        p
    };
    let edited = |edits: &[(usize, usize, &str)]| {
        let mut l = lines.clone();
        for (row, col, v) in edits {
            let mut cells: Vec<String> = l[*row].split(',').map(String::from).collect();
            cells[*col] = v.to_string();
            l[*row] = cells.join(",");
        }
        l
    };
    // One row each: u = 1e308, x = -10 m, f_load = inf, ref = 1e308, a 1 µs step; ref NaN is "absent".
    let t1500: f64 = lines[1500].split(',').next().unwrap().parse().unwrap();
    let step = format!("{:?}", t1500 + 1e-6);
    let bad = write(
        "bad.csv",
        &edited(&[
            (500, 1, "1e308"),
            (1000, 2, "-10"),
            (1200, 6, "inf"),
            (1300, 7, "1e308"),
            (1400, 7, "NaN"),
            (1501, 0, &step),
        ]),
    );
    let out = d.join("out");
    let o = replay(&bad, &out, &["--max-bad-rows", "0.002", "--model", "7"]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    let s = json(&out.join("summary.json"));
    assert_eq!(s["rows"], 3000, "{s:#}");
    assert_eq!(s["rows_skipped"], 5, "{s:#}");
    assert_eq!(s["rows_rejected"]["out_of_range"], 3, "{s:#}");
    assert_eq!(s["rows_rejected"]["non_finite"], 1, "{s:#}");
    assert_eq!(s["rows_rejected"]["step_too_short"], 1, "{s:#}");
    assert_eq!(s["optional_absent"]["ref"], 1, "{s:#}");
    assert_eq!(s["max_bad_fraction"], 0.002, "{s:#}");
    assert_eq!(s["leak_filter"]["resets"], 0, "{s:#}");
    assert_eq!(s["thesis_filter"]["resets"], 0, "{s:#}");
    assert!(s.get("refused").is_none(), "{s:#}");
    let issues = s["issues"].to_string();
    assert!(
        issues.contains("line 501, column `u`: command 1e308 V is outside [-15.0, 15.0] V"),
        "{issues}"
    );
    assert!(
        issues.contains("line 1001, column `x`: position -10.0 m"),
        "{issues}"
    );
    // 5 bad rows of 3000 (0.17 %) pass at 0.2 %; at 0.1 % the file is refused.
    let o = replay(&bad, &d.join("strict"), &["--max-bad-rows", "0.001"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("5 of 3000 rows (0.17 %) are unusable, more than the 0.10 % accepted"),
        "{err}"
    );
    let s = json(&d.join("strict").join("summary.json"));
    assert!(s["refused"].as_str().unwrap().contains("5 of 3000 rows"), "{s:#}");

    // Time reversed: 2999 of 3000 rows rejected, the file is refused.
    let mut rev = vec![lines[0].clone()];
    rev.extend(lines[1..].iter().rev().cloned());
    let o = replay(&write("rev.csv", &rev), &d.join("rev"), &[]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2999 of 3000 rows (99.97 %) are unusable"), "{err}");
    let s = json(&d.join("rev").join("summary.json"));
    assert_eq!(s["rows_rejected"]["time_not_increasing"], 2999, "{s:#}");

    // u = 1e300 in every row: no usable sample, a non-zero exit and no filter run.
    let all: Vec<String> = (0..lines.len())
        .map(|k| {
            if k == 0 {
                return lines[0].clone();
            }
            let mut cells: Vec<&str> = lines[k].split(',').collect();
            cells[1] = "1e300";
            cells.join(",")
        })
        .collect();
    let o = replay(&write("uall.csv", &all), &d.join("uall"), &[]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no usable samples (3000 rows skipped"), "{err}");
    let s = json(&d.join("uall").join("summary.json"));
    assert_eq!(
        (s["samples"].as_u64(), s["leak_filter"]["resets"].as_u64()),
        (Some(0), Some(0))
    );
    // A bad --max-bad-rows is refused by name.
    let o = replay(&bad, &d.join("x"), &["--max-bad-rows", "2"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--max-bad-rows 2"));
    assert!(!o.status.success());
}

/// A one-sample pressure spike to 0 Pa (inside the physical range, so no row check
/// can refuse it) is not taken silently: it is counted as an innovation outlier in
/// summary.json and warned about, and it raises no leak.
#[test]
fn a_one_sample_pressure_spike_is_reported_not_taken_as_a_leak() {
    let d = tmpdir("spike");
    let input = simulate(&d, "loaded-sine", "25", "none");
    let text = std::fs::read_to_string(&input).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // row of t = 15.000 s (header + 15000 rows before it): p1 (the fourth column) = 0
    let mut cells: Vec<String> = lines[15_001].split(',').map(str::to_string).collect();
    assert!(cells[0].starts_with("15"), "{}", lines[15_001]);
    cells[3] = "0".into();
    lines[15_001] = cells.join(",");
    let spiked = d.join("spiked.csv");
    std::fs::write(&spiked, lines.join("\n") + "\n").unwrap();
    let out = d.join("out");
    let o = replay(&spiked, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("far outside what the leak filter expects"), "{err}");
    let s = json(&out.join("summary.json"));
    assert!(s["leak_filter"]["nis_outliers"].as_u64().unwrap() >= 1, "{s:#}");
    let t = s["leak_filter"]["first_nis_outlier_s"].as_f64().unwrap();
    assert!((t - 15.0).abs() < 0.01, "{t}");
    let events = json(&out.join("events.json"));
    let leaks = events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["detector"] == "leak-size" && e["phase"] == "raised")
        .count();
    assert_eq!(leaks, 0, "{events:#}");
    // the same file without the spike: nothing to report
    let o = replay(&input, &d.join("clean"), &[]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("far outside"));
}

#[test]
fn pressures_written_in_bar_are_said_first_and_kept_in_the_summary() {
    let d = tmpdir("bar");
    let input = simulate(&d, "closed-loop-sine", "12", "ext1:0.5lpm@100s");
    let text = std::fs::read_to_string(&input).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    for line in lines.iter_mut().skip(1) {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        for c in [3, 4] {
            let pa: f64 = cells[c].parse().unwrap();
            cells[c] = (pa / 1e5).to_string();
        }
        *line = cells.join(",");
    }
    let bar = d.join("bar.csv");
    std::fs::write(&bar, lines.join("\n") + "\n").unwrap();
    let out = d.join("out");
    let o = replay(&bar, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(ran(&o), "{err}");
    let summary = json(&out.join("summary.json"));
    let first = summary["issues"][0].as_str().unwrap_or_default().to_string();
    // the thesis rig's 13.8 MPa supply
    assert!(first.starts_with("p1 and p2 never read above "), "{summary:#}");
    assert!(
        first.contains("under 1 % of the supply pressure (13.8 MPa)"),
        "{first}"
    );
    assert!(err.contains(&format!("warning: {first}")), "{err}");
    // the same recording in Pa says nothing of the kind
    let o = replay(&input, &d.join("out_pa"), &[]);
    assert!(ran(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("never read above"), "{err}");
}
