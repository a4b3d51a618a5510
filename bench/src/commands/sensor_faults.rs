//! `leakwatch bench sensor-faults`: transducer faults drawn over rig instances,
//! watched by each instance's commissioned chain, and scored.
//!
//! Per instance of the rig (press and lift: drawn over the datasheet's
//! tolerances as by `bench instances`; thesis: the built-in rig, one noise seed
//! per instance), the generator:
//! - commissions the chain on a healthy recording (press and lift: the
//!   README's `commission` on the catalogue datasheet and a recording at 20, 30
//!   or 50 °C; thesis: the healthy state learned on its loaded cycle);
//! - simulates one run per [`RunKind`], each on a duty cycle of the rig under a
//!   drawn oil course, with the fault from a drawn onset;
//! - feeds each run to the chain and scores its events: any leak event, the
//!   first sensor event, its channel and its time from the onset.
//!
//! Nothing is written but the reports: `sensor_faults.md` and `sensor_faults.json`.

use std::path::PathBuf;

use model::instance::Instance;
use model::rng::Rng;
use model::sensor_fault::{Channel, SensorFault, SensorFaultKind};
use model::sim::OilWarmUp;
use serde::Serialize;

use config::Config;
use pipeline::simulate::{self, SimulateRequest};

use super::operating_leak::OperatingLeak;

use super::instances::{self, InstancesRequest};

mod report;
use report::score;
pub use report::{markdown, summarise, KindSummary, Misreading};

/// The kinds of run each instance gets: one healthy twin, one per fault, one leak.
pub const RUN_KINDS: [RunKind; 7] = [
    RunKind::Healthy,
    RunKind::PressureDrift,
    RunKind::Span,
    RunKind::Stuck,
    RunKind::Spikes,
    RunKind::PositionDrift,
    RunKind::Leak,
];

/// A pressure drift's rate, kPa/min (drawn in this range, either sign).
pub const DRIFT_RATE_KPA_PER_MIN: (f64, f64) = (50.0, 300.0);
/// A pressure drift's largest offset, kPa.
pub const DRIFT_MAX_KPA: f64 = 500.0;
/// A span error's size, % (drawn in this range, either sign).
pub const SPAN_PERCENT: (f64, f64) = (1.0, 3.0);
/// The time a span error takes to grow, s (drawn in this range).
pub const SPAN_RAMP_S: (f64, f64) = (30.0, 90.0);
/// An outlier's size on a pressure channel, Pa, and on the position, m.
pub const SPIKE_SIZE: (f64, f64) = (2e6, 5e-3);
/// Outliers per second.
pub const SPIKE_RATE_HZ: f64 = 0.5;
/// A position drift's rate, mm/min (drawn in this range, either sign).
pub const POSITION_DRIFT_MM_PER_MIN: (f64, f64) = (0.5, 2.0);
/// The leak run's size, L/min at the mean drop its path sees before it opens ([`OperatingLeak`]).
pub const LEAK_LPM: f64 = 0.25;
/// The range a fault's onset is drawn in, s (the detector armed before it).
pub const ONSET_S: (f64, f64) = (20.0, 40.0);

/// What one run of an instance carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RunKind {
    /// No fault: the healthy twin.
    Healthy,
    /// A pressure transducer's zero drifting ([`DRIFT_RATE_KPA_PER_MIN`], up to [`DRIFT_MAX_KPA`]).
    PressureDrift,
    /// A pressure transducer's span error growing to [`SPAN_PERCENT`].
    Span,
    /// A transducer (p1, p2 or x) frozen.
    Stuck,
    /// A transducer (p1, p2 or x) giving outliers.
    Spikes,
    /// The position transducer's zero drifting ([`POSITION_DRIFT_MM_PER_MIN`]).
    PositionDrift,
    /// A leak of [`LEAK_LPM`] (ext1, ext2 or int) and no sensor fault.
    Leak,
}

