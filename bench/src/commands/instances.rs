//! `leakwatch bench instances`: plant-style folders of simulated rig
//! instances, each drawn over its datasheet's tolerances
//! ([`model::instance`]), that `leakwatch bench detection --data` scores.
//!
//! Per instance, `OUT/inst_NNN/` holds:
//! - `datasheet.toml`: what a user writes from the catalogues (`[datasheet]`
//!   and the `[model]` facts no datasheet gives), never the drawn values;
//! - `instance.toml`: the simulated rig's config (`[model]`, `[sensors]`,
//!   `[sim]`: the drawn instance; `leakwatch simulate --config` reads it);
//! - `commission_cold.csv`: each duty cycle in turn at a constant oil temperature;
//! - `run_NNN/measured.csv` and `truth.json`: healthy runs on every duty cycle
//!   and leak runs, each under a drawn oil warm-up or cool-down.
//!
//! Every CSV comes from [`pipeline::simulate::build`], the `simulate` command's path.

use std::path::{Path, PathBuf};

use model::instance::{Instance, NominalRig};
use model::rng::Rng;
use model::sim::OilWarmUp;

use config::Config;
use pipeline::simulate::{self, SimulateRequest};

use super::operating_leak::{self, OperatingLeak};

/// The oil temperatures a commissioning recording is held at, °C (one drawn per instance).
pub const COMMISSION_TEMPS_C: [f64; 3] = [20.0, 30.0, 50.0];
/// The range a run's oil starts and ends in, °C.
pub const RUN_TEMP_RANGE_C: (f64, f64) = (20.0, 60.0);
/// The range of a run's oil time constant, s.
pub const RUN_TEMP_TAU_S: (f64, f64) = (60.0, 600.0);
/// The leak sizes of the leak runs, L/min at the mean drop their path sees
/// before they open ([`OperatingLeak`]; each of ext1, ext2, int).
pub const LEAK_SIZES_LPM: [f64; 3] = [0.1, 0.25, 0.5];
/// The leak kinds of the leak runs.
pub const LEAK_KINDS: [&str; 3] = ["ext1", "ext2", "int"];

/// What to generate: the command line of `leakwatch bench instances`.
#[derive(Debug, Clone, clap::Args)]
pub struct InstancesRequest {
    /// The rig: `press` (double-rod; press and handling cycles) or `lift` (vertical single-rod;
    /// lift and handling cycles).
    #[arg(long, value_parser = ["press", "lift"])]
    pub rig: String,
    /// Number of instances.
    #[arg(long, default_value_t = 1)]
    pub instances: usize,
    /// Seed of the set (instance i is drawn from it and i).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Healthy time per instance, hours (in runs of --run-seconds, on the duty cycles in turn).
    #[arg(long, default_value_t = 0.05)]
    pub hours_healthy: f64,
    /// Length of every run, s.
    #[arg(long, default_value_t = 90.0)]
    pub run_seconds: f64,
    /// Length of the commissioning recording, s.
    #[arg(long, default_value_t = 120.0)]
    pub commission_seconds: f64,
    /// The samples carry the oil's temperature (a `temp_c` column).
    #[arg(long)]
    pub temp_c: bool,
    /// Worker threads, each simulating whole recordings (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Only the datasheet and the commissioning recording (no runs): what a
    /// user has before the watch (docs/examples.sh).
    #[arg(long)]
    pub commissioning_only: bool,
}

impl InstancesRequest {
    /// The worker threads: as asked, else one per core.
    fn worker_threads(&self) -> usize {
        self.threads.unwrap_or_else(pipeline::batch::cores).max(1)
    }
}

/// The rig named `rig` and its duty cycles (scenario names).
pub(crate) fn nominal(rig: &str) -> Result<(NominalRig, &'static [&'static str]), String> {
    match rig {
        "press" => Ok((NominalRig::press(), &["press", "handling"])),
        "lift" => Ok((NominalRig::lift(), &["lift", "handling"])),
        other => Err(format!("--rig {other}: expected press or lift")),
    }
}

