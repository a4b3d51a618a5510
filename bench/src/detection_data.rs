//! Detection scored on recorded runs with their truth: any directory of run
//! folders, `run_*/measured.csv[.gz]` with `run_*/truth.json`, the runs fed
//! through the estimator stage and the classifier exactly as `leakwatch replay`
//! feeds them.
//!
//! Per run: detected (a leak raised at or after the onset), the kind at the
//! first alarm and after its updates, the delay from the onset, the size at
//! the first alarm and the last one against the flow the rig really lost
//! (`observed_mean_abs_flow_lpm_after_ramp`), and false alarms (leak events
//! raised before the onset, or at all in a healthy run) over the clean time.
//! The `q_leak`, `f_load` and `ref` columns are never shown to the detector.

use std::path::{Path, PathBuf};

use crate::stats::quantile;
use crate::truth_flow::{FloorClock, TrueFlows};
use detect::{BlindSeconds, LeakEvent, Phase};
use pipeline::{Chain, ChainSettings};
use serde::Serialize;

/// What a run's truth says about its leak.
#[derive(Debug, Clone, Serialize)]
pub struct Truth {
    /// Run name (the folder).
    pub run: String,
    /// Scenario name.
    pub scenario: String,
    /// `ext1`, `ext2`, `int`, or `none`.
    pub kind: String,
    /// Nominal leak size, L/min (0 when healthy).
    pub size_nominal_lpm: f64,
    /// Leak onset, s (NaN when healthy).
    pub t_on_s: f64,
    /// Ramp duration, s.
    pub ramp_s: f64,
    /// Mean absolute leak flow the rig lost after the ramp, L/min (the size reference).
    pub observed_flow_lpm: f64,
}

/// What the leak-size detector did on one run.
#[derive(Debug, Clone, Serialize)]
pub struct DataOutcome {
    /// The truth of the run.
    pub truth: Truth,
    /// A leak was raised at or after the onset.
    pub detected: bool,
    /// Kind first named (the first alarm's, or, when that one was raised with its
    /// kind pending, the kind it was named with; empty if none).
    pub kind_first: String,
    /// Kind of the leak after re-isolations (empty if none).
    pub kind_final: String,
    /// Delay of the first alarm from the onset (kind pending or named), s (NaN if none).
    pub delay_s: f64,
    /// Delay of the first alarm that names a kind from the onset, s (NaN if none).
    pub delay_named_s: f64,
    /// Size reported at the first alarm, L/min (NaN if none).
    pub size_first_lpm: f64,
    /// Last size reported for the leak (that event or the one that replaced it), L/min (NaN if none).
    pub size_final_lpm: f64,
    /// Leak events raised before the onset (or at all when healthy).
    pub false_alarms: u32,
    /// Sensor events raised before the onset (or at all when healthy): these runs have no sensor fault.
    pub sensor_events: u32,
    /// Time in which a false alarm could be raised (before the onset, or the whole run), s.
    pub clean_s: f64,
    /// Samples the run had.
    pub samples: u64,
    /// Thresholds the detector used on the rise of ext1, ext2, int, L/min at p_s/2.
    pub thresholds_lpm: [f64; 3],
    /// The same in healthy spreads.
    pub thresholds_sigma: [f64; 3],
    /// Seconds without evidence after arming (gaps, excursions, NIS), s.
    pub blind_s: f64,
    /// The same seconds by cause, s.
    pub blind_by_cause: BlindSeconds,
    /// Delay of the first alarm from the time the real flow reached the
    /// detector's floor for the leak's kind (`min_size_lpm` for an external leak,
    /// `min_internal_size_lpm` for an internal one), s (NaN if none; the onset for a step).
    /// Negative if the alarm came before the real flow reached the floor.
    pub delay_after_detectable_s: f64,
    /// The true flow averaged as the detector averages its size, at the first
    /// named alarm and at the last, L/min (NaN without the run's true flows).
    pub true_flow_lpm: [f64; 2],
}

