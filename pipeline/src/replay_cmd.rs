//! `leakwatch replay`: the command's checks, a recorded log read through its
//! CSV export, and the warnings and summary printed after [`replay::run`]; a
//! directory or several inputs go to [`crate::batch`].

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicU64;
use std::sync::Arc;

use crate::estimates_out::{EstimatesFormat, LONG_INPUT_BYTES};
use crate::replay;
use config::Config;

/// What `leakwatch replay` was asked to do: its command line (`--force` is global: passed beside it).
#[derive(Debug, Clone, clap::Args)]
pub struct ReplayArgs {
    /// Input: a CSV (t,u,x,p1,p2[,x_sp,f_load,ref,q_leak,temp_c]) or a recorded log (.mcap); or a
    /// directory (its *.csv, *.csv.gz, *.mcap and those of its subfolders, one level down) or
    /// several files: a batch, each file's outputs in OUT/<its relative name without extension>/,
    /// a table on stdout, a non-zero exit if any file failed.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Configuration file (TOML; defaults for everything missing).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Also run the thesis filter, with 6 states (friction from the model) or 7
    /// (estimated load F_e), and write its estimates (the th_* columns)
    #[arg(long)]
    pub model: Option<u32>,
    /// Output directory: estimates.csv (or .parquet), detector.csv, events.json, summary.json, report.html.
    #[arg(long)]
    pub out: PathBuf,
    /// Format of the estimates file: auto (parquet for a batch and for an input of 16 MiB or
    /// more, csv below), csv (text), parquet (columns with statistics, for pandas, polars,
    /// pyarrow, DuckDB; same values bit for bit) or none (no estimates file: the fastest replay).
    #[arg(long, value_enum, default_value_t)]
    pub estimates: crate::estimates_out::EstimatesFormat,
    /// Write the estimates of every Nth sample only (the first, the (N+1)th, ...): a decimated
    /// estimates file, 1 = every sample.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub estimates_every: u64,
    /// Run all stages in one thread instead of over channels (same results).
    #[arg(long)]
    pub single_thread: bool,
    /// Also run the thesis filter, write its estimates (the th_* columns) and report its
    /// MAE detector's decisions (a comparison, labelled as such)
    #[arg(long)]
    pub thesis_baseline: bool,
    /// Largest fraction of unusable input rows (0 to 1) before the file is refused
    /// with a non-zero exit (outputs are still written).
    #[arg(long, default_value_t = dataset::DEFAULT_MAX_BAD_FRACTION)]
    pub max_bad_rows: f64,
    /// Worker threads of a batch, each replaying whole files (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write no report.html (a single file's replay writes one by default: its
    /// leak alarms, blind stretches, smallest detectable leaks and leak panel).
    #[arg(long)]
    pub no_report: bool,
}

/// What every file of a replay shares: the configuration and the output rules.
#[derive(Debug, Clone)]
pub struct Settings {
    /// The configuration, with the command line's changes applied.
    pub cfg: Config,
    /// The configuration file it came from (never overwritten).
    pub config: Option<PathBuf>,
    /// Format of the estimates file (`auto`: resolved per file, [`EstimatesFormat::for_input`]).
    pub estimates: crate::estimates_out::EstimatesFormat,
    /// One estimates row every this many samples (1: every sample).
    pub estimates_every: u64,
    /// The files are a batch's (`auto` estimates are then Parquet whatever their size).
    pub batch: bool,
    /// The thesis filter's estimates were asked for (`--model`).
    pub thesis_estimates: bool,
    /// Largest fraction of unusable input rows (0 to 1).
    pub max_bad_rows: f64,
    /// Replace existing outputs.
    pub force: bool,
}

impl Settings {
    /// Checks the options and loads the configuration (`config`, or ./leakwatch.toml, or the defaults).
    pub fn new(
        config: Option<PathBuf>,
        model: Option<u32>,
        thesis_baseline: bool,
        estimates: (EstimatesFormat, u64),
        max_bad_rows: f64,
        force: bool,
    ) -> Result<Settings, String> {
        let (estimates, estimates_every) = estimates;
        if estimates_every == 0 {
            return Err("--estimates-every 0: one row every 1 or more samples".into());
        }
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
        Ok(Settings {
            cfg,
            config,
            estimates,
            estimates_every,
            batch: false,
            thesis_estimates: model.is_some(),
            max_bad_rows,
            force,
        })
    }
}

