//! Replay results: the same on channels and one thread, the 6-state filter, decimated estimates.

use std::path::Path;

use crate::common::*;

use crate::{json, ran, replay, simulate};

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
