//! The reports and figures a user reads: `commission`'s HTML record beside its
//! TOML (its numbers the TOML's and the terminal's, no external resource, it
//! opens in headless Chromium), and `plot`'s leak panel of a replay as the
//! detector saw it (its SVG: the thresholds and rises at their values).

#[path = "report/commissioning.rs"]
mod commissioning;
mod common;

use std::path::Path;

use common::html::{row, screenshot, self_contained};
use common::{leakwatch, stderr, tmpdir};

/// `simulate` of the built-in rig into `out`.
fn simulate(args: &[&str], out: &Path) {
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    let o = leakwatch(&all);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `plot --out X.svg` of a replay of a simulated 0.5 L/min ext1 leak draws
/// the leak panel as the detector saw it (detector.csv): each kind's
/// threshold (dashed, at the value detector.csv holds), the onset and the
/// alarms marked, the true leak flow; the SVG's y coordinates of the ext1
/// threshold are where the panel's axis puts its value.
#[test]
fn the_replay_figure_draws_the_detectors_view() {
    let d = tmpdir("plot_detector");
    let csv = d.join("leak.csv");
    simulate(
        &[
            "--scenario",
            "loaded-sine",
            "--seconds",
            "30",
            "--fault",
            "ext1:0.5lpm@20s",
        ],
        &csv,
    );
    let out = d.join("leak");
    let o = leakwatch(&["replay", csv.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let trace = std::fs::read_to_string(out.join("detector.csv")).unwrap();
    let mut lines = trace.lines();
    assert_eq!(
        lines.next(),
        Some("t,rise_e1_lpm,rise_e2_lpm,rise_i_lpm,threshold_e1_lpm,threshold_e2_lpm,threshold_i_lpm,blind")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // 100 Hz from arming on; after the leak the ext1 rise passes its threshold
    assert!(rows.len() > 1000, "{} rows", rows.len());
    assert!((rows[1][0] - rows[0][0] - 0.01).abs() < 1e-9);
    assert!(
        rows.iter().any(|r| r[0] > 21.0 && r[1] > r[4]),
        "ext1 never passed its threshold"
    );
    assert!(
        rows.iter().all(|r| r[0] > 20.0 || r[1] < r[4]),
        "a rise before the leak"
    );

    let svg_path = d.join("leak.svg");
    let o = leakwatch(&["plot", out.to_str().unwrap(), "--out", svg_path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    for text in [
        "ext1 threshold",
        "true leak flow",
        "pending alarm",
        "ext1 named",
        "onset",
        "warm-up: not armed",
        "replay of leak.csv",
    ] {
        assert!(svg.contains(text), "no `{text}` in the figure");
    }
    // the ext1 threshold's dashes (palette colour 0 = #1F77B4, dashed: two-point
    // polylines) sit at the value detector.csv holds, on the panel's y axis:
    // the leak panel is the last; its y tick labels give the axis
    let last_panel_top = svg.rfind("Leak-size detector").unwrap();
    let panel = &svg[last_panel_top..];
    // (a text element is `<text ... y="Y" ...>`, then `VALUE` and `</text>` on lines of their own)
    let lines: Vec<&str> = panel.lines().collect();
    let ticks: Vec<(f64, f64)> = lines
        .windows(2)
        .filter(|w| w[0].starts_with("<text") && w[0].contains("text-anchor=\"end\""))
        .filter_map(|w| {
            let y: f64 = w[0].split(" y=\"").nth(1)?.split('"').next()?.parse().ok()?;
            let v: f64 = w[1].trim().parse().ok()?;
            Some((v, y))
        })
        .collect();
    assert!(ticks.len() >= 3, "{ticks:?}");
    let (a, b) = (ticks[0], ticks[ticks.len() - 1]);
    let y_of = |v: f64| a.1 + (v - a.0) * (b.1 - a.1) / (b.0 - a.0);
    let thr = rows.last().unwrap()[4];
    // the dashes: short flat polylines of that colour left of the legend column
    let dashes: Vec<f64> = lines
        .iter()
        .filter(|l| l.starts_with("<polyline") && l.contains("stroke=\"#1F77B4\""))
        .filter_map(|l| {
            let pts: Vec<(f64, f64)> = l
                .split("points=\"")
                .nth(1)?
                .split('"')
                .next()?
                .split_whitespace()
                .filter_map(|p| {
                    let (x, y) = p.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect();
            let (x0, y0) = *pts.first()?;
            let x1 = pts.last()?.0;
            let flat = pts.iter().all(|p| (p.1 - y0).abs() <= 0.5);
            (flat && x1 - x0 <= 10.0 && x0 < 1200.0).then_some(y0)
        })
        .collect();
    assert!(!dashes.is_empty(), "no dashed threshold");
    let want = y_of(thr);
    assert!(
        dashes.iter().filter(|y| (**y - want).abs() <= 1.5).count() * 2 > dashes.len(),
        "threshold {thr} L/min should be at y {want:.1}; dashes at {dashes:?}"
    );
}

/// The numbers of a terminal gap line (`chamber 1 X kPa, chamber 2 Y kPa,
/// force F N, spool S µm per ...; normalised N`), as printed.
fn gap_of(line: &str) -> Vec<String> {
    let after = |key: &str| {
        line.split(key)
            .nth(1)
            .unwrap_or_else(|| panic!("no `{key}` in {line}"))
            .split([' ', '('])
            .next()
            .unwrap()
            .to_string()
    };
    vec![
        after("chamber 1 "),
        after("chamber 2 "),
        after("force "),
        after("spool "),
        after("normalised "),
    ]
}

/// `calibrate --identify` writes report.html beside model.toml: the
/// identified values with σ and the datasheet's as the terminal printed them,
/// the gap before, after each effect and after as the terminal's lines, each
/// effect named with calibration.json's parameters, model.toml's values of
/// them; no external resource, and it opens in headless Chromium.
#[test]
fn the_calibration_report_holds_the_terminals_and_the_files_numbers() {
    let d = tmpdir("calibrate_report");
    // a rig off the nominal one: a spool null offset and softer oil
    let rig = d.join("rig.toml");
    std::fs::write(
        &rig,
        "[rig]\nspool_null_bias_m = -8.0e-6\nbulk_modulus_pa = 4.8e8\n",
    )
    .unwrap();
    let healthy = d.join("healthy.csv");
    let args = "--scenario open-loop-sine --seconds 12 --seed 3 --config";
    let mut args: Vec<&str> = args.split(' ').collect();
    args.push(rig.to_str().unwrap());
    simulate(&args, &healthy);
    let cal = d.join("cal");
    let o = leakwatch(&[
        "calibrate",
        healthy.to_str().unwrap(),
        "--identify",
        "--out",
        cal.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (out, err) = (String::from_utf8_lossy(&o.stdout).to_string(), stderr(&o));
    let html_path = cal.join("report.html");
    assert!(
        out.contains(&format!(
            "{}, {}",
            cal.join("report.md").display(),
            html_path.display()
        )),
        "{out}"
    );
    let html = std::fs::read_to_string(&html_path).unwrap();

    // an identified parameter: value, σ and the datasheet's as the terminal prints them
    let bulk = err
        .lines()
        .find_map(|l| l.trim_start().strip_prefix("effective bulk modulus: "))
        .expect("the bulk modulus is identified");
    let words: Vec<&str> = bulk.split([' ', ')']).collect();
    let (value, sigma, sheet) = (words[0], words[2], words[6]);
    assert_eq!(
        row(&html, "effective bulk modulus")[..3],
        [value, sigma, sheet],
        "{bulk}"
    );
    // what was not identified, with the terminal's reason
    let esc = |t: &str| t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;");
    let mut not_identified = 0;
    for l in err
        .lines()
        .filter(|l| l.contains(": not identifiable from this recording: "))
    {
        let (name, why) = l
            .trim()
            .split_once(": not identifiable from this recording: ")
            .unwrap();
        assert!(html.contains(&esc(name)) && html.contains(&esc(why)), "{l}");
        not_identified += 1;
    }
    assert!(not_identified > 0, "{err}");

    // the gap before and after: the terminal's numbers
    let line = |prefix: &str| {
        out.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` in {out}"))
            .to_string()
    };
    let before = line("gap before (validation RMS): ");
    assert_eq!(row(&html, "before")[..5], gap_of(&before)[..]);
    let after = line("gap after: ");
    let smaller = after.split(" (").last().unwrap().split(' ').next().unwrap();
    let cells = row(&html, "after");
    assert_eq!(cells[..5], gap_of(&after)[..]);
    assert_eq!(cells[5], format!("{smaller} %"));

    // each effect: named as calibration.json names it, its share of the gap as
    // the terminal's, its parameters as the JSON's and model.toml's
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cal.join("calibration.json")).unwrap()).unwrap();
    let effects = json["effects"].as_array().unwrap();
    assert!(!effects.is_empty(), "{json:#}");
    let model: toml::Table =
        toml::from_str(&std::fs::read_to_string(cal.join("model.toml")).unwrap()).unwrap();
    for (i, e) in effects.iter().enumerate() {
        let name = e["name"].as_str().unwrap();
        let share = out
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{}. {name} (", i + 1)))
            .expect("the terminal names it");
        let share = share
            .split("explains ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap();
        let cells = row(&html, &format!("+ {}. {name}", i + 1));
        assert_eq!(cells[5], format!("{share} %"), "{name}");
        for (key, v) in e["parameters"].as_object().unwrap() {
            let v = v.as_f64().unwrap();
            assert!(
                html.contains(&format!("<td>{key}</td><td class=\"n\">{v:.4e}</td>")),
                "{name}: {key}"
            );
            // model.toml holds the calibrated model: a top-level [model] field equals it
            if let Some(m) = model["model"].get(key.as_str()).and_then(|x| x.as_float()) {
                assert_eq!(format!("{m:.4e}"), format!("{v:.4e}"), "{key}");
            }
        }
    }

    self_contained(&html);
    assert!(html.contains("<svg"), "the fit's figure");
    screenshot(&html_path, &d);
}

/// `replay` writes report.html into its folder: each leak alarm's times,
/// size and confidence are events.json's, the watched and blind seconds
/// summary.json's and the terminal's; the leak panel inline; no external
/// resource, and it opens in headless Chromium. `--no-report` writes none.
#[test]
fn the_replay_report_holds_the_events_and_the_summarys_numbers() {
    let d = tmpdir("replay_report");
    let csv = d.join("leak.csv");
    let args = "--scenario loaded-sine --seconds 20 --fault ext1:0.5lpm@10s";
    simulate(&args.split(' ').collect::<Vec<_>>(), &csv);
    let cfg = common::short_warmup_config(&d);
    let out = d.join("leak");
    let o = leakwatch(&[
        "replay",
        csv.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let html_path = out.join("report.html");
    let html = std::fs::read_to_string(&html_path).unwrap();
    assert!(html.contains("<title>Replay of leak.csv on the rig of cfg.toml</title>"));

    // the ext1 alarm: events.json's numbers
    let events: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("events.json")).unwrap()).unwrap();
    let leak_size: Vec<&serde_json::Value> = events
        .iter()
        .filter(|e| e["detector"] == "leak-size" && e["phase"] != "cleared")
        .collect();
    let first = leak_size.first().expect("the leak is raised");
    let named = leak_size
        .iter()
        .find(|e| e["kind"] == "ext1")
        .expect("the leak is named ext1");
    let latest = leak_size
        .iter()
        .rev()
        .find(|e| e["event_id"] == first["event_id"] && e["size_lpm"].is_f64())
        .unwrap();
    let f = |v: &serde_json::Value| format!("{:.3}", v.as_f64().unwrap());
    let cells = row(&html, "ext1");
    assert_eq!(cells[0], f(&first["t_detect_s"]), "raised at");
    assert_eq!(cells[1], f(&latest["t_onset_s"]), "onset");
    assert_eq!(cells[2], f(&latest["size_lpm"]), "size");
    assert_eq!(cells[3], f(&latest["size_lpm_sigma"]), "σ");
    assert_eq!(cells[4], format!("{:.2}", latest["confidence"].as_f64().unwrap()));
    assert!(
        html.contains(&format!("<td>named at {} s</td>", f(&named["t_detect_s"]))),
        "named"
    );
    // the onset near the leak's start (10 s), the size near the 0.5 L/min simulated
    let (onset, size): (f64, f64) = (cells[1].parse().unwrap(), cells[2].parse().unwrap());
    assert!(
        (onset - 10.0).abs() < 1.0 && (size - 0.5).abs() < 0.15,
        "{cells:?}"
    );

    // watched and blind: summary.json's, to the terminal's decimal
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let w = &summary["watch"];
    let one = |v: &serde_json::Value| format!("{:.1}", v.as_f64().unwrap());
    let (watched, run, armed, blind) = (
        one(&w["watched_s"]),
        one(&w["run_s"]),
        one(&w["armed_at_s"]),
        one(&w["blind_s"]),
    );
    assert!(
        err.contains(&format!("watched {watched} of {run} s"))
            && err.contains(&format!("armed at {armed} s, {blind} s without")),
        "{err}"
    );
    assert!(
        html.contains(&format!("Watched <b>{watched}</b> of <b>{run}</b> s"))
            && html.contains(&format!("armed at <b>{armed}</b> s, <b>{blind}</b> s blind")),
        "watch"
    );
    // the thresholds at the end: detector.csv's last row
    let trace = std::fs::read_to_string(out.join("detector.csv")).unwrap();
    let last: Vec<f64> = trace
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(
        row(&html, "threshold at the end"),
        [
            format!("{:.3}", last[4]),
            format!("{:.3}", last[5]),
            format!("{:.3}", last[6])
        ]
    );

    self_contained(&html);
    for text in ["ext1 threshold", "true leak flow", "ext1 named", "onset"] {
        assert!(html.contains(text), "no `{text}` in the figure");
    }
    screenshot(&html_path, &d);

    // --no-report: none
    let quiet = d.join("quiet");
    let o = leakwatch(&[
        "replay",
        csv.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "--estimates",
        "none",
        "--no-report",
        "--out",
        quiet.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(quiet.join("events.json").exists() && !quiet.join("report.html").exists());
}
