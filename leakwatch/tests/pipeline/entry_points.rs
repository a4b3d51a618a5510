//! The pipeline as users start it: the Python example, the binary alone, the README's command.

use std::path::Path;
use std::process::{Command, Stdio};

use crate::common::*;

use crate::{finish, raised_leaks, SERIAL};

/// The Python example (official iceoryx2 bindings) subscribes to a live run and
/// prints its events and estimates. CI installs the bindings (.ci/setup) and
/// sets LEAKWATCH_REQUIRE_PYTHON=1; elsewhere the test says it was skipped.
#[test]
fn the_python_example_sees_live_events_and_estimates() {
    let has_python = Command::new("python3")
        .args(["-c", "import iceoryx2"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !has_python {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_PYTHON").is_err(),
            "python3 with iceoryx2==0.10.0 is required (pip install iceoryx2==0.10.0)"
        );
        eprintln!("SKIPPED: python3 with the iceoryx2 bindings is not installed");
        return;
    }
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("python");
    let cfg = short_warmup_config(&d);
    let prefix = format!("py{}", std::process::id());
    let mut args = vec![
        "run",
        "--rig",
        "pyrig",
        "--scenario",
        "loaded-sine",
        "--seconds",
        "16",
    ];
    args.extend(["--fault", "ext1:0.5lpm@10s"]);
    let cfg_s = cfg.display().to_string();
    let out_s = d.join("out").display().to_string();
    args.extend(["--config", cfg_s.as_str(), "--out", out_s.as_str()]);
    let run = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(&args)
        .env("LEAKWATCH_IOX_PREFIX", &prefix)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/python/live_events.py");
    let py = Command::new("python3")
        .arg(&script)
        .args(["--rig", "pyrig", "--prefix", &prefix, "--seconds", "19"])
        .output()
        .unwrap();
    finish(run);
    let stdout = String::from_utf8_lossy(&py.stdout);
    assert!(
        py.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&py.stderr)
    );
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("EVENT") && l.contains("raised ext1")),
        "{stdout}"
    );
    let n: u64 = stdout
        .lines()
        .find_map(|l| {
            l.strip_prefix("done: ")
                .and_then(|r| r.split(' ').next())
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0);
    assert!(n > 10_000, "estimates seen by Python: {n}\n{stdout}");
}

/// An installed `leakwatch` is the whole tool: a copy of the binary alone in a
/// folder, with no cargo on PATH, runs the four stages (`leakwatch stage NAME`)
/// and detects the leak.
#[test]
fn the_binary_alone_runs_the_pipeline_without_cargo() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("alone");
    let bin_dir = d.join("bin");
    std::fs::create_dir_all(&bin_dir).unwrap();
    let exe = bin_dir.join("leakwatch");
    std::fs::copy(env!("CARGO_BIN_EXE_leakwatch"), &exe).unwrap();
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let o = Command::new(&exe)
        .args([
            "run",
            "--rig",
            "e2e-alone",
            "--scenario",
            "loaded-sine",
            "--seconds",
            "16",
        ])
        .args(["--fault", "ext1:0.5lpm@10s", "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .env("PATH", "/usr/bin:/bin")
        .env_remove("CARGO")
        .current_dir(&d)
        .output()
        .expect("the copied binary runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(
        !stderr.contains("cargo") && !stderr.contains("building"),
        "{stderr}"
    );
    let leaks = raised_leaks(&json(&out.join("events.json")));
    assert_eq!(leaks.len(), 1, "{leaks:?}");
    assert_eq!(leaks[0]["kind"], "ext1");
    let t = leaks[0]["t_detect_s"].as_f64().unwrap();
    // named once one kind has led for 1.5 s after the (kind-pending) alarm
    assert!((10.0..13.0).contains(&t), "raised at {t} s");
    // the stage logs are there: the four children were this binary's stages
    for name in ["acquisition", "estimator", "classifier", "recorder"] {
        assert!(out.join(format!("{name}.log")).is_file(), "{name}.log");
    }
}

/// The lines of `text` that report events (`  t = ...`) or the detection (`detected: ...`).
fn event_lines(text: &str) -> Vec<String> {
    text.lines()
        .filter(|l| l.starts_with("  t = ") || l.starts_with("detected: "))
        .map(str::to_string)
        .collect()
}

/// The README's first command (`run` on its built-in defaults) prints the
/// events the README shows, to the digit: the README's example cannot drift.
#[test]
fn the_readmes_first_command_prints_the_events_the_readme_shows() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md")).unwrap();
    let shown = event_lines(&readme);
    assert_eq!(shown.len(), 3, "the README's demo block: {shown:?}");
    let d = tmpdir("readme");
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["run", "--rig", &rig_id("readme"), "--out"])
        .arg(d.join("out"))
        .current_dir(&*d)
        .output()
        .expect("leakwatch runs");
    let printed = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{printed}");
    assert_eq!(event_lines(&printed), shown, "{printed}");
}
