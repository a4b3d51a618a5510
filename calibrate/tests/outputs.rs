//! The outputs: calibration.json, model.toml (loadable as the `[model]` of a
//! config), report.md and its plots.

use calibrate::suite::{cases, generate, nominal_model};
use calibrate::{load_model, run, write_outputs, CalibrateOptions};

#[test]
fn outputs_are_written_and_the_model_loads_back() {
    let c = cases().into_iter().find(|c| c.name == "leak-ext1").expect("case");
    let data = generate(&c);
    let cal = run(&data, &nominal_model(), &CalibrateOptions::default()).expect("runs");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("calibrate-outputs");
    // the directory persists between test runs: replace what an earlier run left
    let files = write_outputs(&cal, &dir, true, &[]).expect("written");
    // a second write without overwrite is refused before anything is touched
    let before = std::fs::read(&files.json).expect("json");
    let e = write_outputs(&cal, &dir, false, &[]).unwrap_err().to_string();
    assert!(
        e.contains("calibration.json: exists: not overwritten (use --force to replace it)"),
        "{e}"
    );
    assert_eq!(std::fs::read(&files.json).expect("json"), before);
    // an output that is the input is refused even with overwrite
    let e = write_outputs(&cal, &dir, true, &[files.report.as_path()])
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

    let loaded = load_model(&files.model_toml).expect("model.toml loads");
    assert_eq!(loaded, cal.model_after);
    assert_eq!(loaded.leaks.len(), 1);
    let text = std::fs::read_to_string(&files.model_toml).expect("toml");
    assert!(text.contains("[model]"), "{text}");
    assert!(
        text.contains("leakwatch replay MEASURED.csv --config model.toml")
            && text.contains("leakwatch run --config model.toml"),
        "{text}"
    );

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
