//! `leakwatch replay`: file -> estimator -> classifier in one process, faster
//! than real time, as stages connected by crossbeam channels (or in one
//! thread; both give the same output bit for bit).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use dataset::{CsvReader, Limits, RowSource, SampleRows};
use detect::LeakEvent;
use filter::StageEstimate;
use serde::Serialize;

use crate::estimates_out::{EstimatesFormat, EstimatesWriter};
use config::Config;
pub use watch::Watch;
use wiring::{replay_channels, replay_single_thread, Progress};

pub mod figure;
pub mod report;
pub mod trace;
mod watch;
mod wiring;

/// How the stages are connected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wiring {
    /// Reader, estimator and classifier in three threads over bounded crossbeam channels.
    Channels,
    /// Everything in the calling thread.
    SingleThread,
}

/// What to replay and where to write.
#[derive(Debug, Clone)]
pub struct ReplayRequest {
    /// The input: a CSV in the dataset format, or a recorded log (`.mcap`, its first part).
    pub input: PathBuf,
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// The configuration.
    pub config: Config,
    /// How the stages are connected.
    pub wiring: Wiring,
    /// Show a progress bar on a terminal.
    pub progress: bool,
    /// Largest fraction of unusable rows (0 to 1) before the file is refused
    /// (outputs written, then an error).
    pub max_bad_fraction: f64,
    /// Replace existing output files (`--force`).
    pub overwrite: bool,
    /// Other inputs (the config, an original log) that no output may replace.
    pub protect: Vec<PathBuf>,
    /// Format of the estimates file (estimates.csv, estimates.parquet or none;
    /// [`EstimatesFormat::Auto`] resolved before).
    pub estimates: EstimatesFormat,
    /// One estimates row every this many samples (1: every sample; `--estimates-every`).
    pub estimates_every: u64,
    /// Why the estimates take that format (said in the summary).
    pub estimates_why: String,
    /// The thesis filter's estimates were asked for (`--model`): it runs and
    /// the estimates file has its `th_*` columns (as with the thesis baseline).
    pub thesis_estimates: bool,
    /// Samples processed so far, added to as the replay goes (a batch's progress
    /// across its worker threads); none: not counted.
    pub samples_done: Option<std::sync::Arc<std::sync::atomic::AtomicU64>>,
    /// Files the caller writes into the output directory after the replay (the
    /// report): refused as the replay's own are, after them, before anything is
    /// read or written.
    pub also_writes: Vec<PathBuf>,
}

/// What reading a recorded log (MCAP) skipped, reported in summary.json.
#[derive(Debug, Clone, Default, Serialize)]
pub struct LogDamage {
    /// Damaged chunks skipped (byte offset and reason), never decompressed unbounded.
    pub chunks_skipped: Vec<String>,
    /// Sensor frames (samples) lost with them.
    pub frames_lost: u64,
}

/// Residual statistics of one filter.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ResidualRms {
    /// RMS of the a-posteriori position residual, m.
    pub x_m: f64,
    /// RMS of the a-posteriori p1 residual, Pa.
    pub p1_pa: f64,
    /// RMS of the a-posteriori p2 residual, Pa.
    pub p2_pa: f64,
    /// RMS of the p1 innovation, Pa.
    pub innovation_p1_pa: f64,
    /// RMS of the p2 innovation, Pa.
    pub innovation_p2_pa: f64,
    /// Mean normalised innovation squared (3 when consistent).
    pub mean_nis: f64,
    /// Filter resets.
    pub resets: u64,
    /// Samples whose NIS exceeded the classifier's `nis_gate`: a value in the data
    /// far from anything the filter expects (a spike, a glitch) or a stretch the
    /// model does not follow; the leak detector takes no evidence after them for
    /// `recovery_s`.
    pub nis_outliers: u64,
    /// Sample time of the first of them, s (NaN: none).
    pub first_nis_outlier_s: f64,
    /// The oil's stiffness θ at the last estimate, as a multiple of the model's
    /// bulk modulus (1; NaN for a filter without that state): well below 1, the
    /// rig's oil is softer than the model's (entrained air, hoses).
    pub bulk_scale: f64,
    /// One standard deviation of [`Self::bulk_scale`] (1; NaN without that state).
    pub bulk_scale_sigma: f64,
    /// The oil temperatures the model followed, °C, lowest and highest
    /// (`temp_c` of the samples, else read from θ; NaN: neither).
    pub oil_temp_range_c: (f64, f64),
    /// Whether those temperatures were read from the oil's stiffness θ (no `temp_c`).
    pub oil_temp_from_stiffness: bool,
    /// The model's operating range of oil temperatures, °C (lowest, highest):
    /// the range commissioning stated the smallest detectable leaks over.
    pub oil_operating_range_c: (f64, f64),
    /// Time the oil was outside that range by more than its temperature's σ, s.
    pub oil_outside_range_s: f64,
    /// Sample time it first was, s (NaN: never).
    pub first_oil_outside_range_s: f64,
}

