//! The commissioning record: what `leakwatch commission` found and learned,
//! the one source of its terminal lines and of the report it writes beside
//! its TOML, a self-contained HTML page (inline CSS and SVG, no external
//! resource) that prints on A4.

use crate::commission::NullBias;
use crate::html::esc;

/// One parameter the identification names: its value and σ in `unit`, or why
/// it could not be identified, against the datasheet's (the model's) value.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// What it is.
    pub name: String,
    /// The unit of the values.
    pub unit: String,
    /// Value and σ identified, in `unit`; or why it is not identifiable.
    pub found: Result<(f64, f64), String>,
    /// The datasheet's (the model's before the identification) value, in `unit`.
    pub datasheet: f64,
}

impl Param {
    /// `found` (SI) in `unit` (`scale` per SI unit) against `model_value` (SI).
    pub fn new(name: &str, found: &identify::Found, unit: &str, scale: f64, model_value: f64) -> Param {
        Param {
            name: name.to_string(),
            unit: unit.to_string(),
            found: match found {
                identify::Found::Identified(e) => Ok((e.value * scale, e.sigma * scale)),
                identify::Found::NotIdentifiable(why) => Err(why.to_string()),
            },
            datasheet: model_value * scale,
        }
    }

    /// The terminal's line: `name: value ± σ unit (the datasheet's d)` or why not.
    pub fn line(&self) -> String {
        match &self.found {
            Ok((v, sigma)) => format!(
                "  {}: {v:.4} ± {sigma:.4} {} (the datasheet's {:.4})",
                self.name, self.unit, self.datasheet
            ),
            Err(why) => format!("  {}: not identifiable from this recording: {why}", self.name),
        }
    }
}

/// What the identification found, as the terminal says it and the report shows it.
#[derive(Debug, Clone, Default)]
pub struct Identified {
    /// The flow balance's windows, their length (ms) and how many moved.
    pub windows: (usize, f64, usize),
    /// The flow-balance gap before and after, and the sensor floor, L/min RMS.
    pub gap_lpm: (f64, f64, f64),
    /// The flow balance's parameters.
    pub flow: Vec<Param>,
    /// The force balance's sliding samples and its gap before and after, N RMS.
    pub force_gap_n: Option<(usize, f64, f64)>,
    /// The force balance's parameters (empty when it was not identified).
    pub mechanics: Vec<Param>,
    /// Why the force balance was not identified, if it was not.
    pub mechanics_error: Option<String>,
    /// The other lines: transducer lags, oil temperature, the workpiece, what
    /// the recording cannot tell apart.
    pub notes: Vec<String>,
}

impl Identified {
    /// The terminal's lines, in order.
    pub fn lines(&self) -> Vec<String> {
        let (w, ms, moving) = self.windows;
        let (before, after, floor) = self.gap_lpm;
        let mut out = vec![format!(
            "identified on {w} windows of {ms} ms ({moving} moving); flow-balance gap {before:.3} -> {after:.3} L/min RMS (sensor floor {floor:.3}):"
        )];
        out.extend(self.flow.iter().map(Param::line));
        out.extend(self.notes.iter().cloned());
        if let Some((n, b, a)) = self.force_gap_n {
            out.push(format!(
                "force balance on {n} sliding samples: gap {b:.0} -> {a:.0} N RMS"
            ));
        }
        out.extend(self.mechanics.iter().map(Param::line));
        if let Some(e) = &self.mechanics_error {
            out.push(format!("  mass and friction: not identified: {e}"));
        }
        out
    }

