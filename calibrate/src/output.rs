//! Writing the results: `calibration.json`, `model.toml` (a leakwatch
//! configuration with only its `[model]` table: `leakwatch replay|run|calibrate
//! --config model.toml`; its text is made by the caller, this crate writes no
//! TOML), `report.md` and its PNG plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use plot::{Figure, Marker, Panel, Series, Style};

use crate::{CalibrateError, Calibration, RegimeBin};

/// The files written by [`write_outputs`].
#[derive(Debug, Clone, PartialEq)]
pub struct OutputFiles {
    /// `DIR/calibration.json`.
    pub json: PathBuf,
    /// `DIR/model.toml`.
    pub model_toml: PathBuf,
    /// `DIR/report.md`.
    pub report: PathBuf,
    /// The PNG plots.
    pub plots: Vec<PathBuf>,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> CalibrateError + '_ {
    move |source| CalibrateError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn plot_err(e: plot::PlotError) -> CalibrateError {
    CalibrateError::Plot(e.to_string())
}

/// Writes `bytes` to `path` through [`dataset::output`] (no symbolic link followed).
fn write(path: &Path, bytes: &[u8], overwrite: bool, inputs: &[&Path]) -> Result<(), CalibrateError> {
    dataset::output::write_file(path, bytes, overwrite, inputs).map_err(io(path))
}

/// Renders `fig` and writes it as a PNG to `path` (an existing file replaced: the
/// caller has checked).
fn save_png(fig: &Figure, path: &Path) -> Result<(), CalibrateError> {
    let bytes = plot::encode_png(&plot::render(fig).map_err(plot_err)?).map_err(plot_err)?;
    write(path, &bytes, true, &[])
}

/// The files [`write_outputs`] may write into a directory.
const OUTPUT_NAMES: [&str; 7] = [
    "calibration.json",
    "model.toml",
    "report.md",
    "traces.png",
    "breakdown_position.png",
    "breakdown_velocity.png",
    "gap.png",
];

/// Writes `calibration.json`, `model.toml`, `report.md` and the plots into `out_dir`
/// (created if needed; not a symbolic link). `model_file` is the text of
/// `model.toml`, `cal.model_after` in the caller's config format (`leakwatch
/// calibrate` writes it as TOML). An existing output is replaced only if
/// `overwrite` (`--force`); none of `inputs` is ever replaced.
pub fn write_outputs(
    cal: &Calibration,
    out_dir: &Path,
    overwrite: bool,
    inputs: &[&Path],
    model_file: &str,
) -> Result<OutputFiles, CalibrateError> {
    dataset::output::create_dir(out_dir).map_err(io(out_dir))?;
    // Refuse before writing anything, rather than leave a half-replaced set.
    for name in OUTPUT_NAMES {
        let p = out_dir.join(name);
        dataset::output::check_replaceable(&p, overwrite, inputs).map_err(io(&p))?;
    }
    let json = out_dir.join("calibration.json");
    let text = serde_json::to_string_pretty(cal).map_err(|e| CalibrateError::Serialize(e.to_string()))?;
    write(&json, text.as_bytes(), true, inputs)?;
    let mt = out_dir.join("model.toml");
    write(&mt, model_file.as_bytes(), true, inputs)?;

    let mut plots = Vec::new();
    if !cal.traces.t_s.is_empty() {
        let p = out_dir.join("traces.png");
        plot_traces(cal, &p)?;
        plots.push(p);
    }
    for (regime, unit, file) in [
        ("position", "x [m]", "breakdown_position.png"),
        ("velocity", "v [m/s]", "breakdown_velocity.png"),
    ] {
        let p = out_dir.join(file);
        if plot_breakdown(cal, regime, unit, &p)? {
            plots.push(p);
        }
    }
    let g = out_dir.join("gap.png");
    plot_gap(cal, &g)?;
    plots.push(g);

    let report = out_dir.join("report.md");
    write(&report, report_md(cal, &plots).as_bytes(), true, inputs)?;
    Ok(OutputFiles {
        json,
        model_toml: mt,
        report,
        plots,
    })
}

fn plot_traces(cal: &Calibration, path: &Path) -> Result<(), CalibrateError> {
    save_png(&traces_figure(cal), path)
}

/// The figure of the fit (traces.png, and the HTML report's): the first 3 s
/// of the validation part's re-anchored windows, rod position (mm) and the
/// chamber pressures (MPa), measured against the model before and after.
pub fn traces_figure(cal: &Calibration) -> Figure {
    let tr = &cal.traces;
    // the first ~3 s of validation windows
    let mut n = 0;
    let mut finite = 0;
    for t in &tr.t_s {
        if t.is_finite() {
            finite += 1;
        }
        if finite > 3000 {
            break;
        }
        n += 1;
    }
    let t = &tr.t_s[..n];
    let mut fig = Figure::new(
        "Validation part: measured vs nominal model vs calibrated model (re-anchored windows)",
        "t [s]",
    );
    for (k, (title, unit, scale)) in [
        ("rod position", "x [mm]", 1e3),
        ("chamber 1 pressure", "p1 [MPa]", 1e-6),
        ("chamber 2 pressure", "p2 [MPa]", 1e-6),
    ]
    .iter()
    .enumerate()
    {
        let col = |v: &[[f64; 3]]| -> Vec<f64> { v[..n].iter().map(|a| a[k] * scale).collect() };
        fig.panels.push(
            Panel::new(title, unit)
                .with_series(Series::line("measured", t, &col(&tr.measured)).colored([0, 0, 0]))
                .with_series(Series::line("before (nominal)", t, &col(&tr.before)).styled(Style::Dashed))
                .with_series(Series::line("after (calibrated)", t, &col(&tr.after))),
        );
    }
    fig
}

fn plot_breakdown(cal: &Calibration, regime: &str, unit: &str, path: &Path) -> Result<bool, CalibrateError> {
    let pick = |b: &[RegimeBin]| -> Vec<RegimeBin> {
        b.iter()
            .filter(|r| r.regime == regime && r.count > 0)
            .cloned()
            .collect()
    };
    let before = pick(&cal.breakdown_before);
    let after = pick(&cal.breakdown_after);
    if before.is_empty() {
        return Ok(false);
    }
    let mut fig = Figure::new(
        &format!("Mean residual (model - measured) by {regime}, validation part"),
        unit,
    );
    for (k, (title, yl, scale)) in [
        ("rod position", "mean error x [mm]", 1e3),
        ("chamber 1 pressure", "mean error p1 [MPa]", 1e-6),
        ("chamber 2 pressure", "mean error p2 [MPa]", 1e-6),
    ]
    .iter()
    .enumerate()
    {
        let xb: Vec<f64> = before.iter().map(|r| r.centre).collect();
        let yb: Vec<f64> = before.iter().map(|r| r.mean[k] * scale).collect();
        let xa: Vec<f64> = after.iter().map(|r| r.centre).collect();
        let ya: Vec<f64> = after.iter().map(|r| r.mean[k] * scale).collect();
        fig.panels.push(
            Panel::new(title, yl)
                .with_series(Series::line("before", &xb, &yb))
                .with_series(Series::line("after", &xa, &ya)),
        );
    }
    save_png(&fig, path)?;
    Ok(true)
}

fn plot_gap(cal: &Calibration, path: &Path) -> Result<(), CalibrateError> {
    let mut steps = vec![cal.gap_before];
    steps.extend(cal.effects.iter().map(|e| e.gap_after));
    let x: Vec<f64> = (0..steps.len()).map(|i| i as f64).collect();
    let mut fig = Figure::new(
        "Validation gap (RMS) before and after each effect added (0 = nominal model)",
        "effects added",
    );
    let mut px = Panel::new("rod position", "RMS x [mm]").with_series(Series::line(
        "x",
        &x,
        &steps.iter().map(|g| g.x_m * 1e3).collect::<Vec<_>>(),
    ));
    for (i, e) in cal.effects.iter().enumerate() {
        px = px.with_marker(Marker::Vertical {
            x: (i + 1) as f64,
            label: format!("+ {}", e.name),
        });
    }
    fig.panels.push(px);
    fig.panels.push(
        Panel::new("chamber pressures", "RMS p [MPa]")
            .with_series(Series::line(
                "p1",
                &x,
                &steps.iter().map(|g| g.p1_pa * 1e-6).collect::<Vec<_>>(),
            ))
            .with_series(Series::line(
                "p2",
                &x,
                &steps.iter().map(|g| g.p2_pa * 1e-6).collect::<Vec<_>>(),
            )),
    );
    let mut pts = Series::line(
        "normalised",
        &x,
        &steps.iter().map(|g| g.normalised).collect::<Vec<_>>(),
    );
    if steps.len() == 1 {
        pts = pts.styled(Style::Points);
    }
    fig.panels
        .push(Panel::new("combined", "normalised RMS [-]").with_series(pts));
    save_png(&fig, path)
}

fn fmt_gap(g: &crate::Gap) -> String {
    format!(
        "x {:.3} mm, p1 {:.3} MPa, p2 {:.3} MPa, normalised {:.3}",
        g.x_m * 1e3,
        g.p1_pa * 1e-6,
        g.p2_pa * 1e-6,
        g.normalised
    )
}

/// The Markdown report.
pub fn report_md(cal: &Calibration, plots: &[PathBuf]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Calibration report\n");
    report_data(&mut s, cal);
    report_result(&mut s, cal);
    report_rounds(&mut s, cal);
    report_disagreement(&mut s, cal);
    report_plots(&mut s, plots);
    s
}

/// The report's opening: the data used, how it was compared and the input's warnings.
fn report_data(s: &mut String, cal: &Calibration) {
    let d = &cal.data;
    let how = match cal.options.method {
        crate::Method::EquationError => format!(
            "Compared by equation error: {} windows of {:.3} s, each checked from the measured state at \
             its start (chamber continuity, force balance, spool); {} fit and {} validate ({}). \
             Residuals are normalised by {:.3} MPa, {:.0} N and {:.2} µm of spool.",
            d.fit_windows + d.validation_windows,
            d.window_s,
            d.fit_windows,
            d.validation_windows,
            d.split,
            cal.options.scale_p_pa * 1e-6,
            cal.options.scale_f_n,
            cal.options.scale_sp_m * 1e6
        ),
        crate::Method::Shooting => format!(
            "Compared by multiple shooting: {} windows of {:.2} s, each simulated from the measured \
             state at its start; {} fit and {} validate ({}). Residuals are normalised by {:.3} mm and {:.3} MPa.",
            d.fit_windows + d.validation_windows,
            d.window_s,
            d.fit_windows,
            d.validation_windows,
            d.split,
            cal.options.scale_x_m * 1e3,
            cal.options.scale_p_pa * 1e-6
        ),
    };
    let _ = writeln!(
        s,
        "Data: {} samples ({:.1} s at {:.0} Hz). {how}\n",
        d.samples,
        d.seconds,
        1.0 / d.sample_period_s,
    );
    for w in &cal.warnings {
        let _ = writeln!(s, "- Note: {w}");
    }
    if !cal.warnings.is_empty() {
        s.push('\n');
    }
}

/// The `## Result` section: the effects named (or none) and the gap before and after.
fn report_result(s: &mut String, cal: &Calibration) {
    let _ = writeln!(s, "## Result\n");
    if cal.effects.is_empty() {
        let _ = writeln!(
            s,
            "**No effect named**: nothing in the library explains a significant part of the gap; \
             the model is as good as this data can tell.\n"
        );
    } else {
        report_effects(s, cal);
    }
    let _ = writeln!(s, "- Gap before: {}", fmt_gap(&cal.gap_before));
    let _ = writeln!(s, "- Gap after: {}", fmt_gap(&cal.gap_after));
    let _ = writeln!(s, "- Reduction: {:.0} %", 100.0 * cal.gap_reduction);
    if let Some([b, a]) = cal.spool_rms_m {
        let _ = writeln!(
            s,
            "- Measured spool vs model spool (not fitted, a check): RMS {:.2e} m before, {:.2e} m after",
            b, a
        );
    }
    s.push('\n');
}

/// The table of the effects named (SI parameters with their σ, gap reductions in %) and each one in engineering units.
fn report_effects(s: &mut String, cal: &Calibration) {
    let _ = writeln!(
        s,
        "| # | effect | form | parameters (SI) | gap reduction | cumulative |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for (i, e) in cal.effects.iter().enumerate() {
        let params: Vec<String> = e
            .parameters
            .iter()
            .map(|(k, v)| {
                let sd = e.parameter_std.get(k).copied().unwrap_or(f64::NAN);
                format!("{k} = {v:.4e} (± {sd:.1e})")
            })
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.0} % | {:.0} % |",
            i + 1,
            e.name,
            e.form,
            params.join("<br>"),
            100.0 * e.gap_reduction,
            100.0 * e.cumulative_gap_reduction
        );
    }
    s.push('\n');
    for e in &cal.effects {
        let _ = writeln!(s, "**`{}`** in engineering units:\n", e.name);
        for l in &e.engineering {
            let _ = writeln!(s, "- {l}");
        }
        for l in &e.not_identifiable {
            let _ = writeln!(s, "- {l}");
        }
        s.push('\n');
        if let Some(c) = &e.caveat {
            let _ = writeln!(s, "**`{}`**: {c}.\n", e.name);
        }
    }
}