/// What the chain did on one recorded file.
#[derive(Debug, Clone)]
pub struct FileRun {
    /// The leak-size detector's leak events.
    pub events: Vec<LeakEvent>,
    /// When a sensor event (any detector's) was raised, s.
    pub sensor_raised_s: Vec<f64>,
    /// Samples read.
    pub samples: u64,
    /// Time of the last sample, s.
    pub t_end_s: f64,
    /// Thresholds used, L/min at p_s/2.
    pub thresholds_lpm: [f64; 3],
    /// Thresholds in healthy spreads.
    pub thresholds_sigma: [f64; 3],
    /// Seconds without evidence after arming, s.
    pub blind_s: f64,
    /// The same seconds by cause, s.
    pub blind_by_cause: BlindSeconds,
    /// First time the logged leak flow (`q_leak`, never shown to the detector),
    /// or a run folder's `truth_flow.csv[.gz]`, reached the detector's floor for
    /// an external leak and for an internal one (`min_size_lpm`,
    /// `min_internal_size_lpm`) and held there for `confirm_s`, s (NaN if never
    /// or not logged): `crate::truth_flow::FloorClock`. A leak cannot be
    /// declared before its flow gets there.
    pub t_detectable_s: [f64; 2],
    /// The detector's floors, L/min: `min_size_lpm` and `min_internal_size_lpm`.
    pub floors_lpm: [f64; 2],
    /// The time constant over which the detector averages a leak's size, s (`size_window_s`).
    pub size_window_s: f64,
    /// The run's true leak flows, where its folder has them (`truth_flow.csv[.gz]`).
    pub true_flows: Option<TrueFlows>,
}

/// Totals over a directory.
#[derive(Debug, Clone, Serialize)]
pub struct DataSummary {
    /// Size class (nominal L/min) and the fraction detected, right kind at the first alarm,
    /// median delay s, median and p95 of |size error| relative to the real flow (last size).
    pub by_size: Vec<SizeRow>,
    /// The same figures over every leak of [`FROM_SIZE_LPM`] and more, where
    /// the runs have more than one such size (its `size_nominal_lpm` the least).
    pub from_quarter_lpm: Option<SizeRow>,
    /// False alarms in total.
    pub false_alarms: u32,
    /// Sensor events in the clean time, in total (no run has a sensor fault).
    pub sensor_events: u32,
    /// Clean hours (healthy runs plus pre-onset time).
    pub clean_hours: f64,
    /// Seconds without evidence after arming over every run, s.
    pub blind_s: f64,
    /// The same seconds by cause, s.
    pub blind_by_cause: BlindSeconds,
    /// Every run.
    pub runs: Vec<DataOutcome>,
    /// Wall time, s.
    pub wall_s: f64,
}

/// Figures of one nominal size class.
#[derive(Debug, Clone, Serialize)]
pub struct SizeRow {
    /// Nominal size, L/min.
    pub size_nominal_lpm: f64,
    /// Runs.
    pub runs: usize,
    /// Detected fraction.
    pub p_detect: f64,
    /// Fraction whose first named kind was the right one (of all runs of the class).
    pub p_kind_first: f64,
    /// Median delay of the first alarm from onset, s.
    pub delay_median_s: f64,
    /// Median delay of the first alarm that names a kind from onset, s.
    pub delay_named_median_s: f64,
    /// 95th-percentile delay, s.
    pub delay_p95_s: f64,
    /// Median delay from the time the real flow reached the detector's floor for the kind, s.
    pub delay_after_detectable_median_s: f64,
    /// Median |size − real flow| / real flow at the first alarm (right kind only).
    pub size_error_first_median: f64,
    /// Median |size − real flow| / real flow, last size of the event (right kind only).
    pub size_error_median: f64,
    /// 95th percentile of the same.
    pub size_error_p95: f64,
}

impl Truth {
    /// When the leak's flow reached `floor_lpm` (L/min), s: linearly from the onset to
    /// [`Truth::observed_flow_lpm`] over [`Truth::ramp_s`] (NaN without a leak).
    pub fn t_flow_reaches_s(&self, floor_lpm: f64) -> f64 {
        if self.observed_flow_lpm.is_nan() || self.observed_flow_lpm <= 0.0 {
            return f64::NAN;
        }
        self.t_on_s + self.ramp_s * (floor_lpm / self.observed_flow_lpm).min(1.0)
    }
}

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v.get(key).and_then(|x| x.as_f64()).unwrap_or(f64::NAN)
}