    /// The identification's part of a report: the flow and force balances'
    /// gaps against the sensor floor, the table of what was identified
    /// (value, σ, the datasheet's value, the difference) with `extra_rows`
    /// (HTML table rows) at its end, and what could not be identified and why.
    pub fn html(&self, extra_rows: &str) -> String {
        let id = self;
        let (w, ms, moving) = id.windows;
        let (before, after, floor) = id.gap_lpm;
        let mut h = format!(
            "<h2>Identification</h2>\n<p class=\"note\">Flow balance on {w} windows of {ms} ms ({moving} moving): gap {before:.3} → {after:.3} L/min RMS, sensor floor {floor:.3} L/min.</p>\n"
        );
        if let Some((n, b, a)) = id.force_gap_n {
            h += &format!(
                "<p class=\"note\">Force balance on {n} sliding samples: gap {b:.0} → {a:.0} N RMS.</p>\n"
            );
        }
        h += "<table><tr><th>parameter</th><th>identified</th><th>σ</th><th>datasheet</th><th>difference</th><th>unit</th></tr>\n";
        for row in id.flow.iter().chain(&id.mechanics).filter_map(param_row) {
            h += &row;
        }
        h += extra_rows;
        h += "</table>\n<h2>Not identified, and why</h2>\n";
        for p in id.flow.iter().chain(&id.mechanics) {
            if let Err(why) = &p.found {
                h += &format!("<p class=\"note\"><b>{}</b>: {}</p>\n", esc(&p.name), esc(why));
            }
        }
        if let Some(e) = &id.mechanics_error {
            h += &format!("<p class=\"note\"><b>mass and friction</b>: {}</p>\n", esc(e));
        }
        for n in &id.notes {
            h += &format!("<p class=\"note\">{}</p>\n", esc(n.trim()));
        }
        h
    }
}

/// The leak filter's fit to the healthy recording, every [`FitTrace::EVERY`]-th estimate.
#[derive(Debug, Clone, Default)]
pub struct FitTrace {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Measured p1 and p2, MPa.
    pub measured_mpa: [Vec<f64>; 2],
    /// The leak filter's a-posteriori p1 and p2, MPa.
    pub estimated_mpa: [Vec<f64>; 2],
    /// The a-posteriori residuals of p1 and p2, kPa.
    pub residual_kpa: [Vec<f64>; 2],
    /// The normalised innovation squared (1).
    pub nis: Vec<f64>,
    /// Estimates seen.
    seen: u64,
}

impl FitTrace {
    /// One estimate in this many is kept (100 Hz at 1 kHz).
    pub const EVERY: u64 = 10;

    /// Takes estimate `e` (kept every [`Self::EVERY`]-th).
    pub fn push(&mut self, e: &filter::Estimate) {
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(Self::EVERY) {
            return;
        }
        self.t_s.push(e.t_s);
        for k in 0..2 {
            self.measured_mpa[k].push(e.measured[k + 1] * 1e-6);
            self.estimated_mpa[k].push((e.measured[k + 1] - e.residual[k + 1]) * 1e-6);
            self.residual_kpa[k].push(e.residual[k + 1] * 1e-3);
        }
        self.nis.push(e.nis);
    }

    /// The figure of the fit: pressures measured and estimated, residuals, NIS.
    pub fn figure(&self, title: &str) -> plot::Figure {
        use plot::{Marker, Panel, Series};
        let t = &self.t_s;
        let mut fig = plot::Figure::new(title, "t [s]");
        fig.panels.push(
            Panel::new("Chamber pressures: measured and the leak filter's", "p [MPa]")
                .with_series(
                    Series::line("p1 leak filter", t, &self.estimated_mpa[0]).colored(plot::PALETTE[3]),
                )
                .with_series(
                    Series::line("p2 leak filter", t, &self.estimated_mpa[1]).colored(plot::PALETTE[4]),
                )
                .with_series(Series::line("p1 measured", t, &self.measured_mpa[0]).colored(plot::PALETTE[0]))
                .with_series(Series::line("p2 measured", t, &self.measured_mpa[1]).colored(plot::PALETTE[1])),
        );
        fig.panels.push(
            Panel::new("A-posteriori pressure residuals", "e [kPa]")
                .with_series(Series::line("e p1", t, &self.residual_kpa[0]))
                .with_series(Series::line("e p2", t, &self.residual_kpa[1])),
        );
        fig.panels.push(
            Panel::new("Normalised innovation squared", "NIS [-]")
                .with_series(Series::line("NIS", t, &self.nis))
                .with_marker(Marker::Horizontal {
                    y: 3.0,
                    label: "3: the model fits".into(),
                }),
        );
        fig
    }
}

