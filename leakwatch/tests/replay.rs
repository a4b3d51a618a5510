//! `leakwatch replay` end to end on real files: wiring-independent results,
//! detection written to events.json, and bad input reported line by line
//! without poisoning the filter.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::*;

fn simulate(dir: &Path, scenario: &str, seconds: &str, fault: &str) -> PathBuf {
    let out = dir.join("in.csv");
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        scenario,
        "--seconds",
        seconds,
        "--fault",
        fault,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn replay(input: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["replay", input.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    leakwatch(&args)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn channels_and_one_thread_give_identical_results_and_find_the_leak() {
    let d = tmpdir("wiring");
    let input = simulate(&d, "closed-loop-sine", "30", "ext2:0.5lpm@18s");
    let a = d.join("a");
    let b = d.join("b");
    // with the thesis filter's columns (--model 7): both filters' estimates compared
    let o = replay(&input, &a, &["--model", "7"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = replay(&input, &b, &["--single-thread", "--model", "7"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ea = std::fs::read(a.join("estimates.csv")).unwrap();
    let eb = std::fs::read(b.join("estimates.csv")).unwrap();
    assert_eq!(ea.len(), eb.len());
    assert!(ea == eb, "estimates differ between wirings");
    assert_eq!(
        std::fs::read(a.join("events.json")).unwrap(),
        std::fs::read(b.join("events.json")).unwrap()
    );
    // without the estimates file: the same events
    let c = d.join("c");
    let o = replay(&input, &c, &["--single-thread", "--estimates", "none"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!c.join("estimates.csv").exists() && !c.join("estimates.parquet").exists());
    assert_eq!(
        std::fs::read(a.join("events.json")).unwrap(),
        std::fs::read(c.join("events.json")).unwrap()
    );
    assert_eq!(json(&c.join("summary.json"))["samples"], 30_000);
    // nothing read the thesis filter there, so it did not run: no residuals of
    // it, and the same leak events without it
    assert!(json(&c.join("summary.json")).get("thesis_filter").is_none());
    assert!(json(&a.join("summary.json"))["thesis_filter"]["mean_nis"].is_number());
    // asked for its baseline, it runs without an estimates file too
    let e = d.join("e");
    let o = replay(&input, &e, &["--estimates", "none", "--thesis-baseline"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(json(&e.join("summary.json"))["thesis_filter"]["mean_nis"].is_number());
    let text = String::from_utf8(ea).unwrap();
    assert_eq!(text.lines().count(), 30_001);
    assert!(text.starts_with("t,u,x_meas,p1_meas,p2_meas,x_sp,p1,p2,x,v,v_sp,f_e,q_e1_lpm"));

    let summary = json(&a.join("summary.json"));
    assert_eq!(summary["samples"], 30_000);
    assert_eq!(summary["leak_filter"]["resets"], 0);
    assert!(summary["samples_per_s"].as_f64().unwrap() > 0.0);
    let events = json(&a.join("events.json"));
    let raised: Vec<_> = events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["phase"] == "raised" && e["detector"] == "leak-size")
        .collect();
    // one leak event: raised with its kind pending (unless already clear), then
    // raised again under the same id with its kind
    let named: Vec<_> = raised.iter().filter(|e| e["kind"] != "leak").collect();
    assert_eq!(named.len(), 1, "{events:#}");
    assert!(
        raised.iter().all(|e| e["event_id"] == named[0]["event_id"]),
        "{events:#}"
    );
    assert!(
        raised.len() <= 2 && raised[0]["kind"] == "leak" || raised.len() == 1,
        "{events:#}"
    );
    assert_eq!(named[0]["kind"], "ext2");
    let ev = raised[0];
    for field in [
        "t_detect_s",
        "t_onset_s",
        "size_lpm",
        "size_lpm_sigma",
        "confidence",
    ] {
        assert!(ev[field].is_number(), "{field} missing in {ev}");
    }
    let t = ev["t_detect_s"].as_f64().unwrap();
    assert!((18.0..19.5).contains(&t), "detected at {t}");
}

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
fn plot_draws_a_replay_directory() {
    let d = tmpdir("plot");
    let input = simulate(&d, "closed-loop-sine", "12", "int:0.5lpm@8s");
    // the PNG of a replay with `extra` arguments
    let figure = |name: &str, extra: &[&str]| -> Vec<u8> {
        let out = d.join(name);
        assert!(replay(&input, &out, extra).status.success());
        let png = d.join(format!("{name}.png"));
        let o = leakwatch(&["plot", out.to_str().unwrap(), "--out", png.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        bytes
    };
    let four = figure("out", &[]).len();
    assert!(four > 20_000, "a figure with four panels: {four} bytes");
    // with the thesis filter's columns (--model 7): its residuals and MAE, a fifth panel
    let five = figure("with", &["--model", "7"]).len();
    assert!(five > four + 5_000, "five panels {five} bytes, four {four} bytes");
    // Parquet estimates are not drawn: the error says how to get a CSV
    let pq = d.join("pq");
    assert!(replay(&input, &pq, &["--estimates", "parquet"]).status.success());
    let o = leakwatch(&[
        "plot",
        pq.to_str().unwrap(),
        "--out",
        d.join("pq.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--estimates csv"), "{err}");
    assert!(!d.join("pq.png").exists());
}

/// `--model 6` runs the thesis filter with 6 states (friction from the model, no
/// F_e state): its F_e column is NaN throughout while the 7-state default fills it,
/// and its pressure residuals stay small. `--model 8` is refused.
#[test]
fn model_6_replays_the_six_state_thesis_filter() {
    let d = tmpdir("model6");
    let input = simulate(&d, "open-loop-sine", "6", "ext1:0.5lpm@100s");
    let six = d.join("six");
    let seven = d.join("seven");
    let o = replay(&input, &six, &["--model", "6", "--single-thread"]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    let o = replay(&input, &seven, &["--model", "7", "--single-thread"]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(six.join("events.json").exists());

    // The thesis filter's F_e estimate per row, from the column named th_f_e.
    let th_f_e = |dir: &Path| -> Vec<f64> {
        let text = std::fs::read_to_string(dir.join("estimates.csv")).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = header.iter().position(|h| *h == "th_f_e").expect("th_f_e column");
        lines
            .map(|l| l.split(',').nth(col).unwrap().parse::<f64>().unwrap())
            .collect()
    };
    let f6 = th_f_e(&six);
    let f7 = th_f_e(&seven);
    assert_eq!(f6.len(), 6000);
    assert_eq!(f7.len(), 6000);
    assert!(f6.iter().all(|f| f.is_nan()), "6 states has no F_e state");
    assert!(
        f7[1000..].iter().all(|f| f.is_finite() && f.abs() < 1e4),
        "7 states estimates F_e"
    );

    let s6 = json(&six.join("summary.json"));
    assert_eq!(s6["samples"], 6000);
    assert_eq!(s6["thesis_filter"]["resets"], 0);
    let th = &s6["thesis_filter"];
    for key in ["p1_pa", "p2_pa"] {
        let r = th[key].as_f64().unwrap();
        // healthy, after the 2 s convergence flag: a few kPa (the sensor noise is 5.2 kPa RMS)
        assert!(r > 0.0 && r < 2e4, "6-state residual RMS {key} {r} Pa");
    }
    // The leak filter does not depend on --model.
    let s7 = json(&seven.join("summary.json"));
    assert_eq!(s6["leak_filter"]["p1_pa"], s7["leak_filter"]["p1_pa"]);
    assert_ne!(s6["thesis_filter"]["p1_pa"], s7["thesis_filter"]["p1_pa"]);

    // Without --model (or the thesis baseline) the thesis filter does not run:
    // the estimates are the leak filter's 25 columns, the same text as the
    // first 25 columns of a --model replay, row for row.
    let plain = d.join("plain");
    let o = replay(&input, &plain, &["--single-thread"]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(plain.join("estimates.csv")).unwrap();
    let with = std::fs::read_to_string(seven.join("estimates.csv")).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(header.split(',').count(), 25, "{header}");
    assert!(!header.contains("th_"), "{header}");
    assert_eq!(text.lines().count(), 6001);
    assert_eq!(with.lines().count(), 6001);
    for (a, b) in text.lines().zip(with.lines()) {
        assert!(b.starts_with(a) && b[a.len()..].starts_with(','), "{a}\n{b}");
    }
    let s = json(&plain.join("summary.json"));
    assert!(s["thesis_filter"].is_null(), "{}", s["thesis_filter"]);
    assert_eq!(s["leak_filter"]["p1_pa"], s7["leak_filter"]["p1_pa"]);

    let o = replay(&input, &d.join("eight"), &["--model", "8"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--model 8"));
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

#[test]
fn a_recorded_log_with_a_damaged_chunk_replays_the_rest_and_counts_the_lost_samples() {
    use recorder::{Entry, LogWriter, WriterOptions};
    let d = tmpdir("mcap");
    let log = d.join("run.mcap");
    let options = WriterOptions {
        chunk_size: 16 * 1024,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(&log, options).unwrap();
    for i in 0..4000u64 {
        let t = i as f64 * 1e-3;
        let frame = frames::SensorFrame {
            seq: i,
            acq_mono_ns: i * 1_000_000,
            t_s: t,
            u_v: 0.5 * (t * 6.0).sin(),
            x_m: 0.3,
            p1_pa: 6.9e6,
            p2_pa: 6.9e6,
            x_sp_m: f64::NAN,
            f_load_n: f64::NAN,
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
            flags: 0,
            _pad: 0,
            temp_c: f64::NAN,
        };
        assert!(w.write(Entry::Frame(frame, i)).unwrap());
    }
    w.finish().unwrap();
    // declare a wrong uncompressed size in the 10th chunk (offset of the size field:
    // opcode, record length, start and end time)
    let mut bytes = std::fs::read(&log).unwrap();
    let (mut at, mut seen) = (8usize, 0);
    while bytes[at] != 0x06 || seen < 9 {
        if bytes[at] == 0x06 {
            seen += 1;
        }
        at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
    }
    bytes[at + 25..at + 33].copy_from_slice(&1u64.to_le_bytes());
    let bad = d.join("bad.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    let out = d.join("out");
    // with the thesis filter (--model 7): neither filter is poisoned
    let o = replay(&bad, &out, &["--model", "7"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(ran(&o), "{err}");
    assert!(
        err.contains(&format!(
            "damaged chunk at byte {at}: declares 1 bytes uncompressed, but the data holds more; skipped"
        )),
        "{err}"
    );
    let s = json(&out.join("summary.json"));
    let lost = s["log"]["frames_lost"].as_u64().unwrap();
    assert!(lost >= 50, "{s:#}");
    assert_eq!(s["samples"].as_u64().unwrap() + lost, 4000, "{s:#}");
    assert_eq!(s["samples_missing"].as_u64().unwrap(), lost, "{s:#}");
    assert_eq!(s["log"]["chunks_skipped"].as_array().unwrap().len(), 1, "{s:#}");
}

/// `--estimates-every N` writes the estimates of one sample in N (the first, the
/// (N+1)th, ...), the same rows as the full file's, and the summary says which
/// file, how decimated and why; a short input's default is CSV.
#[test]
fn decimated_estimates_are_every_nth_row_of_the_full_file_and_the_summary_says_so() {
    let d = tmpdir("every");
    let input = simulate(&d, "loaded-sine", "3", "none");
    let (full, tenth) = (d.join("full"), d.join("tenth"));
    let o = replay(&input, &full, &[]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("estimates: ")
            && err.contains("estimates.csv (every sample, 3000 rows; the default for an input of"),
        "{err}"
    );
    let o = replay(&input, &tenth, &["--estimates-every", "10"]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    let all = std::fs::read_to_string(full.join("estimates.csv")).unwrap();
    let some = std::fs::read_to_string(tenth.join("estimates.csv")).unwrap();
    let every_tenth: Vec<&str> = all
        .lines()
        .take(1)
        .chain(all.lines().skip(1).step_by(10))
        .collect();
    assert_eq!(some.lines().collect::<Vec<_>>(), every_tenth);
    assert_eq!(some.lines().count(), 301);
    let s = json(&tenth.join("summary.json"));
    assert_eq!(s["estimates"]["format"], "csv", "{s:#}");
    assert_eq!(s["estimates"]["file"], "estimates.csv", "{s:#}");
    assert_eq!(
        (s["estimates"]["every"].as_u64(), s["estimates"]["rows"].as_u64()),
        (Some(10), Some(300))
    );
    assert!(
        s["estimates"]["why"]
            .as_str()
            .unwrap()
            .contains("Parquet from 16 MiB on"),
        "{s:#}"
    );
    // asked for: said so
    let pq = d.join("pq");
    let o = replay(&input, &pq, &["--estimates", "parquet"]);
    assert!(ran(&o), "{}", String::from_utf8_lossy(&o.stderr));
    let s = json(&pq.join("summary.json"));
    assert_eq!(s["estimates"]["why"], "asked for (--estimates parquet)", "{s:#}");
    assert_eq!(s["estimates"]["rows"], 3000, "{s:#}");
    // 0 is refused by name
    let o = replay(&input, &d.join("zero"), &["--estimates-every", "0"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--estimates-every"));
}

/// A log with nothing readable (an 8-byte file of MCAP magic, an empty file) is an
/// error naming the log in `export` and `replay` alike, never an empty export.
#[test]
fn a_log_with_nothing_readable_is_an_error_naming_it() {
    let d = tmpdir("empty-log");
    for (name, bytes) in [("magic.mcap", &b"\x89MCAP0\r\n"[..]), ("empty.mcap", &b""[..])] {
        let log = d.join(name);
        std::fs::write(&log, bytes).unwrap();
        let log_s = log.to_str().unwrap();
        let o = leakwatch(&[
            "export",
            log_s,
            "--csv",
            d.join(format!("{name}-csv")).to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(err.contains(log_s), "{name}: {err}");
        let o = replay(&log, &d.join(format!("{name}-out")), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(log_s) && !err.contains("dataset.csv"),
            "{name}: {err}"
        );
    }
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

/// Writes the samples of `csv` as the sensor frames of a log (CDR, or JSON as
/// logs were before), with a health frame at 10 Hz.
fn log_of(csv: &Path, log: &Path, encoding: recorder::Encoding) {
    log_in_parts(
        csv,
        log,
        encoding,
        recorder::WriterOptions::default().part_span_ns,
    );
}

/// [`log_of`], the file continued in a new part (`run.1.mcap`, ...) after
/// `part_span_ns` of the stream.
fn log_in_parts(csv: &Path, log: &Path, encoding: recorder::Encoding, part_span_ns: u64) {
    let ds = dataset::read_csv(csv, dataset::Limits::default()).unwrap();
    let options = recorder::WriterOptions {
        encoding,
        queue_len: 1 << 16,
        part_span_ns,
        ..recorder::WriterOptions::default()
    };
    let mut w = recorder::LogWriter::create(log, options).unwrap();
    for (i, s) in ds.samples.iter().enumerate() {
        let t = 1_000_000_000 + i as u64 * 1_000_000;
        let frame = frames::SensorFrame {
            seq: i as u64,
            acq_mono_ns: t,
            ..frames::SensorFrame::from(s)
        };
        assert!(w.write(recorder::Entry::Frame(frame, t)).unwrap());
        if i % 100 == 0 {
            let h = frames::HealthFrame {
                seq: i as u64 / 100,
                mono_ns: t,
                t_s: s.t_s,
                ..frames::HealthFrame::default()
            };
            assert!(w.write(recorder::Entry::Health(h, t)).unwrap());
        }
    }
    w.finish().unwrap();
}

/// A log its recorder continued in parts (`run.1.mcap`, ... after each hour
/// of the stream; here after 3 s) replays and exports as the same stream in
/// one file: the same events and estimates, every frame bit for bit.
#[test]
fn a_log_continued_in_parts_replays_and_exports_as_one_file() {
    let d = tmpdir("parts-log");
    let csv = simulate(&d, "loaded-sine", "14", "ext2:0.5lpm@9s");
    let (one, parts) = (d.join("one"), d.join("parts"));
    std::fs::create_dir_all(&one).unwrap();
    std::fs::create_dir_all(&parts).unwrap();
    log_of(&csv, &one.join("run.mcap"), recorder::Encoding::Cdr);
    log_in_parts(
        &csv,
        &parts.join("run.mcap"),
        recorder::Encoding::Cdr,
        3_000_000_000,
    );
    let files: Vec<String> = recorder::with_continuations(&parts.join("run.mcap"))
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        files,
        ["run.mcap", "run.1.mcap", "run.2.mcap", "run.3.mcap", "run.4.mcap"]
    );
    let mut outputs = Vec::new();
    for dir in [&one, &parts] {
        let out = dir.join("replay");
        let o = replay(&dir.join("run.mcap"), &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let csv_dir = dir.join("csv");
        let o = leakwatch(&[
            "export",
            dir.join("run.mcap").to_str().unwrap(),
            "--csv",
            csv_dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let read = |p: PathBuf| std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        outputs.push([
            read(out.join("events.json")),
            read(out.join("estimates.csv")),
            read(csv_dir.join("frames.csv")),
            read(csv_dir.join("dataset.csv")),
        ]);
    }
    for (k, name) in ["events.json", "estimates.csv", "frames.csv", "dataset.csv"]
        .iter()
        .enumerate()
    {
        assert!(
            outputs[0][k] == outputs[1][k],
            "{name}: the parts differ from one file"
        );
    }
    let events = json(&parts.join("replay").join("events.json"));
    assert!(
        events
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "ext2" && e["phase"] == "raised"),
        "{events:#}"
    );
    // 14 s at 1 kHz, each sample once
    assert_eq!(String::from_utf8_lossy(&outputs[1][3]).lines().count(), 14_001);
}

/// A log of the JSON encoding (what earlier versions wrote) replays, exports and
/// plots as the CDR log of the same samples does, and as their CSV does.
#[test]
fn a_json_log_of_an_earlier_version_replays_like_the_cdr_log_and_the_csv() {
    let d = tmpdir("json-log");
    let csv = simulate(&d, "loaded-sine", "14", "ext2:0.5lpm@9s");
    let (cdr, json_log) = (d.join("cdr.mcap"), d.join("json.mcap"));
    log_of(&csv, &cdr, recorder::Encoding::Cdr);
    log_of(&csv, &json_log, recorder::Encoding::Json);
    let read = |p: &Path| recorder::LogReader::open(p).unwrap().read().unwrap();
    assert_eq!(read(&json_log).channels["frames"].message_encoding, "json");
    assert_eq!(read(&cdr).channels["frames"].message_encoding, "cdr");
    let mut estimates = Vec::new();
    for (name, input) in [("csv", &csv), ("cdr", &cdr), ("json", &json_log)] {
        let out = d.join(format!("out-{name}"));
        let o = replay(input, &out, &[]);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let events = json(&out.join("events.json"));
        assert!(
            events
                .as_array()
                .unwrap()
                .iter()
                .any(|e| e["kind"] == "ext2" && e["phase"] == "raised"),
            "{name}: {events:#}"
        );
        estimates.push((name, std::fs::read(out.join("estimates.csv")).unwrap()));
    }
    assert!(estimates[1].1 == estimates[0].1, "cdr log and csv replay alike");
    assert!(estimates[2].1 == estimates[0].1, "json log and csv replay alike");
    // export and plot read the JSON log too
    let o = leakwatch(&[
        "export",
        json_log.to_str().unwrap(),
        "--csv",
        d.join("csv").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = d.join("json.png");
    let o = leakwatch(&["plot", json_log.to_str().unwrap(), "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

/// A replay says how much of the run the detector watched, and plainly when it
/// never armed: a 5 s recording is too short to learn the healthy state, so no
/// leak could have been seen (it used to end with "0 events" and exit 0 as if
/// the rig had been watched). A 30 s recording is watched from its first seconds.
#[test]
fn a_replay_says_how_long_it_watched_and_when_it_never_armed() {
    let d = tmpdir("watch");
    let short = simulate(&d, "closed-loop-sine", "5", "none");
    let out = d.join("short");
    let o = replay(&short, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    // exit status 3: it ran, but could not watch
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("NOT WATCHED: the leak detector never armed"),
        "{err}"
    );
    let w = &json(&out.join("summary.json"))["watch"];
    assert!(w["armed_at_s"].is_null(), "{w}");
    assert_eq!(w["watched_s"].as_f64(), Some(0.0), "{w}");
    assert!(
        w["not_armed"].as_str().unwrap().contains("warm-up too short"),
        "{w}"
    );

    let d2 = d.join("long");
    std::fs::create_dir_all(&d2).unwrap();
    let long = simulate(&d2, "closed-loop-sine", "30", "none");
    let out = d.join("long-out");
    let o = replay(&long, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success() && err.contains("watched "), "{err}");
    let w = &json(&out.join("summary.json"))["watch"];
    let (run, watched) = (w["run_s"].as_f64().unwrap(), w["watched_s"].as_f64().unwrap());
    eprintln!("{w}");
    assert!((run - 29.999).abs() < 1e-6, "{w}");
    assert!(watched > 0.6 * run && watched <= run, "{w}");
}

/// The command ran: exit status 0, or 3 when its detector never armed (a short file).
fn ran(o: &std::process::Output) -> bool {
    matches!(o.status.code(), Some(0) | Some(3))
}

/// A rig with an oil thermometer: `simulate` writes the warming oil as the
/// `temp_c` column (to 0.1 °C), and `replay` follows it: it says the range it
/// followed, summary.json has it, and the oil-stiffness scale θ stays near 1
/// (the model's bulk modulus is the oil's at each temperature).
#[test]
fn a_temp_c_column_is_followed_and_said() {
    let d = tmpdir("temp");
    let cfg = d.join("warming.toml");
    std::fs::write(
        &cfg,
        "[model.oil_temperature]\nreference_c = 20.0\n\
         [sim.oil]\nstart_c = 20.0\nend_c = 50.0\ntime_constant_s = 5.0\nmeasured = true\n",
    )
    .unwrap();
    let csv = d.join("warm.csv");
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "closed-loop-sine",
        "--seconds",
        "20",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().ends_with(",temp_c"));
    assert!(lines.next().unwrap().ends_with(",20.0"), "starts at 20 °C");
    assert!(
        text.lines().last().unwrap().ends_with(",49.5"),
        "20 s of τ = 5 s: 49.45 °C"
    );
    let out = d.join("out");
    let o = replay(&csv, &out, &["--config", cfg.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("oil temperature: 20.0 to 49.5 °C (temp_c): the model followed it"),
        "{err}"
    );
    let s = json(&out.join("summary.json"));
    let range = &s["leak_filter"]["oil_temp_range_c"];
    assert_eq!(
        (range[0].as_f64(), range[1].as_f64()),
        (Some(20.0), Some(49.5)),
        "{s:#}"
    );
    let theta = s["leak_filter"]["bulk_scale"].as_f64().unwrap();
    assert!((theta - 1.0).abs() < 0.03, "θ {theta}");
    // inside the default operating range (20-60 °C) all along
    assert_eq!(
        s["leak_filter"]["oil_outside_range_s"].as_f64(),
        Some(0.0),
        "{s:#}"
    );
    assert!(!err.contains("outside the operating range"), "{err}");
    // with the range's top at 40 °C, the oil passes it at 5 ln 3 = 5.49 s
    let narrow = d.join("narrow.toml");
    let text = std::fs::read_to_string(&cfg).unwrap();
    std::fs::write(
        &narrow,
        text.replace("reference_c = 20.0", "reference_c = 20.0\noperating_max_c = 40.0"),
    )
    .unwrap();
    let out = d.join("out_narrow");
    let o = replay(&csv, &out, &["--config", narrow.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("the oil was outside the operating range 20-40 °C"),
        "{err}"
    );
    let s = json(&out.join("summary.json"));
    let outside = s["leak_filter"]["oil_outside_range_s"].as_f64().unwrap();
    let first = s["leak_filter"]["first_oil_outside_range_s"].as_f64().unwrap();
    assert!((first - 5.49).abs() < 0.1, "first outside at {first} s");
    assert!((outside - (20.0 - 5.49)).abs() < 0.15, "{outside} s outside");
}
