//! `leakwatch`: watch a hydraulic actuator for leaks. One command line for
//! simulation, offline replay, the live pipeline, calibration and benchmarks.

mod benches;
mod commission;
mod config;
#[cfg(test)]
mod config_fuzz;
mod demo;
mod latency;
mod out;
mod plots;
mod replay;
mod run;
mod simulate;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use config::Config;
use out::outln;

#[derive(Parser)]
#[command(
    name = "leakwatch",
    version,
    about = "Detect, isolate and size leaks of a servovalve-driven hydraulic actuator with an EKF at 1 kHz",
    after_help = "Configuration: `--config FILE`; without it, run, replay, simulate, calibrate and commission \
                  use ./leakwatch.toml when the working directory has one (and say so). Benchmarks never pick it up."
)]
struct Cli {
    /// Replace existing output files (logs, CSVs, JSON, PNGs); without it an
    /// existing output is an error. Symbolic links and the inputs are never written.
    #[arg(long, global = true)]
    force: bool,
    #[command(subcommand)]
    command: Command,
}

/// Friction variant of the simulated rig.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum RigVariant {
    /// The thesis' friction as published: 30-40 Hz stick-slip.
    Thesis,
    /// No Stribeck drop (f_st = f_sl): smooth motion.
    Smooth,
}

