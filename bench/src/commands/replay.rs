//! `leakwatch bench replay`: batch replay throughput per number of worker threads.

use std::path::{Path, PathBuf};

use super::write_json;
use config::Config;
use pipeline::out::{self, outln};
use pipeline::simulate;

/// What `leakwatch bench replay` measures: its command line.
#[derive(Debug, Clone, clap::Args)]
pub struct ReplayBenchArgs {
    /// Directory to replay as `leakwatch replay DIR` would (default: generate the files
    /// into OUT/replay-inputs/, removed at the end).
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// Numbers of worker threads to measure, one pass each (default: 1 and all cores).
    #[arg(long, value_delimiter = ',')]
    pub threads: Vec<usize>,
    /// Generated files (without --data).
    #[arg(long, default_value_t = 16)]
    pub files: usize,
    /// Length of each generated file, s (without --data).
    #[arg(long, default_value_t = 600.0)]
    pub seconds: f64,
    /// Format of each replay's estimates file: auto (the default, as a batch of `replay` writes: parquet), csv, parquet or none.
    #[arg(long, value_enum, default_value_t)]
    pub estimates: pipeline::estimates_out::EstimatesFormat,
    /// Output directory: replay.json (each pass's replay outputs are written under it and removed).
    #[arg(long)]
    pub out: PathBuf,
}

/// `leakwatch bench replay`: batch replay throughput, one pass of `leakwatch
/// replay DIR` (the batch path, outputs in OUT/replay-pass-<threads>/, removed
/// after the pass) per number of worker threads in `args.threads` (default: 1
/// and all cores), on `args.data` or on `args.files` closed-loop-random CSVs of
/// `args.seconds` s simulated into OUT/replay-inputs/ (healthy, ext1, ext2, int
/// leaks in turn; removed at the end), each writing its estimates as
/// `args.estimates` says; a table on stdout and OUT/replay.json. The default
/// configuration, never ./leakwatch.toml.
pub fn bench(args: &ReplayBenchArgs, force: bool) -> Result<(), String> {
    use pipeline::batch;
    use pipeline::replay_cmd::Settings;

    let (threads, estimates, out) = (&args.threads, args.estimates, args.out.as_path());

    let cores = pipeline::batch::cores();
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
    let generated = args.data.is_none();
    let dir = match &args.data {
        Some(d) => d.clone(),
        None => generate_inputs(&cfg, args.files, args.seconds, &out.join("replay-inputs"), cores)?,
    };
    let settings = Settings {
        cfg,
        config: None,
        estimates,
        estimates_every: 1,
        batch: true,
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
        estimates: estimates.for_batch().name().to_string(),
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

/// Simulates `files` closed-loop-random CSVs of `seconds` s into `dir` on up
/// to `cores` threads (healthy, ext1, ext2 and int leaks of 0.3 L/min at
/// half-time in turn); returns `dir`.
fn generate_inputs(
    cfg: &Config,
    files: usize,
    seconds: f64,
    dir: &Path,
    cores: usize,
) -> Result<PathBuf, String> {
    use std::sync::atomic::{AtomicUsize, Ordering};

    if files == 0 {
        return Err("--files 0: nothing to replay".into());
    }
    simulate::check_seconds(seconds, cfg.sim.sample_period_s)?;
    out::dir(dir)?;
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
                        if let Err(e) = simulate::run(cfg, &req, &path, true, None) {
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
    match errors.first() {
        Some(e) => Err(e.clone()),
        None => Ok(dir.to_path_buf()),
    }
}
