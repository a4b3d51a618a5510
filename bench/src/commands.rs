//! `leakwatch bench ...`: thin shells over the `bench` crate that print tables and write JSON.

pub mod floors;
pub mod instances;
pub mod latency;
pub mod scale;

use std::path::{Path, PathBuf};

use crate::speed::{step_time, timer_overhead_ns};
use crate::{detection, speed};
use filter::Tuning;

use config::Config;
use pipeline::out::{self, outln};
use pipeline::simulate;

fn write_json(dir: &Path, name: &str, value: &serde_json::Value, force: bool) -> Result<(), String> {
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
    let tp_plant = speed::chain_throughput_on(
        "the default chain on the plant model (single-rod lift, gravity, null leakage, supply sag)",
        &plant,
        &plant_samples,
        5,
        false,
    );
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
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1));
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
fn rig_files(dir: &Path) -> (Option<PathBuf>, Option<PathBuf>) {
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
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1));
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
        format!("# Detection on {}\n\n{md}", dir.display()).as_bytes(),
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

/// The identification of a plant-style folder's rig on its commissioning
/// recording (config: `--config`, else its `datasheet.toml`), scored against its
/// `truth_rig.json` and `commission_cold.truth.json` where present.
fn identification_data(
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
    let rig = read_json(&dir.join("truth_rig.json"))?;
    let rec = read_json(&dir.join("commission_cold.truth.json"))?;
    let score = crate::identification::score(
        &cfg.model,
        cfg.datasheet
            .as_ref()
            .and_then(|d| d.pressure_transducers.lag_bound_s()),
        &id,
        mech.as_ref().ok(),
        rig.as_ref(),
        rec.as_ref(),
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

/// The calibration workflow's hidden-effect suites (smooth and stick-slip rig, or the smooth
/// matrix), or a directory of cases with truth (`--data`).
pub fn calibration(
    matrix: bool,
    data: Option<PathBuf>,
    config: Option<PathBuf>,
    json: bool,
    out: Option<PathBuf>,
    force: bool,
) -> Result<(), String> {
    if let Some(dir) = &data {
        if let (_, Some(recording)) = rig_files(dir) {
            return identification_data(dir, &recording, config.as_deref(), json, out, force);
        }
    }
    let opts = calibrate::CalibrateOptions {
        keep_traces: false,
        ..calibrate::CalibrateOptions::default()
    };
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(2);
    let reports: Vec<(&str, calibrate::BenchReport)> = if let Some(dir) = data {
        let model = match config {
            Some(p) => pipeline::model_file::load_model(&p).map_err(|e| e.to_string())?,
            None => model::ActuatorParams::default(),
        };
        let bar = indicatif::ProgressBar::new(0);
        let r = calibrate::external::bench_dir(&dir, &model, &opts, threads, &|d, n| {
            bar.set_length(n as u64);
            bar.set_position(d as u64);
        })
        .map_err(|e| e.to_string())?;
        bar.finish_and_clear();
        vec![("data", r)]
    } else if matrix {
        let shooting = calibrate::CalibrateOptions::shooting();
        vec![(
            "matrix",
            suite_with_bar("smooth-rig matrix", &calibrate::suite::matrix_cases(), &shooting),
        )]
    } else {
        vec![
            (
                "smooth",
                suite_with_bar("smooth rig", &calibrate::suite::cases(), &opts),
            ),
            (
                "thesis",
                suite_with_bar("stick-slip rig", &calibrate::suite::thesis_cases(), &opts),
            ),
        ]
    };
    if json {
        let v: serde_json::Map<String, serde_json::Value> = reports
            .iter()
            .map(|(k, r)| (k.to_string(), serde_json::to_value(r).unwrap_or_default()))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&v).map_err(|e| e.to_string())?);
    } else {
        for (k, r) in &reports {
            outln!("## {k}\n\n{}", r.markdown());
        }
    }
    if let Some(dir) = out {
        for (k, r) in &reports {
            let d = if reports.len() > 1 {
                dir.join(k)
            } else {
                dir.clone()
            };
            let files = r.write(&d, force).map_err(|e| e.to_string())?;
            for f in files {
                eprintln!("wrote {}", f.display());
            }
        }
    }
    Ok(())
}

