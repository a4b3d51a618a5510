//! Helpers shared by the end-to-end tests of the `leakwatch` binary (each
//! test file uses some of them).
#![allow(dead_code)]

pub mod html;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// `leakwatch ARGS`, run to its end (its status is the caller's to check).
pub fn leakwatch(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args)
        .output()
        .expect("the leakwatch binary runs")
}

/// The standard error of a finished command, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// A fresh folder for one test, `<test file>-<name>`, removed when the test passes.
pub fn tmpdir(name: &str) -> scratch::ScratchDir {
    scratch::ScratchDir::new(&format!("{}-{name}", env!("CARGO_CRATE_NAME")))
}

/// A config whose classifier learns its thresholds in time for a leak at 10 s.
pub fn short_warmup_config(dir: &Path) -> PathBuf {
    short_warmup_config_with(dir, "")
}

/// [`short_warmup_config`] with the TOML `extra` appended.
pub fn short_warmup_config_with(dir: &Path, extra: &str) -> PathBuf {
    let p = dir.join("cfg.toml");
    std::fs::write(
        &p,
        format!("[classifier]\nsettle_s = 2.0\nwarmup_s = 3.0\n{extra}"),
    )
    .unwrap();
    p
}

/// A JSON file of a run.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// True if python3 imports `module`; false (the test skips) only where
/// Python is not required (LEAKWATCH_REQUIRE_PYTHON unset: CI sets it).
pub fn python_with(module: &str) -> bool {
    let ok = Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_PYTHON").is_err(),
            "python3 with {module} is required (.ci/setup installs it)"
        );
        eprintln!("SKIPPED: python3 with {module} is not installed");
    }
    ok
}

/// The rig id of test tag `tag`: unique to this test process.
pub fn rig_id(tag: &str) -> String {
    format!("t{}-{}", std::process::id(), tag.replace('-', "_"))
}

/// PIDs of the stage processes (`leakwatch stage NAME ...`; `stage`: that NAME,
/// or any) of the rig of test tag `tag`, matched argument by argument.
pub fn stage_pids(stage: Option<&str>, tag: &str) -> Vec<i32> {
    let rig = rig_id(tag);
    let mut out = Vec::new();
    for entry in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<i32>() else {
            continue;
        };
        let Ok(cmd) = std::fs::read(entry.path().join("cmdline")) else {
            continue;
        };
        let args: Vec<&[u8]> = cmd.split(|b| *b == 0).collect();
        let is_stage =
            args.get(1) == Some(&&b"stage"[..]) && stage.is_none_or(|s| args.get(2) == Some(&s.as_bytes()));
        let on_rig = args
            .windows(2)
            .any(|w| w[0] == b"--rig" && w[1] == rig.as_bytes());
        if is_stage && on_rig {
            out.push(pid);
        }
    }
    out
}

/// Waits until `cond` holds (a minute at most: a run that never gets there failed).
pub fn wait_until(what: &str, mut cond: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !cond() {
        assert!(t0.elapsed() < Duration::from_secs(60), "never happened: {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits for the stage process `stage` of test tag `tag`'s rig; returns its pid.
pub fn wait_for_stage(stage: &str, tag: &str) -> i32 {
    let mut pid = 0;
    wait_until(&format!("{stage} of {tag} started"), || {
        pid = stage_pids(Some(stage), tag).first().copied().unwrap_or(0);
        pid != 0
    });
    pid
}

/// Sends signal `sig` to process `pid` (a process of this test's run).
pub fn signal(pid: i32, sig: i32) {
    // SAFETY: kill(2) on a pid of this test's run.
    unsafe {
        libc::kill(pid, sig);
    }
}
