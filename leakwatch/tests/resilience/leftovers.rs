//! Shared-memory leftovers: a killed run's removed at the next start and by `clean`, a failed start's.

use std::process::Command;

use crate::common::*;

use crate::{
    assert_no_files_of, kill_run, prefix_of_len, root_and_lock, run_command, shm_files, text, Running, SERIAL,
};

/// The number N in `... (N files or directories, ...` of `text`.
fn removed_count(text: &str) -> Option<usize> {
    let head = text.split(" files or directories").next()?;
    head.rsplit(['(', ' ']).next()?.parse().ok()
}

/// The paths listed in `text` (one per line, indented, followed by their size).
fn listed(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.strip_prefix("  "))
        .filter_map(|l| l.split(" (").next())
        .map(str::to_string)
        .collect()
}

/// A SIGKILLed run leaves its shared memory; the next run on the prefix removes
/// it and says so; `leakwatch clean` is refused while that run holds the prefix,
/// and after it too was killed, removes its files and lock and lists them.
#[test]
fn a_killed_runs_leftovers_are_removed_at_the_next_start_and_by_clean() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("leftovers");
    let cfg = short_warmup_config(&d);
    let prefix = format!("lwcl{}", std::process::id());
    let (root, lock) = root_and_lock(&prefix);
    let clean = || {
        Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .args(["clean", "--prefix", &prefix])
            .output()
            .unwrap()
    };

    // a run killed while it runs
    let a = Running(Some(
        run_command("left-a", "60", None, &d.join("a"), &cfg)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .spawn()
            .unwrap(),
    ));
    wait_for_stage("acquisition", "left-a");
    wait_until("run a publishes its stats", || {
        std::fs::read_to_string(d.join("a/recorder.log")).is_ok_and(|l| l.contains("recorder: rig"))
    });
    kill_run(a, "left-a");
    let left = shm_files(&prefix);
    assert!(left.len() > 10, "leftovers of the killed run: {left:?}");
    assert!(root.is_dir() && lock.is_file());

    // the next run on the prefix removes them and says so
    let b = Running(Some(
        run_command("left-b", "60", None, &d.join("b"), &cfg)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .spawn()
            .unwrap(),
    ));
    wait_for_stage("acquisition", "left-b");
    // ... and holds the prefix: clean is refused, nothing removed
    let refused = clean();
    assert_eq!(refused.status.code(), Some(1));
    let err = text(&refused.stderr);
    assert!(
        err.contains(&format!(
            "not cleaned: the iceoryx2 prefix {prefix:?} is in use by another leakwatch run"
        )),
        "{err}"
    );
    // (the running run's own files come and go as its stages connect; its
    // directory and lock are there from its start to its end)
    assert!(root.is_dir() && lock.is_file() && !shm_files(&prefix).is_empty());
    let b_out = kill_run(b, "left-b");
    let b_err = text(&b_out.stderr);
    assert!(
        b_err.contains(&format!(
            "leakwatch run: removed what a dead run left on the iceoryx2 prefix {prefix:?}"
        )),
        "{b_err}"
    );
    // every shm file of run a, and its directory
    let named = listed(&b_err);
    let extra: Vec<&String> = named
        .iter()
        .filter(|n| !left.iter().any(|f| f.display().to_string() == **n))
        .collect();
    assert_eq!(
        removed_count(&b_err),
        Some(left.len() + 1),
        "{b_err}\nnot counted before: {extra:?}"
    );
    for f in &left {
        assert!(
            b_err.contains(&f.display().to_string()),
            "{} not named:\n{b_err}",
            f.display()
        );
    }

    // run b's leftovers, removed on demand
    let left_b = shm_files(&prefix);
    assert!(
        left_b.len() > 10,
        "leftovers of the second killed run: {left_b:?}"
    );
    let done = clean();
    let said = text(&done.stdout);
    assert_eq!(done.status.code(), Some(0), "{said}{}", text(&done.stderr));
    assert!(
        said.starts_with(&format!(
            "leakwatch clean: removed {} files or directories",
            left_b.len() + 1
        )),
        "{said}"
    );
    assert!(said.contains(&root.display().to_string()), "{said}");
    for f in &left_b {
        assert!(
            said.contains(&f.display().to_string()),
            "{} not listed:\n{said}",
            f.display()
        );
    }
    assert!(shm_files(&prefix).is_empty() && !root.exists() && !lock.exists());
    let again = clean();
    assert_eq!(
        text(&again.stdout),
        format!("leakwatch clean: nothing left on the iceoryx2 prefix {prefix:?}\n")
    );
}

/// A start that fails once the run has opened its prefix (here: a stage's log
/// cannot be created, the stages before it already run) removes what it made:
/// no file of the prefix is left, and the error names the stage.
#[test]
fn a_start_that_fails_leaves_no_files_on_its_prefix() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("failed-start");
    let cfg = short_warmup_config(&d);
    let prefix = prefix_of_len(12, 'f');
    let out = d.join("run");
    // the acquisition, started last, cannot have its log: a directory is in the way
    std::fs::create_dir_all(out.join("acquisition.log")).unwrap();
    let failed = run_command("failed-start", "3", None, &out, &cfg)
        .arg("--force")
        .env("LEAKWATCH_IOX_PREFIX", &prefix)
        .output()
        .unwrap();
    let err = text(&failed.stderr);
    assert_eq!(failed.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot start the acquisition"), "{err}");
    assert!(
        err.contains(&format!(
            "the start failed: removed what it had made on the iceoryx2 prefix {prefix:?}"
        )),
        "{err}"
    );
    assert_no_files_of(&prefix);
    // the stages it had started are gone
    for stage in ["recorder", "estimator", "classifier"] {
        assert!(
            stage_pids(Some(stage), "failed-start").is_empty(),
            "{stage} still runs"
        );
    }
}