/// Reads `truth.json` of one run folder.
pub fn read_truth(dir: &Path) -> Result<Truth, String> {
    let p = dir.join("truth.json");
    let text = std::fs::read_to_string(&p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: not JSON: {e}", p.display()))?;
    let run = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let scenario = v
        .pointer("/scenario/name")
        .and_then(|s| s.as_str())
        .unwrap_or("")
        .to_string();
    let fault = v.get("fault").filter(|f| !f.is_null());
    Ok(match fault {
        None => Truth {
            run,
            scenario,
            kind: "none".into(),
            size_nominal_lpm: 0.0,
            t_on_s: f64::NAN,
            ramp_s: 0.0,
            observed_flow_lpm: 0.0,
        },
        Some(f) => Truth {
            run,
            scenario,
            kind: f
                .get("kind")
                .and_then(|k| k.as_str())
                .ok_or_else(|| format!("{}: fault without a kind", p.display()))?
                .to_string(),
            size_nominal_lpm: num(f, "size_lpm"),
            t_on_s: num(f, "t_on_s"),
            ramp_s: num(f, "ramp_s").max(0.0),
            observed_flow_lpm: num(f, "observed_mean_abs_flow_lpm_after_ramp"),
        },
    })
}

fn measured_file(dir: &Path) -> Result<PathBuf, String> {
    for name in ["measured.csv.gz", "measured.csv"] {
        let p = dir.join(name);
        if p.is_file() {
            return Ok(p);
        }
    }
    Err(format!("{}: no measured.csv or measured.csv.gz", dir.display()))
}

/// Runs one recorded run through the chain; returns every leak-size event and the samples read.
pub fn detect_file(path: &Path, set: &ChainSettings) -> Result<FileRun, String> {
    let limits = dataset::Limits::for_model(&set.model, set.leak_filter.sample_period_s);
    let mut reader = dataset::CsvReader::open(path, limits).map_err(|e| e.to_string())?;
    let mut chain = Chain::new(set)?;
    let (mut events, mut sensor_raised_s) = (Vec::new(), Vec::new());
    let floors = [set.classifier.min_size_lpm, set.classifier.min_internal_size_lpm];
    let mut clock = FloorClock::new(floors, set.classifier.confirm_s);
    let (mut n, mut t_end) = (0u64, 0.0);
    while let Some(row) = reader.next_row() {
        let s = match row {
            dataset::Row::Sample(s) | dataset::Row::AfterGap(s, _) => s,
            dataset::Row::Skipped(_) => continue,
        };
        n += 1;
        t_end = s.t_s;
        clock.push(s.t_s, s.q_leak_lpm);
        chain.step(&s, |ev| {
            if ev.kind.is_leak_alarm() && ev.detector == "leak-size" {
                events.push(ev)
            } else if ev.kind.is_sensor() && ev.phase == Phase::Raised {
                sensor_raised_s.push(ev.t_detect_s)
            }
        });
    }
    dataset::check_bad_fraction(reader.rows, reader.skipped, dataset::DEFAULT_MAX_BAD_FRACTION)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(FileRun {
        events,
        sensor_raised_s,
        samples: n,
        t_end_s: t_end,
        thresholds_lpm: chain.classifier().leak_size.thresholds_lpm(),
        thresholds_sigma: chain.classifier().leak_size.thresholds_sigma(),
        blind_s: chain.classifier().leak_size.blind_s(),
        blind_by_cause: chain.classifier().leak_size.blind_by_cause(),
        t_detectable_s: clock.reached_s(),
        floors_lpm: floors,
        size_window_s: set.classifier.size_window_s,
        true_flows: None,
    })
}

/// Scores one run's events against its truth.
pub fn score_run(truth: Truth, run: &FileRun) -> DataOutcome {
    let (events, samples, t_end_s) = (&run.events[..], run.samples, run.t_end_s);
    let healthy = truth.kind == "none";
    let mine: Vec<&LeakEvent> = events.iter().collect();
    let alarms = crate::alarms::read(&mine, (!healthy).then_some(truth.t_on_s));
    let false_alarms = alarms.false_alarms;
    let clean_s = if healthy {
        t_end_s
    } else {
        truth.t_on_s.min(t_end_s)
    };
    let sensor_events = run.sensor_raised_s.iter().filter(|t| **t < clean_s).count() as u32;
    let first = alarms.first;
    let mut o = DataOutcome {
        truth,
        detected: first.is_some(),
        kind_first: String::new(),
        kind_final: String::new(),
        delay_s: f64::NAN,
        delay_named_s: f64::NAN,
        size_first_lpm: f64::NAN,
        size_final_lpm: f64::NAN,
        false_alarms,
        sensor_events,
        clean_s,
        samples,
        thresholds_lpm: run.thresholds_lpm,
        thresholds_sigma: run.thresholds_sigma,
        blind_s: run.blind_s,
        blind_by_cause: run.blind_by_cause,
        delay_after_detectable_s: f64::NAN,
        true_flow_lpm: [f64::NAN; 2],
    };
    if let Some(ev) = first {
        let named = alarms.first_named.unwrap_or(ev);
        let last = alarms.last.unwrap_or(ev);
        o.kind_first = named.kind.name().into();
        o.kind_final = last.kind.name().into();
        o.delay_s = ev.t_detect_s - o.truth.t_on_s;
        o.delay_named_s = alarms
            .first_named
            .map_or(f64::NAN, |n| n.t_detect_s - o.truth.t_on_s);
        let internal = usize::from(o.truth.kind == "int");
        let mut t_floor = run.t_detectable_s[internal];
        if t_floor.is_nan() {
            t_floor = o.truth.t_flow_reaches_s(run.floors_lpm[internal]);
        }
        o.delay_after_detectable_s = ev.t_detect_s - t_floor.max(o.truth.t_on_s);
        o.size_first_lpm = named.size_lpm;
        o.size_final_lpm = last.size_lpm;
        if let Some(flows) = &run.true_flows {
            let (t_on, ramp) = (o.truth.t_on_s, o.truth.ramp_s);
            o.true_flow_lpm =
                [named, last].map(|e| flows.mean_lpm(e.t_detect_s, run.size_window_s, t_on, ramp));
        }
    }
    o
}

/// Scores every `run_*`-like folder (any folder holding a truth.json) of `dir`,
/// on `threads` threads; `progress(done, total)` after each run.
pub fn score_dir(
    dir: &Path,
    set: &ChainSettings,
    threads: usize,
    progress: impl Fn(usize, usize) + Sync,
) -> Result<DataSummary, String> {
    let t0 = std::time::Instant::now();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("cannot read {}: {e}", dir.display()))?
        .filter_map(|d| d.ok().map(|d| d.path()))
        .filter(|p| p.join("truth.json").is_file())
        .collect();
    dirs.sort();
    if dirs.is_empty() {
        return Err(format!(
            "{}: no run folders (a folder with truth.json and measured.csv[.gz])",
            dir.display()
        ));
    }
    let score = |i: usize| {
        let d = &dirs[i];
        let truth = read_truth(d)?;
        let mut run = detect_file(&measured_file(d)?, set)?;
        if let Some(path) = crate::truth_flow::file(d).filter(|_| truth.t_on_s.is_finite()) {
            let flows = TrueFlows::read(&path)?;
            if run.t_detectable_s[0].is_nan() {
                let clock = FloorClock::new(run.floors_lpm, set.classifier.confirm_s);
                run.t_detectable_s = flows.floor_times(truth.t_on_s, clock);
            }
            run.true_flows = Some(flows);
        }
        Ok(score_run(truth, &run))
    };
    let runs = crate::work::try_map(dirs.len(), threads, score, progress)?;
    Ok(summarise_data(runs, t0.elapsed().as_secs_f64()))
}