/// The estimates file a replay wrote, in summary.json.
#[derive(Debug, Clone, Default, Serialize)]
pub struct EstimatesOut {
    /// `csv`, `parquet` or `none`.
    pub format: String,
    /// Its file name in the output directory (null: none written).
    pub file: Option<String>,
    /// One row every this many samples (1: every sample).
    pub every: u64,
    /// Rows written.
    pub rows: u64,
    /// Why this format: asked for, or the default's rule.
    pub why: String,
}

/// What `summary.json` holds.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Summary {
    /// The input file.
    pub input: String,
    /// Samples processed.
    pub samples: u64,
    /// Data rows read from the input (usable and skipped).
    pub rows: u64,
    /// Rows of the input that could not be used (skipped, each reported).
    pub rows_skipped: u64,
    /// The skipped rows by reason (`not_a_number`, `non_finite`, `out_of_range`,
    /// `time_not_increasing`, `step_too_short`, `wrong_cell_count`, `not_text`,
    /// `read_error`).
    pub rows_rejected: BTreeMap<String, u64>,
    /// Largest fraction of skipped rows accepted (0 to 1, `--max-bad-rows`).
    pub max_bad_fraction: f64,
    /// Why the input was refused (too many unusable rows), if it was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
    /// Usable rows with an optional column absent (empty or NaN), per column present in the header.
    pub optional_absent: BTreeMap<String, u64>,
    /// For a recorded log (MCAP) input: damaged chunks skipped and the samples lost with them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub log: Option<LogDamage>,
    /// Samples missing from the time stamps (gaps), bridged or causing resets.
    pub samples_missing: u64,
    /// Input problems, with line and column (the first 100).
    pub issues: Vec<String>,
    /// Wall time, s.
    pub wall_s: f64,
    /// Samples per second of wall time.
    pub samples_per_s: f64,
    /// The leak filter's residuals.
    pub leak_filter: ResidualRms,
    /// The thesis filter's residuals; absent when nothing read the thesis
    /// filter (no per-sample estimates and no thesis baseline), which then did not run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thesis_filter: Option<ResidualRms>,
    /// Number of events written to events.json.
    pub events: usize,
    /// How much of the run the leak detector watched.
    pub watch: Watch,
    /// How the stages were connected.
    pub wiring: String,
    /// The estimates file: format, name, decimation and why.
    pub estimates: EstimatesOut,
    /// The events written to events.json (not repeated in summary.json): the
    /// batch replay's table reads the leak kinds and first alarm from them.
    #[serde(skip)]
    pub event_log: Vec<LeakEvent>,
}

struct Acc {
    n: f64,
    sq: [f64; 5],
    nis: f64,
    /// NIS above which a sample counts as an outlier (the classifier's `nis_gate`).
    nis_gate: f64,
    outliers: u64,
    first_outlier_s: f64,
    /// θ and its σ at the last estimate that had them.
    bulk_scale: (f64, f64),
    /// Lowest and highest oil temperature the model was at, °C.
    oil_temp_c: (f64, f64),
    /// Some of them were read from θ.
    oil_temp_from_stiffness: bool,
    /// The operating range, °C.
    operating_c: (f64, f64),
    /// Time outside it, s, and when it began (NaN: never).
    outside_s: f64,
    first_outside_s: f64,
    /// The previous estimate's time, s (NaN: none yet).
    last_t_s: f64,
}

impl Acc {
    fn new(nis_gate: f64, operating_c: (f64, f64)) -> Acc {
        Acc {
            n: 0.0,
            sq: [0.0; 5],
            nis: 0.0,
            nis_gate,
            outliers: 0,
            first_outlier_s: f64::NAN,
            bulk_scale: (f64::NAN, f64::NAN),
            oil_temp_c: (f64::NAN, f64::NAN),
            oil_temp_from_stiffness: false,
            operating_c,
            outside_s: 0.0,
            first_outside_s: f64::NAN,
            last_t_s: f64::NAN,
        }
    }

