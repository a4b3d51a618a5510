//! `leakwatch plot`: figures of simulated or measured runs and of recorded logs.

use std::path::Path;

use plot::{Figure, Panel, Series};

fn series(label: &str, x: &[f64], y: Vec<f64>) -> Series {
    Series::line(label, x, &y)
}

/// `leakwatch plot`: a replay output directory, a recorded log (.mcap) or a CSV
/// run drawn into `out`.
pub fn command(input: &Path, out: &Path, force: bool) -> Result<(), String> {
    if input.is_dir() {
        plot_replay(input, out, force)?;
    } else if input.extension().is_some_and(|e| e == "mcap") {
        plot_log(input, out, force)?;
    } else {
        plot_run_csv(input, out, force)?;
    }
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// Draws a run in the CSV format: rod position and reference, both pressures,
/// valve command and leak flow on a shared time axis.
pub fn plot_run_csv(input: &Path, out: &Path, force: bool) -> Result<(), String> {
    let ds = dataset::read_csv(input, dataset::Limits::default()).map_err(|e| e.to_string())?;
    crate::out::check(out, force, &[input])?;
    let s = &ds.samples;
    let t: Vec<f64> = s.iter().map(|s| s.t_s).collect();
    let col = |f: fn(&model::Sample) -> f64, scale: f64| s.iter().map(|s| f(s) * scale).collect::<Vec<f64>>();
    let mut pos =
        Panel::new("Rod position", "x [mm]").with_series(series("measured x", &t, col(|s| s.x_m, 1e3)));
    if ds.has_optional[2] {
        pos = pos.with_series(series("reference", &t, col(|s| s.ref_m, 1e3)));
    }
    let pres = Panel::new("Chamber pressures", "p [MPa]")
        .with_series(series("p1", &t, col(|s| s.p1_pa, 1e-6)))
        .with_series(series("p2", &t, col(|s| s.p2_pa, 1e-6)));
    let cmd = Panel::new("Valve command", "u [V]").with_series(series("u", &t, col(|s| s.u_v, 1.0)));
    let mut panels = vec![pos, pres, cmd];
    if ds.has_optional[3] {
        panels.push(Panel::new("Leak flow", "q_leak [L/min]").with_series(series(
            "q_leak",
            &t,
            col(|s| s.q_leak_lpm, 1.0),
        )));
    }
    let title = input
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut fig = Figure::new(&title, "t [s]");
    fig.panels = panels;
    crate::out::png(&fig, out, force, &[input])
}

/// Draws a recorded log: the sensor frames as [`plot_run_csv`] does (rod
/// position and reference, pressures, valve command), the leak flows the
/// classifier estimated (health frames, 10 Hz) beside the flow channel where
/// the log has one, and the leak events raised.
pub fn plot_log(input: &Path, out: &Path, force: bool) -> Result<(), String> {
    let (log, _, _) = crate::logs::read_log(input)?;
    if log.frames.is_empty() {
        return Err(format!(
            "{}: no sensor frame could be read from the log",
            input.display()
        ));
    }
    if let Some(why) = &log.truncated {
        eprintln!("warning: {}: {why}; drawing what is complete", input.display());
    }
    crate::out::check(out, force, &[input])?;
    let f = &log.frames;
    let t: Vec<f64> = f.iter().map(|f| f.t_s).collect();
    let col = |g: fn(&frames::SensorFrame) -> f64, k: f64| f.iter().map(|f| g(f) * k).collect::<Vec<f64>>();
    let present = |g: fn(&frames::SensorFrame) -> f64| f.iter().any(|f| !g(f).is_nan());
    let mut markers = Vec::new();
    for e in log
        .events
        .iter()
        .filter(|e| e.phase == frames::event_phase::RAISED)
    {
        let kind = frames::code_name(&frames::event_kind::NAMES, e.kind);
        if matches!(kind.as_ref(), "ext1" | "ext2" | "int") {
            markers.push(plot::Marker::Vertical {
                x: e.t_detect_s,
                label: format!("{kind} detected ({})", frames::detector_name(&e.detector)),
            });
        }
    }
    let with_markers = |mut p: Panel| {
        for m in &markers {
            p = p.with_marker(m.clone());
        }
        p
    };
    let mut pos =
        Panel::new("Rod position", "x [mm]").with_series(series("measured x", &t, col(|f| f.x_m, 1e3)));
    if present(|f| f.ref_m) {
        pos = pos.with_series(series("reference", &t, col(|f| f.ref_m, 1e3)));
    }
    let pres = Panel::new("Chamber pressures", "p [MPa]")
        .with_series(series("p1", &t, col(|f| f.p1_pa, 1e-6)))
        .with_series(series("p2", &t, col(|f| f.p2_pa, 1e-6)));
    let cmd = Panel::new("Valve command", "u [V]").with_series(series("u", &t, col(|f| f.u_v, 1.0)));
    let mut leak = Panel::new("Leak flow: estimated (health frames)", "q [L/min]");
    if present(|f| f.q_leak_lpm) {
        leak = leak.with_series(series("q_leak channel", &t, col(|f| f.q_leak_lpm, 1.0)));
    }
    let th: Vec<f64> = log.health.iter().map(|h| h.t_s).collect();
    for (i, name) in ["ext1", "ext2", "int"].iter().enumerate() {
        let q: Vec<f64> = log.health.iter().map(|h| h.leak_flow_lpm[i]).collect();
        if q.iter().any(|v| !v.is_nan()) {
            leak = leak.with_series(series(&format!("{name} estimated"), &th, q));
        }
    }
    let title = input
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut fig = Figure::new(&title, "t [s]");
    fig.panels = vec![with_markers(pos), pres, cmd, with_markers(leak)];
    crate::out::png(&fig, out, force, &[input])
}

/// Reads a CSV with a header into named columns (non-numbers become NaN).
fn read_columns(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .ok_or_else(|| format!("{}: empty file", path.display()))?
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for line in lines {
        for (i, cell) in line.split(',').enumerate().take(header.len()) {
            cols[i].push(cell.trim().parse::<f64>().unwrap_or(f64::NAN));
        }
    }
    Ok((header, cols))
}

/// Draws a replay directory (estimates.csv, events.json): measured against
/// estimated position and pressures, the residuals (and MAE) of the thesis
/// filter when it ran, else of the leak filter, and the leak filter's leak
/// sizes, with detections and onsets marked.
pub fn plot_replay(dir: &Path, out: &Path, force: bool) -> Result<(), String> {
    let (header, cols) = read_columns(&dir.join("estimates.csv"))?;
    crate::out::check(
        out,
        force,
        &[&dir.join("estimates.csv"), &dir.join("events.json")],
    )?;
    let col = |name: &str| -> Result<&Vec<f64>, String> {
        header
            .iter()
            .position(|h| h == name)
            .map(|i| &cols[i])
            .ok_or_else(|| format!("{}: no column `{name}`", dir.join("estimates.csv").display()))
    };
    let scaled =
        |name: &str, k: f64| -> Result<Vec<f64>, String> { Ok(col(name)?.iter().map(|v| v * k).collect()) };
    let t = col("t")?.clone();
    let mut markers = Vec::new();
    if let Ok(text) = std::fs::read_to_string(dir.join("events.json")) {
        if let Ok(events) = serde_json::from_str::<Vec<serde_json::Value>>(&text) {
            for e in events.iter().filter(|e| e["phase"] == "raised") {
                let kind = e["kind"].as_str().unwrap_or("?");
                if !matches!(kind, "ext1" | "ext2" | "int") {
                    continue;
                }
                let det = e["detector"].as_str().unwrap_or("");
                if let Some(td) = e["t_detect_s"].as_f64() {
                    markers.push(plot::Marker::Vertical {
                        x: td,
                        label: format!("{kind} detected ({det})"),
                    });
                }
                if det == "leak-size" {
                    if let Some(to) = e["t_onset_s"].as_f64() {
                        markers.push(plot::Marker::Vertical {
                            x: to,
                            label: "estimated onset".into(),
                        });
                    }
                }
            }
        }
    }
    let with_markers = |mut p: Panel| {
        for m in &markers {
            p = p.with_marker(m.clone());
        }
        p
    };
    let leaks = with_markers(
        Panel::new("Leak filter: estimated leak sizes at nominal drop", "q [L/min]")
            .with_series(series("q_e1", &t, scaled("q_e1_lpm", 1.0)?))
            .with_series(series("q_e2", &t, scaled("q_e2_lpm", 1.0)?))
            .with_series(series("q_i", &t, scaled("q_i_lpm", 1.0)?)),
    );
    // the thesis filter's columns are there when it ran (--model, --thesis-baseline):
    // then its pressures and residuals are drawn, else the leak filter's
    let thesis = col("th_x").is_ok();
    let (name, who, pre) = if thesis {
        ("Thesis filter", "thesis filter", "th_")
    } else {
        ("Leak filter", "leak filter", "")
    };
    let mut pos = Panel::new("Rod position: measured and estimated", "x [mm]");
    if thesis {
        pos = pos.with_series(series("thesis filter", &t, scaled("th_x", 1e3)?));
    }
    let pos = pos
        .with_series(series("leak filter", &t, scaled("x", 1e3)?))
        .with_series(series("measured", &t, scaled("x_meas", 1e3)?));
    let pres = Panel::new("Chamber pressures: measured and estimated", "p [MPa]")
        .with_series(series("p1 measured", &t, scaled("p1_meas", 1e-6)?))
        .with_series(series("p2 measured", &t, scaled("p2_meas", 1e-6)?))
        .with_series(series(
            &format!("p1 {who}"),
            &t,
            scaled(&format!("{pre}p1"), 1e-6)?,
        ))
        .with_series(series(
            &format!("p2 {who}"),
            &t,
            scaled(&format!("{pre}p2"), 1e-6)?,
        ));
    let resid = Panel::new(&format!("{name}: a-posteriori pressure residuals"), "e [kPa]")
        .with_series(series("e p1", &t, scaled(&format!("{pre}r_p1"), 1e-3)?))
        .with_series(series("e p2", &t, scaled(&format!("{pre}r_p2"), 1e-3)?));
    let mut panels = vec![pos, pres, resid];
    if thesis {
        panels.push(with_markers(
            Panel::new(
                "Thesis filter: MAE of the pressure residuals (4000 samples)",
                "MAE [kPa]",
            )
            .with_series(series("MAE p1", &t, scaled("th_mae_p1", 1e-3)?))
            .with_series(series("MAE p2", &t, scaled("th_mae_p2", 1e-3)?)),
        ));
    }
    panels.push(leaks);
    let title = format!("replay {}", dir.display());
    let mut fig = Figure::new(&title, "t [s]");
    fig.panels = panels;
    crate::out::png(
        &fig,
        out,
        force,
        &[&dir.join("estimates.csv"), &dir.join("events.json")],
    )
}
