//! `leakwatch replay` and `simulate` without the rest of the command line: the
//! same library calls (`pipeline::replay_cmd::run`, `pipeline::simulate::run`)
//! in a binary that builds in minutes where `leakwatch` takes far longer (it
//! leaves out the live outputs' and OPC UA server's dependencies), for timing
//! and profiling replays (docs/performance.md).
//!
//! ```sh
//! cargo run --release -p pipeline --example replay_io -- simulate 600 run.csv
//! cargo run --release -p pipeline --example replay_io -- replay run.csv --single-thread --out out
//! ```

use clap::Parser;

/// The two commands.
#[derive(Debug, Parser)]
enum Cli {
    /// As `leakwatch replay` (without --force: outputs are replaced).
    Replay(pipeline::replay_cmd::ReplayArgs),
    /// A loaded-random recording of SECONDS s with an internal leak of 0.3 L/min
    /// from half-time (seed 1) written to OUT.
    Simulate {
        /// Length, s.
        seconds: f64,
        /// The CSV to write.
        out: std::path::PathBuf,
    },
}

fn main() -> std::process::ExitCode {
    let result = match Cli::parse() {
        Cli::Replay(args) => pipeline::replay_cmd::run(args, true),
        Cli::Simulate { seconds, out } => {
            let req = pipeline::simulate::SimulateRequest {
                scenario: "loaded-random".into(),
                seconds: Some(seconds),
                seed: 1,
                faults: vec![format!("int:0.3lpm@{}s", seconds / 2.0)],
                rig_variant: None,
            };
            pipeline::simulate::run(&config::Config::default(), &req, &out, false, None).map(|_| ())
        }
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