    fn push(&mut self, e: &filter::Estimate) {
        if e.nis > self.nis_gate {
            if self.outliers == 0 {
                self.first_outlier_s = e.t_s;
            }
            self.outliers += 1;
        }
        if e.bulk_scale.is_finite() {
            self.bulk_scale = (e.bulk_scale, e.bulk_scale_sigma);
        }
        if e.oil_temp_c.is_finite() {
            // f64::min/max skip the NaN of the start
            self.oil_temp_c = (
                self.oil_temp_c.0.min(e.oil_temp_c),
                self.oil_temp_c.1.max(e.oil_temp_c),
            );
            self.oil_temp_from_stiffness |= e.oil_temp_sigma_k > 0.0;
            self.count_outside(e);
        }
        self.last_t_s = e.t_s;
        if !(e.residual.iter().all(|r| r.is_finite()) && e.flags & filter::FLAG_CONVERGING == 0) {
            return;
        }
        self.n += 1.0;
        self.sq[0] += e.residual[0].powi(2);
        self.sq[1] += e.residual[1].powi(2);
        self.sq[2] += e.residual[2].powi(2);
        self.sq[3] += e.innovation[1].powi(2);
        self.sq[4] += e.innovation[2].powi(2);
        self.nis += e.nis;
    }
    /// Counts the time from the previous estimate to `e` (at most 0.1 s across
    /// a gap) when `e`'s oil temperature is outside the operating range by
    /// more than its σ, or is held at the range's margin
    /// ([`filter::oil::OIL_RANGE_MARGIN_K`]: θ reads it there or beyond).
    fn count_outside(&mut self, e: &filter::Estimate) {
        let sigma = if e.oil_temp_sigma_k.is_finite() {
            e.oil_temp_sigma_k
        } else {
            0.0
        };
        let (lo, hi) = self.operating_c;
        let held = filter::oil::OIL_RANGE_MARGIN_K - filter::oil::OIL_ESTIMATE_STEP_K;
        let at_margin = e.oil_temp_c >= hi + held || e.oil_temp_c <= lo - held;
        if e.oil_temp_c + sigma >= lo && e.oil_temp_c - sigma <= hi && !at_margin {
            return;
        }
        if self.first_outside_s.is_nan() {
            self.first_outside_s = e.t_s;
        }
        let dt = e.t_s - self.last_t_s;
        if dt > 0.0 {
            self.outside_s += dt.min(0.1);
        }
    }

    fn finish(&self, resets: u64) -> ResidualRms {
        let n = self.n.max(1.0);
        let r = |k: usize| (self.sq[k] / n).sqrt();
        ResidualRms {
            x_m: r(0),
            p1_pa: r(1),
            p2_pa: r(2),
            innovation_p1_pa: r(3),
            innovation_p2_pa: r(4),
            mean_nis: self.nis / n,
            resets,
            nis_outliers: self.outliers,
            first_nis_outlier_s: self.first_outlier_s,
            bulk_scale: self.bulk_scale.0,
            bulk_scale_sigma: self.bulk_scale.1,
            oil_temp_range_c: self.oil_temp_c,
            oil_temp_from_stiffness: self.oil_temp_from_stiffness,
            oil_operating_range_c: self.operating_c,
            oil_outside_range_s: self.outside_s,
            first_oil_outside_range_s: self.first_outside_s,
        }
    }
}

/// Writes events as a JSON array (NaN becomes null); an existing file only if
/// `force`, none of `inputs` ever (see [`crate::out::write`]).
pub fn write_events(path: &Path, events: &[LeakEvent], force: bool, inputs: &[&Path]) -> Result<(), String> {
    let text = serde_json::to_string_pretty(events).map_err(|e| format!("events: {e}"))?;
    crate::out::write(path, (text + "\n").as_bytes(), force, inputs)
}

