//! `leakwatch bench ...`: thin shells over the `bench` crate that print tables and write JSON.

pub mod calibration;
pub mod floors;
pub mod instances;
pub mod latency;
pub mod operating_leak;
pub mod replay;
pub mod scale;
pub mod sensor_faults;

use std::path::{Path, PathBuf};

use crate::speed::{step_time, timer_overhead_ns};
use crate::{detection, speed};
use filter::Tuning;

use config::Config;
use pipeline::out::{self, outln};
use pipeline::simulate;

pub(crate) fn write_json(
    dir: &Path,
    name: &str,
    value: &serde_json::Value,
    force: bool,
) -> Result<(), String> {
    out::dir(dir)?;
    let p = dir.join(name);
    let text = serde_json::to_string_pretty(value).map_err(|e| e.to_string())?;
    out::write(&p, (text + "\n").as_bytes(), force, &[])?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

/// The loaded scenario's samples for benchmarks, `seconds` long.
pub(crate) fn samples(seconds: f64) -> Vec<model::Sample> {
    crate::speed::recorded_samples(seconds)
}

/// The rig simulator's speed on the loaded scenario (median of `repeat` runs of
/// `seconds` simulated seconds): a table, and sim.json in `out` (or the JSON on stdout).
pub fn sim(seconds: f64, repeat: u32, out: Option<PathBuf>, force: bool) -> Result<(), String> {
    let cfg = Config::default();
    let req = simulate::SimulateRequest {
        scenario: "loaded-sine".into(),
        seconds: Some(seconds),
        seed: 1,
        faults: vec!["ext1:0.5lpm@20s".into()],
        rig_variant: None,
    };
    let mut times = Vec::new();
    for _ in 0..repeat.max(1) {
        let (mut sim, secs) = simulate::build(&cfg, &req)?;
        let t0 = std::time::Instant::now();
        let samples = sim.run(secs);
        times.push(t0.elapsed().as_secs_f64());
        std::hint::black_box(samples);
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    let rate = seconds / median;
    outln!("| benchmark | simulated s | median wall s | min wall s | × real time |");
    outln!("|---|---|---|---|---|");
    outln!(
        "| sim loaded-sine (RK4, {} sub-steps/ms) | {seconds} | {median:.3} | {:.3} | {rate:.0} |",
        cfg.sim.substeps_per_sample,
        times[0]
    );
    let json = serde_json::json!({
        "benchmark": "sim",
        "scenario": "loaded-sine",
        "simulated_s": seconds,
        "substeps_per_sample": cfg.sim.substeps_per_sample,
        "wall_s": times,
        "median_wall_s": median,
        "real_time_factor": rate,
    });
    if let Some(dir) = out {
        out::dir(&dir)?;
        let p = dir.join("sim.json");
        out::write(
            &p,
            serde_json::to_string_pretty(&json).unwrap_or_default().as_bytes(),
            force,
            &[],
        )?;
    } else {
        outln!("{json}");
    }
    Ok(())
}

/// EKF step time per layout (every step timed individually) and the in-process chain's throughput.
pub fn ekf(steps: u64, out: Option<PathBuf>, force: bool) -> Result<(), String> {
    if let Some(dir) = &out {
        out::dir(dir)?;
        out::check(&dir.join("ekf.json"), force, &[])?;
    }
    let samples = speed::recorded_samples(60.0);
    if samples.is_empty() {
        return Err("could not simulate the recorded scenario".into());
    }
    let mut thesis6 = Tuning::thesis();
    thesis6.states = 6;
    let mut leak10 = Tuning::sensor_derived();
    leak10.states = 10;
    let overhead = timer_overhead_ns(100_000);
    let rows = [
        step_time(
            "thesis filter, thesis tuning",
            &Tuning::thesis(),
            &samples,
            steps,
            overhead,
        ),
        step_time("thesis filter, 6 states", &thesis6, &samples, steps, overhead),
        step_time(
            "leak filter without spool bias",
            &leak10,
            &samples,
            steps,
            overhead,
        ),
        step_time(
            "leak filter (default)",
            &Tuning::sensor_derived(),
            &samples,
            steps,
            overhead,
        ),
    ];
    outln!(
        "Each predict + update timed on its own with std::time::Instant; every figure includes \
         the clock's own cost, {overhead:.0} ns here (median of an empty timed region)."
    );
    outln!("| filter | states | steps | median ns | p99 ns | p99.9 ns | max ns | mean ns |");
    outln!("|---|---|---|---|---|---|---|---|");
    for r in &rows {
        outln!(
            "| {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0} |",
            r.filter,
            r.states,
            r.steps,
            r.median_ns,
            r.p99_ns,
            r.p999_ns,
            r.max_ns,
            r.mean_ns
        );
    }
    let tp = speed::chain_throughput(&samples, 5);
    let tp_thesis = speed::chain_throughput_with_thesis(&samples, 5);
    let plant = speed::plant_model();
    let plant_samples = speed::recorded_samples_on(&plant, "lift", 60.0);
    let tp_plant = speed::plant_chain_throughput(&plant_samples, 5);
    outln!("\n| chain | samples | wall s | samples/s (one core) |\n|---|---|---|---|");
    for t in [&tp, &tp_thesis, &tp_plant] {
        outln!(
            "| {} | {} | {:.3} | {:.0} |",
            t.chain,
            t.samples,
            t.wall_s,
            t.samples_per_s
        );
    }
    let json = serde_json::json!({
        "step_time": rows,
        "timing": "per step (std::time::Instant around each predict + update; figures include timer_overhead_ns)",
        "throughput": tp,
        "throughput_thesis_baseline": tp_thesis,
        "throughput_plant": tp_plant,
    });
    match out {
        Some(dir) => write_json(&dir, "ekf.json", &json, force),
        None => {
            outln!("{json}");
            Ok(())
        }
    }
}

/// What `leakwatch bench detection` runs: its command line.
#[derive(Debug, Clone, clap::Args)]
pub struct DetectionBenchArgs {
    /// Runs per leak kind and size.
    #[arg(long, default_value_t = 20)]
    pub runs: usize,
    /// Simulated healthy hours for the false-alarm rate.
    #[arg(long, default_value_t = 10.0)]
    pub hours: f64,
    /// Suite seed.
    #[arg(long, default_value_t = 2026)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Score recorded runs instead of simulating: a directory of run folders, each
    /// with measured.csv[.gz] and truth.json (e.g. DIR/run_000/).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Configuration file (model, filters, classifier) for the chain, with --data.
    #[arg(long, requires = "data")]
    pub config: Option<PathBuf>,
    /// Output directory: detection.json, detection.md (and detection.png for the suite).
    #[arg(long, default_value = "bench-detection")]
    pub out: PathBuf,
}

/// `leakwatch bench detection`: the seeded suite ([`detection`]), or recorded
/// runs with `--data` ([`detection_data`]).
pub fn detection_command(args: &DetectionBenchArgs, force: bool) -> Result<(), String> {
    match &args.data {
        Some(data) => detection_data(data, args.config.as_deref(), args.threads, &args.out, force),
        None => detection(args.runs, args.hours, args.seed, args.threads, &args.out, force),
    }
}

/// The detection suite.
pub fn detection(
    runs: usize,
    hours: f64,
    seed: u64,
    threads: Option<usize>,
    out: &Path,
    force: bool,
) -> Result<(), String> {
    if runs == 0 && hours <= 0.0 {
        return Err("nothing to run: --runs and --hours are both zero".into());
    }
    out::dir(out)?;
    for name in ["detection.md", "detection.png", "detection.json"] {
        out::check(&out.join(name), force, &[])?;
    }
    let threads = threads.unwrap_or_else(pipeline::batch::cores);
    let cases = detection::cases(runs, hours, seed);
    let simulated: f64 = cases.iter().map(|c| c.seconds).sum();
    eprintln!(
        "detection suite: {} runs, {:.1} simulated hours, {threads} threads",
        cases.len(),
        simulated / 3600.0
    );
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    let r = detection::run_suite(&cases, threads, |done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let md = detection::markdown(&r);
    outln!("{md}");
    outln!("suite wall time {:.0} s", r.wall_s);
    out::write(
        &out.join("detection.md"),
        format!("# Detection suite\n{md}").as_bytes(),
        force,
        &[],
    )?;
    out::png(
        &detection::probability_figure(&r),
        &out.join("detection.png"),
        force,
        &[],
    )?;
    for name in ["detection.md", "detection.png"] {
        eprintln!("wrote {}", out.join(name).display());
    }
    let json = serde_json::to_value(&r).map_err(|e| e.to_string())?;
    write_json(out, "detection.json", &json, force)
}

/// The rig's own description and commissioning recording in a plant-style data
/// directory: `datasheet.toml` and `commission_cold.csv[.gz]` beside its `run_*/`
/// folders (either file may be absent).
pub(crate) fn rig_files(dir: &Path) -> (Option<PathBuf>, Option<PathBuf>) {
    let sheet = dir.join("datasheet.toml");
    let recording = ["commission_cold.csv.gz", "commission_cold.csv"]
        .iter()
        .map(|n| dir.join(n))
        .find(|p| p.is_file());
    (sheet.is_file().then_some(sheet), recording)
}

/// Detection scored on recorded runs with truth (`run_*/measured.csv[.gz]` with
/// `truth.json`). A directory laid out like plant_dev runs the README's
/// workflow first: without `--config`, its `datasheet.toml` is the config; with a
/// commissioning recording, `commission` runs on it (bias identified, healthy
/// state learned) before the runs are scored.
pub fn detection_data(
    dir: &Path,
    config: Option<&Path>,
    threads: Option<usize>,
    out: &Path,
    force: bool,
) -> Result<(), String> {
    let (sheet, recording) = rig_files(dir);
    let config_path = config.map(Path::to_path_buf).or(sheet);
    let mut cfg = config::Config::load_or_default(config_path.as_deref())?;
    match &config_path {
        Some(p) => eprintln!("config: {}", p.display()),
        // a rig with a commissioning recording but no description: say what stands in for it
        None if recording.is_some() => {
            config::Config::note_builtin_rig(&format!("datasheet.toml in {}", dir.display()))
        }
        None => {}
    }
    if let Some(rec) = &recording {
        if cfg.classifier.commissioning.is_none() {
            eprintln!("commissioning on {}", rec.display());
            cfg = pipeline::commission::commission(rec, &cfg)?;
        }
    }
    out::dir(out)?;
    let mut inputs: Vec<&Path> = config_path.iter().map(PathBuf::as_path).collect();
    inputs.extend(recording.as_deref());
    for name in ["detection.md", "detection.json"] {
        out::check(&out.join(name), force, &inputs)?;
    }
    let set = pipeline::ChainSettings {
        model: cfg.model.clone(),
        leak_filter: cfg.leak_filter.clone(),
        thesis_filter: cfg.estimator.clone(),
        classifier: cfg.classifier.clone(),
    };
    let threads = threads.unwrap_or_else(pipeline::batch::cores);
    eprintln!("scoring the runs of {} on {threads} threads", dir.display());
    let bar = indicatif::ProgressBar::new(0);
    let r = crate::detection_data::score_dir(dir, &set, threads, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let md = crate::detection_data::data_markdown(&r);
    outln!("{md}");
    outln!("wall time {:.1} s", r.wall_s);
    out::write(
        &out.join("detection.md"),
        // the data set's name, not this machine's path to it
        format!(
            "# Detection on {}\n\n{md}",
            dir.file_name()
                .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned())
        )
        .as_bytes(),
        force,
        &inputs,
    )?;
    eprintln!("wrote {}", out.join("detection.md").display());
    let json = serde_json::to_value(&r).map_err(|e| e.to_string())?;
    write_json(out, "detection.json", &json, force)
}

/// A JSON file read for scoring, if the directory has it.
fn read_json(path: &Path) -> Result<Option<serde_json::Value>, String> {
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| format!("{}: not JSON: {e}", path.display()))
}

/// The truth of a plant-style folder's rig, scored against `model`: an
/// in-repo instance's `instance.toml` (`bench instances`) at its recording's
/// oil temperature, else plant_dev's `truth_rig.json`; with neither, none.
fn truth_of(dir: &Path, model: &model::ActuatorParams) -> Result<crate::identification::Truth, String> {
    let recording = read_json(&dir.join("commission_cold.truth.json"))?;
    let instance = dir.join("instance.toml");
    if !instance.is_file() {
        let rig = read_json(&dir.join("truth_rig.json"))?;
        return Ok(crate::identification::Truth::from_plant(
            model,
            rig.as_ref(),
            recording.as_ref(),
        ));
    }
    let drawn = config::Config::load(&instance)?;
    // (a commissioning recording's oil holds one temperature)
    let oil = |key: &str| {
        recording
            .as_ref()
            .and_then(|r| r.get("oil_temperature")?.get(key)?.as_f64())
    };
    let temp_c = match (oil("start_c"), oil("end_c")) {
        (Some(a), Some(b)) if a == b => a,
        _ => f64::NAN,
    };
    Ok(crate::identification::Truth::from_instance(
        model,
        drawn.rig.as_ref().unwrap_or(&drawn.model),
        &drawn.sensors,
        temp_c,
    ))
}

/// The identification of a plant-style folder's rig on its commissioning
/// recording (config: `--config`, else its `datasheet.toml`), scored against its
/// truth where it has one ([`truth_of`]).
pub(crate) fn identification_data(
    dir: &Path,
    recording: &Path,
    config: Option<&Path>,
    json: bool,
    out: Option<PathBuf>,
    force: bool,
) -> Result<(), String> {
    let (sheet, _) = rig_files(dir);
    let config_path = config.map(Path::to_path_buf).or(sheet);
    let cfg = config::Config::load_or_default(config_path.as_deref())?;
    if let Some(p) = &config_path {
        eprintln!("config: {}", p.display());
    }
    eprintln!("identifying the rig on {}", recording.display());
    let t0 = std::time::Instant::now();
    let found = pipeline::commission::identify_on(recording, &cfg)?;
    let (id, mech) = (found.rig, found.mechanics);
    let wall_s = t0.elapsed().as_secs_f64();
    let truth = truth_of(dir, &cfg.model)?;
    let score = crate::identification::score(
        &cfg.model,
        cfg.datasheet
            .as_ref()
            .and_then(|d| d.pressure_transducers.lag_bound_s()),
        &id,
        mech.as_ref().ok(),
        &truth,
    );
    let md = format!(
        "{}
Identified in {wall_s:.2} s.
",
        score.markdown()
    );
    if json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&score).map_err(|e| e.to_string())?
        );
    } else {
        outln!("{md}");
    }
    if let Some(out) = out {
        out::dir(&out)?;
        let mut inputs: Vec<&Path> = config_path.iter().map(PathBuf::as_path).collect();
        inputs.push(recording);
        out::write(
            &out.join("identification.md"),
            format!("# Identification on {}\n\n{md}", dir.display()).as_bytes(),
            force,
            &inputs,
        )?;
        let v = serde_json::to_value(&score).map_err(|e| e.to_string())?;
        write_json(&out, "identification.json", &v, force)?;
    }
    Ok(())
}