impl RunKind {
    /// The name in the reports.
    pub fn name(self) -> &'static str {
        match self {
            RunKind::Healthy => "healthy",
            RunKind::PressureDrift => "pressure drift",
            RunKind::Span => "span error",
            RunKind::Stuck => "stuck",
            RunKind::Spikes => "spikes",
            RunKind::PositionDrift => "position drift",
            RunKind::Leak => "leak 0.25 L/min",
        }
    }
}

/// The command line of `leakwatch bench sensor-faults`.
#[derive(Debug, Clone, clap::Args)]
pub struct SensorFaultsArgs {
    /// The rig: `press` (double-rod), `lift` (vertical single-rod) or `thesis` (the built-in rig).
    #[arg(long, value_parser = ["press", "lift", "thesis"], required_unless_present = "data", conflicts_with = "data")]
    pub rig: Option<String>,
    /// A plant-style folder (like plant_dev's: `commission_cold.csv[.gz]`,
    /// `datasheet.toml` or `--config`, `run_*/`): the faults are laid onto its
    /// healthy recordings, watched by the chain commissioned as `bench
    /// detection --data` does; instance i takes recording i mod R.
    #[arg(long)]
    pub data: Option<PathBuf>,
    /// With `--data`: the config (the folder's `datasheet.toml` without it).
    #[arg(long, requires = "data", conflicts_with = "rig")]
    pub config: Option<PathBuf>,
    /// Number of instances.
    #[arg(long, default_value_t = 12)]
    pub instances: usize,
    /// Seed of the set (instance i is drawn from it and i; press and lift draw the same
    /// instances as `bench instances` with this seed).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Length of every run, s (with `--data`: the recordings' own).
    #[arg(long, default_value_t = 360.0, conflicts_with = "data")]
    pub seconds: f64,
    /// Output directory for sensor_faults.md and sensor_faults.json.
    #[arg(long)]
    pub out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Keeps each instance's commissioned config (inst_NNN/rig.toml; with
    /// `--data` the one config, rig.toml) and each run's recording
    /// (inst_NNN/KIND.csv), to replay a run with `leakwatch replay`.
    #[arg(long)]
    pub keep: bool,
    /// The recordings carry the oil's temperature (a `temp_c` column), the
    /// commissioning's as well: the model follows a thermometer instead of
    /// the temperature read from the oil's stiffness.
    #[arg(long, conflicts_with = "data")]
    pub temp_c: bool,
}

impl SensorFaultsArgs {
    /// The simulated rig's name (empty with `--data`).
    pub fn rig_name(&self) -> &str {
        self.rig.as_deref().unwrap_or("")
    }
}

/// One scored run.
#[derive(Debug, Clone, Serialize)]
pub struct FaultRunOutcome {
    /// Instance index.
    pub instance: usize,
    /// What the run carries.
    pub kind: RunKind,
    /// The fault as `leakwatch simulate` takes it (`--sensor-fault` or `--fault`; empty: none).
    pub spec: String,
    /// The faulty channel (`p1`, `p2`, `x`) or the leak's kind; empty for the healthy twin.
    pub channel: String,
    /// The fault's onset, s (NaN for the healthy twin).
    pub onset_s: f64,
    /// The duty cycle.
    pub scenario: String,
    /// Leak events raised (a pending `leak` included) that are not the run's leak.
    pub leak_events: usize,
    /// Whether a leak alarm that is not the run's leak still stands at the
    /// run's end (not cleared or withdrawn).
    pub leak_alarm_at_end: bool,
    /// The first sensor event raised after the onset: kind, channel, time, s.
    pub first_sensor: Option<(String, String, f64)>,
    /// Sensor events raised before the onset (or in the healthy twin, at all).
    pub sensor_events_before_onset: usize,
    /// A sensor event on the faulty channel raised after the onset.
    pub named_right: bool,
    /// Time from the onset to the first sensor event on the right channel, or to
    /// the leak named right, s (NaN: none).
    pub delay_s: f64,
    /// How far the fault made its transducer read off, beside the least the detector names.
    pub misreading: Misreading,
    /// The onset the sensor event on the right channel stated (its
    /// `t_onset_s`) minus the fault's onset, s (NaN: none, or none stated).
    pub stated_onset_error_s: f64,
}

