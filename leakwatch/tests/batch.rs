//! `leakwatch replay DIR`: a batch over worker threads writes, for every file,
//! the bytes a replay of that file alone writes; a file that fails is reported
//! and the others complete, and the exit status says so.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::*;

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// A closed-loop-random run of `seconds` with `fault`, written to `out`.
fn simulate_random(seconds: &str, seed: &str, fault: &str, out: &Path) {
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).unwrap();
    }
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "closed-loop-random",
        "--seconds",
        seconds,
        "--seed",
        seed,
        "--fault",
        fault,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Three small runs: two at the top of `dir`, one a level down as the
/// leaks_dev layout has them (run_002/measured.csv); their output folder names.
fn three_runs(dir: &Path) -> Vec<(PathBuf, &'static str)> {
    let runs = vec![
        (dir.join("a.csv"), "a"),
        (dir.join("b.csv"), "b"),
        (dir.join("run_002").join("measured.csv"), "run_002/measured"),
    ];
    simulate_random("20", "1", "ext1:0.4lpm@10s", &runs[0].0);
    simulate_random("20", "2", "none", &runs[1].0);
    simulate_random("20", "3", "int:0.4lpm@12s", &runs[2].0);
    runs
}

/// Replays `input` alone into `out` (the default wiring: threads over
/// channels), its estimates as Parquet (a batch's default; a 20 s file alone
/// would write CSV).
fn replay_alone(input: &Path, out: &Path) {
    let o = leakwatch(&[
        "replay",
        input.to_str().unwrap(),
        "--estimates",
        "parquet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

fn assert_same_outputs(batch: &Path, alone: &Path) {
    for name in ["estimates.parquet", "events.json"] {
        let (a, b) = (
            std::fs::read(batch.join(name)).unwrap(),
            std::fs::read(alone.join(name)).unwrap(),
        );
        assert!(!a.is_empty());
        assert!(
            a == b,
            "{} differs from {}",
            batch.join(name).display(),
            alone.join(name).display()
        );
    }
    assert!(batch.join("summary.json").is_file());
}

#[test]
fn a_directory_replayed_on_two_threads_matches_each_file_replayed_alone() {
    let d = tmpdir("same");
    let data = d.join("data");
    let runs = three_runs(&data);
    // something that is not a recording is left alone
    std::fs::write(data.join("run_002").join("truth.json"), "{}").unwrap();
    let out = d.join("out");
    let o = leakwatch(&[
        "replay",
        data.to_str().unwrap(),
        "--threads",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("replaying 3 files on 2 threads"), "{err}");
    assert!(err.contains("[3/3]") && err.contains("samples/s"), "{err}");
    // the totals of the files, and the estimates' format said (Parquet, a batch's default)
    assert!(
        err.contains("totals of 3 files: ")
            && err.contains("60000 samples, 0 rows skipped")
            && err.contains("estimates (parquet): 60000 rows"),
        "{err}"
    );
    let summary = json(&out.join("a").join("summary.json"));
    assert_eq!(summary["estimates"]["format"], "parquet", "{summary:#}");
    assert_eq!(summary["estimates"]["rows"], 20000, "{summary:#}");
    assert!(
        summary["estimates"]["why"].as_str().unwrap().contains("batch"),
        "{summary:#}"
    );
    let table = stdout(&o);
    assert!(table.starts_with("| file | samples | events raised |"), "{table}");
    for (input, name) in &runs {
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("| {name} |")))
            .unwrap_or_else(|| panic!("no row for {name}: {table}"));
        assert!(row.contains("| 20000 |"), "{row}");
        let alone = d.join("alone").join(name);
        replay_alone(input, &alone);
        assert_same_outputs(&out.join(name), &alone);
    }
    // the leak runs raised a leak; the healthy one none
    let row = |name: &str| {
        table
            .lines()
            .find(|l| l.starts_with(&format!("| {name} |")))
            .unwrap()
            .to_string()
    };
    assert!(row("b").contains("| none | – |"), "{table}");
    assert!(!row("a").contains("| none |"), "{table}");
    // the first alarm's kind, size and time
    for name in ["a", "run_002/measured"] {
        let first = row(name);
        assert!(
            first.contains(" L/min at ")
                && (first.contains("| leak ") || first.contains("| ext1 ") || first.contains("| int ")),
            "{first}"
        );
    }
    // the outputs exist now: a second batch refuses them without --force
    let o = leakwatch(&["replay", data.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        stdout(&o).contains("--force") || stderr(&o).contains("--force"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn a_malformed_file_is_reported_and_the_others_complete() {
    let d = tmpdir("bad");
    let data = d.join("data");
    let runs = three_runs(&data);
    std::fs::write(data.join("broken.csv"), "this is not,a leakwatch csv\n1,2\n").unwrap();
    let out = d.join("out");
    let o = leakwatch(&[
        "replay",
        data.to_str().unwrap(),
        "--threads",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("1 of 4 files failed"), "{}", stderr(&o));
    let table = stdout(&o);
    let bad = table
        .lines()
        .find(|l| l.starts_with("| broken |"))
        .unwrap_or_else(|| panic!("{table}"));
    assert!(bad.contains("broken.csv"), "the error names the file: {bad}");
    for (input, name) in &runs {
        let alone = d.join("alone").join(name);
        replay_alone(input, &alone);
        assert_same_outputs(&out.join(name), &alone);
    }
}

#[test]
fn several_files_are_a_batch_named_by_their_stems_and_clashes_are_refused() {
    let d = tmpdir("files");
    let a = d.join("x").join("a.csv");
    let b = d.join("y").join("b.csv");
    simulate_random("5", "4", "none", &a);
    simulate_random("5", "5", "none", &b);
    let out = d.join("out");
    let o = leakwatch(&[
        "replay",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    // (5 s files: their detector never arms, exit status 3)
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    for name in ["a", "b"] {
        assert!(out.join(name).join("events.json").is_file(), "{name}");
    }
    // two files that would share an output folder: nothing is replayed
    let clash = d.join("y").join("a.csv");
    std::fs::copy(&a, &clash).unwrap();
    let out2 = d.join("out2");
    let o = leakwatch(&[
        "replay",
        a.to_str().unwrap(),
        clash.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("would both write to"), "{}", stderr(&o));
    assert!(!out2.exists());
    // outputs written into the input directory are not inputs the next time
    let x = d.join("x");
    for _ in 0..2 {
        let o = leakwatch(&[
            "replay",
            x.to_str().unwrap(),
            "--out",
            x.to_str().unwrap(),
            "--force",
        ]);
        assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
        assert!(stderr(&o).contains("replaying 1 files"), "{}", stderr(&o));
    }
    assert!(x.join("a").join("estimates.parquet").is_file());
    // a directory with nothing to replay
    let empty = d.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = leakwatch(&["replay", empty.to_str().unwrap(), "--out", out2.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("no *.csv, *.csv.gz or *.mcap file"),
        "{}",
        stderr(&o)
    );
}
