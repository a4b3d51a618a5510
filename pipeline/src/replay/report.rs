//! The replay's report, `report.html` in its output folder: what the
//! detectors found (each leak alarm: when raised, its onset, size, confidence,
//! named or pending, when cleared), how long they were blind and when, the
//! smallest detectable leak per kind, and the leak panel as the detector saw
//! it; one self-contained page (inline CSS and SVG) that prints on A4. Its
//! numbers come from the [`Summary`] that writes summary.json and its events,
//! those written to events.json.

use std::path::Path;

use config::Config;
use detect::{EventKind, LeakEvent, Phase};

use super::figure::{self, DetectorView};
use super::Summary;
use crate::html::{esc, num};

/// The report's file name in a replay's output directory.
pub const FILE_NAME: &str = "report.html";

/// What the report is made of: the replay's summary (its events included),
/// its configuration and where its outputs are.
pub struct ReplayReport<'a> {
    /// The replay's summary, as summary.json holds it, and its events.
    pub summary: &'a Summary,
    /// The configuration the replay ran with.
    pub config: &'a Config,
    /// The configuration file it came from (none: the built-in rig).
    pub config_path: Option<&'a Path>,
    /// The replay's output folder (detector.csv is read from it).
    pub out_dir: &'a Path,
}

/// One leak alarm over its phases (the events of one id).
#[derive(Debug, Clone, PartialEq)]
pub struct Alarm {
    /// The kind named (`ext1`, `ext2`, `int`), or `leak` while pending.
    pub kind: &'static str,
    /// The detector that raised it.
    pub detector: String,
    /// When it was first raised, s.
    pub raised_s: f64,
    /// When its kind was named, s (none: it stayed pending).
    pub named_s: Option<f64>,
    /// The estimated onset, s (NaN: unknown).
    pub onset_s: f64,
    /// Its latest size at the measured pressures and its σ, L/min (NaN: not sized).
    pub size_lpm: (f64, f64),
    /// Its latest confidence (0 to 1).
    pub confidence: f64,
    /// When it was cleared, s (none: open at the end).
    pub cleared_s: Option<f64>,
}

/// The leak alarms among `events` (events.json's), one per event id, in the order raised.
pub fn alarms(events: &[LeakEvent]) -> Vec<Alarm> {
    let mut out: Vec<(u64, Alarm)> = Vec::new();
    for e in events.iter().filter(|e| e.kind.is_leak_alarm()) {
        let at = match out.iter().position(|(id, _)| *id == e.event_id) {
            Some(i) => i,
            None => {
                out.push((
                    e.event_id,
                    Alarm {
                        kind: e.kind.name(),
                        detector: e.detector.clone(),
                        raised_s: e.t_detect_s,
                        named_s: None,
                        onset_s: f64::NAN,
                        size_lpm: (f64::NAN, f64::NAN),
                        confidence: f64::NAN,
                        cleared_s: None,
                    },
                ));
                out.len() - 1
            }
        };
        let a = &mut out[at].1;
        if e.phase == Phase::Cleared {
            a.cleared_s = Some(e.t_detect_s);
            continue;
        }
        if e.kind.is_leak() {
            a.kind = e.kind.name();
            a.named_s.get_or_insert(e.t_detect_s);
        }
        if e.t_onset_s.is_finite() {
            a.onset_s = e.t_onset_s;
        }
        if e.size_lpm.is_finite() {
            a.size_lpm = (e.size_lpm, e.size_lpm_sigma);
        }
        a.confidence = e.confidence;
    }
    out.into_iter().map(|(_, a)| a).collect()
}

/// A phase as events.json names it.
fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Raised => "raised",
        Phase::Updated => "updated",
        Phase::Cleared => "cleared",
    }
}

/// `v` with three decimals, `–` when not a number.
fn f3(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "–".into()
    }
}