/// An instance ready to watch: its config with its commissioning, the sim's rig, the duty cycles.
struct Watched {
    /// The commissioned config (model, filters, detector).
    rig: Config,
    /// What commissioning said the detector names on each transducer.
    reach: pipeline::commission::SensorReach,
    /// The drawn instance (press, lift); `None`: the built-in rig simulates itself.
    instance: Option<Instance>,
    /// The duty cycles its runs take in turn.
    cycles: &'static [&'static str],
    /// The instance's seed.
    seed: u64,
}

/// The thesis rig's duty cycles.
const THESIS_CYCLES: &[&str] = &["loaded-random", "loaded-sine"];

/// Commissions instance `index` of `args.rig`; says what it learned on stderr.
fn commission_instance(args: &SensorFaultsArgs, index: usize) -> Result<Watched, String> {
    let rig = args.rig_name();
    let dir = args.out.join(format!("inst_{index:03}"));
    pipeline::out::dir(&dir)?;
    let recording = dir.join("commission.csv");
    let seed = instances::instance_seed(args.seed, index);
    let (cfg, instance, cycles, samples) = if rig == "thesis" {
        let cfg = Config::default();
        let req = SimulateRequest {
            scenario: THESIS_CYCLES[0].into(),
            seconds: Some(120.0),
            seed,
            faults: vec![],
            rig_variant: None,
        };
        let (mut sim, seconds) = simulate::build(&cfg, &req)?;
        (cfg, None, THESIS_CYCLES, sim.run(seconds))
    } else {
        let (nominal, cycles) = instances::nominal(rig)?;
        let inst = Instance::draw(&nominal, seed);
        let plans = instances::plan_instance(&instances_request(args), cycles, index, inst.seed);
        let plan = plans.first().ok_or("no commissioning recording planned")?;
        let sheet = instances::user_datasheet(&nominal, &inst, plan.oil.start_c)?;
        let cfg = Config::parse(&sheet).map_err(|e| format!("instance {index}'s datasheet: {e}"))?;
        let sim_cfg = instances::instance_config(&inst, Some(plan.oil));
        let (samples, _) = instances::simulate_plan(&sim_cfg, plan, &[])?;
        (cfg, Some(inst), cycles, samples)
    };
    let file = pipeline::out::create(&recording, true, &[])?;
    let mut w = std::io::BufWriter::new(file);
    simulate::write_csv(&mut w, &samples).map_err(|e| dataset::output::message(&recording, &e))?;
    drop(w);
    let commissioned = if instance.is_some() {
        pipeline::commission::commission_recorded(&recording, &cfg)
            .map(|(rig, record)| (rig, record.learned.sensor_reach))
    } else {
        pipeline::commission::learn_traced(&recording, &cfg).map(|t| {
            let reach = pipeline::commission::sensor_reach(&t.responses, &t.commissioning, &cfg);
            let mut cfg = cfg.clone();
            cfg.model.oil_temperature.reference_stiffness = t.theta;
            cfg.classifier.commissioning = Some(t.commissioning);
            (cfg, reach)
        })
    };
    let (rig, reach) = commissioned.map_err(|e| format!("instance {index}: {e}"))?;
    if args.keep {
        let text = toml::to_string(&rig).map_err(|e| format!("instance {index}'s config: {e}"))?;
        pipeline::out::write(&dir.join("rig.toml"), text.as_bytes(), true, &[])?;
    } else {
        // the recording is rebuilt from the seed: only the reports are kept
        let _ = std::fs::remove_file(&recording);
        let _ = std::fs::remove_dir(&dir);
    }
    Ok(Watched {
        rig,
        reach,
        instance,
        cycles,
        seed,
    })
}

/// The `bench instances` request whose instances and commissioning recordings these are.
fn instances_request(args: &SensorFaultsArgs) -> InstancesRequest {
    InstancesRequest {
        rig: args.rig_name().to_string(),
        instances: args.instances,
        seed: args.seed,
        out: args.out.clone(),
        hours_healthy: 0.0,
        run_seconds: args.seconds,
        commission_seconds: 120.0,
        temp_c: args.temp_c,
        threads: None,
        commissioning_only: false,
    }
}