/// Whether `path` is a recorded log (`.mcap`, any case), read by its sensor frames.
pub fn is_log(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

/// Runs a replay and writes estimates.csv (or .parquet), events.json and summary.json into the output directory.
/// The input is a CSV (read row by row) or a recorded log ([`is_log`]: its
/// sensor frames, every part, decoded into memory and checked as the rows of
/// their CSV export would be).
pub fn run(req: &ReplayRequest) -> Result<Summary, String> {
    let paths = OutputPaths::prepare(req)?;
    let cfg = &req.config;
    let limits = Limits::for_model(&cfg.model, cfg.leak_filter.sample_period_s);
    if is_log(&req.input) {
        let (samples, damage) = crate::logs::log_samples(&req.input)?;
        let mut summary = new_summary(req);
        summary.log = Some(damage);
        run_rows(req, &paths, SampleRows::new(samples, limits), summary)
    } else {
        let reader = CsvReader::open(&req.input, limits).map_err(|e| e.to_string())?;
        run_rows(req, &paths, reader, new_summary(req))
    }
}

/// The replay of `rows` (the input of `req`) into `paths`, from `summary` as it starts.
fn run_rows(
    req: &ReplayRequest,
    paths: &OutputPaths<'_>,
    reader: impl RowSource + Send,
    mut summary: Summary,
) -> Result<Summary, String> {
    let est_name = &paths.est_name;
    let cfg = &req.config;
    // The thesis filter runs when its output is asked for: its estimates
    // (`--model`, the `th_*` columns) or the thesis' baseline; otherwise it
    // does not (a third of the work).
    let thesis_wanted = req.thesis_estimates || cfg.classifier.thesis_baseline;
    let mut out = open_estimates(req, paths, thesis_wanted)?;
    let mut trace = match &paths.trace {
        Some(p) => Some(
            trace::DetectorTrace::new(crate::out::create(p, req.overwrite, &paths.inputs)?)
                .map_err(|e| format!("{}: {e}", p.display()))?,
        ),
        None => None,
    };
    let mut chain = crate::Chain::new(&crate::ChainSettings::from(cfg))?.with_thesis(thesis_wanted);
    // (the channel wiring runs the stage and the detectors on two threads)
    let (stage, cls) = chain.parts_mut();
    if req.progress {
        eprintln!("note: {}", cls.start_note());
    }
    let mut events: Vec<LeakEvent> = Vec::new();
    let thesis_runs = stage.thesis_runs();
    let gate = req.config.classifier.nis_gate;
    let oil = &req.config.model.oil_temperature;
    let operating_c = (oil.operating_min_c, oil.operating_max_c);
    let mut acc = (Acc::new(gate, operating_c), Acc::new(gate, operating_c));
    let mut last_t = 0.0;
    let mut first_t = f64::NAN;
    let progress = Progress::new(req);
    let started = Instant::now();

    // The sink: classifier, accumulation and file writing.
    let mut write_err: Option<String> = None;
    let every = req.estimates_every.max(1);
    let mut rows_written = 0u64;
    let mut reach = dataset::PressureReach::default();
    let mut sink = |s: &StageEstimate, summary: &mut Summary| {
        summary.samples += 1;
        reach.add_pressures(s.leak.measured[1], s.leak.measured[2]);
        last_t = s.leak.t_s;
        if first_t.is_nan() {
            first_t = s.leak.t_s;
        }
        acc.0.push(&s.leak);
        if thesis_runs {
            acc.1.push(&s.thesis);
        }
        cls.on_stage(s, |ev| events.push(ev));
        if write_err.is_none() && (summary.samples - 1).is_multiple_of(every) {
            rows_written += 1;
            if let Err(e) = out.write(s) {
                write_err = Some(format!("{est_name}: {e}"));
            }
            if let Some(Err(e)) = trace.as_mut().map(|t| t.push(&s.leak, cls)) {
                write_err = Some(format!("{}: {e}", trace::FILE_NAME));
            }
        }
    };
    let has_optional = reader.has_optional();
    let absent = match req.wiring {
        Wiring::SingleThread => replay_single_thread(reader, stage, &mut summary, &mut sink, &progress),
        Wiring::Channels => replay_channels(reader, stage, &mut summary, &mut sink, &progress),
    };
    progress.count(summary.samples);
    cls.finish(last_t, |ev| events.push(ev));
    progress.bar.finish_and_clear();
    if let Some(e) = write_err {
        return Err(e);
    }
    out.finish().map_err(|e| format!("{est_name}: {e}"))?;
    if let Some(t) = trace {
        t.finish().map_err(|e| format!("{}: {e}", trace::FILE_NAME))?;
    }
    summary.wall_s = started.elapsed().as_secs_f64();
    summary.samples_per_s = summary.samples as f64 / summary.wall_s.max(1e-9);
    summary.samples_missing = stage.missing_samples();
    summary.leak_filter = acc.0.finish(stage.leak().counters().resets);
    summary.thesis_filter = thesis_runs.then(|| acc.1.finish(stage.thesis().counters().resets));
    summary.events = events.len();
    summary.watch = Watch::of(cls, &events, first_t, last_t);
    summary.rows = summary.samples + summary.rows_skipped;
    summary.max_bad_fraction = req.max_bad_fraction;
    for (k, name) in dataset::COLUMNS[dataset::REQUIRED.len()..].iter().enumerate() {
        if has_optional[k] {
            summary.optional_absent.insert(name.to_string(), absent[k]);
        }
    }
    summary.refused = refusal(&summary, req);
    // (said first: every other warning follows from it)
    if let Err(e) = reach.check(cfg.model.supply_pressure_pa) {
        summary.issues.insert(0, e);
    }
    summary.estimates = EstimatesOut {
        format: req.estimates.name().into(),
        file: req.estimates.file_name().map(str::to_string),
        every,
        rows: rows_written,
        why: req.estimates_why.clone(),
    };
    write_events(&paths.events, &events, req.overwrite, &paths.inputs)?;
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    crate::out::write(
        &paths.summary,
        (text + "\n").as_bytes(),
        req.overwrite,
        &paths.inputs,
    )?;
    if let Some(why) = &summary.refused {
        return Err(why.clone());
    }
    summary.event_log = events;
    Ok(summary)
}

/// Where a replay writes, and what it must not overwrite.
struct OutputPaths<'a> {
    /// The inputs (the recording, then `req.protect`), which no output may replace.
    inputs: Vec<&'a Path>,
    /// The estimates file, unless none is written.
    estimates: Option<PathBuf>,
    /// detector.csv, written with the estimates file.
    trace: Option<PathBuf>,
    /// events.json and summary.json.
    events: PathBuf,
    summary: PathBuf,
    /// The estimates file's name in messages (the output directory when none is written).
    est_name: String,
}

