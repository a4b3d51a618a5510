//! The calibration report: what `leakwatch calibrate` identified against the
//! datasheet and which missing effects its search named, as one
//! self-contained HTML page (inline CSS and SVG, no external resource) that
//! prints on A4, written beside its model.toml as `report.html`.

use calibrate::{Calibration, Gap};

use crate::commission_report::Identified;
use crate::html::{esc, num};

/// The normalised validation gap a model that fits the rig leaves, from the
/// sensors' noise alone (lowest, highest; dimensionless).
pub const NORMALISED_SENSOR_FLOOR: (f64, f64) = (0.2, 0.4);

/// The report's file name, in calibrate's output directory.
pub const FILE_NAME: &str = "report.html";

/// How the identification before the search went.
#[derive(Debug, Clone)]
pub enum Identification {
    /// Not asked for (no `[datasheet]`, no `--identify`): the search started from the config's model.
    NotAsked,
    /// What it found.
    Found(Identified),
    /// Why it failed (the search then started from the config's model).
    Failed(String),
}

/// Everything a calibration found on one recording.
#[derive(Debug, Clone)]
pub struct CalibrationRecord<'a> {
    /// The measured recording.
    pub input: String,
    /// The identification before the search.
    pub identification: Identification,
    /// The search's result (the same that calibration.json holds).
    pub cal: &'a Calibration,
}

/// The numbers of one gap as the terminal prints them: chamber 1 and 2 (kPa),
/// force (N), spool (µm) and the normalised gap (1).
pub fn gap_numbers(gap: &Gap) -> [String; 5] {
    [
        format!("{:.1}", gap.p1_pa / 1e3),
        format!("{:.1}", gap.p2_pa / 1e3),
        format!("{:.0}", gap.force_n),
        format!("{:.2}", gap.spool_m * 1e6),
        format!("{:.3}", gap.normalised),
    ]
}

impl CalibrationRecord<'_> {
    /// The report: one self-contained HTML page that prints on A4.
    pub fn html(&self) -> Result<String, String> {
        let name = std::path::Path::new(&self.input)
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_else(|| self.input.clone());
        let d = &self.cal.data;
        let mut h = crate::html::page_start(&format!("Calibration report: {name}"));
        h += &format!(
            "<p class=\"note\">Recording <code>{}</code>: {} samples ({:.1} s); {} windows of {:.0} ms fit, {} validate ({}).</p>\n",
            esc(&self.input),
            d.samples,
            d.seconds,
            d.fit_windows,
            d.window_s * 1e3,
            d.validation_windows,
            esc(&d.split)
        );
        h += &match &self.identification {
            Identification::Found(id) => id.html(""),
            Identification::Failed(why) => format!(
                "<h2>Identification</h2>\n<p class=\"note\">Not identified: {}; the search started from the config's model.</p>\n",
                esc(why)
            ),
            Identification::NotAsked => "<h2>Identification</h2>\n<p class=\"note\">Not asked for (no [datasheet] in the config, no --identify): the search started from the config's model, so there are no datasheet values to hold the model against.</p>\n".to_string(),
        };
        h += &self.gaps_html();
        h += &self.effects_html();
        for w in &self.cal.warnings {
            h += &format!("<p class=\"note\">Note: {}</p>\n", esc(w));
        }
        h += "<h2>The fit: measured against the model before and after</h2>\n";
        if self.cal.traces.t_s.is_empty() {
            h += "<p class=\"note\">No trace was kept of the comparison windows: no figure.</p>\n";
        } else {
            h += &crate::html::figure(&calibrate::output::traces_figure(self.cal))?;
        }
        h += crate::html::PAGE_END;
        Ok(h)
    }

    /// The validation gap before the search, after each effect it added and
    /// after all, against the sensor floor.
    fn gaps_html(&self) -> String {
        let cal = self.cal;
        let (lo, hi) = NORMALISED_SENSOR_FLOOR;
        let mut h = format!(
            "<h2>The gap before and after each effect</h2>\n<p class=\"note\">Validation RMS per {:.0} ms window. A model that fits the rig leaves the sensor floor, a normalised gap of about {lo:.1}-{hi:.1}.</p>\n\
             <table><tr><th>model</th><th>chamber 1 [kPa]</th><th>chamber 2 [kPa]</th><th>force [N]</th><th>spool [µm]</th><th>normalised</th><th>explains</th></tr>\n",
            cal.data.window_s * 1e3
        );
        let row = |label: &str, gap: &Gap, explains: Option<f64>| {
            let cells: String = gap_numbers(gap).iter().map(|c| num(c)).collect();
            let explains = explains.map_or("–".to_string(), |r| format!("{:.0} %", r * 100.0));
            format!("<tr><td>{}</td>{cells}{}</tr>\n", esc(label), num(&explains))
        };
        h += &row("before", &cal.gap_before, None);
        for (i, e) in cal.effects.iter().enumerate() {
            h += &row(
                &format!("+ {}. {}", i + 1, e.name),
                &e.gap_after,
                Some(e.gap_reduction),
            );
        }
        h += &row("after", &cal.gap_after, Some(cal.gap_reduction));
        h += "</table>\n";
        if cal.gap_after.normalised > 1.0 {
            h += &format!(
                "<p class=\"note\">The remaining gap ({:.2}) is well above the sensor floor: the rig differs in something the library does not have, or a channel is scaled or wired differently.</p>\n",
                cal.gap_after.normalised
            );
        }
        h
    }

    /// The effects the search named: their parameters (SI, with σ), in
    /// engineering units, what the recording could not pin down.
    fn effects_html(&self) -> String {
        let cal = self.cal;
        let mut h = "<h2>The effects named</h2>\n".to_string();
        if cal.effects.is_empty() {
            h += "<p class=\"note\">None: no missing effect explains a significant part of the gap; the model stands as it is.</p>\n";
            return h;
        }
        h += "<table><tr><th>#</th><th>effect</th><th>form</th><th>parameter</th><th>value (SI)</th><th>σ (SI)</th></tr>\n";
        for (i, e) in cal.effects.iter().enumerate() {
            for (k, (param, v)) in e.parameters.iter().enumerate() {
                let sigma = e
                    .parameter_std
                    .get(param)
                    .map_or("–".to_string(), |s| format!("{s:.1e}"));
                let (n, effect, form) = if k == 0 {
                    ((i + 1).to_string(), esc(&e.name), esc(&e.form))
                } else {
                    Default::default()
                };
                h += &format!(
                    "<tr><td>{n}</td><td>{effect}</td><td>{form}</td><td>{}</td>{}{}</tr>\n",
                    esc(param),
                    num(&format!("{v:.4e}")),
                    num(&sigma)
                );
            }
        }
        h += "</table>\n";
        for e in &cal.effects {
            let lines: Vec<&String> = e
                .engineering
                .iter()
                .chain(&e.not_identifiable)
                .chain(&e.caveat)
                .collect();
            if !lines.is_empty() {
                let text: Vec<String> = lines.iter().map(|l| esc(l.trim())).collect();
                h += &format!(
                    "<p class=\"note\"><b>{}</b>: {}</p>\n",
                    esc(&e.name),
                    text.join("; ")
                );
            }
        }
        h
    }
}
