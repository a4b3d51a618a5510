//! `bench` on a plant folder: a missing datasheet named, detection and calibration scored.

use crate::common::*;

use crate::simulate_random;

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