impl ReplayReport<'_> {
    /// The report's page.
    pub fn html(&self) -> Result<String, String> {
        let s = self.summary;
        let input = Path::new(&s.input);
        let name = |p: &Path| {
            p.file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().to_string())
        };
        let rig = self.config_path.map_or("the built-in rig".to_string(), |p| {
            format!("the rig of {}", name(p))
        });
        let mut h = crate::html::page_start(&format!("Replay of {} on {rig}", name(input)));
        h += &format!(
            "<p class=\"note\">Recording <code>{}</code>: {} samples, {} rows skipped, {} samples missing; the leak filter's mean NIS {:.1} (3 when the model fits the rig).</p>\n",
            esc(&s.input),
            s.samples,
            s.rows_skipped,
            s.samples_missing,
            s.leak_filter.mean_nis
        );
        let view = DetectorView::read(self.out_dir)?;
        h += &self.events_html();
        h += &self.blind_html(view.as_ref());
        h += &self.detectable_html(view.as_ref());
        h += "<h2>The leak panel as the detector saw it</h2>\n";
        match &view {
            Some(v) if !v.t_s.is_empty() => h += &crate::html::figure(&self.figure(v, &name(input))?)?,
            Some(_) => {
                h += "<p class=\"note\">The detector never armed: detector.csv has no rows, no figure.</p>\n"
            }
            None => {
                h += "<p class=\"note\">No detector.csv in this replay (--estimates none): no figure.</p>\n"
            }
        }
        h += crate::html::PAGE_END;
        Ok(h)
    }

    /// The leak alarms' table and the other events.
    fn events_html(&self) -> String {
        let events = &self.summary.event_log;
        let list = alarms(events);
        let mut h = format!("<h2>Leak alarms ({})</h2>\n", list.len());
        if list.is_empty() {
            h += "<p class=\"note\">None raised.</p>\n";
        } else {
            h += "<table><tr><th>kind</th><th>raised at [s]</th><th>onset [s]</th><th>size [L/min]</th><th>± σ [L/min]</th><th>confidence</th><th>detector</th><th>named</th><th>cleared at [s]</th></tr>\n";
            for a in &list {
                let named = match a.named_s {
                    Some(t) => format!("named at {t:.3} s"),
                    None => "pending".into(),
                };
                h += &format!(
                    "<tr><td>{}</td>{}{}{}{}{}<td>{}</td><td>{named}</td>{}</tr>\n",
                    a.kind,
                    num(&f3(a.raised_s)),
                    num(&f3(a.onset_s)),
                    num(&f3(a.size_lpm.0)),
                    num(&f3(a.size_lpm.1)),
                    num(&format!("{:.2}", a.confidence)),
                    esc(&a.detector),
                    num(&a.cleared_s.map_or("–".into(), f3))
                );
            }
            h += "</table>\n<p class=\"note\">Size: the leak flow at the measured pressures, the latest estimate.</p>\n";
        }
        let others: Vec<&LeakEvent> = events
            .iter()
            .filter(|e| !e.kind.is_leak_alarm() && e.kind != EventKind::NotArmed)
            .collect();
        if !others.is_empty() {
            h += "<h2>Other events</h2>\n<table><tr><th>event</th><th>phase</th><th>at [s]</th><th>channel</th><th>detail</th></tr>\n";
            for e in others {
                h += &format!(
                    "<tr><td>{}</td><td>{}</td>{}<td>{}</td><td>{}</td></tr>\n",
                    e.kind.name(),
                    phase_name(e.phase),
                    num(&f3(e.t_detect_s)),
                    esc(&e.channel),
                    esc(&e.detail)
                );
            }
            h += "</table>\n";
        }
        h
    }
}

/// The stretches listed in the report at most.
const MAX_STRETCHES: usize = 20;