/// Draws the fault of a run of kind `kind` with onset `onset_s` (s): the sensor
/// fault, or the leak's kind for [`RunKind::Leak`], `None` for the healthy twin.
fn draw_fault(kind: RunKind, onset_s: f64, rng: &mut Rng) -> (Option<SensorFault>, Option<&'static str>) {
    let mut pick = |n: u64| (rng.next_u64() % n) as usize;
    let pressure = [Channel::P1, Channel::P2][pick(2)];
    let any = [Channel::P1, Channel::P2, Channel::X][pick(3)];
    let sign = if pick(2) == 0 { 1.0 } else { -1.0 };
    let fault = |channel, kind| {
        Some(SensorFault {
            channel,
            kind,
            onset_s,
        })
    };
    match kind {
        RunKind::Healthy => (None, None),
        RunKind::Leak => (None, Some(["ext1", "ext2", "int"][pick(3)])),
        RunKind::PressureDrift => {
            let rate = sign * rng.uniform_in(DRIFT_RATE_KPA_PER_MIN.0, DRIFT_RATE_KPA_PER_MIN.1) * 1e3 / 60.0;
            let max_abs_si = DRIFT_MAX_KPA * 1e3;
            (
                fault(
                    pressure,
                    SensorFaultKind::Drift {
                        rate_si_per_s: rate,
                        max_abs_si,
                    },
                ),
                None,
            )
        }
        RunKind::Span => {
            let gain_error = sign * rng.uniform_in(SPAN_PERCENT.0, SPAN_PERCENT.1) / 100.0;
            let ramp_s = rng.uniform_in(SPAN_RAMP_S.0, SPAN_RAMP_S.1).round();
            (
                fault(pressure, SensorFaultKind::Span { gain_error, ramp_s }),
                None,
            )
        }
        RunKind::Stuck => (fault(any, SensorFaultKind::Stuck), None),
        RunKind::Spikes => {
            let amplitude_si = if any == Channel::X {
                SPIKE_SIZE.1
            } else {
                SPIKE_SIZE.0
            };
            (
                fault(
                    any,
                    SensorFaultKind::Spikes {
                        amplitude_si,
                        rate_hz: SPIKE_RATE_HZ,
                    },
                ),
                None,
            )
        }
        RunKind::PositionDrift => {
            let rate =
                sign * rng.uniform_in(POSITION_DRIFT_MM_PER_MIN.0, POSITION_DRIFT_MM_PER_MIN.1) * 1e-3 / 60.0;
            let max_abs_si = f64::INFINITY;
            (
                fault(
                    Channel::X,
                    SensorFaultKind::Drift {
                        rate_si_per_s: rate,
                        max_abs_si,
                    },
                ),
                None,
            )
        }
    }
}