/// What commissioning learned of the healthy state, and the thresholds it gives.
#[derive(Debug, Clone)]
pub struct Learned {
    /// The oil's stiffness on the recording, of the model's bulk modulus (1); `None` without that state.
    pub theta: Option<f64>,
    /// The oil temperature the model's values hold at, °C.
    pub reference_c: f64,
    /// Healthy data learned from, s.
    pub healthy_s: f64,
    /// Data left out, s: where the leak estimates made a pattern no leak can make.
    pub left_out_s: f64,
    /// Healthy offsets of the ext1, ext2 and int sizes, L/min at p_s/2.
    pub offsets_lpm: [f64; 3],
    /// Their healthy spreads, L/min at p_s/2.
    pub spreads_lpm: [f64; 3],
    /// The internal leak's pressure factors r1/r2 when not the nominal ones (1).
    pub internal_factors: Option<[f64; 2]>,
    /// The thresholds of ext1, ext2 and int on any rise, L/min at p_s/2 (a
    /// rise past twice one raises a leak with its kind pending).
    pub thresholds_lpm: [f64; 3],
    /// The thresholds that name each kind (its rise explained clearly), L/min
    /// at p_s/2 ([`detect::Commissioning::clear_spreads_lpm`]).
    pub naming_thresholds_lpm: [f64; 3],
    /// The false-alarm rate the thresholds are set for, 1/h.
    pub false_alarms_per_hour: f64,
    /// The smallest detectable leaks (L/min at p_s/2) at oil temperatures (°C).
    pub detectable: [(f64, [f64; 3]); 3],
    /// The terminal's line of [`Self::detectable`].
    pub detectable_line: String,
    /// The leak filter's mean NIS on the recording (1; 3 when the model fits).
    pub nis_mean: f64,
    /// Per kind, the stretch of the recording that sets its threshold, and
    /// the threshold the rest would give (L/min at p_s/2); `None` for a kind
    /// whose spread is the whole recording's.
    pub set_by: [Option<(detect::Stretch, f64)>; 3],
    /// The smallest misreading of each transducer named on a duty cycle like the recording's.
    pub sensor_reach: crate::commission::SensorReach,
    /// The terminal's line of the healthy rises' own misreading, where one was
    /// taken ([`detect::Commissioning::healthy_offsets_kpa`]).
    pub healthy_misreading: Option<String>,
    /// The terminal's line of how uncertain the transducers' delay taken
    /// off the leak sizes is ([`detect::Commissioning::delay_uncertainty_s`]), where it is.
    pub delay_uncertainty: Option<String>,
}

/// Three values as `a/b/c` with three decimals.
fn three(v: [f64; 3]) -> String {
    format!("{:.3}/{:.3}/{:.3}", v[0], v[1], v[2])
}

impl Learned {
    /// The terminal's lines, in order.
    pub fn lines(&self) -> Vec<String> {
        let mut out: Vec<String> = self.delay_uncertainty.iter().cloned().collect();
        if let Some(theta) = self.theta {
            out.push(format!(
                "oil stiffness on this recording: {theta:.3} of the model's bulk modulus, at {:.1} °C: \
                 without temp_c the leak filter reads the oil's temperature against it",
                self.reference_c
            ));
        }
        out.push(format!(
            "learned {:.0} s of healthy data: offsets ext1/ext2/int {} L/min, spreads {} L/min (at p_s/2)",
            self.healthy_s,
            three(self.offsets_lpm),
            three(self.spreads_lpm)
        ));
        out.extend(self.left_out_line());
        if let Some(f) = self.internal_factors {
            out.push(format!(
                "the chambers rest at pressures whose difference keeps its sign: the internal leak's pressure factors {:.3}/{:.3} (r1/r2, docs/plant.md)",
                f[0], f[1]
            ));
        }
        out.push(format!(
            "the detector will name leaks from {} L/min (ext1/ext2/int, at p_s/2; thresholds on each kind's rises where it explains them clearly, {} on all its rises) at {} false alarms per hour",
            three(self.naming_thresholds_lpm),
            three(self.thresholds_lpm),
            self.false_alarms_per_hour
        ));
        out.extend(self.set_by_lines());
        out.push(self.detectable_line.clone());
        out.push(self.sensor_reach.line());
        out.push(format!(
            "the leak filter's mean NIS on this recording is {:.1} (3 when the model fits the rig)",
            self.nis_mean
        ));
        out
    }
}

