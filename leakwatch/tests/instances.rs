//! `leakwatch bench instances`: one instance of each plant rig, drawn over its
//! datasheet's tolerances, written as a plant-style folder that `bench
//! detection --data` commissions and scores. Detection quality is not asserted
//! here: the runs are short, and the figures are the benchmark's.

use std::path::Path;
use std::process::Command;

fn leakwatch(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(args)
        .output()
        .expect("leakwatch runs")
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The drawn value of `name` in a truth file's instance draw, and its range.
fn drawn(truth: &serde_json::Value, name: &str) -> (f64, f64, f64, f64) {
    let d = truth["instance"]["drawn"]
        .as_array()
        .and_then(|a| a.iter().find(|d| d["name"] == name))
        .unwrap_or_else(|| panic!("{name} not drawn: {truth:#}"));
    let f = |k: &str| d[k].as_f64().unwrap_or(f64::NAN);
    (f("nominal"), f("low"), f("high"), f("value"))
}

#[test]
fn instances_of_both_rigs_are_written_as_folders_that_bench_detection_scores() {
    let scratch = scratch::ScratchDir::new("instances");
    for (rig, cycles) in [("press", ["press", "handling"]), ("lift", ["lift", "handling"])] {
        let out = scratch.join(rig);
        let o = leakwatch(&[
            "bench",
            "instances",
            "--rig",
            rig,
            "--instances",
            "1",
            "--seed",
            "4",
            "--hours-healthy",
            "0.01",
            "--run-seconds",
            "15",
            "--commission-seconds",
            "40",
            "--temp-c",
            "--out",
            out.to_str().unwrap_or_default(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{err}");
        let inst = out.join("inst_000");
        // the catalogue's config holds no drawn value; the simulator's does
        let sheet = std::fs::read_to_string(inst.join("datasheet.toml")).unwrap_or_default();
        assert!(sheet.contains("[datasheet.valve]") && sheet.contains("null_leakage_l_min = 0.3"));
        // (the model's line resistance is commissioning's to identify: 0 there)
        assert!(
            sheet
                .lines()
                .filter(|l| l.contains("line_resistance"))
                .all(|l| l.trim_end() == "line_resistance_pa_s_per_m3 = 0.0"),
            "{sheet}"
        );
        let sim = std::fs::read_to_string(inst.join("instance.toml")).unwrap_or_default();
        assert!(sim.contains("line_resistance_pa_s_per_m3") && !sim.contains("[datasheet"));
        let commission = json(&inst.join("commission_cold.truth.json"));
        let t0 = commission["oil_temperature"]["start_c"]
            .as_f64()
            .unwrap_or(f64::NAN);
        assert!([20.0, 30.0, 50.0].contains(&t0), "{t0}");
        assert_eq!(commission["scenario"]["name"], cycles[0]);
        // 36 s of healthy runs of 15 s: 3 runs, then 9 leaks
        let runs: Vec<serde_json::Value> = (0..12)
            .map(|k| json(&inst.join(format!("run_{k:03}")).join("truth.json")))
            .collect();
        assert!(!inst.join("run_012").exists());
        assert_eq!(runs.iter().filter(|t| t["fault"].is_null()).count(), 3);
        for t in &runs {
            let oil = &t["oil_temperature"];
            for k in ["start_c", "end_c"] {
                let c = oil[k].as_f64().unwrap_or(f64::NAN);
                assert!((20.0..=60.0).contains(&c), "{k} {c}: {t:#}");
            }
            let tau = oil["time_constant_s"].as_f64().unwrap_or(f64::NAN);
            assert!((60.0..=600.0).contains(&tau), "{tau}");
            assert!(cycles.contains(&t["scenario"]["name"].as_str().unwrap_or_default()));
            if !t["fault"].is_null() {
                let on = t["fault"]["t_on_s"].as_f64().unwrap_or(f64::NAN);
                assert!((5.0..=10.0).contains(&on), "{on}");
                let flow = t["fault"]["observed_mean_abs_flow_lpm_after_ramp"]
                    .as_f64()
                    .unwrap_or(f64::NAN);
                // sized at its path's mean drop before it opens: it passes about its size
                // (less once it has lowered its chamber's pressure)
                let size = t["fault"]["size_lpm"].as_f64().unwrap_or(f64::NAN);
                assert!(
                    flow > 0.6 * size && flow < 1.2 * size,
                    "{flow} L/min for {size}: {t:#}"
                );
                let dp = t["fault"]["calib_mean_dp_Pa"].as_f64().unwrap_or(f64::NAN);
                assert!(dp > 1e5 && dp < 21e6, "{dp}");
            }
        }
        // the samples carry the oil's temperature, to 0.1 °C
        let csv = std::fs::read_to_string(inst.join("run_000").join("measured.csv")).unwrap_or_default();
        let last = csv.lines().last().unwrap_or_default();
        let temp: f64 = last
            .rsplit(',')
            .next()
            .and_then(|v| v.parse().ok())
            .unwrap_or(f64::NAN);
        assert!((20.0..=60.0).contains(&temp), "{last}");
        // the instance differs from its datasheet within the tolerances
        let t = &runs[0];
        let (nominal, low, high, mass) = drawn(t, "model.mass_kg");
        assert!((low..high).contains(&mass) && mass != nominal, "{mass}");
        assert!((high / nominal - 1.08).abs() < 1e-12, "{high}");
        let (_, _, _, beta) = drawn(t, "model.bulk_modulus_pa");
        assert!((1.1e9..1.6e9).contains(&beta), "{beta}");
        let (_, _, _, lag) = drawn(t, "sensors.pressure_lag_s");
        assert!((2e-4..1e-3).contains(&lag), "{lag}");
        // every run of the instance shares the one draw
        assert!(runs.iter().all(|r| r["instance"] == t["instance"]));
        // bench detection commissions on the folder's recording and scores every run
        let scored = scratch.join(format!("{rig}-scored"));
        let o = leakwatch(&[
            "bench",
            "detection",
            "--data",
            inst.to_str().unwrap_or_default(),
            "--out",
            scored.to_str().unwrap_or_default(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{err}");
        assert!(err.contains("commissioning on"), "{err}");
        let r = json(&scored.join("detection.json"));
        let rows = r["runs"].as_array().map_or(0, Vec::len);
        assert_eq!(rows, 12, "{r:#}");
        scores_the_identification_against_the_draw(&inst, t0);
    }
}

/// `bench calibration --data` on an instance folder scores the identification
/// against the drawn rig at the commissioning's oil temperature `t0_c` (°C).
fn scores_the_identification_against_the_draw(inst: &Path, t0_c: f64) {
    let o = leakwatch(&[
        "bench",
        "calibration",
        "--data",
        inst.to_str().unwrap_or_default(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_default();
    let param = |name: &str| -> serde_json::Value {
        r["params"]
            .as_array()
            .and_then(|a| {
                a.iter()
                    .find(|p| p["name"].as_str().unwrap_or_default().starts_with(name))
            })
            .cloned()
            .unwrap_or_else(|| panic!("no {name}: {r:#}"))
    };
    let value = |p: &serde_json::Value, k: &str| p[k].as_f64().unwrap_or(f64::NAN);
    let commission = json(&inst.join("commission_cold.truth.json"));
    // the datasheet's Cd, spool gain and density are the instance's: the
    // drawn area gradient is the truth as it stands (mm²/mm)
    let (_, _, _, gradient) = drawn(&commission, "model.area_gradient_m2_per_m");
    let flow = param("port A area gradient");
    assert!((value(&flow, "truth") - 1e3 * gradient).abs() < 1e-9, "{flow:#}");
    assert!(value(&flow, "error_pct").abs() < 2.0, "{flow:#}");
    // the oil's law moves the drawn bulk modulus (at 40 °C) by −0.45 %/K
    let (_, _, _, beta) = drawn(&commission, "model.bulk_modulus_pa");
    let stiffness = param("effective bulk modulus");
    let at_t0 = 1e-6 * beta * (1.0 - 0.0045 * (t0_c - 40.0));
    assert!(
        (value(&stiffness, "truth") / at_t0 - 1.0).abs() < 1e-9,
        "{stiffness:#}"
    );
    assert!(value(&stiffness, "error_pct").abs() < 20.0, "{stiffness:#}");
    // and the dry friction by −0.4 %/K
    let (_, _, _, slip) = drawn(&commission, "model.friction.slip_n");
    let coulomb = param("Coulomb friction");
    let at_t0 = slip * (1.0 - 0.004 * (t0_c - 40.0));
    assert!(
        (value(&coulomb, "truth") / at_t0 - 1.0).abs() < 1e-9,
        "{coulomb:#}"
    );
}