/// One calibration suite on two threads, with a progress bar of its cases on stderr.
fn suite_with_bar(
    name: &str,
    cases: &[calibrate::suite::SuiteCase],
    opts: &calibrate::CalibrateOptions,
) -> calibrate::BenchReport {
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg}: {bar:30} {pos}/{len} cases  {elapsed} (eta {eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(name.to_string());
    let r = calibrate::suite::bench_cases_with_progress(cases, opts, 2, &|d, _| bar.set_position(d as u64));
    bar.finish();
    r
}

/// `leakwatch bench replay`: batch replay throughput, one pass of `leakwatch
/// replay DIR` (the batch path, outputs in OUT/replay-pass-<threads>/, removed
/// after the pass) per number of worker threads in `threads` (default: 1 and
/// all cores), on `data` or on `files` closed-loop-random CSVs of `seconds` s
/// simulated into OUT/replay-inputs/ (healthy, ext1, ext2, int leaks in turn;
/// removed at the end), each writing its estimates as `estimates` says; a
/// table on stdout and OUT/replay.json. The default configuration, never
/// ./leakwatch.toml.
pub fn replay(
    data: Option<&Path>,
    threads: &[usize],
    files: usize,
    seconds: f64,
    estimates: pipeline::estimates_out::EstimatesFormat,
    out: &Path,
    force: bool,
) -> Result<(), String> {
    use pipeline::batch;
    use pipeline::replay_cmd::Settings;
    use std::sync::atomic::{AtomicUsize, Ordering};

    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let mut counts: Vec<usize> = if threads.is_empty() {
        vec![1, cores]
    } else {
        threads.to_vec()
    };
    counts.dedup();
    if counts.contains(&0) {
        return Err("--threads 0: at least one worker thread".into());
    }
    out::dir(out)?;
    let json_path = out.join("replay.json");
    out::check(&json_path, force, &[])?;
    let pass_dir = |n: usize| out.join(format!("replay-pass-{n}"));
    for &n in &counts {
        if pass_dir(n).exists() && !force {
            return Err(format!(
                "{} exists (a pass's outputs): remove it or use --force",
                pass_dir(n).display()
            ));
        }
    }
    let cfg = Config::default();
    let generated = data.is_none();
    let dir = match data {
        Some(d) => d.to_path_buf(),
        None => {
            if files == 0 {
                return Err("--files 0: nothing to replay".into());
            }
            simulate::check_seconds(seconds, cfg.sim.sample_period_s)?;
            let dir = out.join("replay-inputs");
            out::dir(&dir)?;
            eprintln!(
                "simulating {files} files of {seconds} s into {} on {cores} threads",
                dir.display()
            );
            let next = AtomicUsize::new(0);
            let errors: Vec<String> = std::thread::scope(|scope| {
                let workers: Vec<_> = (0..cores.min(files))
                    .map(|_| {
                        scope.spawn(|| {
                            let mut errors = Vec::new();
                            loop {
                                let i = next.fetch_add(1, Ordering::Relaxed);
                                if i >= files {
                                    return errors;
                                }
                                let onset_s = seconds / 2.0;
                                let fault = match i % 4 {
                                    0 => "none".to_string(),
                                    1 => format!("ext1:0.3lpm@{onset_s}s"),
                                    2 => format!("ext2:0.3lpm@{onset_s}s"),
                                    _ => format!("int:0.3lpm@{onset_s}s"),
                                };
                                let req = simulate::SimulateRequest {
                                    scenario: "closed-loop-random".into(),
                                    seconds: Some(seconds),
                                    seed: i as u64 + 1,
                                    faults: vec![fault],
                                    rig_variant: None,
                                };
                                let path = dir.join(format!("run_{i:03}.csv"));
                                if let Err(e) = simulate::run(&cfg, &req, &path, true, None) {
                                    errors.push(e);
                                }
                            }
                        })
                    })
                    .collect();
                workers
                    .into_iter()
                    .flat_map(|w| w.join().unwrap_or_else(|_| vec!["a simulation panicked".into()]))
                    .collect()
            });
            if let Some(e) = errors.first() {
                return Err(e.clone());
            }
            dir
        }
    };
    let settings = Settings {
        cfg,
        config: None,
        estimates,
        thesis_estimates: false,
        max_bad_rows: dataset::DEFAULT_MAX_BAD_FRACTION,
        force: true,
    };
    let mut passes: Vec<crate::replay::ReplayPass> = Vec::new();
    for &n in &counts {
        let pass_out = pass_dir(n);
        let jobs = batch::jobs(std::slice::from_ref(&dir), &pass_out)?;
        let threads = batch::threads_for(Some(n), jobs.len())?;
        eprintln!("pass: {} files on {threads} threads", jobs.len());
        out::dir(&pass_out)?;
        let b = batch::replay_all(&jobs, &pass_out, &settings, threads, true);
        let per_file = jobs
            .iter()
            .zip(&b.done)
            .map(|(job, d)| crate::replay::FileTime {
                file: job.name.clone(),
                samples: d.result.as_ref().map_or(0, |s| s.samples),
                wall_s: d.wall_s,
                error: d.result.as_ref().err().cloned(),
            })
            .collect();
        let first = passes.first().map(|p| p.samples_per_s);
        passes.push(crate::replay::ReplayPass::new(threads, per_file, b.wall_s, first));
        std::fs::remove_dir_all(&pass_out)
            .map_err(|e| format!("cannot remove {}: {e}", pass_out.display()))?;
    }
    if generated {
        std::fs::remove_dir_all(&dir).map_err(|e| format!("cannot remove {}: {e}", dir.display()))?;
    }
    let report = crate::replay::ReplayBench {
        data: dir.display().to_string(),
        generated,
        cores,
        estimates: format!("{estimates:?}").to_lowercase(),
        passes,
    };
    outln!("{}", crate::replay::table(&report));
    for p in &report.passes {
        if let Some(f) = p.per_file.iter().find(|f| f.error.is_some()) {
            eprintln!(
                "warning: {} of {} files failed on {} threads; first: {}: {}",
                p.failed,
                p.files,
                p.threads,
                f.file,
                f.error.as_deref().unwrap_or_default()
            );
        }
    }
    let json = serde_json::to_value(&report).map_err(|e| e.to_string())?;
    write_json(out, "replay.json", &json, force)
}