/// Totals per nominal size class.
pub fn summarise_data(runs: Vec<DataOutcome>, wall_s: f64) -> DataSummary {
    let mut sizes: Vec<f64> = runs
        .iter()
        .filter(|r| r.truth.kind != "none")
        .map(|r| r.truth.size_nominal_lpm)
        .collect();
    sizes.sort_by(f64::total_cmp);
    sizes.dedup();
    let by_size = sizes
        .iter()
        .map(|&size| {
            let these: Vec<&DataOutcome> = runs
                .iter()
                .filter(|r| r.truth.kind != "none" && r.truth.size_nominal_lpm == size)
                .collect();
            size_row(size, &these)
        })
        .collect();
    // (the class the plant rigs' acceptance reads: every leak of 0.25 L/min and
    // more, where there is more than one such size)
    let from_quarter: Vec<&DataOutcome> = runs
        .iter()
        .filter(|r| r.truth.kind != "none" && r.truth.size_nominal_lpm >= FROM_SIZE_LPM)
        .collect();
    let from_quarter_lpm = (sizes.iter().filter(|s| **s >= FROM_SIZE_LPM).count() > 1)
        .then(|| size_row(FROM_SIZE_LPM, &from_quarter));
    let false_alarms = runs.iter().map(|r| r.false_alarms).sum();
    let sensor_events = runs.iter().map(|r| r.sensor_events).sum();
    let clean_hours = runs.iter().map(|r| r.clean_s).sum::<f64>() / 3600.0;
    let mut blind_by_cause = BlindSeconds::default();
    for r in &runs {
        blind_by_cause += r.blind_by_cause;
    }
    DataSummary {
        by_size,
        from_quarter_lpm,
        false_alarms,
        sensor_events,
        clean_hours,
        blind_s: runs.iter().map(|r| r.blind_s).sum(),
        blind_by_cause,
        runs,
        wall_s,
    }
}

