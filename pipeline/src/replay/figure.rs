//! The leak panel of a replay as the detector saw it (detector.csv, events
//! and the input's true leak flow): what `leakwatch plot` draws of a replay
//! folder and the replay's report shows inline.

use std::path::Path;

use plot::{Marker, Panel, Series};

/// Reads a CSV with a header into named columns (non-numbers become NaN).
pub fn read_columns(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
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

/// The markers of a replay's leak events (events.json's objects): each
/// leak-size alarm's estimated onset (once per onset), the pending alarm (a
/// leak of kind not yet named) and the named alarm; the thesis' MAE detections.
pub fn event_markers(events: &[serde_json::Value]) -> Vec<Marker> {
    let mut markers = Vec::new();
    let mut onsets: Vec<f64> = Vec::new();
    for e in events.iter().filter(|e| e["phase"] == "raised") {
        let kind = e["kind"].as_str().unwrap_or("?");
        let det = e["detector"].as_str().unwrap_or("");
        let Some(td) = e["t_detect_s"].as_f64() else {
            continue;
        };
        let label = match (det, kind) {
            ("leak-size", "leak") => format!("pending alarm {td:.2} s"),
            ("leak-size", "ext1" | "ext2" | "int") => format!("{kind} named {td:.2} s"),
            (_, "ext1" | "ext2" | "int") => format!("{kind} detected ({det}) {td:.2} s"),
            _ => continue,
        };
        markers.push(Marker::Vertical { x: td, label });
        if det == "leak-size" {
            if let Some(to) = e["t_onset_s"]
                .as_f64()
                .filter(|to| !onsets.iter().any(|o| (o - to).abs() < 1e-6))
            {
                onsets.push(to);
                markers.push(Marker::Vertical {
                    x: to,
                    label: format!("onset {to:.2} s"),
                });
            }
        }
    }
    markers
}

/// detector.csv read back: the detector's view at 100 Hz from arming on.
#[derive(Debug, Clone, Default)]
pub struct DetectorView {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// The ext1, ext2 and int rises above their healthy baselines, L/min at p_s/2.
    pub rise_lpm: [Vec<f64>; 3],
    /// Their thresholds, L/min at p_s/2.
    pub threshold_lpm: [Vec<f64>; 3],
    /// 1 where the detector was blind (took no evidence), else 0.
    pub blind: Vec<f64>,
}

impl DetectorView {
    /// detector.csv of the replay folder `dir`; `None` when the replay wrote none.
    pub fn read(dir: &Path) -> Result<Option<DetectorView>, String> {
        let path = super::trace::path_in(dir);
        if !path.exists() {
            return Ok(None);
        }
        let (header, mut cols) = read_columns(&path)?;
        let mut col = |name: &str| -> Result<Vec<f64>, String> {
            header
                .iter()
                .position(|h| h == name)
                .map(|i| std::mem::take(&mut cols[i]))
                .ok_or_else(|| format!("{}: no column `{name}`", path.display()))
        };
        let mut view = DetectorView {
            t_s: col("t")?,
            blind: col("blind")?,
            ..DetectorView::default()
        };
        for (k, kind) in ["e1", "e2", "i"].iter().enumerate() {
            view.rise_lpm[k] = col(&format!("rise_{kind}_lpm"))?;
            view.threshold_lpm[k] = col(&format!("threshold_{kind}_lpm"))?;
        }
        Ok(Some(view))
    }

    /// The stretches the detector was blind, (from, to) in s: from the row
    /// before the first blind one to the row after the last.
    pub fn blind_stretches(&self) -> Vec<(f64, f64)> {
        let (t, blind) = (&self.t_s, &self.blind);
        let mut out = Vec::new();
        let mut k = 0;
        while k < t.len() {
            if blind[k] != 1.0 {
                k += 1;
                continue;
            }
            let from = k;
            while k < t.len() && blind[k] == 1.0 {
                k += 1;
            }
            let to = t.get(k).copied().unwrap_or(t[k - 1]);
            out.push((t[from.saturating_sub(1)], to));
        }
        out
    }

    /// The leak panel: each kind's rise with its threshold (dashed), the
    /// warm-up from `t_first_s` (s) to arming and the blind stretches shaded,
    /// the true leak flow (`truth`: times s, L/min) where the recording has it.
    pub fn panel(&self, t_first_s: f64, truth: Option<(Vec<f64>, Vec<f64>)>) -> Panel {
        let t = &self.t_s;
        let mut panel = Panel::new(
            "Leak-size detector: each kind's rise above its healthy baseline and its threshold; the true leak flow at the measured pressures",
            "rise [L/min at p_s/2]",
        );
        if let Some(&t_armed) = t.first() {
            panel = panel.with_marker(Marker::Span {
                x_from: t_first_s,
                x_to: t_armed,
                label: "warm-up: not armed".into(),
            });
        }
        for k in 0..3 {
            let color = plot::PALETTE[k];
            let name = ["ext1", "ext2", "int"][k];
            panel = panel
                .with_series(Series::line(name, t, &self.rise_lpm[k]).colored(color))
                .with_series(
                    Series::line(&format!("{name} threshold"), t, &self.threshold_lpm[k])
                        .styled(plot::Style::Dashed)
                        .colored(color),
                );
        }
        for (i, (x_from, x_to)) in self.blind_stretches().into_iter().enumerate() {
            let label = if i == 0 { "blind: no evidence" } else { "" };
            panel = panel.with_marker(Marker::Span {
                x_from,
                x_to,
                label: label.into(),
            });
        }
        if let Some((tt, q)) = truth {
            panel = panel.with_series(Series::line("true leak flow", &tt, &q).colored([0, 0, 0]));
        }
        panel
    }
}

/// The true leak flow of a recording (its `q_leak` column: times s, L/min),
/// when it has one that is not all zero.
pub fn truth(ds: &dataset::Dataset) -> Option<(Vec<f64>, Vec<f64>)> {
    if !ds.has_optional[3]
        || ds
            .samples
            .iter()
            .all(|s| s.q_leak_lpm == 0.0 || s.q_leak_lpm.is_nan())
    {
        return None;
    }
    Some((
        ds.samples.iter().map(|s| s.t_s).collect(),
        ds.samples.iter().map(|s| s.q_leak_lpm).collect(),
    ))
}