impl From<RigVariant> for model::FrictionPreset {
    fn from(v: RigVariant) -> Self {
        match v {
            RigVariant::Thesis => model::FrictionPreset::Thesis,
            RigVariant::Smooth => model::FrictionPreset::Smooth,
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// One stage process of `run`, from this binary: `leakwatch stage NAME [ARGS]...` with
    /// NAME acquisition, estimator, classifier or recorder (ARGS: `leakwatch stage NAME --help`).
    Stage {
        /// acquisition, estimator, classifier or recorder.
        name: String,
        /// The stage's own arguments.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// The built-in demonstration, in one process: the loaded scenario on a rig that
    /// differs from the model, a 0.5 L/min chamber-1 leak at 20 s, events printed as they happen.
    Demo {
        /// Leak to inject (default ext1:0.5lpm@20s).
        #[arg(long = "fault")]
        faults: Vec<String>,
        /// Scenario (default loaded-sine).
        #[arg(long, default_value = "loaded-sine")]
        scenario: String,
        /// Simulated seconds (default 40).
        #[arg(long, default_value_t = 40.0)]
        seconds: f64,
        /// Seed.
        #[arg(long, default_value_t = 7)]
        seed: u64,
    },
    /// Run the live pipeline: acquisition, estimator, classifier and recorder as processes over
    /// iceoryx2. Without a fault or a config (with or without `--scenario loaded-sine`): the
    /// demonstration, an off-nominal rig with a 0.5 L/min chamber-1 leak at 20 s, events printed
    /// as they happen. With `--source udp://IP:PORT` the samples are a real rig's UDP sensor
    /// stream instead (README "On a real rig"). Every argument is checked before any stage starts.
    Run {
        /// Simulated seconds (default 40).
        #[arg(long)]
        seconds: Option<f64>,
        /// Scenario (default loaded-sine).
        #[arg(long)]
        scenario: Option<String>,
        /// Leak to inject, as in `simulate` (repeatable); `none` for a healthy run.
        #[arg(long = "fault")]
        faults: Vec<String>,
        /// Rig id: names the services, so several rigs can run side by side.
        #[arg(long, default_value = "rig1")]
        rig: String,
        /// Configuration file.
        #[arg(long)]
        config: Option<PathBuf>,
        /// How stages wait for input: event, low-latency or busy-poll.
        #[arg(long, default_value = "event")]
        mode: String,
        /// Also report the thesis' MAE detector's decisions (a comparison, labelled as such).
        #[arg(long)]
        thesis_baseline: bool,
        /// Output directory (default ./leakwatch-run).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Where samples come from: `sim` (the simulated rig, default) or `udp://IP:PORT`, a
        /// real rig's UDP sensor stream (format: frames/README.md; examples/udp has a C header
        /// and a Python sender), published as it arrives; raw counts are scaled by the config's
        /// [udp] section. Not with --scenario, --fault or --seconds.
        #[arg(long, value_name = "sim|udp://IP:PORT")]
        source: Option<String>,
        /// With --source udp://...: the stream ends when no datagram came for this long, s
        /// (default 5; counted from the first datagram, before which the run waits).
        #[arg(long)]
        udp_idle_timeout_s: Option<f64>,
    },
    /// Export a recorded log (MCAP) as one CSV per channel, plus dataset.csv (the replay/calibrate format).
    Export {
        /// The log file (run.mcap).
        log: PathBuf,
        /// Output directory.
        #[arg(long)]
        csv: PathBuf,
    },
    /// Repair a recorded log (MCAP) whose recorder was killed (no summary, a cut
    /// last chunk) or that has damaged chunks: every intact message is written
    /// into a complete MCAP file that any MCAP reader opens.
    Repair {
        /// The damaged log.
        log: PathBuf,
        /// The repaired log to write (never the input; an existing file only with --force).
        #[arg(long)]
        out: PathBuf,
    },
    /// Find where the model and measured data disagree, name the missing effect, fit it, show the gap shrink.
    Calibrate {
        /// Measured data: CSV (t,u,x,p1,p2[,x_sp,f_load,...], also .csv.gz) or a recorded log (.mcap); u drives the model.
        input: PathBuf,
        /// Configuration whose [model] is the starting model (default: the built-in model).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output directory: calibration.json, model.toml, report.md and plots.
        #[arg(long)]
        out: PathBuf,
        /// Effects to consider, comma-separated (default: the whole library; `friction` fits
        /// static/Coulomb, viscous per direction and the Stribeck velocity, on request only).
        #[arg(long, value_delimiter = ',')]
        effects: Vec<String>,
    },
    /// Replay a recorded or simulated CSV through the estimator and classifier, faster than real time.
    Replay {
        /// Input: a CSV (t,u,x,p1,p2[,x_sp,f_load,ref,q_leak]) or a recorded log (.mcap).
        input: PathBuf,
        /// Configuration file (TOML; defaults for everything missing).
        #[arg(long)]
        config: Option<PathBuf>,
        /// States of the thesis filter: 6 (friction from the model) or 7 (estimated load F_e).
        #[arg(long)]
        model: Option<u32>,
        /// Output directory: estimates.csv, events.json, summary.json.
        #[arg(long)]
        out: PathBuf,
        /// Run all stages in one thread instead of over channels (same results).
        #[arg(long)]
        single_thread: bool,
        /// Also report the thesis' MAE detector's decisions (a comparison, labelled as such).
        #[arg(long)]
        thesis_baseline: bool,
        /// Largest fraction of unusable input rows (0 to 1) before the file is refused
        /// with a non-zero exit (outputs are still written).
        #[arg(long, default_value_t = dataset::DEFAULT_MAX_BAD_FRACTION)]
        max_bad_rows: f64,
    },
    /// Learn the healthy state of a rig from a healthy recording and write a config
    /// that `replay`, `run` and every stage load with --config: a leak present when
    /// monitoring starts then shows against it.
    Commission {
        /// A healthy recording (CSV, .csv.gz) of the rig.
        input: PathBuf,
        /// The rig's model (e.g. the model.toml that `calibrate` wrote); defaults otherwise.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output config file (TOML) to write; an existing file is not overwritten.
        #[arg(long)]
        out: PathBuf,
    },
    /// Simulate a scenario on the rig and write a CSV (t,u,x,p1,p2,x_sp,f_load,ref,q_leak).
    Simulate {
        /// Scenario: open-loop-sine, open-loop-chirp, closed-loop-sine, closed-loop-random, loaded-sine, loaded-random.
        #[arg(long)]
        scenario: String,
        /// Run length in seconds (default: the scenario's own, 40 or 60 s).
        #[arg(long, allow_negative_numbers = true)]
        seconds: Option<f64>,
        /// Noise and reference seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// A leak, KIND:SIZE@ONSET[,ramp=SECONDS][,law=sqrt|linear], e.g. ext1:0.3lpm@20s or int:k=6e-12@18s,law=linear.
        #[arg(long = "fault")]
        faults: Vec<String>,
        /// Friction variant of the rig (default: as configured, the thesis' friction).
        #[arg(long, value_enum)]
        rig_variant: Option<RigVariant>,
        /// Configuration file (TOML); defaults apply to everything it leaves out.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output CSV file (`-`: standard output).
        #[arg(long)]
        out: PathBuf,
    },
    /// Draw a run (a simulate or measured CSV) as a PNG.
    Plot {
        /// Input: a CSV in the dataset format, or a replay output directory (estimates.csv, events.json).
        input: PathBuf,
        /// Output PNG.
        #[arg(long)]
        out: PathBuf,
    },
    /// Show the configuration.
    Config {
        /// Print the full default configuration as TOML.
        #[arg(long)]
        print_default: bool,
        /// Check a configuration file and print it with every default filled in.
        #[arg(long)]
        check: Option<PathBuf>,
    },
    /// Benchmarks (they print a table and write JSON).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Time the rig simulator on the loaded scenario.
    Sim {
        /// Simulated seconds.
        #[arg(long, default_value_t = 60.0)]
        seconds: f64,
        /// Repetitions.
        #[arg(long, default_value_t = 5)]
        repeat: u32,
        /// Output directory for sim.json.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// EKF step time (median, p99 ns per predict + update) and in-process chain throughput.
    Ekf {
        /// Steps timed per filter (≥ 1e6 for the figures of BENCHMARKS.md).
        #[arg(long, default_value_t = 1_000_000)]
        steps: u64,
        /// Output directory for ekf.json.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The calibration workflow over its hidden-effect suites (BENCHMARKS.md §3): the smooth rig
    /// (16 cases) and the stick-slip rig (32 cases); or a directory of cases with truth.
    Calibration {
        /// Run the full smooth-rig matrix (every effect under every input, 44 cases, multiple shooting).
        #[arg(long)]
        matrix: bool,
        /// Score a directory laid out like ../shared/data/hidden_dev: DIR/case_*/measured.csv[.gz] + truth.json.
        #[arg(long)]
        data: Option<PathBuf>,
        /// Configuration whose [model] is the starting model for --data (default: the built-in model).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Print the report as JSON on stdout instead of the Markdown tables.
        #[arg(long)]
        json: bool,
        /// Output directory for calibration_bench.md and .json.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Pipeline latency at 1 kHz: iceoryx2 processes (event and low-latency modes) beside the
    /// same stages as threads over Unix sockets and over crossbeam channels.
    Latency {
        /// Seconds per transport.
        #[arg(long, default_value_t = 20.0)]
        seconds: f64,
        /// Output directory for latency.json.
        #[arg(long)]
        out: PathBuf,
    },
    /// The seeded detection suite (BENCHMARKS.md §2), both detectors side by side.
    Detection {
        /// Runs per leak kind and size.
        #[arg(long, default_value_t = 20)]
        runs: usize,
        /// Simulated healthy hours for the false-alarm rate.
        #[arg(long, default_value_t = 10.0)]
        hours: f64,
        /// Suite seed.
        #[arg(long, default_value_t = 2026)]
        seed: u64,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Score recorded runs instead of simulating: a directory of run folders, each
        /// with measured.csv[.gz] and truth.json (laid out like ../shared/data/leaks_dev).
        #[arg(long)]
        data: Option<PathBuf>,
        /// Configuration file (model, filters, classifier) for the chain, with --data.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Output directory: detection.json, detection.md (and detection.png for the suite).
        #[arg(long, default_value = "bench-detection")]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    // `leakwatch stage NAME ARGS...` hands its arguments to the stage untouched.
    let argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if argv.get(1).is_some_and(|a| a == "stage") {
        return run::stage_main(&argv[2..]);
    }
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("leakwatch: error: {msg}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<(), String> {
    let force = cli.force;
    match cli.command {
        Command::Stage { name, .. } => Err(format!(
            "`stage {name}` must be the first argument (`leakwatch stage {name} ...`)"
        )),
        Command::Demo {
            faults,
            scenario,
            seconds,
            seed,
        } => demo::run(&scenario, seconds, seed, &faults),
        Command::Run {
            seconds,
            scenario,
            faults,
            rig,
            config,
            mode,
            out,
            thesis_baseline,
            source,
            udp_idle_timeout_s,
        } => run::run(run::RunArgs {
            seconds,
            scenario,
            faults,
            rig,
            config: Config::pick(config),
            mode,
            out,
            thesis_baseline,
            force,
            source,
            udp_idle_timeout_s,
        }),
        Command::Export { log, csv } => {
            let (files, _) = export_log(&log, &csv, force, false)?;
            for f in files {
                eprintln!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Repair { log, out } => {
            let r = recorder::repair(&log, &out, force).map_err(|e| e.to_string())?;
            if let Some(why) = &r.truncated {
                eprintln!("{}: ends early ({why}); kept everything before", log.display());
            }
            for c in &r.chunks_skipped {
                eprintln!("{}: damaged {c}; skipped", log.display());
            }
            if r.messages_without_channel > 0 {
                eprintln!(
                    "{}: {} messages dropped: their channel record was lost",
                    log.display(),
                    r.messages_without_channel
                );
            }
            let total: u64 = r.messages.values().sum();
            let per: Vec<String> = r.messages.iter().map(|(t, n)| format!("{t} {n}")).collect();
            eprintln!(
                "wrote {} ({} bytes): {total} messages ({})",
                out.display(),
                r.bytes,
                per.join(", ")
            );
            Ok(())
        }
        Command::Commission { input, config, out } => {
            commission::run(&input, Config::pick(config).as_deref(), &out, force)
        }
        Command::Calibrate {
            input,
            config,
            out,
            effects,
        } => calibrate_cmd(&input, Config::pick(config).as_deref(), &out, effects, force),
        Command::Replay {
            input,
            config,
            model,
            out,
            single_thread,
            thesis_baseline,
            max_bad_rows,
        } => {
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
            };
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
        Command::Simulate {
            scenario,
            seconds,
            seed,
            faults,
            rig_variant,
            config,
            out,
        } => {
            let config = Config::pick(config);
            let cfg = Config::load_or_default(config.as_deref())?;
            let req = simulate::SimulateRequest {
                scenario,
                seconds,
                seed,
                faults,
                rig_variant: rig_variant.map(Into::into),
            };
            let n = simulate::run(&cfg, &req, &out, force, config.as_deref())?;
            if out.as_os_str() == "-" {
                eprintln!("wrote {n} samples to standard output");
            } else {
                eprintln!("wrote {n} samples to {}", out.display());
            }
            Ok(())
        }
        Command::Plot { input, out } => {
            if input.is_dir() {
                plots::plot_replay(&input, &out, force)?;
            } else {
                plots::plot_run_csv(&input, &out, force)?;
            }
            eprintln!("wrote {}", out.display());
            Ok(())
        }
        Command::Config { print_default, check } => {
            if let Some(path) = check {
                let cfg = Config::load(&path)?;
                out::stdout(&toml::to_string(&cfg).map_err(|e| e.to_string())?)
            } else if print_default {
                out::stdout(&Config::default_toml())
            } else {
                Err("nothing to do: use --print-default or --check FILE".into())
            }
        }
        Command::Bench { which } => match which {
            BenchCommand::Sim { seconds, repeat, out } => bench_sim(seconds, repeat, out, force),
            BenchCommand::Ekf { steps, out } => benches::ekf(steps, out, force),
            BenchCommand::Calibration {
                matrix,
                data,
                config,
                json,
                out,
            } => benches::calibration(matrix, data, config, json, out, force),
            BenchCommand::Latency { seconds, out } => latency::bench(seconds, &out, force),
            BenchCommand::Detection {
                threads,
                data: Some(data),
                config,
                out,
                ..
            } => benches::detection_data(&data, config.as_deref(), threads, &out, force),
            BenchCommand::Detection {
                runs,
                hours,
                seed,
                threads,
                data: None,
                config: _,
                out,
            } => benches::detection(runs, hours, seed, threads, &out, force),
        },
    }
}

fn bench_sim(seconds: f64, repeat: u32, out: Option<PathBuf>, force: bool) -> Result<(), String> {
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

fn calibrate_cmd(
    input: &std::path::Path,
    config: Option<&std::path::Path>,
    out: &std::path::Path,
    effects: Vec<String>,
    force: bool,
) -> Result<(), String> {
    let original = input;
    let model = match config {
        Some(p) => calibrate::load_model(p).map_err(|e| e.to_string())?,
        None => model::ActuatorParams::default(),
    };
    // A recorded log is read through its frames, exported as dataset.csv.
    let input = if input.extension().is_some_and(|e| e == "mcap") {
        out::dir(out)?;
        let dir = out.join("log-export");
        export_log(input, &dir, force, true)?;
        dir.join("dataset.csv")
    } else {
        input.to_path_buf()
    };
    let measured = calibrate::load_measured(&input).map_err(|e| e.to_string())?;
    let opts = calibrate::CalibrateOptions {
        candidates: effects,
        ..calibrate::CalibrateOptions::default()
    };
    let span = match (measured.first(), measured.last()) {
        (Some(a), Some(b)) => b.t_s - a.t_s,
        _ => 0.0,
    };
    eprintln!(
        "read {} samples ({span:.1} s) from {}; the whole record is used, no decimation: \
         {} comparison windows of {:.0} ms{}, started from the measured state, 70 % fit / 30 % validate",
        measured.len(),
        input.display(),
        (span / opts.window_s) as usize,
        opts.window_s * 1e3,
        if span / opts.window_s > opts.max_windows as f64 {
            format!(
                " (for speed {} of them, spread over the whole record)",
                opts.max_windows
            )
        } else {
            String::new()
        }
    );
    let cal = calibrate::run_with_progress(&measured, &model, &opts, &|m: &str| eprintln!("  {m}"))
        .map_err(|e| e.to_string())?;
    for w in &cal.warnings {
        eprintln!("note: {w}");
    }
    let mut inputs = vec![original, input.as_path()];
    inputs.extend(config);
    let files = calibrate::write_outputs(&cal, out, force, &inputs).map_err(|e| e.to_string())?;
    let g = |gap: &calibrate::Gap| {
        format!(
            "chamber 1 {:.1} kPa, chamber 2 {:.1} kPa, force {:.0} N, spool {:.2} µm per {:.0} ms window; normalised {:.3}",
            gap.p1_pa / 1e3,
            gap.p2_pa / 1e3,
            gap.force_n,
            gap.spool_m * 1e6,
            cal.data.window_s * 1e3,
            gap.normalised
        )
    };
    outln!("gap before (validation RMS): {}", g(&cal.gap_before));
    if cal.effects.is_empty() {
        if cal
            .warnings
            .iter()
            .any(|w| w.contains(calibrate::NOT_IDENTIFIABLE))
        {
            outln!("nothing identifiable from this data (see the note above); the model is left as it is");
        } else {
            outln!("no missing effect explains a significant part of the gap: the model stands as it is");
        }
    }
    if cal.gap_after.normalised > 1.0 {
        outln!(
            "the remaining gap ({:.2}) is well above the sensor floor (about 0.2-0.4): the rig differs in \
             something the library does not have, or a channel is scaled or wired differently",
            cal.gap_after.normalised
        );
    }
    for (i, e) in cal.effects.iter().enumerate() {
        let params: Vec<String> = e
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v:.4e}"))
            .collect();
        outln!(
            "{}. {} ({}), explains {:.0} % of the gap: {} (SI)",
            i + 1,
            e.name,
            e.form,
            e.gap_reduction * 100.0,
            params.join(", ")
        );
        for l in e.engineering.iter().chain(&e.not_identifiable) {
            outln!("   {l}");
        }
        if let Some(c) = &e.caveat {
            outln!("   {c}");
        }
    }
    outln!(
        "gap after: {} ({:.0} % smaller)",
        g(&cal.gap_after),
        cal.gap_reduction * 100.0
    );
    outln!(
        "wrote {}, {}, {}",
        files.json.display(),
        files.model_toml.display(),
        files.report.display()
    );
    Ok(())
}

/// The loaded scenario's samples for benchmarks, `seconds` long.
pub(crate) fn benches_samples(seconds: f64) -> Vec<model::Sample> {
    bench::speed::recorded_samples(seconds)
}

/// Writes every channel of a recorded log as CSV into `dir` (plus dataset.csv);
/// returns the files and what reading the log skipped (damaged chunks).
/// Exports the log `log` as CSVs into `dir`; with `need_frames`, a log without a
/// readable sensor frame is an error naming the log (what replay and calibrate read),
/// and any log without a single readable message is one.
fn export_log(
    log: &std::path::Path,
    dir: &std::path::Path,
    force: bool,
    need_frames: bool,
) -> Result<(Vec<PathBuf>, replay::LogDamage), String> {
    let l = recorder::LogReader::open(log)
        .and_then(|r| r.read())
        .map_err(|e| format!("{}: {e}", log.display()))?;
    let messages = l.frames.len() + l.estimates.len() + l.events.len() + l.health.len() + l.stats.len();
    if messages == 0 || need_frames && l.frames.is_empty() {
        let why = match (&l.truncated, l.chunks_skipped.first()) {
            (_, Some(c)) => format!(" ({} damaged chunks skipped; first: {c})", l.chunks_skipped.len()),
            (Some(t), None) => format!(" ({t})"),
            (None, None) => String::new(),
        };
        return Err(format!(
            "{}: no {} could be read from the log{why}",
            log.display(),
            if messages == 0 { "message" } else { "sensor frame" }
        ));
    }
    if let Some(why) = &l.truncated {
        eprintln!("warning: {}: {why}; reading what is complete", log.display());
    }
    for c in &l.chunks_skipped {
        eprintln!("warning: {}: damaged {c}; skipped", log.display());
    }
    if !l.chunks_skipped.is_empty() {
        eprintln!(
            "warning: {}: {} damaged chunks skipped, {} samples lost with them",
            log.display(),
            l.chunks_skipped.len(),
            l.frames_lost
        );
    }
    let files = recorder::export_csv(&l, dir, force).map_err(|e| e.to_string())?;
    let damage = replay::LogDamage {
        chunks_skipped: l.chunks_skipped,
        frames_lost: l.frames_lost,
    };
    Ok((files, damage))
}
