//! `leakwatch`: watch a hydraulic actuator for leaks. One command line for
//! simulation, offline replay, the live pipeline, calibration and benchmarks.

#![forbid(unsafe_code)]

mod calibrate_cmd;
mod cli;
mod init;
mod plots;
mod watch;

use bench::commands::{self as benches, instances, latency, scale};
use pipeline::{commission, demo, logs, model_file, out, replay_cmd, simulate, status};
use runtime as run;

use std::process::ExitCode;

use clap::Parser;

use cli::{BenchCommand, Cli, Command};
use config::Config;

fn main() -> ExitCode {
    // `leakwatch stage NAME ARGS...` hands its arguments to the stage untouched.
    let argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if argv.get(1).is_some_and(|a| a == "stage") {
        return run::stage_main(&argv[2..]);
    }
    let cli = Cli::parse();
    // (benchmarks run pipelines and replays of their own: their status is theirs)
    let watches = matches!(cli.command, Command::Run { .. } | Command::Replay(..));
    match run(cli) {
        Ok(()) if watches && status::not_watched() => ExitCode::from(status::NOT_WATCHED),
        Ok(()) if watches && status::output_failed() => ExitCode::from(status::OUTPUT_FAILED),
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            bus::say!("leakwatch: error: {msg}");
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
            rig,
        } => demo::run(scenario.as_deref(), seconds, seed, &faults, rig == "lift"),
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
            placement,
            live_view,
            zenoh,
            zenoh_connect,
            runs_dir,
            keep_days,
            keep_gib,
            opcua,
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
            placement,
            live_view,
            zenoh,
            zenoh_connect,
            runs_dir,
            keep_days,
            keep_gib,
            opcua,
        }),
        Command::Watch {
            listen,
            connect,
            seconds,
            config,
        } => watch::command(listen, connect, seconds, config.as_deref()),
        Command::Clean { prefix, all } => {
            if all {
                run::clean_all()
            } else {
                run::clean(prefix.as_deref())
            }
        }
        Command::Export { log, csv } => logs::export(&log, &csv, force),
        Command::Repair { log, out } => logs::repair(&log, &out, force),
        Command::Info { log, config_out } => logs::info(&log, config_out.as_deref(), force),
        Command::Commission { input, config, out } => {
            commission::run(&input, Config::pick(config).as_deref(), &out, force)
        }
        Command::Calibrate {
            input,
            config,
            identify,
            out,
            effects,
        } => calibrate_cmd::run(
            &input,
            Config::pick(config).as_deref(),
            identify,
            &out,
            effects,
            force,
        ),
        Command::Replay(args) => replay_cmd::run(args, force),
        Command::Simulate {
            scenario,
            seconds,
            seed,
            faults,
            sensor_faults,
            rig_variant,
            config,
            out,
        } => {
            let req = simulate::SimulateRequest {
                scenario,
                seconds,
                seed,
                faults,
                rig_variant: rig_variant.map(Into::into),
            };
            simulate::command(config, req, &sensor_faults, &out, force)
        }
        Command::Plot { input, out } => plots::command(&input, &out, force),
        Command::Init { single_rod, out } => init::command(single_rod, &out, force),
        Command::Config {
            print_default,
            check,
            reference,
        } => config_command(print_default, check, reference),
        Command::Bench { which } => bench(which, force),
    }
}

/// `leakwatch config`: checks a file, or prints the defaults or the reference.
fn config_command(
    print_default: bool,
    check: Option<std::path::PathBuf>,
    reference: bool,
) -> Result<(), String> {
    if let Some(path) = check {
        let cfg = Config::load(&path)?;
        out::stdout(&toml::to_string(&cfg).map_err(|e| e.to_string())?)
    } else if print_default {
        out::stdout(&Config::default_toml())
    } else if reference {
        out::stdout(&config::reference_markdown()?)
    } else {
        Err("nothing to do: use --print-default, --reference or --check FILE".into())
    }
}

/// `leakwatch bench ...`: each benchmark's command ([`bench::commands`]).
fn bench(which: BenchCommand, force: bool) -> Result<(), String> {
    match which {
        BenchCommand::Sim { seconds, repeat, out } => benches::sim(seconds, repeat, out, force),
        BenchCommand::Ekf { steps, out } => benches::ekf(steps, out, force),
        BenchCommand::Calibration {
            matrix,
            data,
            config,
            json,
            out,
        } => benches::calibration::bench(matrix, data, config, json, out, force),
        BenchCommand::Replay(args) => benches::replay::bench(&args, force),
        BenchCommand::Latency { seconds, out } => latency::bench(seconds, &out, force),
        BenchCommand::Instances(req) => instances::command(&req, force),
        BenchCommand::Scale { rigs, seconds, out } => scale::bench(&rigs, seconds, &out, force),
        BenchCommand::Detection(args) => benches::detection_command(&args, force),
        BenchCommand::SensorFaults(args) => bench::commands::sensor_faults::command(&args, force),
    }
}