impl<'a> OutputPaths<'a> {
    /// Creates the output directory and refuses an output that exists (without
    /// `--force`) or is an input, before anything is read or written.
    fn prepare(req: &'a ReplayRequest) -> Result<OutputPaths<'a>, String> {
        crate::out::dir(&req.out_dir)?;
        let mut inputs: Vec<&Path> = vec![req.input.as_path()];
        inputs.extend(req.protect.iter().map(|p| p.as_path()));
        let est_path = req.estimates.file_name().map(|name| req.out_dir.join(name));
        let events_path = req.out_dir.join("events.json");
        let summary_path = req.out_dir.join("summary.json");
        let trace_path = est_path.as_ref().map(|_| trace::path_in(&req.out_dir));
        // Refuse before reading or writing anything.
        for p in est_path
            .iter()
            .chain(&trace_path)
            .chain([&events_path, &summary_path])
            .chain(&req.also_writes)
        {
            crate::out::check(p, req.overwrite, &inputs)?;
        }
        let est_name = est_path.as_deref().unwrap_or(&req.out_dir).display().to_string();
        Ok(OutputPaths {
            inputs,
            estimates: est_path,
            trace: trace_path,
            events: events_path,
            summary: summary_path,
            est_name,
        })
    }
}

/// Creates the estimates file (if one is asked for) and its writer, with the
/// thesis filter's columns when `thesis_wanted`.
fn open_estimates(
    req: &ReplayRequest,
    paths: &OutputPaths<'_>,
    thesis_wanted: bool,
) -> Result<EstimatesWriter, String> {
    let file = match &paths.estimates {
        Some(p) => Some(crate::out::create(p, req.overwrite, &paths.inputs)?),
        None => None,
    };
    EstimatesWriter::new(file, req.estimates, thesis_wanted).map_err(|e| format!("{}: {e}", paths.est_name))
}

/// The summary before the replay: its input, the log's damage and the wiring.
fn new_summary(req: &ReplayRequest) -> Summary {
    Summary {
        input: req.input.display().to_string(),
        wiring: match req.wiring {
            Wiring::Channels => "channels".into(),
            Wiring::SingleThread => "single-thread".into(),
        },
        ..Summary::default()
    }
}

/// Why the recording is refused, if it is: no usable sample, or more bad rows
/// than `req.max_bad_fraction` (the first issue that is not a gap named).
fn refusal(summary: &Summary, req: &ReplayRequest) -> Option<String> {
    let first = summary
        .issues
        .iter()
        .find(|i| !i.contains("gap of"))
        .map(|i| format!("; first: {i}"))
        .unwrap_or_default();
    if summary.samples == 0 {
        Some(format!(
            "{}: no usable samples ({} rows skipped{first})",
            req.input.display(),
            summary.rows_skipped
        ))
    } else {
        dataset::check_bad_fraction(summary.rows, summary.rows_skipped, req.max_bad_fraction)
            .err()
            .map(|e| {
                format!(
                    "{}: {e} (--max-bad-rows {}){first}; see summary.json",
                    req.input.display(),
                    req.max_bad_fraction
                )
            })
    }
}