/// Simulates and watches run `k` (of [`RUN_KINDS`]) of instance `index`.
fn watch_run(
    args: &SensorFaultsArgs,
    index: usize,
    w: &Watched,
    k: usize,
) -> Result<FaultRunOutcome, String> {
    let kind = RUN_KINDS[k];
    // the rig's name in the seed: each rig draws its own faults
    let salt = args
        .rig_name()
        .bytes()
        .fold(0u64, |h, b| h.rotate_left(8) ^ u64::from(b));
    let mut rng = Rng::new(w.seed ^ salt ^ 0x5E_45_0F_A1 ^ ((k as u64 + 1) << 40));
    let onset_s = instances::on_grid(rng.uniform_in(ONSET_S.0, ONSET_S.1));
    let (sensor, leak) = draw_fault(kind, onset_s, &mut rng);
    let scenario = w.cycles[(index + k) % w.cycles.len()];
    let (lo, hi) = instances::RUN_TEMP_RANGE_C;
    let oil = OilWarmUp {
        start_c: rng.uniform_in(lo, hi),
        end_c: rng.uniform_in(lo, hi),
        time_constant_s: rng.uniform_in(instances::RUN_TEMP_TAU_S.0, instances::RUN_TEMP_TAU_S.1),
        measured: args.temp_c,
    };
    let sim_cfg = match &w.instance {
        Some(inst) => instances::instance_config(inst, Some(oil)),
        None => Config::default(),
    };
    let sensor_spec = sensor.map(|f| f.to_string());
    let mut req = SimulateRequest {
        scenario: scenario.into(),
        seconds: Some(args.seconds),
        seed: rng.next_u64() >> 12,
        faults: Vec::new(),
        rig_variant: None,
    };
    let leak_spec = match leak {
        Some(kind) => Some(leak_on_healthy_twin(&sim_cfg, &req, kind, onset_s)?),
        None => None,
    };
    req.faults = leak_spec.iter().cloned().collect();
    let sensor_specs: Vec<String> = sensor_spec.iter().cloned().collect();
    let (mut sim, seconds) = simulate::build_with_sensor_faults(&sim_cfg, &req, &sensor_specs)?;
    let samples = sim.run(seconds);
    let misreading = sensor.map_or(Misreading::NONE, |f| {
        Misreading::of(
            &f,
            &samples,
            w.rig.classifier.pressure_full_scale_pa,
            [
                w.rig.classifier.pressure_zero_offset_max_pa,
                w.rig.classifier.pressure_span_error_max,
            ],
        )
        .stated_by(f.channel, &w.reach)
    });
    if args.keep {
        keep_recording(args, index, kind, &samples)?;
    }
    let mut chain = pipeline::Chain::new(&pipeline::ChainSettings::from(&w.rig))?;
    let mut events = Vec::new();
    for s in &samples {
        chain.step(s, |e| events.push(e));
    }
    chain.finish(samples.last().map_or(0.0, |s| s.t_s), |e| events.push(e));
    let channel = match (sensor, leak) {
        (Some(f), _) => f.channel.name().to_string(),
        (None, Some(kind)) => kind.to_string(),
        (None, None) => String::new(),
    };
    let onset = if kind == RunKind::Healthy {
        f64::NAN
    } else {
        onset_s
    };
    let mut outcome = score(
        index,
        kind,
        leak_spec.or(sensor_spec).unwrap_or_default(),
        channel,
        onset,
        scenario,
        &events,
    );
    outcome.misreading = misreading;
    Ok(outcome)
}

/// Writes run `kind` of instance `index`, `samples`, where `--keep` keeps it
/// ([`kept_recording`]; its folder made if missing).
pub(super) fn keep_recording(
    args: &SensorFaultsArgs,
    index: usize,
    kind: RunKind,
    samples: &[model::Sample],
) -> Result<(), String> {
    let path = kept_recording(args, index, kind);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let file = pipeline::out::create(&path, true, &[])?;
    // (`write_csv` flushes)
    simulate::write_csv(&mut std::io::BufWriter::new(file), samples)
        .map(|_| ())
        .map_err(|e| dataset::output::message(&path, &e))
}

/// Where `--keep` writes run `kind` of instance `index`: inst_NNN/KIND.csv
/// (the kind's name in the reports, `_` for its spaces and dots).
pub(super) fn kept_recording(args: &SensorFaultsArgs, index: usize, kind: RunKind) -> PathBuf {
    let name = format!("{}.csv", kind.name().replace([' ', '.', '/'], "_"));
    args.out.join(format!("inst_{index:03}")).join(name)
}

/// The `simulate` spec of a [`LEAK_LPM`] leak of `kind` opening at `onset_s`
/// (s) in the run `req` under `cfg`, sized at the mean drop its path sees
/// before then in the run's healthy twin ([`OperatingLeak`]).
fn leak_on_healthy_twin(
    cfg: &Config,
    req: &SimulateRequest,
    kind: &str,
    onset_s: f64,
) -> Result<String, String> {
    let path = super::operating_leak::leak_path(kind)?;
    let (mut twin, seconds) = simulate::build(cfg, req)?;
    let samples = twin.run(onset_s.min(seconds));
    OperatingLeak::size(path, LEAK_LPM, onset_s, &samples, cfg.model.return_pressure_pa).map(|l| l.spec)
}

