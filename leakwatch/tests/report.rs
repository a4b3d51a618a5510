//! The reports and figures a user reads: `commission`'s HTML record beside its
//! TOML (its numbers the TOML's and the terminal's, no external resource, it
//! opens in headless Chromium), and `plot`'s leak panel of a replay as the
//! detector saw it (its SVG: the thresholds and rises at their values).

mod common;

use std::path::Path;

use common::{leakwatch, stderr, tmpdir};

/// `simulate` of the built-in rig into `out`.
fn simulate(args: &[&str], out: &Path) {
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    let o = leakwatch(&all);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The numbers of the report's table row named `name` (the cells after it).
fn row(html: &str, name: &str) -> Vec<String> {
    let start = html
        .find(&format!("<tr><td>{name}</td>"))
        .unwrap_or_else(|| panic!("no row {name}"));
    let end = start + html[start..].find("</tr>").unwrap();
    html[start..end]
        .split("<td class=\"n\">")
        .skip(1)
        .map(|c| c.split('<').next().unwrap().to_string())
        .collect()
}

/// True where headless Chromium runs; false (the test skips) only where it is
/// not required (LEAKWATCH_REQUIRE_CHROMIUM unset: CI sets it).
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser"].into_iter().find(|c| {
        std::process::Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    });
    if found.is_none() {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_CHROMIUM").is_err(),
            "chromium is required (.ci/setup installs it)"
        );
        eprintln!("SKIPPED: chromium is not installed");
    }
    found
}

/// `commission` writes rig.html beside rig.toml: the thresholds, offsets,
/// smallest detectable leaks and mean NIS are the terminal's and the TOML's
/// (to their printed decimals); the page loads nothing from outside and opens
/// in headless Chromium (a screenshot is taken).
#[test]
fn the_commissioning_record_holds_the_terminals_and_the_tomls_numbers() {
    let d = tmpdir("commission_report");
    let healthy = d.join("healthy.csv");
    simulate(
        &[
            "--scenario",
            "closed-loop-random",
            "--seconds",
            "25",
            "--seed",
            "5",
        ],
        &healthy,
    );
    let toml_path = d.join("rig.toml");
    let o = leakwatch(&[
        "commission",
        healthy.to_str().unwrap(),
        "--out",
        toml_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let html_path = d.join("rig.html");
    assert!(
        err.contains(&format!(
            "wrote {} (the commissioning record)",
            html_path.display()
        )),
        "{err}"
    );
    let html = std::fs::read_to_string(&html_path).unwrap();

    // the thresholds: the terminal's line, the report's row
    let line = err
        .lines()
        .find_map(|l| l.strip_prefix("the detector will raise leaks from "))
        .expect("the thresholds are stated");
    let terminal: Vec<String> = line
        .split(' ')
        .next()
        .unwrap()
        .split('/')
        .map(str::to_string)
        .collect();
    assert_eq!(row(&html, "threshold"), terminal);
    // the offsets: the TOML's values, the terminal's and the report's
    let t: toml::Table = toml::from_str(&std::fs::read_to_string(&toml_path).unwrap()).unwrap();
    let c = &t["classifier"]["commissioning"];
    let offsets: Vec<String> = c["offsets_lpm"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{:.3}", v.as_float().unwrap()))
        .collect();
    assert_eq!(row(&html, "healthy offset"), offsets);
    assert!(
        err.contains(&format!("offsets ext1/ext2/int {} L/min", offsets.join("/"))),
        "{err}"
    );
    let spreads: Vec<String> = c["spreads_lpm"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{:.3}", v.as_float().unwrap()))
        .collect();
    assert_eq!(row(&html, "healthy spread"), spreads);
    // the smallest detectable leaks per oil temperature
    for temp in ["20", "40", "60"] {
        let at = err.split(&format!("{temp} °C ")).nth(1).unwrap();
        let v: Vec<String> = at
            .split([',', ' ', '\n'])
            .next()
            .unwrap()
            .split('/')
            .map(str::to_string)
            .collect();
        assert_eq!(
            row(&html, &format!("smallest detectable at {temp} °C")),
            v,
            "{temp} °C"
        );
    }
    // the mean NIS: the TOML's, to the terminal's one decimal
    let nis = format!("{:.1}", c["nis_mean"].as_float().unwrap());
    assert!(
        err.contains(&format!("mean NIS on this recording is {nis} ")),
        "{err}"
    );
    assert!(html.contains(&format!("mean NIS on this recording: <b>{nis}</b>")));
    // an identified parameter's line: value and σ as the terminal prints them
    let bulk = err
        .lines()
        .find(|l| l.trim_start().starts_with("effective bulk modulus: "))
        .unwrap();
    let value = bulk.split(": ").nth(1).unwrap().split(' ').next().unwrap();
    assert!(
        html.contains(&format!(
            "<td>effective bulk modulus</td><td class=\"n\">{value}</td>"
        )),
        "{bulk}"
    );

    // self-contained: nothing fetched from outside
    for bad in ["src=", "href=", "@import", "url(", "<link", "<script"] {
        assert!(!html.contains(bad), "the report holds `{bad}`");
    }
    assert!(html.contains("<svg") && html.contains("@page { size: A4"));

    if let Some(browser) = chromium() {
        let shot = d.join("rig.png");
        let o = std::process::Command::new(browser)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--no-first-run",
                "--window-size=794,1123",
                &format!("--user-data-dir={}", d.join("chromium").display()),
                &format!("--screenshot={}", shot.display()),
                &format!("file://{}", html_path.display()),
            ])
            .output()
            .expect("chromium runs");
        assert!(o.status.success(), "{}", stderr(&o));
        let png = std::fs::read(&shot).expect("the screenshot is written");
        assert!(
            png.len() > 10_000 && png.starts_with(b"\x89PNG"),
            "{} bytes",
            png.len()
        );
    }
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
