//! `leakwatch plot`: figures of simulated or measured runs and of recorded logs.

use std::path::Path;

use pipeline::replay::figure::{self, read_columns};
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
    crate::out::figure(&fig, out, force, &[input])
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
    crate::out::figure(&fig, out, force, &[input])
}

/// The markers of the replay's leak events (its events.json; none when it
/// cannot be read), as [`figure::event_markers`] places them.
fn event_markers(dir: &Path) -> Vec<plot::Marker> {
    let Ok(text) = std::fs::read_to_string(dir.join("events.json")) else {
        return Vec::new();
    };
    let Ok(events) = serde_json::from_str::<Vec<serde_json::Value>>(&text) else {
        return Vec::new();
    };
    figure::event_markers(&events)
}

/// The leak panel as the detector saw it (detector.csv, [`figure::DetectorView::panel`]);
/// `None` when the replay wrote no detector.csv.
fn detector_panel(
    dir: &Path,
    t_first_s: f64,
    truth: Option<(Vec<f64>, Vec<f64>)>,
) -> Result<Option<Panel>, String> {
    Ok(figure::DetectorView::read(dir)?.map(|v| v.panel(t_first_s, truth)))
}

/// The true leak flow of the replay's input (its `q_leak` column), when the
/// input named in summary.json is there and has one that is not all zero.
fn truth_of(dir: &Path) -> Option<(Vec<f64>, Vec<f64>)> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let summary: serde_json::Value = serde_json::from_str(&text).ok()?;
    let input = Path::new(summary["input"].as_str()?);
    let ds = dataset::read_csv(input, dataset::Limits::default()).ok()?;
    figure::truth(&ds)
}

/// The figure's title: the replay's input and its folder.
fn replay_title(dir: &Path) -> String {
    let input = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["input"].as_str().map(str::to_string));
    let name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default()
    };
    match input {
        Some(i) => format!("replay of {} (folder {})", name(Path::new(&i)), name(dir)),
        None => format!("replay folder {}", name(dir)),
    }
}

/// Draws a replay directory (estimates.csv, events.json, detector.csv):
/// measured against estimated position and pressures, the residuals (and MAE)
/// of the thesis filter when it ran, else of the leak filter, and the leak
/// panel as the detector saw it (or, for a replay without detector.csv, the
/// leak filter's sizes), with the onsets and alarms marked.
pub fn plot_replay(dir: &Path, out: &Path, force: bool) -> Result<(), String> {
    if !dir.join("estimates.csv").exists() && dir.join("estimates.parquet").exists() {
        return Err(format!(
            "{}: its estimates are Parquet; `plot` draws estimates.csv: replay with `--estimates csv` \
             (`--estimates-every 10` for a long input)",
            dir.display()
        ));
    }
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
    let markers = event_markers(dir);
    let with_markers = |mut p: Panel| {
        for m in &markers {
            p = p.with_marker(m.clone());
        }
        p
    };
    let t0 = t.first().copied().unwrap_or(0.0);
    let leaks = match detector_panel(dir, t0, truth_of(dir))? {
        Some(p) => with_markers(p),
        None => with_markers(
            Panel::new("Leak filter: estimated leak sizes at nominal drop", "q [L/min]")
                .with_series(series("q_e1", &t, scaled("q_e1_lpm", 1.0)?))
                .with_series(series("q_e2", &t, scaled("q_e2_lpm", 1.0)?))
                .with_series(series("q_i", &t, scaled("q_i_lpm", 1.0)?)),
        ),
    };
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
    // the estimates first, the measured pressures drawn over them
    let pres = Panel::new("Chamber pressures: measured and estimated", "p [MPa]")
        .with_series(
            series(&format!("p1 {who}"), &t, scaled(&format!("{pre}p1"), 1e-6)?).colored(plot::PALETTE[3]),
        )
        .with_series(
            series(&format!("p2 {who}"), &t, scaled(&format!("{pre}p2"), 1e-6)?).colored(plot::PALETTE[4]),
        )
        .with_series(series("p1 measured", &t, scaled("p1_meas", 1e-6)?).colored(plot::PALETTE[0]))
        .with_series(series("p2 measured", &t, scaled("p2_meas", 1e-6)?).colored(plot::PALETTE[1]));
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
    let mut fig = Figure::new(&replay_title(dir), "t [s]");
    fig.panels = panels;
    crate::out::figure(
        &fig,
        out,
        force,
        &[&dir.join("estimates.csv"), &dir.join("events.json")],
    )
}
