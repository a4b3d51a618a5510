//! `leakwatch replay`: the command's checks, a recorded log read through its
//! CSV export, and the warnings and summary printed after [`replay::run`].

use std::path::PathBuf;

use crate::config::Config;
use crate::logs::export_log;
use crate::{out, replay};

/// What `leakwatch replay` was asked to do: its arguments (`cli::Command::Replay`) and `--force`.
pub struct ReplayArgs {
    /// Input: a CSV or a recorded log (.mcap).
    pub input: PathBuf,
    /// Configuration file.
    pub config: Option<PathBuf>,
    /// States of the thesis filter (6 or 7).
    pub model: Option<u32>,
    /// Output directory.
    pub out: PathBuf,
    /// Format of the estimates file.
    pub estimates: crate::estimates_out::EstimatesFormat,
    /// Run all stages in one thread instead of over channels.
    pub single_thread: bool,
    /// Also report the thesis' MAE detector's decisions.
    pub thesis_baseline: bool,
    /// Largest fraction of unusable input rows (0 to 1).
    pub max_bad_rows: f64,
    /// Replace existing outputs.
    pub force: bool,
}

/// `leakwatch replay`.
pub fn run(args: ReplayArgs) -> Result<(), String> {
    let ReplayArgs {
        input,
        config,
        model,
        out,
        estimates,
        single_thread,
        thesis_baseline,
        max_bad_rows,
        force,
    } = args;
    if !(0.0..=1.0).contains(&max_bad_rows) {
        return Err(format!(
            "--max-bad-rows {max_bad_rows}: must be a fraction from 0 to 1"
        ));
    }
    let config = Config::pick(config);
    let mut cfg = Config::load_or_default(config.as_deref())?;
    cfg.classifier.thesis_baseline |= thesis_baseline;
    if let Some(m) = model {
        if m != 6 && m != 7 {
            return Err(format!("--model {m}: the thesis filter has 6 or 7 states"));
        }
        cfg.estimator.states = m;
    }
    // A recorded log is replayed through its frames, exported as dataset.csv.
    let mut protect: Vec<PathBuf> = config.iter().cloned().collect();
    let mut log = None;
    let input = if input.extension().is_some_and(|e| e == "mcap") {
        out::dir(&out)?;
        let dir = out.join("log-export");
        log = Some(export_log(&input, &dir, force, true)?.1);
        protect.push(input);
        dir.join("dataset.csv")
    } else {
        input
    };
    let req = replay::ReplayRequest {
        input,
        out_dir: out.clone(),
        config: cfg,
        wiring: if single_thread {
            replay::Wiring::SingleThread
        } else {
            replay::Wiring::Channels
        },
        progress: true,
        max_bad_fraction: max_bad_rows,
        overwrite: force,
        protect,
        log,
        estimates,
    };
    let (cfg_nis_gate, cfg_recovery_s) = (req.config.classifier.nis_gate, req.config.classifier.recovery_s);
    let model_bulk_modulus_pa = req.config.model.bulk_modulus_pa;
    let s = replay::run(&req)?;
    for (name, f) in [("leak", &s.leak_filter), ("thesis", &s.thesis_filter)] {
        if f.resets * 10 > s.samples {
            eprintln!(
                "warning: the {name} filter was reset {} times in {} samples: its tuning does not fit \
                 the data (its estimates are mostly NaN)",
                f.resets, s.samples
            );
        }
    }
    for i in s.issues.iter().take(10) {
        eprintln!("warning: {i}");
    }
    if s.issues.len() > 10 {
        eprintln!(
            "warning: ... {} more input problems in summary.json",
            s.issues.len() - 10
        );
    }
    if s.leak_filter.nis_outliers > 0 {
        eprintln!(
            "warning: {} samples far outside what the leak filter expects (NIS above the gate {}), first at \
             t = {:.3} s: a spike or glitch in the data, or a stretch the model does not follow; no leak \
             evidence is taken after them for {} s",
            s.leak_filter.nis_outliers, cfg_nis_gate, s.leak_filter.first_nis_outlier_s, cfg_recovery_s
        );
    }
    if let Some(line) = estimator::oil_stiffness_line(
        s.leak_filter.bulk_scale,
        s.leak_filter.bulk_scale_sigma,
        model_bulk_modulus_pa,
    ) {
        eprintln!("{line}");
    }
    let w = &s.watch;
    match w.armed_at_s {
        None => eprintln!(
            "NOT WATCHED: the leak detector never armed in this run ({}): no leak could have been seen",
            w.not_armed.as_deref().unwrap_or("no healthy state learned")
        ),
        Some(armed) => eprintln!(
            "watched {:.1} of {:.1} s ({:.0} %): armed at {:.1} s, {:.1} s without evidence after it",
            w.watched_s,
            w.run_s,
            100.0 * w.watched_s / w.run_s.max(1e-9),
            armed,
            w.blind_s
        ),
    }
    eprintln!(
        "replayed {} samples in {:.2} s ({:.0} samples/s); {} rows skipped, {} samples missing; {} events; wrote {}",
        s.samples,
        s.wall_s,
        s.samples_per_s,
        s.rows_skipped,
        s.samples_missing,
        s.events,
        out.display()
    );
    Ok(())
}
