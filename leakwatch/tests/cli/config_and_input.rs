//! Configuration and bad input: leakwatch.toml, one clear error, `config print-default`, `init`.

use std::process::Command;

use crate::common::*;

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
