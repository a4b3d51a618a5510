//! The command line as a user meets it: real runs of the built binary.

use std::process::Command;

mod common;
use common::*;

#[test]
fn simulate_writes_the_documented_csv() {
    let d = tmpdir("sim");
    let out = d.join("run.csv");
    let args = [
        "simulate",
        "--scenario",
        "loaded-sine",
        "--seconds",
        "2",
        "--fault",
        "ext1:0.3lpm@1s",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = leakwatch(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(
        text.lines().next(),
        Some("t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c")
    );
    assert_eq!(text.lines().count(), 2001);
    let ds = dataset::read_csv(&out, dataset::Limits::default()).unwrap();
    assert_eq!(ds.samples.len(), 2000);
    assert!(ds.samples[999].q_leak_lpm == 0.0 && ds.samples[1500].q_leak_lpm > 0.1);
    // same seed, same file
    let again = d.join("again.csv");
    let mut args2 = args;
    args2[8] = again.to_str().unwrap();
    assert!(leakwatch(&args2).status.success());
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
}

/// `--sensor-fault` drifts the p1 column by its equation, against the healthy
/// run of the same seed, to one ADC step (5.05 kPa); the other columns and the
/// rows before the onset are the healthy ones.
#[test]
fn simulate_drifts_a_pressure_transducer() {
    let d = tmpdir("sim-sensor-fault");
    let (healthy, faulty) = (d.join("healthy.csv"), d.join("drift.csv"));
    let args = |out: &std::path::Path, fault: &[&str]| {
        let mut a = vec!["simulate", "--scenario", "loaded-sine", "--seconds", "30"];
        a.extend_from_slice(fault);
        a.extend(["--out", out.to_str().unwrap()]);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    // 600 kPa/min = 10 kPa/s from 10 s, at most 100 kPa (from 20 s)
    let spec = ["--sensor-fault", "p1:drift=600kPa/min,max=100kPa@10s"];
    for (out, fault) in [(&healthy, &[][..]), (&faulty, &spec[..])] {
        let a = args(out, fault);
        let o = leakwatch(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |p: &std::path::Path| dataset::read_csv(p, dataset::Limits::default()).unwrap().samples;
    let (h, f) = (read(&healthy), read(&faulty));
    assert_eq!((h.len(), f.len()), (30_000, 30_000));
    for (t, want_pa) in [(15.0, 50e3), (25.0, 100e3)] {
        let i = (t * 1000.0) as usize;
        assert_eq!(f[i].t_s, t);
        let offset = f[i].p1_pa - h[i].p1_pa;
        assert!(
            (offset - want_pa).abs() <= 5.06e3,
            "t = {t} s: p1 offset {offset} Pa"
        );
    }
    assert!(f[..10_000].iter().zip(&h).all(|(a, b)| a.p1_pa == b.p1_pa));
    assert!(f
        .iter()
        .zip(&h)
        .all(|(a, b)| (a.x_m, a.p2_pa, a.u_v) == (b.x_m, b.p2_pa, b.u_v)));
    // a bad spec names its bad part
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "loaded-sine",
        "--sensor-fault",
        "p1:drift=1mm/min@1s",
        "--out",
        "-",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("p1 reads a pressure, so the unit is one of Pa, kPa, MPa or bar, not `mm`"),
        "{}",
        stderr(&o)
    );
}

/// `--out -` writes the CSV to standard output (the same bytes as the file); a
/// reader that stops early (`| head`) ends it with a named error, not a panic.
#[test]
fn simulate_writes_to_standard_output_and_names_a_closed_pipe() {
    use std::io::Read;
    let d = tmpdir("sim-stdout");
    let file = d.join("run.csv");
    let args = |out: &str| {
        [
            "simulate",
            "--scenario",
            "loaded-sine",
            "--seconds",
            "2",
            "--out",
            out,
        ]
        .map(str::to_string)
        .to_vec()
    };
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args(file.to_str().unwrap()))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args("-"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(o.stdout, std::fs::read(&file).unwrap());
    assert_eq!(stderr(&o).trim(), "wrote 2000 samples to standard output");
    assert!(
        !std::path::Path::new("-").exists(),
        "no file named '-' is written"
    );
    // the reader takes 100 bytes and closes the pipe
    let mut child = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args("-"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 100];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(first.starts_with(b"t,u,x,p1,p2"));
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!(
        stderr(&o).trim(),
        "leakwatch: error: cannot write the CSV to standard output: Broken pipe (os error 32)"
    );
}

/// A `leakwatch.toml` in the working directory is used when no `--config` is
/// given, and said so; `--config` wins; a bad one is named.
#[test]
fn a_leakwatch_toml_in_the_working_directory_is_picked_up() {
    let d = tmpdir("cwd-config");
    std::fs::write(d.join("leakwatch.toml"), "[sim]\nsample_period_s = 0.002\n").unwrap();
    let sim = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .current_dir(&d)
            .args([
                "simulate",
                "--scenario",
                "closed-loop-sine",
                "--seconds",
                "2",
                "--force",
                "--out",
                "a.csv",
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = sim(&[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("using ./leakwatch.toml from the working directory"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_to_string(d.join("a.csv")).unwrap().lines().count(),
        1001,
        "2 s at 2 ms"
    );
    std::fs::write(d.join("other.toml"), "").unwrap();
    let o = sim(&["--config", "other.toml"]);
    assert!(
        o.status.success() && !stderr(&o).contains("leakwatch.toml"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_to_string(d.join("a.csv")).unwrap().lines().count(),
        2001,
        "2 s at 1 ms"
    );
    std::fs::write(d.join("leakwatch.toml"), "[sim]\nsample_period_s = -1\n").unwrap();
    let o = sim(&[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("leakwatch.toml") && stderr(&o).contains("sample_period_s"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_input_gets_one_clear_error_and_nonzero_exit() {
    let d = tmpdir("bad");
    let out = d.join("x.csv");
    let out = out.to_str().unwrap();
    let cfg_bad_field = d.join("bad_field.toml");
    std::fs::write(&cfg_bad_field, "[model]\nsupply_pressure_psi = 2000\n").unwrap();
    let cfg_bad_unit = d.join("bad_unit.toml");
    std::fs::write(&cfg_bad_unit, "[model]\nsupply_pressure_pa = \"13.8 MPa\"\n").unwrap();
    let bad_field = cfg_bad_field.to_str().unwrap();
    let bad_unit = cfg_bad_unit.to_str().unwrap();
    let sim = ["simulate", "--scenario", "open-loop-sine"];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["simulate", "--scenario", "nope", "--out", out],
            "unknown scenario `nope`",
        ),
        (
            [&sim[..], &["--fault", "ext1:0.3@2s", "--out", out]].concat(),
            "needs a unit",
        ),
        (
            [&sim[..], &["--fault", "ext1:-0.3lpm@2s", "--out", out]].concat(),
            "must be >= 0",
        ),
        (
            [&sim[..], &["--config", bad_field, "--out", out]].concat(),
            "supply_pressure_psi",
        ),
        (
            [&sim[..], &["--config", bad_unit, "--out", out]].concat(),
            "supply_pressure_pa",
        ),
        (
            [&sim[..], &["--out", "/nonexistent-dir/x.csv"]].concat(),
            "/nonexistent-dir/x.csv",
        ),
        (
            [&sim[..], &["--seconds", "-1", "--out", out]].concat(),
            "--seconds",
        ),
    ];
    for (args, needle) in cases {
        let o = leakwatch(&args);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(e.contains(needle), "{args:?}: expected `{needle}` in: {e}");
        assert_eq!(e.trim().lines().count(), 1, "one clear error line, got: {e}");
    }
}

#[test]
fn config_print_default_is_loadable() {
    let o = leakwatch(&["config", "--print-default"]);
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("piston_area_m2 = 0.000633"), "{text}");
    let d = tmpdir("cfg");
    let p = d.join("default.toml");
    std::fs::write(&p, &text).unwrap();
    let o = leakwatch(&["config", "--check", p.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn plot_draws_a_png() {
    let d = tmpdir("plot");
    let csv = d.join("r.csv");
    let png = d.join("r.png");
    let (csv_s, png_s) = (csv.to_str().unwrap(), png.to_str().unwrap());
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "open-loop-sine",
        "--seconds",
        "3",
        "--fault",
        "ext2:0.5lpm@1s",
        "--out",
        csv_s,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = leakwatch(&["plot", csv_s, "--out", png_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let missing = d.join("missing.csv");
    let o = leakwatch(&["plot", missing.to_str().unwrap(), "--out", png_s]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("missing.csv"));
}

#[test]
fn calibrate_names_a_hidden_leak_and_writes_a_loadable_model() {
    let d = tmpdir("calibrate");
    let measured = d.join("m.csv");
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "closed-loop-random",
        "--rig-variant",
        "smooth",
        "--fault",
        "ext1:0.3lpm@0s",
        "--seconds",
        "12",
        "--out",
        measured.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cfg = d.join("smooth.toml");
    std::fs::write(&cfg, "[model.friction]\nstatic_n = 1100.0\n").unwrap();
    let out = d.join("cal");
    let o = leakwatch(&[
        "calibrate",
        measured.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap()).unwrap();
    assert_eq!(json["effects"][0]["name"], "leak-ext1", "{json:#}");
    let k = json["effects"][0]["parameters"]["leaks.ext1.sqrt_m3_s_sqrt_pa"]
        .as_f64()
        .unwrap();
    let truth = model::units::lpm_to_m3_s(0.3) / (13.8e6f64 / 2.0).sqrt();
    assert!((k - truth).abs() < 0.1 * truth, "fitted {k:e}, truth {truth:e}");
    // the extended model loads with --config everywhere
    let o = leakwatch(&["config", "--check", out.join("model.toml").to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    // a model file that does not load is one clear error
    let o = leakwatch(&[
        "calibrate",
        measured.to_str().unwrap(),
        "--config",
        "/nonexistent.toml",
        "--out",
        "x",
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("/nonexistent.toml"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn commissioning_calibrate_a_healthy_record_then_replay_a_leak_with_the_model() {
    // an off-nominal rig (spool null offset, oil with a lower bulk modulus;
    // thesis friction, so the rod stick-slips): calibrate on a healthy
    // record, then replay a leak run of the same rig with the calibrated
    // model and with the nominal one
    let d = tmpdir("commissioning");
    let rig = d.join("rig.toml");
    std::fs::write(
        &rig,
        "[rig]\nspool_null_bias_m = -8.0e-6\nbulk_modulus_pa = 4.8e8\n",
    )
    .unwrap();
    let healthy = d.join("healthy.csv");
    let leak = d.join("leak.csv");
    for (scenario, seconds, seed, fault, out) in [
        ("open-loop-sine", "12", "3", None, &healthy),
        ("closed-loop-random", "30", "4", Some("ext1:0.5lpm@15s"), &leak),
    ] {
        let mut args = vec![
            "simulate",
            "--config",
            rig.to_str().unwrap(),
            "--scenario",
            scenario,
            "--seconds",
            seconds,
            "--seed",
            seed,
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(f) = fault {
            args.extend_from_slice(&["--fault", f]);
        }
        let o = leakwatch(&args);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let cal = d.join("cal");
    let o = leakwatch(&[
        "calibrate",
        healthy.to_str().unwrap(),
        "--out",
        cal.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cal.join("calibration.json")).unwrap()).unwrap();
    let names: Vec<&str> = json["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["spool-bias", "bulk-modulus"], "{json:#}");
    let after = &json["model_after"];
    let bias = after["spool_null_bias_m"].as_f64().unwrap();
    assert!((bias + 8.0e-6).abs() < 0.4e-6, "{bias:e}");
    let beta = after["bulk_modulus_pa"].as_f64().unwrap();
    assert!((beta - 4.8e8).abs() < 0.2e8, "{beta:e}");

    // the model.toml is taken by replay --config as it is
    let summary = |name: &str, extra: &[&str]| -> serde_json::Value {
        let out = d.join(name);
        let mut args = vec!["replay", leak.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = leakwatch(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
    };
    // with the thesis filter (--model 7), whose model is fixed
    let nominal = summary("nominal", &["--model", "7"]);
    let model = cal.join("model.toml");
    let calibrated = summary(
        "calibrated",
        &["--config", model.to_str().unwrap(), "--model", "7"],
    );
    let f = |s: &serde_json::Value, filter: &str, k: &str| s[filter][k].as_f64().unwrap();
    eprintln!("nominal {nominal:#}\ncalibrated {calibrated:#}");
    // the calibrated model explains the rig: the thesis filter, whose model is
    // fixed, innovates less (measured: mean NIS 85 -> 63, p1 innovation RMS
    // 279 -> 196 kPa, p2 288 -> 136 kPa)
    let ratio = |k: &str| f(&calibrated, "thesis_filter", k) / f(&nominal, "thesis_filter", k);
    assert!(ratio("mean_nis") < 0.85, "thesis NIS ratio {}", ratio("mean_nis"));
    assert!(
        ratio("innovation_p1_pa") < 0.85,
        "p1 innovation ratio {}",
        ratio("innovation_p1_pa")
    );
    assert!(
        ratio("innovation_p2_pa") < 0.6,
        "p2 innovation ratio {}",
        ratio("innovation_p2_pa")
    );
    // the leak filter estimates the spool bias and the oil's stiffness itself, so
    // the nominal model serves it as well as the calibrated one (measured: mean
    // NIS 10.97 and 11.08; 96 and 13 before it estimated the stiffness)
    let (nis_nominal, nis_calibrated) = (
        f(&nominal, "leak_filter", "mean_nis"),
        f(&calibrated, "leak_filter", "mean_nis"),
    );
    assert!(
        (nis_nominal - nis_calibrated).abs() < 0.1 * nis_calibrated && nis_nominal < 20.0,
        "leak filter NIS {nis_nominal} (nominal model) vs {nis_calibrated} (calibrated)"
    );
    // ...and says how soft the oil is against each model: 4.8e8 of 6.89e8 Pa
    // (0.70) against the nominal one, about 1 against the calibrated one
    let theta = |s: &serde_json::Value| f(s, "leak_filter", "bulk_scale");
    assert!(
        (theta(&nominal) - 4.8 / 6.89).abs() < 0.04,
        "θ {}",
        theta(&nominal)
    );
    assert!(
        (theta(&calibrated) * beta / 4.8e8 - 1.0).abs() < 0.06,
        "θ {} against the calibrated {beta:e} Pa",
        theta(&calibrated)
    );
}

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

#[test]
fn repair_rewrites_a_killed_recorders_log_and_export_reads_it_whole() {
    let d = tmpdir("repair");
    let full = d.join("full.mcap");
    let options = recorder::WriterOptions {
        chunk_size: 4096,
        ..recorder::WriterOptions::default()
    };
    let mut w = recorder::LogWriter::create(&full, options).unwrap();
    for i in 0..1500u64 {
        let f = frames::SensorFrame {
            seq: i,
            t_s: i as f64 * 1e-3,
            x_m: 0.3,
            p1_pa: 6.9e6,
            p2_pa: 6.8e6,
            ..frames::SensorFrame::default()
        };
        assert!(w.write(recorder::Entry::Frame(f, i)).unwrap());
    }
    w.finish().unwrap();
    // a recorder killed mid-chunk: no summary, a cut last chunk (at 30 %: the
    // frames compress so well that the index and summary are much of the file)
    let bytes = std::fs::read(&full).unwrap();
    let killed = d.join("killed.mcap");
    std::fs::write(&killed, &bytes[..bytes.len() * 3 / 10]).unwrap();
    let kept = recorder::LogReader::open(&killed).unwrap().read().unwrap();
    assert!(
        kept.truncated.is_some() && kept.frames.len() > 100 && kept.frames.len() < 1500,
        "{:?}, {} frames of {} bytes",
        kept.truncated,
        kept.frames.len(),
        bytes.len()
    );
    let fixed = d.join("fixed.mcap");
    let o = leakwatch(&[
        "repair",
        killed.to_str().unwrap(),
        "--out",
        fixed.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("killed.mcap: ends early"), "{err}");
    // every frame in the batches; the frames channel holds every 40th
    assert!(err.contains("messages (frame_batches "), "{err}");
    assert_eq!(
        recorder::LogReader::open(&fixed)
            .unwrap()
            .read()
            .unwrap()
            .frames
            .len(),
        kept.frames.len()
    );
    // the repaired file is complete; export reads every frame of it without a warning
    let csv = d.join("csv");
    let o = leakwatch(&["export", fixed.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let dataset = std::fs::read_to_string(csv.join("dataset.csv")).unwrap();
    assert_eq!(dataset.lines().count(), kept.frames.len() + 1);
    // not over an existing file without --force, never over the input
    let o = leakwatch(&[
        "repair",
        killed.to_str().unwrap(),
        "--out",
        fixed.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("exists"),
        "{}",
        stderr(&o)
    );
    let o = leakwatch(&[
        "repair",
        killed.to_str().unwrap(),
        "--out",
        killed.to_str().unwrap(),
        "--force",
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("is the input"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(&killed).unwrap(), &bytes[..bytes.len() * 3 / 10]);
}

/// A log like `run`'s: 3 s of frames with the configuration stored, a leak raised.
fn write_run_log(path: &std::path::Path, config: Option<&str>) {
    let options = recorder::WriterOptions {
        config_toml: config.map(str::to_string),
        ..recorder::WriterOptions::default()
    };
    let mut w = recorder::LogWriter::create(path, options).unwrap();
    for i in 0..3000u64 {
        let t = 2_000_000_000 + i * 1_000_000;
        let f = frames::SensorFrame {
            seq: i,
            acq_mono_ns: t,
            t_s: i as f64 * 1e-3,
            u_v: (i as f64 * 0.01).sin(),
            x_m: 0.3 + 0.01 * (i as f64 * 0.01).sin(),
            p1_pa: 6.9e6,
            p2_pa: 6.8e6,
            ..frames::SensorFrame::default()
        };
        assert!(w.write(recorder::Entry::Frame(f, t)).unwrap());
        if i % 100 == 0 {
            let h = frames::HealthFrame {
                seq: i / 100,
                mono_ns: t,
                t_s: i as f64 * 1e-3,
                leak_flow_lpm: [i as f64 * 1e-4, 0.0, 0.0],
                ..frames::HealthFrame::default()
            };
            assert!(w.write(recorder::Entry::Health(h, t)).unwrap());
        }
    }
    let e = frames::LeakEventFrame {
        seq: 2100,
        acq_mono_ns: 4_100_000_000,
        event_id: 1,
        kind: frames::event_kind::EXT1,
        phase: frames::event_phase::RAISED,
        t_detect_s: 2.1,
        t_onset_s: 1.5,
        size_lpm: 0.3,
        size_lpm_sigma: 0.01,
        detector: frames::detector_bytes("leak-size"),
        ..frames::LeakEventFrame::default()
    };
    assert!(w.write(recorder::Entry::Event(e, 4_100_000_100)).unwrap());
    w.finish().unwrap();
}

#[test]
fn info_summarises_a_log_and_writes_the_config_it_holds() {
    let d = tmpdir("info");
    let log = d.join("run.mcap");
    let config = "[classifier]\nwarmup_s = 8.0\n";
    write_run_log(&log, Some(config));
    let o = leakwatch(&["info", log.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for want in [
        "File:        ",
        // from the first frame to the last on the frames channel (every 40th; a
        // batch is logged at its first frame's time)
        "Duration:    2.960 s",
        "frames                75 msgs      25.0 Hz  cdr leakwatch_msgs/msg/SensorFrame (ros2msg)",
        "frame_batches         30 msgs    10.000 Hz  cdr leakwatch_msgs/msg/SensorFrameBatch (ros2msg)",
        "health                30 msgs",
        "Gaps:        none recorded",
        "Events:      1 raised",
        "ext1             leak-size  id 1  onset 1.50 s  size 0.300 ± 0.010 L/min",
        "Truncated:   no",
        "Config:      stored (2 lines): [classifier]",
    ] {
        assert!(out.contains(want), "{want:?} in\n{out}");
    }
    // the configuration, to a file or to standard output
    let cfg = d.join("config.toml");
    let o = leakwatch(&[
        "info",
        log.to_str().unwrap(),
        "--config-out",
        cfg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&cfg).unwrap(), config);
    assert!(stderr(&o).contains("wrote "), "{}", stderr(&o));
    let o = leakwatch(&["info", log.to_str().unwrap(), "--config-out", "-"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), config);
    // not over an existing file without --force
    let o = leakwatch(&[
        "info",
        log.to_str().unwrap(),
        "--config-out",
        cfg.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("exists"),
        "{}",
        stderr(&o)
    );
    // a log without one says so; a file that is not a log is an error naming it
    let bare = d.join("bare.mcap");
    write_run_log(&bare, None);
    let o = leakwatch(&["info", bare.to_str().unwrap(), "--config-out", "-"]);
    assert!(
        !o.status.success() && stderr(&o).contains("bare.mcap: the log holds no configuration"),
        "{}",
        stderr(&o)
    );
    let junk = d.join("junk.mcap");
    std::fs::write(&junk, b"not a log").unwrap();
    let o = leakwatch(&["info", junk.to_str().unwrap()]);
    assert!(
        !o.status.success() && stderr(&o).contains("junk.mcap"),
        "{}",
        stderr(&o)
    );
    // the JSON log of the version before the CDR encoding
    let old =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../recorder/tests/fixtures/json_v1.mcap");
    let o = leakwatch(&["info", old.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("json leakwatch.SensorFrame.v1 (jsonschema)"),
        "{out}"
    );
    assert!(out.contains("Config:      not stored in the log"), "{out}");
}

/// `plot run.mcap` draws the log (it used to read it as a CSV: "stream did not
/// contain valid UTF-8").
#[test]
fn plot_draws_a_recorded_log() {
    let d = tmpdir("plot-log");
    let log = d.join("run.mcap");
    write_run_log(&log, None);
    let png = d.join("run.png");
    let o = leakwatch(&["plot", log.to_str().unwrap(), "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert!(bytes.len() > 10_000, "{} bytes", bytes.len());
    assert!(stderr(&o).contains("wrote "), "{}", stderr(&o));
}

/// `seconds` of `scenario` on the config `config`'s rig, with `fault`, to `out`.
fn simulate_scenario(
    scenario: &str,
    config: &std::path::Path,
    seconds: &str,
    seed: &str,
    fault: &str,
    out: &std::path::Path,
) {
    let o = leakwatch(&[
        "simulate",
        "--config",
        config.to_str().unwrap(),
        "--scenario",
        scenario,
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

/// `simulate --scenario closed-loop-random` of the rig in `config` into `out`.
fn simulate_random(config: &std::path::Path, seconds: &str, seed: &str, fault: &str, out: &std::path::Path) {
    simulate_scenario("closed-loop-random", config, seconds, seed, fault, out);
}

/// `commission` identifies the spool's null bias on a healthy recording (the
/// leak filter with its leak sizes held at zero), writes it into `[model]` and
/// holds it in the leak filter; the leak sizes then learn a healthy state near
/// zero instead of a pair of opposite leaks that cancels a wandering bias.
#[test]
fn commissioning_identifies_the_spool_null_bias_and_holds_it() {
    let d = tmpdir("commission_bias");
    let rig = d.join("rig.toml");
    std::fs::write(&rig, "[rig]\nspool_null_bias_m = -6.0e-6\n").unwrap();
    let healthy = d.join("healthy.csv");
    simulate_random(&rig, "25", "5", "none", &healthy);
    let out = d.join("commissioned.toml");
    let o = leakwatch(&[
        "commission",
        healthy.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("spool null bias: -"), "{}", stderr(&o));
    // without --config it says whose model it starts from
    assert!(
        stderr(&o).starts_with(
            "note: no --config and no ./leakwatch.toml: the rig is taken to be the built-in one"
        ),
        "{}",
        stderr(&o)
    );
    // it says from what size on it will see a leak (measured 0.033/0.030/0.040 L/min)
    let err = stderr(&o);
    let line = err
        .lines()
        .find_map(|l| l.strip_prefix("the detector will raise leaks from "))
        .expect("the thresholds are stated");
    let sizes: Vec<f64> = line
        .split(' ')
        .next()
        .unwrap()
        .split('/')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        sizes.len() == 3 && sizes.iter().all(|s| *s >= 0.03 && *s < 0.1),
        "{line}"
    );
    let t: toml::Table = toml::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let bias = t["model"]["spool_null_bias_m"].as_float().unwrap();
    eprintln!("identified bias {bias:e} m (true -6e-6)");
    assert!((bias + 6.0e-6).abs() < 0.3e-6, "{bias:e}");
    assert_eq!(t["leak_filter"]["q_bias_m2"].as_float(), Some(0.0));
    let offsets = t["classifier"]["commissioning"]["offsets_lpm"]
        .as_array()
        .unwrap();
    for o in offsets {
        let o = o.as_float().unwrap();
        assert!(o.abs() < 0.05, "healthy offset {o} L/min");
    }
    // the leak filter's stiffness at the recording's temperature is kept (the
    // built-in model's bulk modulus is the rig's: about 1)
    let theta = t["model"]["oil_temperature"]["reference_stiffness"]
        .as_float()
        .unwrap();
    assert!((theta - 1.0).abs() < 0.1, "θ_ref {theta}");
    // and the smallest detectable leaks at 20, 40 and 60 °C: the thresholds at
    // the reference (40 °C), wider away from it
    let line = err
        .lines()
        .find(|l| l.starts_with("smallest detectable leak"))
        .expect("stated over the temperature");
    let at = |t: &str| -> Vec<f64> {
        let rest = line.split(&format!("{t} °C ")).nth(1).expect(t);
        let v = rest.split([',', ' ']).next().unwrap();
        v.split('/').map(|x| x.parse().unwrap()).collect()
    };
    let (cold, reference, warm) = (at("20"), at("40"), at("60"));
    for k in 0..3 {
        assert!((reference[k] - sizes[k]).abs() < 1.5e-3, "{line}");
        assert!(cold[k] >= reference[k] && warm[k] >= reference[k], "{line}");
    }
}

/// A plant-style folder with a commissioning recording but no datasheet.toml
/// (and no --config) is scored on the built-in rig, and `bench detection` says
/// so before it commissions; with a datasheet.toml it names that file instead
/// ([`bench_detection_on_a_plant_folder_commissions_then_scores`]).
#[test]
fn bench_detection_says_when_a_plant_folder_has_no_datasheet() {
    let d = tmpdir("plant_no_sheet");
    let sheet = d.join("elsewhere.toml");
    std::fs::write(&sheet, "[rig]\n").unwrap();
    let data = d.join("data");
    std::fs::create_dir_all(&data).unwrap();
    simulate_random(&sheet, "12", "5", "none", &data.join("commission_cold.csv"));
    let o = leakwatch(&[
        "bench",
        "detection",
        "--data",
        data.to_str().unwrap(),
        "--out",
        d.join("scored").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    let note = err.lines().next().unwrap_or_default();
    assert!(
        note.starts_with("note: no --config and no datasheet.toml in") && note.contains("built-in one"),
        "{err}"
    );
    assert!(!err.contains("config: "), "{err}");
}

/// `bench detection --data DIR` on a folder laid out like plant_dev runs the
/// README's workflow itself: its `datasheet.toml` is the config, `commission`
/// runs on its `commission_cold.csv` (the spool bias identified and held), then
/// the runs are scored. Here a simulated rig with a −6 µm spool bias: the
/// leak is found and named, the healthy run raises nothing.
#[test]
fn bench_detection_on_a_plant_folder_commissions_then_scores() {
    let d = tmpdir("plant_folder");
    std::fs::write(d.join("datasheet.toml"), "[rig]\nspool_null_bias_m = -6.0e-6\n").unwrap();
    let sheet = d.join("datasheet.toml");
    simulate_random(&sheet, "25", "5", "none", &d.join("commission_cold.csv"));
    for (run, seed, fault, truth) in [
        (
            "run_000",
            "6",
            "ext2:0.5lpm@20s",
            r#"{"scenario": {"name": "closed-loop-random"}, "fault": {"kind": "ext2", "size_lpm": 0.5, "t_on_s": 20.0, "ramp_s": 0.0, "observed_mean_abs_flow_lpm_after_ramp": 0.5}}"#,
        ),
        (
            "run_001",
            "7",
            "none",
            r#"{"scenario": {"name": "closed-loop-random"}, "fault": null}"#,
        ),
    ] {
        let dir = d.join(run);
        std::fs::create_dir_all(&dir).unwrap();
        simulate_random(&sheet, "30", seed, fault, &dir.join("measured.csv"));
        std::fs::write(dir.join("truth.json"), truth).unwrap();
    }
    let out = d.join("scored");
    let o = leakwatch(&[
        "bench",
        "detection",
        "--data",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains(&format!("config: {}", sheet.display())), "{err}");
    assert!(!err.contains("no datasheet.toml"), "{err}");
    assert!(err.contains("commissioning on"), "{err}");
    let bias_um: f64 = err
        .split("spool null bias: ")
        .nth(1)
        .and_then(|rest| rest.split(" µm").next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no spool null bias in: {err}"));
    assert!(
        (bias_um + 6.0).abs() < 0.1,
        "spool null bias {bias_um} µm (rig −6 µm)"
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("detection.json")).unwrap()).unwrap();
    // The healthy run raises nothing. The leak run starts into a saturated move:
    // the filter's start transient (its leak sizes take up to 1.3 L/min in the
    // first 0.1 s, decaying over 2 s) now lands in the leak sizes, not the held
    // spool bias, and the commissioned detector, armed at 1 s, raised a false leak
    // at 1.2 s (open: docs/plant.md). So the leak run's false alarms are counted
    // after the first 3 s only, from its events.
    let healthy = r["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["truth"]["run"] == "run_001")
        .unwrap();
    assert_eq!(healthy["false_alarms"].as_u64(), Some(0), "{healthy:#}");
    let leak = r["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["truth"]["run"] == "run_000")
        .unwrap();
    assert_eq!(leak["detected"], true, "{leak:#}");
    assert_eq!(leak["kind_first"], "ext2", "{leak:#}");
    let delay = leak["delay_s"].as_f64().unwrap();
    eprintln!("ext2 0.5 L/min raised {delay:.2} s after its onset");
    assert!(delay < 2.0, "{delay}");
    assert!(leak["false_alarms"].as_u64().unwrap() <= 1, "{leak:#}");
    // the same run replayed with the commissioned config: nothing between 3 s and the onset
    let commissioned = d.join("rig.toml");
    let o = leakwatch(&[
        "commission",
        d.join("commission_cold.csv").to_str().unwrap(),
        "--config",
        sheet.to_str().unwrap(),
        "--out",
        commissioned.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let replayed = d.join("replayed");
    let o = leakwatch(&[
        "replay",
        d.join("run_000").join("measured.csv").to_str().unwrap(),
        "--config",
        commissioned.to_str().unwrap(),
        "--out",
        replayed.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let events: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(replayed.join("events.json")).unwrap()).unwrap();
    let early: Vec<_> = events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["phase"] == "raised" && e["detector"] == "leak-size")
        .filter(|e| {
            let t = e["t_detect_s"].as_f64().unwrap();
            t > 3.0 && t < 20.0
        })
        .collect();
    assert!(early.is_empty(), "false leaks before the onset: {early:#?}");
}

/// `bench calibration --data DIR` on a folder laid out like plant_dev identifies
/// the rig on its commissioning recording and scores it against its
/// `truth_rig.json`. Here the datasheet's valve passes 10 % too much and its oil
/// is 20 % too stiff; the identification finds the simulated rig's values.
#[test]
fn bench_calibration_on_a_plant_folder_scores_the_identification() {
    let d = tmpdir("plant_identification");
    let rig = model::ActuatorParams::default();
    let sheet = d.join("datasheet.toml");
    std::fs::write(
        &sheet,
        format!(
            // the simulated rig is `[rig]` (the built-in one), the datasheet `[model]`
            "[model]\narea_gradient_m2_per_m = {}\nbulk_modulus_pa = {}\n[rig]\nspool_null_bias_m = 0.0\n",
            1.1 * rig.area_gradient_m2_per_m,
            1.2 * rig.bulk_modulus_pa
        ),
    )
    .unwrap();
    simulate_random(&sheet, "30", "5", "none", &d.join("commission_cold.csv"));
    let truth = serde_json::json!({"params": {
        "Cd": rig.discharge_coefficient, "w": rig.area_gradient_m2_per_m, "k_sp": rig.spool_gain_m_per_v,
        "rho": rig.oil_density_kg_m3, "beta": rig.bulk_modulus_pa, "beta_tc": 0.0045, "T_ref": 40.0,
        "supply_sag": 0.0, "nu_tc": 0.028}});
    std::fs::write(d.join("truth_rig.json"), truth.to_string()).unwrap();
    std::fs::write(
        d.join("commission_cold.truth.json"),
        r#"{"nuisances": {"oil_temperature": {"T_C": 40.0}}}"#,
    )
    .unwrap();
    let o = leakwatch(&["bench", "calibration", "--data", d.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let params = r["params"].as_array().unwrap();
    let error = |name: &str| -> f64 {
        let p = params
            .iter()
            .find(|p| p["name"].as_str().unwrap().starts_with(name))
            .unwrap_or_else(|| panic!("no {name} in {r:#}"));
        p["error_pct"].as_f64().unwrap_or_else(|| panic!("{p:#}"))
    };
    assert!(error("port A area gradient").abs() < 1.0, "{r:#}");
    assert!(error("effective bulk modulus").abs() < 5.0, "{r:#}");
    let gap = r["gap_lpm"].as_array().unwrap();
    assert!(gap[1].as_f64().unwrap() < 0.5 * gap[0].as_f64().unwrap(), "{r:#}");
}

/// A vertical single-rod lift (`ActuatorParams::vertical_lift`: 2.0/1.2e-3 m²,
/// 200 kg, matched valve) through the README's workflow: commissioned on a
/// healthy minute, then one 0.3 L/min leak of each kind and a healthy run.
/// Its chambers rest at unequal pressures (p2 > p1 while holding the load), so
/// the commissioning takes the internal leak's pressure factors (r1, r2 < 0);
/// each leak is found and named, the healthy run raises nothing.
#[test]
fn a_single_rod_lift_is_commissioned_and_each_leak_found_and_named() {
    let d = tmpdir("lift_folder");
    // The lift described as a user would: its datasheet, and in [model] only
    // what no datasheet gives (friction, damping, end stops); installed as a plant's is.
    let lift = model::ActuatorParams::vertical_lift();
    let mut rest = toml::Table::try_from(&lift).unwrap();
    for (section, field, _) in model::datasheet::DERIVED_FIELDS {
        if section == "model" {
            rest.remove(field);
        }
    }
    let mut cfg = toml::Table::new();
    cfg.insert(
        "datasheet".into(),
        toml::Value::try_from(model::Datasheet::vertical_lift()).unwrap(),
    );
    cfg.insert("model".into(), toml::Value::Table(rest));
    // and what an installation adds (the simulated rig's sensors; the model has none
    // of it): transducers at the valve manifold (0.15 MPa at 50 L/min), lagging
    // 0.5 ms, with offsets and span errors
    let installation: toml::Table = toml::from_str(
        "line_resistance_pa_s_per_m3 = 1.8e8\npressure_lag_s = 5e-4\n\
         pressure_offset_pa = [30e3, -20e3]\npressure_gain_error = [0.004, -0.003]\n",
    )
    .unwrap();
    cfg.insert("sensors".into(), toml::Value::Table(installation));
    // and a pump that ripples ±0.4 % at 250 Hz
    // and oil at 30 °C while commissioning, warming from 35 towards 55 °C (τ 60 s)
    // in the runs, with no thermometer: the model must bear 5-16 K it was not
    // commissioned at (bulk modulus −2 to −7 %, viscosity down to 0.45×)
    let pump: toml::Table = toml::from_str(
        "supply_ripple_fraction = 0.004\n[oil]\nstart_c = 30.0\nend_c = 30.0\ntime_constant_s = 60.0\n",
    )
    .unwrap();
    cfg.insert("sim".into(), toml::Value::Table(pump));
    std::fs::write(d.join("datasheet.toml"), toml::to_string(&cfg).unwrap()).unwrap();
    let sheet = d.join("datasheet.toml");
    simulate_scenario("lift", &sheet, "60", "11", "none", &d.join("commission_cold.csv"));
    let warm_dir = tmpdir("lift_warm");
    let warm = warm_dir.join("warming.toml");
    let warming: toml::Table = toml::from_str(
        "supply_ripple_fraction = 0.004\n[oil]\nstart_c = 35.0\nend_c = 55.0\ntime_constant_s = 60.0\n",
    )
    .unwrap();
    cfg.insert("sim".into(), toml::Value::Table(warming));
    std::fs::write(&warm, toml::to_string(&cfg).unwrap()).unwrap();
    let runs = [
        ("run_000", "12", "ext1"),
        ("run_001", "13", "ext2"),
        ("run_002", "14", "int"),
        ("run_003", "15", "none"),
    ];
    for (run, seed, kind) in runs {
        let dir = d.join(run);
        std::fs::create_dir_all(&dir).unwrap();
        let (fault, truth) = if kind == "none" {
            (
                "none".to_string(),
                r#"{"scenario": {"name": "lift"}, "fault": null}"#.to_string(),
            )
        } else {
            (
                format!("{kind}:0.3lpm@30s"),
                format!(
                    r#"{{"scenario": {{"name": "lift"}}, "fault": {{"kind": "{kind}", "size_lpm": 0.3, "t_on_s": 30.0, "ramp_s": 0.0, "observed_mean_abs_flow_lpm_after_ramp": 0.3}}}}"#
                ),
            )
        };
        simulate_scenario("lift", &warm, "50", seed, &fault, &dir.join("measured.csv"));
        std::fs::write(dir.join("truth.json"), truth).unwrap();
    }
    let out = d.join("scored");
    let o = leakwatch(&[
        "bench",
        "detection",
        "--data",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("detection.json")).unwrap()).unwrap();
    let rows = r["runs"].as_array().expect("runs");
    assert_eq!(rows.len(), 4, "{r:#}");
    for row in rows {
        let name = row["truth"]["run"].as_str().unwrap_or_default();
        let kind = row["truth"]["kind"].as_str().unwrap_or_default();
        assert_eq!(row["false_alarms"], 0, "{name}: {row:#}");
        if kind == "none" {
            assert_eq!(row["detected"], false, "{name}: {row:#}");
        } else {
            assert_eq!(row["detected"], true, "{name}: {row:#}");
            assert_eq!(row["kind_first"].as_str(), Some(kind), "{name}: {row:#}");
            let delay = row["delay_s"].as_f64().unwrap_or(f64::NAN);
            assert!(delay < 5.0, "{name}: found after {delay} s");
        }
    }
    // The commissioning took the internal leak's pressure factors: both negative (p2 > p1).
    let factors: Vec<f64> = err
        .split("internal leak's pressure factors ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .map(|v| v.split('/').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_default();
    assert!(
        factors.len() == 2 && factors.iter().all(|r| (-1.0..-0.1).contains(r)),
        "{factors:?} in {err}"
    );
    // calibrate on a datasheet identifies first, then searches on top; its
    // model.toml is a whole config without the datasheet, and it loads
    let cal = d.join("cal");
    let o = leakwatch(&[
        "calibrate",
        d.join("commission_cold.csv").to_str().unwrap(),
        "--config",
        sheet.to_str().unwrap(),
        "--out",
        cal.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("flow-balance gap")
            && err.contains("the search for missing effects starts from the identified model"),
        "{err}"
    );
    let written = std::fs::read_to_string(cal.join("model.toml")).unwrap();
    assert!(
        !written.lines().any(|l| l.starts_with("[datasheet")) && written.contains("adc_bits = 16"),
        "{written}"
    );
    let o = leakwatch(&["config", "--check", cal.join("model.toml").to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `init` writes a datasheet template that loads, and refuses to overwrite it.
#[test]
fn init_writes_a_datasheet_template_that_loads() {
    let d = tmpdir("init");
    let file = d.join("leakwatch.toml");
    let o = leakwatch(&["init", "--single-rod", "--out", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(
        text.contains("kind = \"single-rod\"") && text.contains("rated_flow_b_l_min = 18.0"),
        "{text}"
    );
    let o = leakwatch(&["config", "--check", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let resolved = String::from_utf8_lossy(&o.stdout).to_string();
    // the cap area of a 50 mm bore and the angle of a lift, derived
    assert!(
        resolved.contains("piston_area_m2 = 0.0019634954084936")
            && resolved.contains("mounting_angle_rad = 1.5707963267948966"),
        "{resolved}"
    );
    let o = leakwatch(&["init", "--out", file.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    // a fact written twice is refused, naming both places
    std::fs::write(&file, text + "\n[model]\nmass_kg = 250.0\n").unwrap();
    let o = leakwatch(&["config", "--check", file.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("[model] mass_kg") && err.contains("cylinder.moving_mass_kg"),
        "{err}"
    );
}

/// Prints, for a log, what `rosbags` (the pure-Python rosbag2 reader) reads:
/// the message count, each connection's topic, type and count, the first log
/// time, and every frame's seq, p1 (IEEE-754 bits), log time and acquisition
/// stamp as JSON: from the frame batches (every frame in columns; a batch's
/// log time is its first frame's), the frames topic the plotting copy.
const ROSBAGS_SCRIPT: &str = r#"
import json, struct, sys
from pathlib import Path
from rosbags.highlevel import AnyReader

with AnyReader([Path(sys.argv[1])]) as reader:
    out = {"message_count": reader.message_count, "start_time": reader.start_time,
           "connections": {c.topic: [c.msgtype, c.msgcount] for c in reader.connections},
           "frames": []}
    batches = [c for c in reader.connections if c.topic.endswith("/frame_batches")]
    for connection, timestamp, rawdata in reader.messages(connections=batches):
        m = reader.deserialize(rawdata, connection.msgtype)
        n = len(m.p1_pa)
        acq = bytes(m.acq_mono_ns_shuffled.tolist())  # byte j of stamp i at j*n + i
        for i in range(n):
            p1 = struct.unpack("<Q", struct.pack("<d", float(m.p1_pa[i])))[0]
            stamp = int.from_bytes(bytes(acq[j * n + i] for j in range(8)), "little")
            out["frames"].append([m.first_seq + i, p1, timestamp, stamp])
    print(json.dumps(out))
"#;

/// A real run's log opens in `rosbags` as a rosbag2 file, and its folder as a
/// rosbag2 bag: every channel's message count and every frame's p1 equal
/// `leakwatch export`'s CSV, bit for bit, and its times are the wall clock of
/// the run (Unix time, ns).
#[test]
fn a_runs_log_opens_in_rosbags_and_equals_the_export() {
    let has = Command::new("python3")
        .args(["-c", "import rosbags.highlevel"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !has {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_PYTHON").is_err(),
            "python3 with rosbags is required (.ci/setup installs it)"
        );
        eprintln!("SKIPPED: python3 with the rosbags package is not installed");
        return;
    }
    let d = tmpdir("rosbags");
    let run = d.join("run");
    let wall_before = bus::wall_clock_ns();
    let o = leakwatch(&[
        "run",
        "--rig",
        "press-3",
        "--seconds",
        "3",
        "--fault",
        "none",
        "--out",
        run.to_str().unwrap(),
    ]);
    // exit 3: the detector never armed in 3 s (not watched); the log is whole
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    let wall_after = bus::wall_clock_ns();
    let log = run.join("run.mcap");
    let csv = d.join("csv");
    let o = leakwatch(&["export", log.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = Command::new("python3")
        .args(["-c", ROSBAGS_SCRIPT])
        .arg(&log)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let rows = |name: &str| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(csv.join(format!("{name}.csv"))).expect("the export's CSV");
        text.lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    };
    let mut total = 0;
    // the frames topic, for plotting: every 40th frame and every flagged one
    let n = plotted_frames(&rows("frames"));
    let topic = "/leakwatch/press-3/frames";
    assert_eq!(
        r["connections"][topic],
        serde_json::json!(["leakwatch_msgs/msg/SensorFrame", n]),
        "{}",
        r["connections"]
    );
    total += n;
    // every frame in the batches, 100 a message but where a chunk closes and at the end
    let batches = &r["connections"]["/leakwatch/press-3/frame_batches"];
    assert_eq!(batches[0], "leakwatch_msgs/msg/SensorFrameBatch", "{batches}");
    let n = batches[1].as_u64().expect("a count");
    assert!((30..=40).contains(&n), "{batches}");
    total += n;
    for (name, msg) in [
        ("estimates", "EstimateFrame"),
        ("events", "LeakEventFrame"),
        ("health", "HealthFrame"),
        ("stats", "StatsFrame"),
        ("gaps", "Gap"),
    ] {
        let n = rows(name).len() as u64 - 1;
        let topic = format!("/leakwatch/press-3/{name}");
        assert_eq!(
            r["connections"][&topic],
            serde_json::json!([format!("leakwatch_msgs/msg/{msg}"), n]),
            "{topic}: {}",
            r["connections"]
        );
        total += n;
    }
    assert_eq!(r["message_count"], total);
    // a 3 s run at 1 kHz
    let frames = rows("frames");
    assert!(frames.len() > 2900, "{} frames", frames.len());
    let col = |name: &str| frames[0].iter().position(|c| c == name).expect("a column");
    let (seq, p1, acq) = (col("seq"), col("p1_pa"), col("acq_mono_ns"));
    let got = r["frames"].as_array().expect("frames");
    assert_eq!(got.len(), frames.len() - 1);
    for (g, row) in got.iter().zip(&frames[1..]) {
        let want_p1: f64 = row[p1].parse().expect("a number");
        assert_eq!(g[0].as_u64(), row[seq].parse().ok(), "{g}");
        assert_eq!(
            g[1].as_u64(),
            Some(want_p1.to_bits()),
            "frame {}: p1 {want_p1}",
            row[seq]
        );
        assert_eq!(g[3].as_u64(), row[acq].parse().ok(), "{g}");
    }
    // Unix time of the run: the first message after the run started, the last before it ended
    let first = r["start_time"].as_u64().expect("a start time");
    assert!(
        wall_before < first && first < wall_after,
        "{wall_before} < {first} < {wall_after}"
    );
    let last_frame = got.last().and_then(|g| g[2].as_u64()).expect("a time");
    assert!(last_frame < wall_after, "{last_frame} < {wall_after}");
    // the run's folder opens as a rosbag2 bag too (its metadata.yaml), with the same content
    let o = Command::new("python3")
        .args(["-c", ROSBAGS_SCRIPT])
        .arg(&run)
        .output()
        .expect("python3 runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let folder: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(folder, r, "the folder reads as the file");
}

/// `demo --rig lift`: the vertical single-rod lift, commissioned first on a
/// simulated healthy minute (negative pressure factors printed); an internal
/// leak is raised and named.
#[test]
fn demo_runs_the_single_rod_lift_and_names_an_internal_leak() {
    let o = leakwatch(&[
        "demo",
        "--rig",
        "lift",
        "--seconds",
        "50",
        "--fault",
        "int:0.3lpm@35s",
    ]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{out}{}", stderr(&o));
    assert!(
        out.contains("lift (single-rod, vertical) rig, scenario lift"),
        "{out}"
    );
    assert!(out.contains("the internal leak's pressure factors -0."), "{out}");
    let named: Vec<&str> = out
        .lines()
        .filter(|l| l.contains(" raised ") && !l.contains(" leak  "))
        .collect();
    assert!(
        !named.is_empty() && named.iter().all(|l| l.contains(" int ")),
        "{out}"
    );
    let t: f64 = named[0]
        .split("t = ")
        .nth(1)
        .and_then(|r| r.split(' ').find(|w| !w.is_empty()))
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN);
    assert!((35.0..40.0).contains(&t), "named at {t} s: {out}");
    assert!(out.contains("leak detected"), "{out}");
}

/// The folder of Foxglove's npm clients (`LEAKWATCH_NODE_MODULES`, whose
/// `node_modules` .ci/setup fills from .ci/node/package.json) when node runs;
/// `None`, the test skipped, elsewhere; a failure where LEAKWATCH_REQUIRE_NODE
/// is set (CI).
fn node_clients(package: &str) -> Option<std::path::PathBuf> {
    let required = std::env::var("LEAKWATCH_REQUIRE_NODE").is_ok_and(|v| v == "1");
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let dir = std::env::var_os("LEAKWATCH_NODE_MODULES").map(std::path::PathBuf::from);
    let has = dir.as_ref().is_some_and(|d| {
        d.join("node_modules")
            .join(package)
            .join("package.json")
            .is_file()
    });
    if node && has {
        return dir;
    }
    let why = if !node {
        "node is not installed".to_string()
    } else {
        format!("LEAKWATCH_NODE_MODULES has no node_modules/{package}")
    };
    assert!(
        !required,
        "{why} (.ci/setup installs it; LEAKWATCH_REQUIRE_NODE=1)"
    );
    eprintln!("SKIPPED: {why}");
    None
}

/// Foxglove's MCAP stack in Node.js (examples/mcap/decode_log.js: @mcap/core's
/// indexed reader, @foxglove/rosmsg, @foxglove/rosmsg2-serialization) decodes
/// every message of a run's log: per topic the count of `leakwatch export`
/// (the frames topic: the frames plotted), no decode error, and every frame's
/// seq and p1 (from the batches) bit for bit.
#[test]
fn a_runs_log_decodes_with_foxglove_mcap_stack_in_node() {
    let Some(modules) = node_clients("@mcap/core") else {
        return;
    };
    let d = tmpdir("node-mcap");
    let run = d.join("run");
    let o = leakwatch(&[
        "run",
        "--rig",
        "press-4",
        "--seconds",
        "3",
        "--fault",
        "none",
        "--out",
        run.to_str().unwrap(),
    ]);
    // exit 3: the detector never armed in 3 s (not watched); the log is whole
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let log = run.join("run.mcap");
    let csv = d.join("csv");
    let o = leakwatch(&["export", log.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mcap/decode_log.js");
    let o = Command::new("node")
        .arg(&script)
        .arg(&log)
        .env("NODE_PATH", modules.join("node_modules"))
        .output()
        .expect("node runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(r["profile"], "ros2");
    let rows = |name: &str| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(csv.join(format!("{name}.csv"))).expect("the export's CSV");
        text.lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect()
    };
    let mut total = 0;
    // the frames topic, for plotting: every 40th frame and every flagged one
    let t = &r["topics"]["/leakwatch/press-4/frames"];
    assert_eq!(t["schema"], "leakwatch_msgs/msg/SensorFrame", "{t}");
    let n = plotted_frames(&rows("frames"));
    assert_eq!(
        (t["errors"].as_u64(), t["count"].as_u64()),
        (Some(0), Some(n)),
        "{t}"
    );
    total += n;
    // every frame in the batches, 100 a message but where a chunk closes and at the end
    let t = &r["topics"]["/leakwatch/press-4/frame_batches"];
    assert_eq!(t["schema"], "leakwatch_msgs/msg/SensorFrameBatch", "{t}");
    assert_eq!(t["errors"], 0, "{t}");
    let n = t["count"].as_u64().expect("a count");
    assert!((30..=40).contains(&n), "{t}");
    total += n;
    for (name, msg) in [
        ("estimates", "EstimateFrame"),
        ("events", "LeakEventFrame"),
        ("health", "HealthFrame"),
        ("stats", "StatsFrame"),
        ("gaps", "Gap"),
    ] {
        let n = rows(name).len() as u64 - 1;
        let t = &r["topics"][format!("/leakwatch/press-4/{name}")];
        assert_eq!(t["schema"], format!("leakwatch_msgs/msg/{msg}"), "{t}");
        assert_eq!(t["errors"], 0, "{name}: {t}");
        assert_eq!(t["count"].as_u64(), Some(n), "{name}: {t}");
        total += n;
    }
    assert_eq!(r["statistics_messages"], total.to_string());
    // nested messages and codes by name
    let first = |name: &str| r["topics"][format!("/leakwatch/press-4/{name}")]["first"].clone();
    assert!(
        first("estimates")["state"]["p1_pa"].is_f64(),
        "{}",
        first("estimates")
    );
    assert_eq!(first("events")["kind"], "not-armed");
    assert!(
        first("health")["leak_flow_sigma_lpm"]["ext1"].is_f64(),
        "{}",
        first("health")
    );
    // every frame, bit for bit
    let frames = rows("frames");
    assert!(frames.len() > 2900, "{} frames", frames.len());
    let col = |name: &str| frames[0].iter().position(|c| c == name).expect("a column");
    let (seq, p1) = (col("seq"), col("p1_pa"));
    let got = r["frames"].as_array().expect("frames");
    assert_eq!(got.len(), frames.len() - 1);
    for (g, row) in got.iter().zip(&frames[1..]) {
        let want: f64 = row[p1].parse().expect("a number");
        assert_eq!(g[0].as_str(), Some(row[seq].as_str()), "{g}");
        assert_eq!(
            g[1].as_str(),
            Some(hex_le(want).as_str()),
            "frame {}: p1 {want}",
            row[seq]
        );
    }
}

/// How many of the exported frames (`frames.csv` rows, header first) the
/// recorder also puts on the frames topic for plotting: every 40th by sequence
/// number and every flagged one (`recorder::WriterOptions::frames_every`).
fn plotted_frames(rows: &[Vec<String>]) -> u64 {
    let col = |name: &str| rows[0].iter().position(|c| c == name).expect("a column");
    let (seq, flags) = (col("seq"), col("flags"));
    rows[1..]
        .iter()
        .filter(|r| r[seq].parse::<u64>().expect("a seq") % 40 == 0 || r[flags] != "0")
        .count() as u64
}

/// The little-endian bytes of `x` in hex, as node's `Buffer.writeDoubleLE` gives them.
fn hex_le(x: f64) -> String {
    x.to_le_bytes().iter().map(|b| format!("{b:02x}")).collect()
}