impl Learned {
    /// The line that says how long the learning left out (none under 0.05 s).
    pub fn left_out_line(&self) -> Option<String> {
        (self.left_out_s >= 0.05).then(|| {
            format!(
                "left out {:.1} s where the leak estimates made a pattern no leak can make (the model does not \
                 follow the rig there; the detector takes no evidence from such a pattern either)",
                self.left_out_s
            )
        })
    }

    /// One line per kind whose threshold one stretch of the recording sets ([`Learned::set_by`]).
    pub fn set_by_lines(&self) -> Vec<String> {
        let kinds = ["ext1", "ext2", "int"];
        let mut out = Vec::new();
        for (k, set) in self.set_by.iter().enumerate() {
            let Some((s, without)) = set else { continue };
            out.push(format!(
                "warning: the {} threshold ({:.3} L/min) is set by {:.1}-{:.1} s of the recording (rises up to {:.3} L/min, \
                 {:.0} % of its spread); the rest would give {:.3} L/min. The model does not follow the rig there \
                 (a fast move, a transient; the transducers' lag and the lines' drop identified above are not in \
                 the filters): {} leaks below the threshold are not seen; `leakwatch calibrate` on this recording \
                 searches for what the model lacks, or commission on one without that stretch",
                kinds[k],
                self.thresholds_lpm[k],
                s.from_s,
                s.to_s,
                s.peak_lpm,
                100.0 * s.share,
                without,
                kinds[k]
            ));
        }
        out
    }
}

/// Everything a commissioning found and learned on one healthy recording.
#[derive(Debug, Clone)]
pub struct CommissionRecord {
    /// The healthy recording.
    pub input: String,
    /// What the identification found.
    pub identified: Identified,
    /// The spool's null bias found, and the datasheet's (model's) before it, m.
    pub null_bias: Option<(NullBias, f64)>,
    /// The transducers' misreading fitted, and whether it was taken.
    pub misreading: Option<crate::commission::MisreadingTaken>,
    /// The transducers' delay fitted, and whether it was taken.
    pub delay: Option<crate::commission::DelayTaken>,
    /// The healthy state and the thresholds.
    pub learned: Learned,
    /// The leak filter's fit to the recording.
    pub fit: FitTrace,
}

/// One row of the identification table: value, σ, datasheet, difference (and %).
fn param_row(p: &Param) -> Option<String> {
    let (v, sigma) = p.found.as_ref().ok()?;
    let d = v - p.datasheet;
    let pct = if p.datasheet != 0.0 {
        format!(" ({:+.1} %)", 100.0 * d / p.datasheet.abs())
    } else {
        String::new()
    };
    Some(format!(
        "<tr><td>{}</td><td class=\"n\">{v:.4}</td><td class=\"n\">{sigma:.4}</td><td class=\"n\">{:.4}</td><td class=\"n\">{d:+.4}{pct}</td><td>{}</td></tr>\n",
        esc(&p.name),
        p.datasheet,
        esc(&p.unit)
    ))
}