/// Replays one file (a CSV, or a recorded log read by its sensor frames) into
/// `out`: the one path of a single replay and of every file of a batch, so
/// their outputs are the same bytes. `also_writes`: the files the caller
/// writes into `out` after it (refused with the replay's own).
pub fn replay_file(
    input: &Path,
    out: &Path,
    settings: &Settings,
    wiring: replay::Wiring,
    progress: bool,
    samples_done: Option<Arc<AtomicU64>>,
    also_writes: &[PathBuf],
) -> Result<replay::Summary, String> {
    let protect: Vec<PathBuf> = settings.config.iter().cloned().collect();
    let bytes = std::fs::metadata(input).map(|m| m.len()).unwrap_or(0);
    let (estimates, estimates_why) = match (settings.estimates, settings.batch) {
        (EstimatesFormat::Auto, true) => (
            EstimatesFormat::Parquet,
            "the default for a batch (Parquet; --estimates csv for text)".to_string(),
        ),
        (EstimatesFormat::Auto, false) => {
            let long = EstimatesFormat::long_input_bytes(input);
            (
                settings.estimates.for_input(bytes, long),
                format!(
                    "the default for an input of {:.1} MiB: Parquet from {} MiB on{}, CSV below",
                    bytes as f64 / f64::from(1 << 20),
                    long >> 20,
                    if long < LONG_INPUT_BYTES {
                        " for a compressed input"
                    } else {
                        ""
                    }
                ),
            )
        }
        (asked, _) => (asked, format!("asked for (--estimates {})", asked.name())),
    };
    let req = replay::ReplayRequest {
        input: input.to_path_buf(),
        out_dir: out.to_path_buf(),
        config: settings.cfg.clone(),
        wiring,
        progress,
        max_bad_fraction: settings.max_bad_rows,
        overwrite: settings.force,
        protect,
        estimates,
        estimates_every: settings.estimates_every,
        estimates_why,
        thesis_estimates: settings.thesis_estimates,
        samples_done,
        also_writes: also_writes.to_vec(),
    };
    replay::run(&req)
}

