//! What a replay tells: its plot, how long it watched or that it never armed, a temp_c column.

use crate::common::*;

use crate::{json, replay, simulate};

#[test]
fn plot_draws_a_replay_directory() {
    let d = tmpdir("plot");
    let input = simulate(&d, "closed-loop-sine", "12", "int:0.5lpm@8s");
    // the PNG of a replay with `extra` arguments
    let figure = |name: &str, extra: &[&str]| -> Vec<u8> {
        let out = d.join(name);
        assert!(replay(&input, &out, extra).status.success());
        let png = d.join(format!("{name}.png"));
        let o = leakwatch(&["plot", out.to_str().unwrap(), "--out", png.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        bytes
    };
    let four = figure("out", &[]).len();
    assert!(four > 20_000, "a figure with four panels: {four} bytes");
    // with the thesis filter's columns (--model 7): its residuals and MAE, a fifth panel
    let five = figure("with", &["--model", "7"]).len();
    assert!(five > four + 5_000, "five panels {five} bytes, four {four} bytes");
    // Parquet estimates are not drawn: the error says how to get a CSV
    let pq = d.join("pq");
    assert!(replay(&input, &pq, &["--estimates", "parquet"]).status.success());
    let o = leakwatch(&[
        "plot",
        pq.to_str().unwrap(),
        "--out",
        d.join("pq.png").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--estimates csv"), "{err}");
    assert!(!d.join("pq.png").exists());
}

/// A replay says how much of the run the detector watched, and plainly when it
/// never armed: a 5 s recording is too short to learn the healthy state, so no
/// leak could have been seen (it used to end with "0 events" and exit 0 as if
/// the rig had been watched). A 30 s recording is watched from its first seconds.
#[test]
fn a_replay_says_how_long_it_watched_and_when_it_never_armed() {
    let d = tmpdir("watch");
    let short = simulate(&d, "closed-loop-sine", "5", "none");
    let out = d.join("short");
    let o = replay(&short, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    // exit status 3: it ran, but could not watch
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("NOT WATCHED: the leak detector never armed"),
        "{err}"
    );
    let w = &json(&out.join("summary.json"))["watch"];
    assert!(w["armed_at_s"].is_null(), "{w}");
    assert_eq!(w["watched_s"].as_f64(), Some(0.0), "{w}");
    assert!(
        w["not_armed"].as_str().unwrap().contains("warm-up too short"),
        "{w}"
    );

    let d2 = d.join("long");
    std::fs::create_dir_all(&d2).unwrap();
    let long = simulate(&d2, "closed-loop-sine", "30", "none");
    let out = d.join("long-out");
    let o = replay(&long, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success() && err.contains("watched "), "{err}");
    let w = &json(&out.join("summary.json"))["watch"];
    let (run, watched) = (w["run_s"].as_f64().unwrap(), w["watched_s"].as_f64().unwrap());
    eprintln!("{w}");
    assert!((run - 29.999).abs() < 1e-6, "{w}");
    assert!(watched > 0.6 * run && watched <= run, "{w}");
}

/// A rig with an oil thermometer: `simulate` writes the warming oil as the
/// `temp_c` column (to 0.1 °C), and `replay` follows it: it says the range it
/// followed, summary.json has it, and the oil-stiffness scale θ stays near 1
/// (the model's bulk modulus is the oil's at each temperature).
#[test]
fn a_temp_c_column_is_followed_and_said() {
    let d = tmpdir("temp");
    let cfg = d.join("warming.toml");
    std::fs::write(
        &cfg,
        "[model.oil_temperature]\nreference_c = 20.0\n\
         [sim.oil]\nstart_c = 20.0\nend_c = 50.0\ntime_constant_s = 5.0\nmeasured = true\n",
    )
    .unwrap();
    let csv = d.join("warm.csv");
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        "closed-loop-sine",
        "--seconds",
        "20",
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().ends_with(",temp_c"));
    assert!(lines.next().unwrap().ends_with(",20.0"), "starts at 20 °C");
    assert!(
        text.lines().last().unwrap().ends_with(",49.5"),
        "20 s of τ = 5 s: 49.45 °C"
    );
    let out = d.join("out");
    let o = replay(&csv, &out, &["--config", cfg.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("oil temperature: 20.0 to 49.5 °C (temp_c): the model followed it"),
        "{err}"
    );
    let s = json(&out.join("summary.json"));
    let range = &s["leak_filter"]["oil_temp_range_c"];
    assert_eq!(
        (range[0].as_f64(), range[1].as_f64()),
        (Some(20.0), Some(49.5)),
        "{s:#}"
    );
    let theta = s["leak_filter"]["bulk_scale"].as_f64().unwrap();
    assert!((theta - 1.0).abs() < 0.03, "θ {theta}");
    // inside the default operating range (20-60 °C) all along
    assert_eq!(
        s["leak_filter"]["oil_outside_range_s"].as_f64(),
        Some(0.0),
        "{s:#}"
    );
    assert!(!err.contains("outside the operating range"), "{err}");
    // with the range's top at 40 °C, the oil passes it at 5 ln 3 = 5.49 s
    let narrow = d.join("narrow.toml");
    let text = std::fs::read_to_string(&cfg).unwrap();
    std::fs::write(
        &narrow,
        text.replace("reference_c = 20.0", "reference_c = 20.0\noperating_max_c = 40.0"),
    )
    .unwrap();
    let out = d.join("out_narrow");
    let o = replay(&csv, &out, &["--config", narrow.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("the oil was outside the operating range 20-40 °C"),
        "{err}"
    );
    let s = json(&out.join("summary.json"));
    let outside = s["leak_filter"]["oil_outside_range_s"].as_f64().unwrap();
    let first = s["leak_filter"]["first_oil_outside_range_s"].as_f64().unwrap();
    assert!((first - 5.49).abs() < 0.1, "first outside at {first} s");
    assert!((outside - (20.0 - 5.49)).abs() < 0.15, "{outside} s outside");
}
