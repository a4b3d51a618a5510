//! `run` and the stages: started from the binary, bad arguments refused, a new folder each time.

use std::process::Command;

use crate::common::*;

/// `leakwatch stage NAME` runs a stage's own command line; an unknown stage is named.
#[test]
fn stages_run_from_the_leakwatch_binary() {
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["stage", "estimator", "--help"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(help.contains("--rig") && help.contains("--config"), "{help}");
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["stage", "pump"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("unknown stage \"pump\"") && err.contains("acquisition, estimator"),
        "{err}"
    );
}

/// `run` checks its arguments before any stage starts: a bad fault, scenario,
/// duration or mode is named, and nothing is written.
#[test]
fn run_refuses_bad_arguments_before_starting_anything() {
    let dir = tmpdir("runargs");
    for (args, needle) in [
        (vec!["--fault", "ext9:0.5lpm@10s"], "--fault ext9:0.5lpm@10s"),
        (vec!["--scenario", "sideways"], "--scenario sideways"),
        (vec!["--seconds", "0"], "--seconds 0"),
        (vec!["--mode", "hurry"], "--mode hurry"),
    ] {
        let out = dir.join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .arg("run")
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(
            !out.join("config.toml").exists() && !out.join("run.mcap").exists(),
            "{args:?}"
        );
    }
}

/// `run` without `--out` writes into a new folder named by its start time,
/// so the README's first command runs again without `--force`.
#[test]
fn run_without_out_writes_a_new_folder_each_time() {
    let dir = tmpdir("run-default-out");
    for _ in 0..2 {
        let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .args(["run", "--seconds", "1", "--fault", "none", "--rig", "dflt"])
            .current_dir(&*dir)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string() + &String::from_utf8_lossy(&o.stdout);
        // a 1 s run ends before the detector arms: exit 3, said, not an error of the folder
        assert!(!err.contains("exists"), "{err}");
        assert!(err.contains("output leakwatch-run-20"), "{err}");
    }
    let runs: Vec<_> = std::fs::read_dir(&*dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("leakwatch-run-20"))
        .filter(|e| e.path().join("events.json").is_file())
        .collect();
    assert_eq!(runs.len(), 2, "{runs:?}");
}