/// The least nominal size of the summary's row over every larger leak
/// ([`DataSummary::from_quarter_lpm`]), L/min.
pub const FROM_SIZE_LPM: f64 = 0.25;

/// The figures of the runs `these`, under the nominal size `size` (L/min).
fn size_row(size: f64, these: &[&DataOutcome]) -> SizeRow {
    let n = these.len();
    let mut delays: Vec<f64> = these.iter().filter(|o| o.detected).map(|o| o.delay_s).collect();
    let mut named: Vec<f64> = these
        .iter()
        .map(|o| o.delay_named_s)
        .filter(|d| d.is_finite())
        .collect();
    let mut after: Vec<f64> = these
        .iter()
        .filter(|o| o.detected)
        .map(|o| o.delay_after_detectable_s)
        .filter(|d| d.is_finite())
        .collect();
    let err = |o: &&&DataOutcome, s: f64, at: usize| {
        let truth = Some(o.true_flow_lpm[at])
            .filter(|q| *q > 0.0)
            .unwrap_or(o.truth.observed_flow_lpm);
        (s - truth).abs() / truth
    };
    let right = |o: &&&DataOutcome| o.kind_first == o.truth.kind;
    let mut e_first: Vec<f64> = these
        .iter()
        .filter(right)
        .map(|o| err(&o, o.size_first_lpm, 0))
        .collect();
    let mut e_last: Vec<f64> = these
        .iter()
        .filter(|o| o.kind_final == o.truth.kind)
        .map(|o| err(&o, o.size_final_lpm, 1))
        .collect();
    SizeRow {
        size_nominal_lpm: size,
        runs: n,
        p_detect: these.iter().filter(|o| o.detected).count() as f64 / n as f64,
        p_kind_first: these.iter().filter(right).count() as f64 / n as f64,
        delay_median_s: quantile(&mut delays, 0.5),
        delay_named_median_s: quantile(&mut named, 0.5),
        delay_p95_s: quantile(&mut delays, 0.95),
        delay_after_detectable_median_s: quantile(&mut after, 0.5),
        size_error_first_median: quantile(&mut e_first, 0.5),
        size_error_median: quantile(&mut e_last, 0.5),
        size_error_p95: quantile(&mut e_last, 0.95),
    }
}