/// Checks the command line before anything runs.
fn check(args: &SensorFaultsArgs) -> Result<(), String> {
    if args.instances == 0 {
        return Err("--instances 0: nothing to run".into());
    }
    if args.temp_c && args.rig_name() == "thesis" {
        return Err(
            "--temp-c: the thesis rig's runs have no oil course to measure (--rig press or lift)".into(),
        );
    }
    if args.seconds.is_nan() || args.seconds < ONSET_S.1 + 30.0 {
        return Err(format!(
            "--seconds {}: expected at least {} s (onsets are drawn up to {} s)",
            args.seconds,
            ONSET_S.1 + 30.0,
            ONSET_S.1
        ));
    }
    simulate::check_seconds(args.seconds, 1e-3)
}

/// Runs `job(i)` for i in 0..n on `threads` threads under a progress bar
/// ([`crate::work::try_map`]).
fn parallel<T: Send>(
    n: usize,
    threads: usize,
    job: impl Fn(usize) -> Result<T, String> + Sync,
) -> Result<Vec<T>, String> {
    let bar = indicatif::ProgressBar::new(n as u64);
    let out = crate::work::try_map(n, threads, job, |done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    out
}

/// `leakwatch bench sensor-faults`: commissions each instance, watches its runs,
/// prints the table and writes sensor_faults.md and .json into `args.out`.
pub fn command(args: &SensorFaultsArgs, force: bool) -> Result<(), String> {
    if let Some(dir) = &args.data {
        return recorded::command(args, dir, force);
    }
    check(args)?;
    prepare_out(args, force)?;
    let threads = args.threads.unwrap_or_else(pipeline::batch::cores).max(1);
    let t0 = std::time::Instant::now();
    eprintln!(
        "commissioning {} instances of the {} rig",
        args.instances,
        args.rig_name()
    );
    let watched = parallel(args.instances, threads, |i| commission_instance(args, i))?;
    let jobs = args.instances * RUN_KINDS.len();
    eprintln!("watching {jobs} runs of {} s on {threads} threads", args.seconds);
    let runs = parallel(jobs, threads, |j| {
        let (i, k) = (j / RUN_KINDS.len(), j % RUN_KINDS.len());
        watch_run(args, i, &watched[i], k)
    })?;
    let set = serde_json::json!({
        "rig": args.rig_name(),
        "instances": args.instances,
        "seed": args.seed,
        "seconds": args.seconds,
        "temp_c": args.temp_c,
    });
    report(args, force, set, &runs, t0)
}

/// Makes `args.out` and checks that its reports may be written (`force`).
fn prepare_out(args: &SensorFaultsArgs, force: bool) -> Result<(), String> {
    pipeline::out::dir(&args.out)?;
    for name in ["sensor_faults.md", "sensor_faults.json"] {
        pipeline::out::check(&args.out.join(name), force, &[])?;
    }
    Ok(())
}

/// Prints the table of `runs` and writes sensor_faults.md and .json into
/// `args.out`: the JSON object `set` says which runs these are, beside the
/// wall time since `t0`, the totals per kind and the runs.
fn report(
    args: &SensorFaultsArgs,
    force: bool,
    mut set: serde_json::Value,
    runs: &[FaultRunOutcome],
    t0: std::time::Instant,
) -> Result<(), String> {
    let sums = summarise(runs);
    let md = markdown(args, &sums);
    print!("{md}");
    set["wall_s"] = serde_json::json!(t0.elapsed().as_secs_f64());
    set["summary"] = serde_json::to_value(&sums).map_err(|e| e.to_string())?;
    set["runs"] = serde_json::to_value(runs).map_err(|e| e.to_string())?;
    let text = serde_json::to_string_pretty(&set).map_err(|e| e.to_string())?;
    pipeline::out::write(&args.out.join("sensor_faults.md"), md.as_bytes(), force, &[])?;
    pipeline::out::write(
        &args.out.join("sensor_faults.json"),
        (text + "\n").as_bytes(),
        force,
        &[],
    )?;
    eprintln!(
        "wrote {} in {:.0} s",
        args.out.display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

mod recorded;
#[cfg(test)]
mod tests;
