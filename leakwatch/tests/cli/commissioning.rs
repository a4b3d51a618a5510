//! `calibrate` and `commission`: a hidden leak named, a healthy record's model, the null bias.

use crate::common::*;

use crate::simulate_random;

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
        .find_map(|l| l.strip_prefix("the detector will name leaks from "))
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
    // and the smallest transducer offsets it names on this duty cycle: the
    // pressures' at 0.5 % of the 20.7 MPa range, 1 % drifting (their
    // response shows 19/30 kPa); x's where its response shows it (measured
    // 4.1 mm), within the 1-15 mm the detector fits
    let reach = err
        .lines()
        .find(|l| l.starts_with("transducer offsets named"))
        .expect("the transducers' reach is stated");
    assert!(
        reach.contains("p1 from 104 kPa, p2 from 104 kPa") && reach.contains("207 kPa for a drifting one"),
        "{reach}"
    );
    let x_mm: f64 = reach
        .split("x from ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("x is watched on the thesis rig: {reach}"));
    assert!((1.0..=15.0).contains(&x_mm), "{reach}");
}