/// How far the tank thermometer a user reads during the commissioning
/// recording may be off the oil in the chambers, K (either way).
const TANK_READING_ERROR_K: f64 = 2.0;

/// `datasheet.toml`: the catalogue datasheet and the nominal `[model]` fields
/// no datasheet gives (as a user writes them), nothing of the drawn instance;
/// and, as the README asks, the tank thermometer's reading during the
/// commissioning recording, `tank_c` (°C), as the oil law's reference.
fn catalogue_toml(n: &NominalRig, tank_c: f64) -> Result<String, String> {
    let mut rest = toml::Table::try_from(&n.model).map_err(|e| e.to_string())?;
    if let Some(oil) = rest.get_mut("oil_temperature").and_then(|v| v.as_table_mut()) {
        oil.insert(
            "reference_c".into(),
            toml::Value::Float((tank_c * 10.0).round() / 10.0),
        );
    }
    for (section, field, _) in model::datasheet::DERIVED_FIELDS {
        if section != "model" {
            continue;
        }
        match field.split_once('.') {
            Some((table, key)) => {
                if let Some(t) = rest.get_mut(table).and_then(|v| v.as_table_mut()) {
                    t.remove(key);
                }
            }
            None => {
                rest.remove(field);
            }
        }
    }
    let mut cfg = toml::Table::new();
    cfg.insert(
        "datasheet".into(),
        toml::Value::try_from(n.datasheet).map_err(|e| e.to_string())?,
    );
    cfg.insert("model".into(), toml::Value::Table(rest));
    let body = toml::to_string(&cfg).map_err(|e| e.to_string())?;
    Ok(format!(
        "# The {} rig as its catalogues give it (docs/rig.md), and the [model] facts no datasheet gives.\n\
         # The simulated instance differs from it within the datasheet's tolerances: instance.toml.\n\n{body}",
        n.name
    ))
}

/// The `datasheet.toml` a user writes for instance `inst` of rig `n`
/// ([`catalogue_toml`]), with the tank's reading of the commissioning's oil at
/// `commission_c` (°C), off by up to [`TANK_READING_ERROR_K`] (drawn from the instance's seed).
pub(crate) fn user_datasheet(n: &NominalRig, inst: &Instance, commission_c: f64) -> Result<String, String> {
    let misread = Rng::new(inst.seed ^ 0x5EED_7A4C).uniform_in(-TANK_READING_ERROR_K, TANK_READING_ERROR_K);
    catalogue_toml(n, commission_c + misread)
}

/// The simulated instance's config: `[model]` the drawn rig, `[sensors]` its
/// sensors and installation, `[sim]` its pump (and `oil`, when given).
pub(crate) fn instance_config(inst: &Instance, oil: Option<OilWarmUp>) -> Config {
    let mut cfg = Config {
        model: inst.rig.clone(),
        sensors: inst.sensors,
        ..Config::default()
    };
    cfg.sim.supply_ripple_fraction = inst.supply_ripple_fraction;
    cfg.sim.supply_ripple_hz = inst.supply_ripple_hz;
    cfg.sim.oil = oil;
    cfg.derive_rig_facts();
    cfg
}

/// `instance.toml`: [`instance_config`] without an oil course, as TOML.
fn instance_toml(inst: &Instance, rig: &str, index: usize) -> Result<String, String> {
    let cfg = instance_config(inst, None);
    let mut t = toml::Table::new();
    for (name, value) in [
        ("model", toml::Value::try_from(&cfg.model)),
        ("sensors", toml::Value::try_from(cfg.sensors)),
        ("sim", toml::Value::try_from(cfg.sim)),
    ] {
        t.insert(name.into(), value.map_err(|e| e.to_string())?);
    }
    let body = toml::to_string(&t).map_err(|e| e.to_string())?;
    Ok(format!(
        "# Instance {index} of the {rig} rig (seed {}), drawn over its datasheet's tolerances: the simulated\n\
         # rig's truth for `leakwatch simulate --config`. Each run's oil course is in its truth.json.\n\n{body}",
        inst.seed
    ))
}