/// The `## Selection, round by round` section: every candidate's score and verdict.
fn report_rounds(s: &mut String, cal: &Calibration) {
    let _ = writeln!(s, "## Selection, round by round\n");
    for (k, r) in cal.rounds.iter().enumerate() {
        let _ = writeln!(s, "Round {} (validation gap {:.3}):\n", k + 1, r.gap_before);
        let _ = writeln!(
            s,
            "| effect | form | gap reduction | ΔBIC | parameters | verdict |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        for c in &r.candidates {
            let params: Vec<String> = c
                .parameters
                .iter()
                .map(|(k, v)| format!("{k} = {v:.3e}"))
                .collect();
            let _ = writeln!(
                s,
                "| {} | {} | {:.1} % | {:.0} | {} | {} |",
                c.name,
                c.form,
                100.0 * c.gap_reduction,
                c.delta_bic,
                params.join("<br>"),
                c.status
            );
        }
        s.push('\n');
    }
}

/// The `## Where the model disagreed` section: the nominal model's error by regime (mm, MPa), then the signatures of the effects named.
fn report_disagreement(s: &mut String, cal: &Calibration) {
    let _ = writeln!(
        s,
        "## Where the model disagreed (validation part, nominal model)\n"
    );
    let _ = writeln!(
        s,
        "| regime | bin | samples | mean x [mm] | mean p1 [MPa] | mean p2 [MPa] | RMS x [mm] | RMS p1 [MPa] | RMS p2 [MPa] |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for b in &cal.breakdown_before {
        if b.count == 0 {
            continue;
        }
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
            b.regime,
            b.bin,
            b.count,
            b.mean[0] * 1e3,
            b.mean[1] * 1e-6,
            b.mean[2] * 1e-6,
            b.rms[0] * 1e3,
            b.rms[1] * 1e-6,
            b.rms[2] * 1e-6
        );
    }
    s.push('\n');
    if !cal.effects.is_empty() {
        let _ = writeln!(s, "Signatures of the effects named:\n");
        for e in &cal.effects {
            let _ = writeln!(s, "- `{}`: {}", e.name, e.signature);
        }
        s.push('\n');
    }
}

/// The `## Plots` section: the figures written, and where the calibrated model is.
fn report_plots(s: &mut String, plots: &[PathBuf]) {
    let _ = writeln!(s, "## Plots\n");
    for p in plots {
        if let Some(name) = p.file_name().and_then(|n| n.to_str()) {
            let _ = writeln!(s, "![{name}]({name})\n");
        }
    }
    let _ = writeln!(
        s,
        "The calibrated model is in `model.toml` (`leakwatch replay MEASURED.csv --config model.toml --out DIR`, \
         or `leakwatch run --config model.toml`); every number is in `calibration.json`."
    );
}
