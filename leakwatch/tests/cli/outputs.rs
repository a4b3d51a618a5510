//! Writing outputs safely: never through a symlink over an input, a full disk, a closed stdout.

use std::process::Command;

use crate::common::*;

#[test]
fn outputs_are_never_written_through_a_symlink_over_an_input_or_over_an_earlier_output() {
    let d = tmpdir("safe-out");
    let csv = d.join("run.csv");
    let sim = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "--scenario",
            "closed-loop-sine",
            "--seconds",
            "2",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        leakwatch(&args)
    };
    let o = sim(&csv, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let original = std::fs::read(&csv).unwrap();
    assert_eq!(original.iter().filter(|b| **b == b'\n').count(), 2001);

    // an existing output: refused without --force (simulate used to overwrite), replaced with it
    let o = sim(&csv, &["--seed", "2"]);
    assert!(!o.status.success());
    assert_eq!(
        stderr(&o).trim(),
        format!(
            "leakwatch: error: cannot write {}: exists: not overwritten (use --force to replace it)",
            csv.display()
        )
    );
    assert_eq!(std::fs::read(&csv).unwrap(), original);
    let other = d.join("other.csv");
    assert!(sim(&other, &["--seed", "2"]).status.success());
    let o = sim(&csv, &["--seed", "2", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&csv).unwrap(), std::fs::read(&other).unwrap());
    let o = sim(&csv, &[]);
    assert!(!o.status.success());
    let o = sim(&csv, &["--force"]);
    assert!(o.status.success());
    assert_eq!(std::fs::read(&csv).unwrap(), original);

    // a symlink as the output file: refused even with --force, its target untouched
    let victim = d.join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let link = d.join("link.csv");
    std::os::unix::fs::symlink(&victim, &link).unwrap();
    let o = sim(&link, &["--force"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("link.csv: is a symbolic link"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");

    // replay into a symlinked output directory: refused
    let real = d.join("real");
    std::fs::create_dir(&real).unwrap();
    let outlink = d.join("outlink");
    std::os::unix::fs::symlink(&real, &outlink).unwrap();
    let o = leakwatch(&[
        "replay",
        csv.to_str().unwrap(),
        "--out",
        outlink.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("outlink: is a symbolic link"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read_dir(&real).unwrap().count(), 0);

    // replay: a second run into the same directory needs --force
    let out = d.join("out");
    let replay = |extra: &[&str]| {
        let mut args = vec!["replay", csv.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        leakwatch(&args)
    };
    // (a short file: the detector never arms, exit status 3)
    assert_eq!(replay(&[]).status.code(), Some(3));
    let first = std::fs::read(out.join("estimates.csv")).unwrap();
    let o = replay(&[]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("estimates.csv: exists: not overwritten"),
        "{}",
        stderr(&o)
    );
    let o = replay(&["--force"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("estimates.csv")).unwrap(), first);

    // the output is the input: `replay DIR/estimates.csv --out DIR` used to truncate its own input
    let est = out.join("estimates.csv");
    let before = std::fs::read(&est).unwrap();
    for extra in [&[][..], &["--force"][..]] {
        let mut args = vec!["replay", est.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = leakwatch(&args);
        assert!(!o.status.success());
        assert!(
            stderr(&o).contains(&format!("estimates.csv: is the input {}", est.display())),
            "{}",
            stderr(&o)
        );
    }
    assert_eq!(std::fs::read(&est).unwrap(), before);
    // plot over its own input, too
    let o = leakwatch(&[
        "plot",
        csv.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
        "--force",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&csv).unwrap(), original);
}

#[test]
fn a_full_disk_is_an_error_and_a_closed_stdout_no_panic() {
    if !std::path::Path::new("/dev/full").exists() {
        eprintln!("no /dev/full here: skipped");
        return;
    }
    let run_to = |stdout: std::process::Stdio, args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .args(args)
            .stdout(stdout)
            .output()
            .expect("runs")
    };
    let full = || std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    // `config --print-default >/dev/full` used to panic in print!
    let o = run_to(full().into(), &["config", "--print-default"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        stderr(&o).trim(),
        "leakwatch: error: cannot write to standard output: No space left on device (os error 28)"
    );
    // stdout closed (`>&-`): the Rust runtime reopens it on /dev/null at start, so the
    // output is lost but nothing panics and the exit is clean
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "exec '{}' config --print-default >&-",
            env!("CARGO_BIN_EXE_leakwatch")
        ))
        .output()
        .unwrap();
    assert_eq!((o.status.code(), stderr(&o).as_str()), (Some(0), ""));
    // a file on a full disk
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "closed-loop-sine",
        "--seconds",
        "2",
        "--out",
        "/dev/full",
        "--force",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        stderr(&o).trim(),
        "leakwatch: error: cannot write /dev/full: No space left on device (os error 28)"
    );
}