impl CommissionRecord {
    /// The report: one self-contained HTML page (inline CSS, the fit as inline
    /// SVG, no external resource) that prints on A4.
    pub fn html(&self) -> Result<String, String> {
        let id = &self.identified;
        let l = &self.learned;
        let name = std::path::Path::new(&self.input)
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_else(|| self.input.clone());
        let mut h = crate::html::page_start(&format!("Commissioning record: {name}"));
        h += &format!(
            "<p class=\"note\">Healthy recording <code>{}</code>. Identified against the datasheet, then the healthy state of the leak filter's estimates learned.</p>\n",
            esc(&self.input)
        );
        let null_bias = self.null_bias.as_ref().map(|(b, model_m)| {
            format!(
                "<tr><td>spool null bias (spread {:.2} µm over {:.0} s)</td><td class=\"n\">{:+.2}</td><td class=\"n\">–</td><td class=\"n\">{:+.2}</td><td class=\"n\">{:+.2}</td><td>µm</td></tr>\n",
                b.spread_m * 1e6,
                b.over_s,
                (model_m + b.bias_m) * 1e6,
                model_m * 1e6,
                b.bias_m * 1e6
            )
        });
        let mut extra = null_bias.unwrap_or_default();
        if let Some(m) = self.misreading.filter(|m| m.taken) {
            for (name, z) in ["p1", "p2"].iter().zip(m.found.pa) {
                extra += &format!(
                    "<tr><td>{name} transducer's misreading at the working point</td><td class=\"n\">{:+.1}</td><td class=\"n\">–</td><td class=\"n\">0</td><td class=\"n\">{:+.1}</td><td>kPa</td></tr>\n",
                    z * 1e-3,
                    z * 1e-3
                );
            }
        }
        if let Some(d) = self.delay.filter(|d| d.taken) {
            extra += &format!(
                "<tr><td>pressure transducers' delay taken off the leak sizes</td><td class=\"n\">{:.3}</td><td class=\"n\">–</td><td class=\"n\">0</td><td class=\"n\">{:+.3}</td><td>ms</td></tr>\n",
                d.delay_s * 1e3,
                d.delay_s * 1e3
            );
        }
        h += &id.html(&extra);
        h += &self.learned_html(l);
        h += "<h2>The fit to the recording</h2>\n";
        h += &crate::html::figure(&self.fit.figure(&format!("The leak filter on {name}")))?;
        h += crate::html::PAGE_END;
        Ok(h)
    }

    /// The healthy state, the thresholds per kind and per oil temperature, and the mean NIS.
    fn learned_html(&self, l: &Learned) -> String {
        let mut h = format!(
            "<h2>Healthy state and thresholds</h2>\n<p class=\"note\">Learned from {:.0} s of healthy data; thresholds for {} false alarms per hour. L/min at p_s/2.</p>\n\
             <table><tr><th></th><th>ext1</th><th>ext2</th><th>int</th></tr>\n",
            l.healthy_s, l.false_alarms_per_hour
        );
        let row = |name: &str, v: [f64; 3]| {
            format!(
                "<tr><td>{name}</td><td class=\"n\">{:.3}</td><td class=\"n\">{:.3}</td><td class=\"n\">{:.3}</td></tr>\n",
                v[0], v[1], v[2]
            )
        };
        h += &row("healthy offset", l.offsets_lpm);
        h += &row("healthy spread", l.spreads_lpm);
        h += &row("threshold on all rises", l.thresholds_lpm);
        h += &row("threshold that names the kind", l.naming_thresholds_lpm);
        for (t, d) in &l.detectable {
            h += &row(&format!("smallest detectable at {t:.0} °C"), *d);
        }
        h += "</table>\n";
        h += &format!("<p class=\"note\">{}</p>\n", esc(&l.sensor_reach.line()));
        if let Some(line) = &l.delay_uncertainty {
            h += &format!("<p class=\"note\">{}</p>\n", esc(line));
        }
        let healthy = l.healthy_misreading.as_deref().unwrap_or(
            "no healthy misreading taken: no offset or span error on p1 or p2 explains a third of the healthy rises' energy",
        );
        h += &format!("<p class=\"note\">{}</p>\n", esc(healthy));
        if let Some(line) = l.left_out_line() {
            h += &format!("<p class=\"note\">{}</p>\n", esc(&line));
        }
        for line in l.set_by_lines() {
            h += &format!("<p class=\"note\"><b>{}</b></p>\n", esc(&line));
        }
        if let Some(f) = l.internal_factors {
            h += &format!(
                "<p class=\"note\">Internal leak's pressure factors r1/r2: {:.3}/{:.3}.</p>\n",
                f[0], f[1]
            );
        }
        if let Some(theta) = l.theta {
            h += &format!(
                "<p class=\"note\">Oil stiffness on this recording: {theta:.3} of the model's bulk modulus, at {:.1} °C.</p>\n",
                l.reference_c
            );
        }
        h += &format!(
            "<p class=\"note\">The leak filter's mean NIS on this recording: <b>{:.1}</b> (3 when the model fits the rig).</p>\n",
            l.nis_mean
        );
        h
    }
}