/// The per-run and per-size tables in Markdown.
pub fn data_markdown(r: &DataSummary) -> String {
    let f = |v: f64, d: usize| {
        if v.is_finite() {
            format!("{v:.d$}")
        } else {
            "–".into()
        }
    };
    let pct = |v: f64| {
        if v.is_finite() {
            format!("{:.0} %", v * 100.0)
        } else {
            "–".into()
        }
    };
    let mut s = String::from(
        "| run | scenario | truth | real flow L/min | kind named | delay s | kind named after s | size first | size last | false alarms | thresholds L/min (σ) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for o in &r.runs {
        let t = &o.truth;
        let truth = if t.kind == "none" {
            "healthy".to_string()
        } else {
            format!("{} {} @{:.1}s", t.kind, t.size_nominal_lpm, t.t_on_s)
        };
        let first = if o.detected {
            if o.kind_final != o.kind_first {
                format!("{} (then {})", o.kind_first, o.kind_final)
            } else {
                o.kind_first.clone()
            }
        } else {
            "–".into()
        };
        s.push_str(&format!(
            "| {} | {} | {truth} | {} | {first} | {} | {} | {} | {} | {} | {} |\n",
            t.run,
            t.scenario,
            f(t.observed_flow_lpm, 3),
            f(o.delay_s, 2),
            f(o.delay_named_s, 2),
            f(o.size_first_lpm, 3),
            f(o.size_final_lpm, 3),
            o.false_alarms,
            o.thresholds_lpm
                .iter()
                .zip(&o.thresholds_sigma)
                .map(|(l, z)| format!("{} ({})", f(*l, 3), f(*z, 1)))
                .collect::<Vec<_>>()
                .join(" ")
        ));
    }
    s.push_str(
        "\n| nominal L/min | runs | detected | right kind first named | delay median s | delay p95 s | delay after detectable, median s | kind named after, median s | size error at first alarm (median) | size error median | size error p95 |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let rows = r.by_size.iter().map(|c| (c.size_nominal_lpm.to_string(), c));
    let from = r
        .from_quarter_lpm
        .iter()
        .map(|c| (format!("≥ {}", c.size_nominal_lpm), c));
    for (size, c) in rows.chain(from) {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            size,
            c.runs,
            pct(c.p_detect),
            pct(c.p_kind_first),
            f(c.delay_median_s, 2),
            f(c.delay_p95_s, 2),
            f(c.delay_after_detectable_median_s, 2),
            f(c.delay_named_median_s, 2),
            pct(c.size_error_first_median),
            pct(c.size_error_median),
            pct(c.size_error_p95),
        ));
    }
    s.push_str(&format!(
        "\nFalse alarms: {} in {:.2} clean hours (healthy runs and pre-onset time). Sizes are scored against \
         the flow the rig really lost after the ramp; where the run has `truth_flow.csv[.gz]`, against \
         its true flow averaged as the detector averages the size (over `size_window_s`) at that alarm. Delays are counted from the onset, and also from \
         the time the real flow reached the detector's floor for its kind (`min_size_lpm` for an external \
         leak, `min_internal_size_lpm` for an internal one) and held there for `confirm_s`: a leak cannot be declared before its flow gets \
         there (up a ramp, or across a resting rod's chambers that it has equalised). Where the recording \
         has no `q_leak` column, that time is read from the run's `truth_flow.csv[.gz]`; without one, it is \
         the truth's: its flow after the ramp reached linearly over `ramp_s`. \
         The first alarm may say `leak` with its kind pending; \"kind named after\" is the delay of the \
         first alarm that names a kind, the kind scored.\n\nSensor events in the same time: {} (no run has a \
         sensor fault).\n\nWithout evidence after arming: {:.1} s over all runs ({}).\n",
        r.false_alarms,
        r.clean_hours,
        r.sensor_events,
        r.blind_s,
        match r.blind_by_cause.describe() {
            d if d.is_empty() => "none".to_string(),
            d => d,
        }
    ));
    s
}

#[cfg(test)]
mod tests;