impl ReplayReport<'_> {
    /// How much of the run the detector watched, the stretches it was blind
    /// (detector.csv) with the events raised in them, and what blinds it, as
    /// summary.json counts it.
    fn blind_html(&self, view: Option<&DetectorView>) -> String {
        let s = self.summary;
        let w = &s.watch;
        let mut h = "<h2>What the detector watched, and when it was blind</h2>\n".to_string();
        match w.armed_at_s {
            None => {
                return h + &format!(
                    "<p class=\"note\"><b>NOT WATCHED</b>: the leak detector never armed in this run ({}): no leak could have been seen.</p>\n",
                    esc(w.not_armed.as_deref().unwrap_or("no healthy state learned"))
                )
            }
            Some(armed) => {
                h += &format!(
                    "<p class=\"note\">Watched <b>{:.1}</b> of <b>{:.1}</b> s ({:.0} %): armed at <b>{armed:.1}</b> s, <b>{:.1}</b> s blind (without evidence) after it.</p>\n",
                    w.watched_s,
                    w.run_s,
                    100.0 * w.watched_s / w.run_s.max(1e-9),
                    w.blind_s
                )
            }
        }
        let cfg = &self.config.classifier;
        let lf = &s.leak_filter;
        h += "<table><tr><th>what blinds the detector</th><th>this run</th><th>from</th></tr>\n";
        let mut cause = |what: String, count: String, from: f64| {
            h += &format!("<tr><td>{what}</td>{}{}</tr>\n", num(&count), num(&f3(from)));
        };
        cause(
            format!(
                "values the filter did not expect (NIS above {}), each for {} s",
                cfg.nis_gate, cfg.recovery_s
            ),
            lf.nis_outliers.to_string(),
            lf.first_nis_outlier_s,
        );
        cause(
            "samples missing (gaps)".into(),
            s.samples_missing.to_string(),
            f64::NAN,
        );
        cause("leak filter resets".into(), lf.resets.to_string(), f64::NAN);
        cause(
            "oil outside the operating range [s]".into(),
            format!("{:.1}", lf.oil_outside_range_s),
            lf.first_oil_outside_range_s,
        );
        h += "</table>\n<table><tr><th>seconds without evidence, by cause</th><th>s</th></tr>\n";
        for (what, seconds) in w.blind_by_cause.named() {
            h += &format!("<tr><td>{what}</td>{}</tr>\n", num(&format!("{seconds:.1}")));
        }
        h += "</table>\n";
        if let Some(phrase) = cfg.commissioning.as_ref().and_then(|c| c.not_watched()) {
            let mut sentence = phrase.to_string();
            sentence[..1].make_ascii_uppercase();
            h += &format!("<p class=\"note\"><b>{}</b>.</p>\n", esc(&sentence));
        }
        let Some(view) = view else {
            return h;
        };
        let stretches = view.blind_stretches();
        let total: f64 = stretches.iter().map(|(a, b)| b - a).sum();
        h += &format!(
            "<p class=\"note\">{} blind stretches in detector.csv (100 Hz rows), {total:.1} s in all:</p>\n\
             <table><tr><th>from [s]</th><th>to [s]</th><th>length [s]</th><th>events raised in it</th></tr>\n",
            stretches.len()
        );
        for (from, to) in stretches.iter().take(MAX_STRETCHES) {
            let mut kinds: Vec<&str> = s
                .event_log
                .iter()
                .filter(|e| e.phase == Phase::Raised && e.t_detect_s >= *from && e.t_detect_s <= *to)
                .map(|e| e.kind.name())
                .collect();
            kinds.dedup();
            h += &format!(
                "<tr>{}{}{}<td>{}</td></tr>\n",
                num(&f3(*from)),
                num(&f3(*to)),
                num(&format!("{:.2}", to - from)),
                kinds.join(", ")
            );
        }
        h += "</table>\n";
        if stretches.len() > MAX_STRETCHES {
            h += &format!(
                "<p class=\"note\">... {} more (detector.csv).</p>\n",
                stretches.len() - MAX_STRETCHES
            );
        }
        h
    }

    /// The smallest detectable leak per kind: over the operating range as the
    /// commissioning states it, else the thresholds learned in this run's
    /// warm-up as they stood at its end (detector.csv).
    fn detectable_html(&self, view: Option<&DetectorView>) -> String {
        let mut h = "<h2>The smallest detectable leak per kind</h2>\n".to_string();
        let row = |name: &str, v: [f64; 3]| {
            format!(
                "<tr><td>{name}</td>{}{}{}</tr>\n",
                num(&f3(v[0])),
                num(&f3(v[1])),
                num(&f3(v[2]))
            )
        };
        let head = "<table><tr><th>L/min at p_s/2</th><th>ext1</th><th>ext2</th><th>int</th></tr>\n";
        let cfg = self.config;
        if let Some(c) = &cfg.classifier.commissioning {
            let (_, thr) = detect::thresholds(&cfg.classifier, c.naming_spreads_lpm(), c.crossings_per_s);
            h += &format!(
                "<p class=\"note\">From the commissioning ({}), at {} false alarms per hour:</p>\n{head}",
                esc(&c.source),
                cfg.classifier.false_alarms_per_hour
            );
            h += &row("threshold that names the kind", thr);
            for (t, d) in crate::commission::detectable_at(&cfg.model, thr, c.offsets_lpm) {
                h += &row(&format!("smallest detectable at {t:.0} °C"), d);
            }
            return h + "</table>\n";
        }
        let last = view.and_then(|v| {
            let k = v.t_s.len().checked_sub(1)?;
            Some((
                v.t_s[k],
                std::array::from_fn::<f64, 3, _>(|i| v.threshold_lpm[i][k]),
            ))
        });
        match last {
            Some((t, thr)) => {
                h += &format!(
                    "<p class=\"note\">Not commissioned: the thresholds learned in this run's warm-up, as they stood at {t:.2} s (detector.csv):</p>\n{head}"
                );
                h += &row("threshold at the end", thr);
                h += "</table>\n";
            }
            None => h += "<p class=\"note\">Not known: no commissioning and no detector.csv.</p>\n",
        }
        h
    }

    /// The leak panel as the detector saw it, with the alarms and onsets
    /// marked and the recording's true leak flow where it has one.
    fn figure(&self, view: &DetectorView, name: &str) -> Result<plot::Figure, String> {
        let events = serde_json::to_value(&self.summary.event_log).map_err(|e| format!("events: {e}"))?;
        let markers = figure::event_markers(events.as_array().map_or(&[][..], |a| a.as_slice()));
        let input = dataset::read_csv(Path::new(&self.summary.input), dataset::Limits::default()).ok();
        let t_first = input
            .as_ref()
            .and_then(|ds| ds.samples.first().map(|s| s.t_s))
            .or(view.t_s.first().copied())
            .unwrap_or(0.0);
        let mut panel = view.panel(t_first, input.as_ref().and_then(figure::truth));
        for m in markers {
            panel = panel.with_marker(m);
        }
        let mut fig = plot::Figure::new(&format!("replay of {name}"), "t [s]");
        fig.panels.push(panel);
        Ok(fig)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An event of the leak-size detector: `kind`, `phase`, id 7, at `t` s,
    /// sized `size` ± 0.01 L/min, confidence `conf`.
    fn ev(kind: EventKind, phase: Phase, t: f64, size: f64, conf: f64) -> LeakEvent {
        LeakEvent {
            size_lpm: size,
            size_lpm_sigma: 0.01,
            confidence: conf,
            ..LeakEvent::plain(kind, phase, "leak-size", 7, t, 10.0)
        }
    }

    /// A pending leak named later, resized and cleared is one alarm: raised
    /// when pending, named when its kind came, the latest size and
    /// confidence, cleared; sensor events are no alarm.
    #[test]
    fn an_alarms_phases_make_one_row() {
        let events = [
            ev(EventKind::Leak, Phase::Raised, 10.5, 0.40, 0.6),
            LeakEvent::plain(
                EventKind::SensorSpikes,
                Phase::Raised,
                "sensors",
                8,
                11.0,
                f64::NAN,
            ),
            ev(EventKind::Ext1, Phase::Raised, 12.0, 0.45, 0.9),
            ev(EventKind::Ext1, Phase::Updated, 13.0, 0.50, 0.95),
            ev(EventKind::Ext1, Phase::Cleared, 20.0, f64::NAN, 1.0),
        ];
        let got = alarms(&events);
        assert_eq!(
            got,
            [Alarm {
                kind: "ext1",
                detector: "leak-size".into(),
                raised_s: 10.5,
                named_s: Some(12.0),
                onset_s: 10.0,
                size_lpm: (0.50, 0.01),
                confidence: 0.95,
                cleared_s: Some(20.0),
            }]
        );
        // one never named stays pending, open at the end
        let pending = alarms(&events[..1]);
        assert_eq!(
            (pending[0].kind, pending[0].named_s, pending[0].cleared_s),
            ("leak", None, None)
        );
    }
}
