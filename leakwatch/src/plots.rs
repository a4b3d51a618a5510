//! `leakwatch plot`: figures of simulated or measured runs.

use std::path::Path;

use plot::{Figure, Panel, Series};

fn series(label: &str, x: &[f64], y: Vec<f64>) -> Series {
    Series::line(label, x, &y)
}

/// Draws a run in the CSV format: rod position and reference, both pressures,
/// valve command and leak flow on a shared time axis.
pub fn plot_run_csv(input: &Path, out: &Path) -> Result<(), String> {
    let ds = dataset::read_csv(input, dataset::Limits::default()).map_err(|e| e.to_string())?;
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
    plot::render_png(&fig, out).map_err(|e| e.to_string())
}
