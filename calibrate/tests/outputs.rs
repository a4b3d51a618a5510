//! The outputs: calibration.json, model.toml (the caller's text, written as it
//! is; leakwatch's tests check that its TOML loads back), report.md and its plots.

use calibrate::suite::{cases, generate, nominal_model};
use calibrate::{run, write_outputs, CalibrateOptions};

const MODEL_FILE: &str = "# the caller's model file\n[model]\nmass_kg = 12.0\n";

#[test]
fn outputs_are_written_and_the_model_loads_back() {
    let c = cases().into_iter().find(|c| c.name == "leak-ext1").expect("case");
    let data = generate(&c);
    let cal = run(&data, &nominal_model(), &CalibrateOptions::default()).expect("runs");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("calibrate-outputs");
    // the directory persists between test runs: replace what an earlier run left
    let files = write_outputs(&cal, &dir, true, &[], MODEL_FILE).expect("written");
    // a second write without overwrite is refused before anything is touched
    let before = std::fs::read(&files.json).expect("json");
    let e = write_outputs(&cal, &dir, false, &[], MODEL_FILE)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("calibration.json: exists: not overwritten (use --force to replace it)"),
        "{e}"
    );
    assert_eq!(std::fs::read(&files.json).expect("json"), before);
    // an output that is the input is refused even with overwrite
    let e = write_outputs(&cal, &dir, true, &[files.report.as_path()], MODEL_FILE)
        .unwrap_err()
        .to_string();
    assert!(e.contains("report.md: is the input"), "{e}");

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files.json).expect("json")).expect("parses");
    assert_eq!(json["effects"][0]["name"], "leak-ext1");
    assert!(json["effects"][0]["parameters"]["leaks.ext1.sqrt_m3_s_sqrt_pa"].is_number());
    assert!(json["effects"][0]["gap_reduction"].as_f64().expect("number") > 0.7);
    for key in ["p1_pa", "normalised"] {
        let b = json["gap_before"][key].as_f64().expect("number");
        let a = json["gap_after"][key].as_f64().expect("number");
        assert!(a < b, "{key}: {a} !< {b}");
    }

    let text = std::fs::read_to_string(&files.model_toml).expect("model.toml");
    assert_eq!(text, MODEL_FILE);

    let report = std::fs::read_to_string(&files.report).expect("report");
    assert!(
        report.contains("leak-ext1") && report.contains("Gap before"),
        "{report}"
    );
    assert!(files.plots.len() >= 4, "{:?}", files.plots);
    for p in &files.plots {
        let bytes = std::fs::read(p).expect("png");
        assert!(bytes.starts_with(b"\x89PNG"), "{}", p.display());
        let name = p.file_name().and_then(|n| n.to_str()).expect("name");
        assert!(report.contains(name), "{name} not linked");
    }
}