/// One recording to simulate.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    /// Instance index.
    pub(crate) instance: usize,
    /// Folder under the instance's (empty: the commissioning recording).
    pub(crate) run: String,
    pub(crate) scenario: &'static str,
    /// The commissioning recording's duty cycles, recorded in turn for an
    /// equal share of its length (empty for a run).
    pub(crate) segments: Vec<&'static str>,
    pub(crate) seed: u64,
    pub(crate) seconds: f64,
    pub(crate) oil: OilWarmUp,
    /// (kind, size L/min, onset s).
    pub(crate) leak: Option<(&'static str, f64, f64)>,
}

/// Milliseconds: a drawn time on the sample grid, s.
pub(crate) fn on_grid(t_s: f64) -> f64 {
    (t_s * 1000.0).round() / 1000.0
}

/// The recordings of instance `index` (seed `inst_seed`): the commissioning
/// recording, the healthy runs on each duty cycle in turn, then a leak run of
/// each size and kind, each with a drawn oil course and onset.
pub(crate) fn plan_instance(
    req: &InstancesRequest,
    cycles: &[&'static str],
    index: usize,
    inst_seed: u64,
) -> Vec<Plan> {
    let mut rng = Rng::new(inst_seed ^ 0x7E3A_55C1_0B9D_2F48);
    let commission_temp = COMMISSION_TEMPS_C[(rng.next_u64() % COMMISSION_TEMPS_C.len() as u64) as usize];
    let mut out = vec![Plan {
        instance: index,
        run: String::new(),
        scenario: cycles[0],
        segments: cycles.to_vec(),
        seed: rng.next_u64() >> 12,
        seconds: req.commission_seconds,
        oil: OilWarmUp {
            start_c: commission_temp,
            end_c: commission_temp,
            time_constant_s: 60.0,
            measured: req.temp_c,
        },
        leak: None,
    }];
    let healthy = (req.hours_healthy * 3600.0 / req.run_seconds).ceil().max(0.0) as usize;
    let leaks: Vec<(&'static str, f64)> = LEAK_SIZES_LPM
        .iter()
        .flat_map(|&s| LEAK_KINDS.iter().map(move |&k| (k, s)))
        .collect();
    let (lo, hi) = RUN_TEMP_RANGE_C;
    for k in 0..healthy + leaks.len() {
        let oil = OilWarmUp {
            start_c: rng.uniform_in(lo, hi),
            end_c: rng.uniform_in(lo, hi),
            time_constant_s: rng.uniform_in(RUN_TEMP_TAU_S.0, RUN_TEMP_TAU_S.1),
            measured: req.temp_c,
        };
        let leak = k.checked_sub(healthy).map(|j| {
            let (kind, size) = leaks[j];
            let onset = rng.uniform_in(req.run_seconds / 3.0, 2.0 * req.run_seconds / 3.0);
            (kind, size, on_grid(onset))
        });
        let cycle = match k.checked_sub(healthy) {
            Some(j) => cycles[j % cycles.len()],
            None => cycles[k % cycles.len()],
        };
        out.push(Plan {
            instance: index,
            run: format!("run_{k:03}"),
            scenario: cycle,
            segments: Vec::new(),
            seed: rng.next_u64() >> 12,
            seconds: req.run_seconds,
            oil,
            leak,
        });
    }
    out
}

/// Instance `index`'s seed in a set seeded `seed`.
pub(crate) fn instance_seed(seed: u64, index: usize) -> u64 {
    Rng::new(seed.wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(index as u64 + 1))).next_u64() >> 12
}

/// The folder of instance `index`.
fn instance_dir(out: &Path, index: usize) -> PathBuf {
    out.join(format!("inst_{index:03}"))
}

/// Pause between the commissioning recording's segments, s: a gap in its
/// samples, after which the filter re-anchors (as after any long gap).
const SEGMENT_GAP_S: f64 = 1.0;

/// The samples of `plan` under config `cfg` with `faults`, and their span, s:
/// one simulation, or for the commissioning recording one per duty cycle in
/// turn, joined with a gap of [`SEGMENT_GAP_S`].
pub(crate) fn simulate_plan(
    cfg: &Config,
    plan: &Plan,
    faults: &[String],
) -> Result<(Vec<model::Sample>, f64), String> {
    let cycles: Vec<&str> = if plan.segments.is_empty() {
        vec![plan.scenario]
    } else {
        plan.segments.clone()
    };
    let share = plan.seconds / cycles.len() as f64;
    let (mut all, mut t0) = (Vec::new(), 0.0);
    for (i, cycle) in cycles.iter().enumerate() {
        let sim_req = SimulateRequest {
            scenario: (*cycle).into(),
            seconds: Some(share),
            seed: plan.seed.wrapping_add(i as u64),
            faults: faults.to_vec(),
            rig_variant: None,
        };
        let (mut sim, seconds) = simulate::build(cfg, &sim_req)?;
        let mut samples = sim.run(seconds);
        for s in &mut samples {
            s.t_s = on_grid(s.t_s + t0);
        }
        t0 = samples.last().map_or(t0, |s| s.t_s) + SEGMENT_GAP_S;
        all.extend(samples);
    }
    let span = all.last().map_or(0.0, |s| s.t_s);
    Ok((all, span))
}

/// Simulates one recording and writes it with its truth; returns its samples.
fn write_recording(
    req: &InstancesRequest,
    plan: &Plan,
    inst: &Instance,
    force: bool,
) -> Result<usize, String> {
    let dir = instance_dir(&req.out, plan.instance);
    let (csv, truth) = if plan.run.is_empty() {
        (
            dir.join("commission_cold.csv"),
            dir.join("commission_cold.truth.json"),
        )
    } else {
        let d = dir.join(&plan.run);
        pipeline::out::dir(&d)?;
        (d.join("measured.csv"), d.join("truth.json"))
    };
    let cfg = instance_config(inst, Some(plan.oil));
    let sized = match plan.leak {
        Some((kind, size, onset)) => Some(size_on_healthy_twin(&cfg, plan, kind, size, onset)?),
        None => None,
    };
    let faults: Vec<String> = sized.iter().map(|l| l.spec.clone()).collect();
    let file = pipeline::out::create(&csv, force, &[])?;
    let (samples, seconds) = simulate_plan(&cfg, plan, &faults)?;
    let mut w = std::io::BufWriter::new(file);
    simulate::write_csv(&mut w, &samples).map_err(|e| dataset::output::message(&csv, &e))?;
    let fault = plan.leak.map(|(kind, size, onset)| {
        let after: Vec<f64> = samples
            .iter()
            .filter(|s| s.t_s >= onset)
            .map(|s| s.q_leak_lpm.abs())
            .collect();
        let mean = after.iter().sum::<f64>() / after.len().max(1) as f64;
        let max = after.iter().cloned().fold(0.0, f64::max);
        serde_json::json!({
            "kind": kind,
            "law": "sqrt",
            "size_lpm": size,
            "t_on_s": onset,
            "ramp_s": 0.0,
            "coef_m3_s_sqrtPa": sized.as_ref().map(|l| l.coefficient),
            "calib_mean_dp_Pa": sized.as_ref().map(|l| l.mean_drop_pa),
            "calib_window_s": [operating_leak::CALIBRATION_START_S, onset],
            "coef_rule": "coef = size_lpm/60000/sqrt(mean |dp| over calib_window_s of the healthy twin)",
            "observed_mean_abs_flow_lpm_after_ramp": mean,
            "observed_max_abs_flow_lpm": max,
        })
    });
    let temps = [plan.oil.at(0.0), plan.oil.at(seconds)];
    let truth_json = serde_json::json!({
        "run": if plan.run.is_empty() { "commission_cold" } else { plan.run.as_str() },
        "rig": req.rig,
        "healthy": plan.leak.is_none(),
        "fault": fault,
        "scenario": {"name": plan.scenario, "segments": plan.segments, "seed": plan.seed, "duration_s": seconds},
        "oil_temperature": {
            "start_c": plan.oil.start_c,
            "end_c": plan.oil.end_c,
            "time_constant_s": plan.oil.time_constant_s,
            "measured": plan.oil.measured,
            "range_c": [temps[0].min(temps[1]), temps[0].max(temps[1])],
        },
        "simulate": {
            "config": "instance.toml, with [sim.oil] as oil_temperature",
            "scenario": plan.scenario,
            "seconds": seconds,
            "seed": plan.seed,
            "faults": faults,
        },
        "instance": {"index": plan.instance, "seed": inst.seed, "drawn": inst.describe()},
        "samples": samples.len(),
    });
    let text = serde_json::to_string_pretty(&truth_json).map_err(|e| e.to_string())?;
    pipeline::out::write(&truth, (text + "\n").as_bytes(), force, &[])?;
    Ok(samples.len())
}

/// The leak `kind` of `size_lpm` (L/min) opening at `onset_s` (s) in `plan`,
/// sized at the mean drop its path sees before then in the plan's healthy
/// twin (the same seed without the leak): [`OperatingLeak`].
fn size_on_healthy_twin(
    cfg: &Config,
    plan: &Plan,
    kind: &str,
    size_lpm: f64,
    onset_s: f64,
) -> Result<OperatingLeak, String> {
    let path = super::operating_leak::leak_path(kind)?;
    let (twin, _) = simulate_plan(cfg, plan, &[])?;
    OperatingLeak::size(path, size_lpm, onset_s, &twin, cfg.model.return_pressure_pa)
}

/// Checks a request's numbers before anything is written.
fn check(req: &InstancesRequest) -> Result<(), String> {
    if req.instances == 0 {
        return Err("--instances 0: nothing to generate".into());
    }
    if !(0.0..=1000.0).contains(&req.hours_healthy) {
        return Err(format!(
            "--hours-healthy {}: expected 0 to 1000 hours",
            req.hours_healthy
        ));
    }
    for (name, s) in [
        ("--run-seconds", req.run_seconds),
        ("--commission-seconds", req.commission_seconds),
    ] {
        if s.is_nan() || s < 3.0 {
            return Err(format!("{name} {s}: expected at least 3 s"));
        }
        simulate::check_seconds(s, 1e-3)?;
    }
    Ok(())
}

/// `leakwatch bench instances`: draws `req.instances` instances of the rig and
/// writes each one's folder (see the module's documentation), the recordings
/// simulated on `req.threads` threads; says how much and how long.
pub fn command(req: &InstancesRequest, force: bool) -> Result<(), String> {
    check(req)?;
    let (nominal, cycles) = nominal(&req.rig)?;
    let t0 = std::time::Instant::now();
    let mut instances = Vec::with_capacity(req.instances);
    let mut plans = Vec::new();
    for i in 0..req.instances {
        let inst = Instance::draw(&nominal, instance_seed(req.seed, i));
        let dir = instance_dir(&req.out, i);
        pipeline::out::dir(&dir)?;
        let mut plan = plan_instance(req, cycles, i, inst.seed);
        if req.commissioning_only {
            plan.truncate(1);
        }
        let commission_c = plan.first().map_or(40.0, |p| p.oil.start_c);
        let catalogue = user_datasheet(&nominal, &inst, commission_c)?;
        pipeline::out::write(&dir.join("datasheet.toml"), catalogue.as_bytes(), force, &[])?;
        let text = instance_toml(&inst, &req.rig, i)?;
        pipeline::out::write(&dir.join("instance.toml"), text.as_bytes(), force, &[])?;
        plans.extend(plan);
        instances.push(inst);
    }
    let simulated: f64 = plans.iter().map(|p| p.seconds).sum();
    eprintln!(
        "{} instances of the {} rig: {} recordings, {:.2} simulated hours, {} threads",
        req.instances,
        req.rig,
        plans.len(),
        simulated / 3600.0,
        req.worker_threads()
    );
    let bar = indicatif::ProgressBar::new(plans.len() as u64);
    let written = crate::work::try_map(
        plans.len(),
        req.worker_threads(),
        |i| write_recording(req, &plans[i], &instances[plans[i].instance], force),
        |done, _| bar.set_position(done as u64),
    );
    bar.finish_and_clear();
    written?;
    let wall = t0.elapsed().as_secs_f64();
    eprintln!(
        "wrote {} instances to {} in {wall:.1} s ({:.0}x real time); score one with \
         `leakwatch bench detection --data {}`",
        req.instances,
        req.out.display(),
        simulated / wall,
        instance_dir(&req.out, 0).display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> InstancesRequest {
        InstancesRequest {
            rig: "press".into(),
            instances: 2,
            seed: 3,
            out: PathBuf::from("unused"),
            hours_healthy: 0.05,
            run_seconds: 90.0,
            commission_seconds: 120.0,
            temp_c: false,
            threads: Some(1),
            commissioning_only: false,
        }
    }

    #[test]
    fn a_plan_has_healthy_runs_on_each_cycle_and_every_leak_under_drawn_temperatures() {
        let req = request();
        let plans = plan_instance(&req, &["press", "handling"], 0, instance_seed(3, 0));
        // the commissioning, 180 s of healthy runs (2 of 90 s) and 9 leaks
        assert_eq!(plans.len(), 1 + 2 + 9);
        let c = &plans[0];
        assert!(c.run.is_empty() && c.scenario == "press" && c.seconds == 120.0);
        assert!(COMMISSION_TEMPS_C.contains(&c.oil.start_c) && c.oil.start_c == c.oil.end_c);
        assert_eq!((plans[1].scenario, plans[2].scenario), ("press", "handling"));
        for p in &plans[1..] {
            for t in [p.oil.start_c, p.oil.end_c] {
                assert!((20.0..60.0).contains(&t), "{t}");
            }
            assert!((60.0..600.0).contains(&p.oil.time_constant_s));
            if let Some((_, _, onset)) = p.leak {
                assert!((30.0..=60.0).contains(&onset), "{onset}");
            }
        }
        let leaks: Vec<_> = plans.iter().filter_map(|p| p.leak).collect();
        assert_eq!(leaks.len(), 9);
        for kind in LEAK_KINDS {
            for size in LEAK_SIZES_LPM {
                assert_eq!(leaks.iter().filter(|l| l.0 == kind && l.1 == size).count(), 1);
            }
        }
        // another instance, other draws
        let other = plan_instance(&req, &["press", "handling"], 1, instance_seed(3, 1));
        assert_ne!(other[1].oil, plans[1].oil);
        assert_ne!(instance_seed(3, 0), instance_seed(3, 1));
        assert_ne!(instance_seed(3, 0), instance_seed(4, 0));
    }

    #[test]
    fn the_catalogue_config_loads_and_is_the_datasheet_not_the_instance() {
        let (n, _) = nominal("press").expect("rig");
        let text = catalogue_toml(&n, 31.26).expect("toml");
        let cfg = Config::parse(&text).expect("loads");
        // the tank's reading, to 0.1 °C, is the one fact beyond the catalogue
        assert_eq!(cfg.model.oil_temperature.reference_c, 31.3);
        let mut model = cfg.model.clone();
        model.oil_temperature.reference_c = n.model.oil_temperature.reference_c;
        assert_eq!(model, n.model);
        assert_eq!(cfg.datasheet, Some(n.datasheet));
        let inst = Instance::draw(&n, 5);
        assert_ne!(cfg.model.mass_kg, inst.rig.mass_kg);
        let sim = Config::parse(&instance_toml(&inst, "press", 0).expect("toml")).expect("loads");
        assert_eq!(sim.model, inst.rig);
        assert_eq!(sim.sensors, inst.sensors);
        assert_eq!(sim.sim.supply_ripple_hz, inst.supply_ripple_hz);
        assert!(nominal("crane").is_err());
    }
}
