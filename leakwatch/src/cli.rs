//! The command line: the clap definitions of `leakwatch`'s commands and their arguments.

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};

#[derive(Parser)]
#[command(
    name = "leakwatch",
    version,
    about = "Detect, isolate and size leaks of a servovalve-driven hydraulic actuator with an EKF at 1 kHz",
    after_help = "Configuration: `--config FILE`; without it, run, replay, simulate, calibrate and commission \
                  use ./leakwatch.toml when the working directory has one (and say so). Benchmarks never pick it up."
)]
pub(crate) struct Cli {
    /// Replace existing output files (logs, CSVs, JSON, PNGs); without it an
    /// existing output is an error. Symbolic links and the inputs are never written.
    #[arg(long, global = true)]
    pub(crate) force: bool,
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// Friction variant of the simulated rig.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum RigVariant {
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
pub(crate) enum Command {
    /// One stage process of `run`, from this binary: `leakwatch stage NAME [ARGS]...` with
    /// NAME acquisition, estimator, classifier, recorder, estimator+classifier (those two in one
    /// process), liveview or gateway (ARGS: `leakwatch stage NAME --help`).
    Stage {
        /// acquisition, estimator, classifier, recorder, estimator+classifier, liveview or gateway.
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
        /// Scenario (default loaded-sine; `lift` on the lift rig).
        #[arg(long)]
        scenario: Option<String>,
        /// Simulated seconds (default 40).
        #[arg(long, default_value_t = 40.0)]
        seconds: f64,
        /// Seed.
        #[arg(long, default_value_t = 7)]
        seed: u64,
        /// The rig: `thesis` (the double-rod test rig) or `lift` (a vertical single-rod
        /// cylinder lifting 200 kg, docs/plant.md).
        #[arg(long, default_value = "thesis", value_parser = ["thesis", "lift"])]
        rig: String,
    },
    /// Run the live pipeline: acquisition, estimator, classifier and recorder as processes over
    /// iceoryx2. Without a fault or a config (with or without `--scenario loaded-sine`): the
    /// demonstration, an off-nominal rig with a 0.5 L/min chamber-1 leak at 20 s, events printed
    /// as they happen. With `--source udp://IP:PORT` the samples are a real rig's UDP sensor
    /// stream instead (docs/live.md, "A real rig's input"). Every argument is checked before any stage starts.
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
        /// Also run the thesis filter and report its MAE detector's decisions (a
        /// comparison, labelled as such; without it the thesis filter does not run).
        #[arg(long)]
        thesis_baseline: bool,
        /// Output directory (default ./leakwatch-run-YYYYMMDD-HHMMSS, its UTC start time: a new folder each run).
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
        /// Where the stages run: `split` (a process each, default) or `estimator+classifier`
        /// (those two in one process: one iceoryx2 hop fewer, the same events).
        #[arg(long, value_name = "split|estimator+classifier")]
        placement: Option<String>,
        /// Serve the live view (Foxglove WebSocket, ws://127.0.0.1:PORT; default port 8765, or
        /// [live_view] port; also on with [live_view] enabled = true). Off by default.
        #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "0")]
        live_view: Option<u16>,
        /// Publish the rig's events, health and estimates on Zenoh (leakwatch/<rig>/<topic>)
        /// through the gateway stage, connecting to the [zenoh] endpoints (default
        /// tcp/127.0.0.1:7447: a `leakwatch watch` on this machine); also on with [zenoh] enabled.
        #[arg(long)]
        zenoh: bool,
        /// Zenoh endpoint the gateway connects to instead of [zenoh] connect (repeatable;
        /// implies --zenoh), e.g. tcp/10.0.0.5:7447.
        #[arg(long, value_name = "ENDPOINT")]
        zenoh_connect: Vec<String>,
        /// A new folder per run in this directory (leakwatch-run-YYYYMMDD-HHMMSS; not with --out),
        /// as a service runs: docs/service.md.
        #[arg(long, value_name = "DIR")]
        runs_dir: Option<PathBuf>,
        /// With --runs-dir: remove earlier runs whose newest file is older than this, days.
        #[arg(long, value_name = "DAYS")]
        keep_days: Option<f64>,
        /// With --runs-dir: remove the oldest earlier runs while all runs together exceed this, GiB.
        #[arg(long, value_name = "GIB")]
        keep_gib: Option<f64>,
        /// Serve the rig's state and its leak and sensor events to a SCADA over OPC UA
        /// (opc.tcp://127.0.0.1:PORT/, read-only; default port 4840, or [opcua] port; also on
        /// with [opcua] enabled = true; docs/opcua.md). Off by default.
        #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "0")]
        opcua: Option<u16>,
    },
    /// Print the events of every rig reachable over Zenoh as they happen (the rigs' `run --zenoh`
    /// gateways publish them under leakwatch/<rig>/...), and each rig's health status when it
    /// changes, until Ctrl-C or --seconds.
    Watch {
        /// Zenoh endpoint to listen on, where gateways connect (repeatable; default
        /// tcp/127.0.0.1:7447 when no --connect is given; tcp/0.0.0.0:7447 for other machines).
        #[arg(long, value_name = "ENDPOINT")]
        listen: Vec<String>,
        /// Zenoh endpoint to connect to: a gateway or router that listens (repeatable).
        #[arg(long, value_name = "ENDPOINT")]
        connect: Vec<String>,
        /// Stop after this many seconds (default: until Ctrl-C).
        #[arg(long)]
        seconds: Option<f64>,
        /// Configuration file: its [zenoh] multicast_scouting.
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// Remove what a killed run left in shared memory: the iceoryx2 files of its prefix
    /// (/dev/shm/lw_<prefix>_*, <private dir>/<prefix>/) and its lock file. Refused while a
    /// run holds the prefix or a process of it still runs.
    Clean {
        /// The iceoryx2 prefix (a run's `run<pid>`, or the LEAKWATCH_IOX_PREFIX it was started
        /// with; default: LEAKWATCH_IOX_PREFIX).
        #[arg(long, conflicts_with = "all")]
        prefix: Option<String>,
        /// Every prefix with leakwatch's iceoryx2 files on this machine; those a live run
        /// holds are named and left.
        #[arg(long)]
        all: bool,
    },
    /// Export a recorded log (MCAP) as one CSV per channel, plus dataset.csv (the replay/calibrate format).
    Export {
        /// The log file (run.mcap).
        log: PathBuf,
        /// Output directory.
        #[arg(long)]
        csv: PathBuf,
    },
    /// Summarise a recorded log (MCAP), in the manner of `ros2 bag info`: file, size, duration,
    /// channels with message counts, mean rates and encodings, gaps, the events raised, damaged
    /// chunks or truncation, and the configuration the run used (stored in the log by `run`).
    Info {
        /// The log file (run.mcap).
        log: PathBuf,
        /// Write the configuration stored in the log (TOML) to this file (`-`: standard output),
        /// e.g. for `leakwatch replay LOG --config FILE`.
        #[arg(long, value_name = "FILE")]
        config_out: Option<PathBuf>,
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
        /// A config with a [datasheet] is identified on INPUT first (as `commission` does)
        /// and the search starts from the identified model.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Identify the valve, the oil and the mechanics on INPUT first, also for a config
        /// without a [datasheet] (one whose [model] was entered from datasheets by hand).
        #[arg(long)]
        identify: bool,
        /// Output directory: calibration.json, model.toml, report.md and plots, report.html (one A4 page).
        #[arg(long)]
        out: PathBuf,
        /// Effects to consider, comma-separated (default: the whole library; `friction` fits
        /// static/Coulomb, viscous per direction and the Stribeck velocity, on request only).
        #[arg(long, value_delimiter = ',')]
        effects: Vec<String>,
    },
    /// Replay a recorded or simulated CSV through the estimator and classifier, faster than real time;
    /// a directory or several files are replayed as a batch over all cores.
    Replay(pipeline::replay_cmd::ReplayArgs),
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
    /// Simulate a scenario on the rig and write a CSV (t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c).
    Simulate {
        /// Scenario: open-loop-sine, open-loop-chirp, closed-loop-sine, closed-loop-random, loaded-sine,
        /// loaded-random, lift, press, handling.
        #[arg(long)]
        scenario: String,
        /// Run length in seconds (default: the scenario's own, 40 or 60 s).
        #[arg(long, allow_negative_numbers = true)]
        seconds: Option<f64>,
        /// Noise and reference seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// A leak, KIND:SIZE@ONSET[,ramp=SECONDS][,law=sqrt|linear], e.g. ext1:0.3lpm@20s or int:k=6e-12@18s,law=linear (`none`: healthy).
        #[arg(long = "fault")]
        faults: Vec<String>,
        /// A sensor fault (repeatable): CHANNEL:KIND@ONSET, CHANNEL p1, p2 or x, KIND drift=RATE[,max=SIZE],
        /// span=±PERCENT%[,ramp=S], stuck or spikes=SIZE,rate=COUNT/s; e.g. p1:drift=200kPa/min,max=500kPa@30s,
        /// p2:span=+2%@20s, p1:stuck@40s, x:drift=1mm/min@10s, p2:spikes=2MPa,rate=0.5/s@0s. It changes the
        /// readings only (a closed loop's controller reads the faulty x), not the rig.
        #[arg(long = "sensor-fault", value_name = "SPEC")]
        sensor_faults: Vec<String>,
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
    /// Draw a run (a simulate or measured CSV, a recorded log, or a replay) as a PNG or an SVG.
    Plot {
        /// Input: a CSV in the dataset format, a recorded log (.mcap), or a replay output
        /// directory (estimates.csv, events.json, detector.csv).
        input: PathBuf,
        /// Output: an SVG file if it ends in .svg, else a PNG.
        #[arg(long)]
        out: PathBuf,
    },
    /// Write a config to fill in with your rig's datasheet (`[datasheet]`: cylinder, hoses,
    /// oil, valve, supply, transducers; each fact commented with its unit, docs/rig.md).
    Init {
        /// The example rig in the template is a vertical single-rod lift (default: a
        /// horizontal double-rod cylinder).
        #[arg(long)]
        single_rod: bool,
        /// The file to write.
        #[arg(long, default_value = "leakwatch.toml")]
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
        /// Print the configuration reference in Markdown: per section, each field's unit, range, default and meaning (docs/config.md).
        #[arg(long)]
        reference: bool,
    },
    /// Benchmarks (they print a table and write JSON).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand)]
pub(crate) enum BenchCommand {
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
        /// Steps timed per filter (≥ 1e6 for the figures of docs/performance.md).
        #[arg(long, default_value_t = 1_000_000)]
        steps: u64,
        /// Output directory for ekf.json.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The calibration workflow over its hidden-effect suites (docs/calibration/README.md):
    /// the smooth rig (16 cases) and the stick-slip rig (32 cases); or a directory of cases
    /// with truth.
    Calibration {
        /// Run the full smooth-rig matrix (every effect under every input, 44 cases, multiple shooting).
        #[arg(long)]
        matrix: bool,
        /// Score a directory of cases: DIR/case_*/measured.csv[.gz] + truth.json;
        /// or, laid out like plant_dev (a commission_cold.csv[.gz]), identify the rig on its recording and
        /// score it against its truth_rig.json.
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
    /// N rigs side by side on this host (each a whole `run`: four stage processes and a
    /// supervisor), for each N: CPU per rig, latency medians and tails, frames lost, and the
    /// capacity that implies for this host and (an estimate) a 16-core rig PC.
    Scale {
        /// Numbers of rigs to run side by side, one after the other.
        #[arg(long, value_delimiter = ',', default_value = "1,2,4,8")]
        rigs: Vec<usize>,
        /// Seconds per run.
        #[arg(long, default_value_t = 20.0)]
        seconds: f64,
        /// Output directory for scale.json and the runs' outputs.
        #[arg(long)]
        out: PathBuf,
    },
    /// Batch replay throughput: samples per second per core and in total, for each number of
    /// worker threads, on a directory of recordings (default: 16 simulated ten-minute CSVs).
    Replay(bench::commands::replay::ReplayBenchArgs),
    /// Plant-style folders of simulated rig instances, each drawn over its datasheet's tolerances
    /// (docs/plant.md): OUT/inst_NNN/ with datasheet.toml (the catalogue's, as a user writes it),
    /// instance.toml (the drawn rig, for the simulator), commission_cold.csv (each duty cycle in turn
    /// at 20, 30 or 50 °C), and run_NNN/measured.csv + truth.json: healthy runs on each duty cycle
    /// and a leak run of 0.1, 0.25 and 0.5 L/min of each kind, under oil warming or cooling across
    /// 20-60 °C. `bench detection --data OUT/inst_NNN` scores one; `bench calibration --data
    /// OUT/inst_NNN` scores its identification against the draw.
    Instances(bench::commands::instances::InstancesRequest),
    /// The seeded detection suite (docs/detection/README.md), both detectors side by side.
    Detection(bench::commands::DetectionBenchArgs),
    /// Transducer faults on rig instances, watched by each instance's commissioned chain
    /// (docs/sensor-faults.md): per instance a healthy twin, a pressure drift, a span
    /// error, a stuck and a spiking transducer, a position drift and a 0.25 L/min leak, each
    /// scored for leak events and for the sensor event on the faulty channel.
    SensorFaults(bench::commands::sensor_faults::SensorFaultsArgs),
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    /// Every command's long help, by its path (`leakwatch bench replay`).
    fn helps(cmd: &mut clap::Command, path: &str, out: &mut Vec<(String, String)>) {
        out.push((path.to_string(), cmd.render_long_help().to_string()));
        for sub in cmd.get_subcommands_mut() {
            let sub_path = format!("{path} {}", sub.get_name());
            helps(sub, &sub_path, out);
        }
    }

    #[test]
    fn no_help_shows_a_rustdoc_link() {
        let mut cli = super::Cli::command();
        cli.build();
        let mut all = Vec::new();
        helps(&mut cli, "leakwatch", &mut all);
        assert!(all.len() > 20, "{} commands", all.len());
        assert!(all.iter().any(|(path, _)| path == "leakwatch bench replay"));
        for (path, text) in &all {
            // a doc comment's link, `[`Name`]`, is rustdoc's, not the user's
            assert!(
                !text.contains("[`"),
                "`{path} --help` shows a rustdoc link:\n{text}"
            );
        }
    }
}