/// `leakwatch replay`: one file as before; a directory or several files as a
/// batch; `force`: replace existing outputs.
pub fn run(args: ReplayArgs, force: bool) -> Result<(), String> {
    let ReplayArgs {
        inputs,
        config,
        model,
        out,
        estimates,
        estimates_every,
        single_thread,
        thesis_baseline,
        max_bad_rows,
        threads,
        no_report,
    } = args;
    let settings = Settings::new(
        config,
        model,
        thesis_baseline,
        (estimates, estimates_every),
        max_bad_rows,
        force,
    )?;
    let input = match inputs.as_slice() {
        [one] if !one.is_dir() => one,
        _ => return crate::batch::run(&inputs, &out, &settings, threads),
    };
    let wiring = if single_thread {
        replay::Wiring::SingleThread
    } else {
        replay::Wiring::Channels
    };
    let report = (!no_report).then(|| out.join(replay::report::FILE_NAME));
    let s = replay_file(input, &out, &settings, wiring, true, None, report.as_slice())?;
    let cfg = &settings.cfg;
    let (cfg_nis_gate, cfg_recovery_s) = (cfg.classifier.nis_gate, cfg.classifier.recovery_s);
    let model_bulk_modulus_pa = cfg.model.bulk_modulus_pa;
    for (name, f) in [
        ("leak", Some(&s.leak_filter)),
        ("thesis", s.thesis_filter.as_ref()),
    ]
    .into_iter()
    .filter_map(|(name, f)| Some((name, f?)))
    {
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
    for line in oil_lines(&s.leak_filter) {
        eprintln!("{line}");
    }
    if let Some(line) = filter::oil_stiffness_line(
        s.leak_filter.bulk_scale,
        s.leak_filter.bulk_scale_sigma,
        model_bulk_modulus_pa,
    ) {
        eprintln!("{line}");
    }
    let w = &s.watch;
    match w.armed_at_s {
        None => {
            eprintln!(
                "NOT WATCHED: the leak detector never armed in this run ({}): no leak could have been seen",
                w.not_armed.as_deref().unwrap_or("no healthy state learned")
            );
            crate::status::set_not_watched();
        }
        Some(armed) => {
            let causes = w.blind_by_cause.describe();
            eprintln!(
                "watched {:.1} of {:.1} s ({:.0} %): armed at {:.1} s, {:.1} s without evidence after it{}",
                w.watched_s,
                w.run_s,
                100.0 * w.watched_s / w.run_s.max(1e-9),
                armed,
                w.blind_s,
                if causes.is_empty() {
                    String::new()
                } else {
                    format!(" ({causes})")
                }
            )
        }
    }
    let e = &s.estimates;
    eprintln!(
        "estimates: {} ({}{}; {})",
        e.file.as_deref().unwrap_or("none written"),
        if e.every == 1 {
            "every sample".to_string()
        } else {
            format!("one sample in {}", e.every)
        },
        match e.file {
            Some(_) => format!(", {} rows", e.rows),
            None => String::new(),
        },
        e.why
    );
    if let Some(r) = &report {
        write_report(r, &s, &settings, &out, input)?;
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

/// Writes the replay's report `path` from its summary `s` (its events those
/// of events.json), the configuration of `settings` and the folder `out`;
/// never over `input` or the config file.
/// The lines a replay prints about the oil's temperature from the leak
/// filter's summary `f`: the range the model followed and how it knew it, and
/// a warning when the oil was outside its operating range.
fn oil_lines(f: &replay::ResidualRms) -> Vec<String> {
    let mut lines = Vec::new();
    let (cold, warm) = f.oil_temp_range_c;
    if cold.is_finite() {
        lines.push(if f.oil_temp_from_stiffness {
            format!(
                "oil temperature: {cold:.1} to {warm:.1} °C, read from the oil's stiffness (no temp_c): \
                 the null leakage and the viscous friction followed it"
            )
        } else {
            format!("oil temperature: {cold:.1} to {warm:.1} °C (temp_c): the model followed it")
        });
    }
    if f.oil_outside_range_s > 0.0 {
        let (lo, hi) = f.oil_operating_range_c;
        let read_from_theta = if f.oil_temp_from_stiffness {
            "; read from the oil's stiffness, the temperature moves with a leak or a pressure transducer \
             reading off as well (a thermometer's temp_c tells them apart)"
        } else {
            ""
        };
        lines.push(format!(
            "warning: the oil was outside the operating range {lo:.0}-{hi:.0} °C ([model.oil_temperature]) \
             for {:.1} s from t = {:.3} s: the smallest detectable leaks commissioning stated hold inside \
             it; beyond it the thresholds keep widening, so a leak is raised later or not at all{read_from_theta}",
            f.oil_outside_range_s, f.first_oil_outside_range_s
        ));
    }
    lines
}

fn write_report(
    path: &Path,
    s: &replay::Summary,
    settings: &Settings,
    out: &Path,
    input: &Path,
) -> Result<(), String> {
    let report = replay::report::ReplayReport {
        summary: s,
        config: &settings.cfg,
        config_path: settings.config.as_deref(),
        out_dir: out,
    };
    let mut inputs = vec![input, Path::new(&s.input)];
    inputs.extend(settings.config.as_deref());
    crate::out::write(path, report.html()?.as_bytes(), settings.force, &inputs)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The warning says that a reading from θ moves with a leak or a
    /// misreading only where the temperature was read from θ.
    #[test]
    fn the_oil_lines_say_how_the_temperature_was_known() {
        let mut f = replay::ResidualRms {
            oil_temp_range_c: (31.0, 64.5),
            oil_temp_from_stiffness: true,
            oil_operating_range_c: (20.0, 60.0),
            oil_outside_range_s: 12.5,
            first_oil_outside_range_s: 100.25,
            ..Default::default()
        };
        let read = oil_lines(&f);
        assert_eq!(read.len(), 2, "{read:?}");
        assert!(read[0].starts_with("oil temperature: 31.0 to 64.5 °C, read from the oil's stiffness"));
        assert!(read[1].starts_with("warning: the oil was outside the operating range 20-60 °C"));
        assert!(read[1].contains("for 12.5 s from t = 100.250 s"), "{}", read[1]);
        assert!(
            read[1].ends_with("(a thermometer's temp_c tells them apart)"),
            "{}",
            read[1]
        );
        f.oil_temp_from_stiffness = false;
        let measured = oil_lines(&f);
        assert_eq!(
            measured[0],
            "oil temperature: 31.0 to 64.5 °C (temp_c): the model followed it"
        );
        assert!(
            measured[1].ends_with("so a leak is raised later or not at all"),
            "{}",
            measured[1]
        );
        f.oil_outside_range_s = 0.0;
        f.oil_temp_range_c = (f64::NAN, f64::NAN);
        assert!(oil_lines(&f).is_empty());
    }
}
