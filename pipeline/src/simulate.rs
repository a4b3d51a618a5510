//! `leakwatch simulate`: run a scenario on the simulated rig and write the CSV.

use std::path::{Path, PathBuf};

use model::fault::{Fault, FaultSchedule};
use model::params::FrictionPreset;
use model::scenario::Scenario;
use model::sensor_fault::SensorFaultSchedule;
use model::sim::Simulator;

use config::Config;

/// Most samples one `simulate` writes (an hour at 1 kHz; about 260 MB in memory).
pub const MAX_SAMPLES: f64 = 3.6e6;

/// What to simulate.
#[derive(Debug, Clone)]
pub struct SimulateRequest {
    /// Scenario name.
    pub scenario: String,
    /// Run length, s (None: the scenario's default).
    pub seconds: Option<f64>,
    /// Noise seed.
    pub seed: u64,
    /// Fault specs `KIND:SIZE@ONSET[,ramp=S][,law=sqrt|linear]`.
    pub faults: Vec<String>,
    /// Friction variant of the rig (None: as configured).
    pub rig_variant: Option<FrictionPreset>,
}

/// Checks a run length `seconds` (s) at sample period `period_s` (s): positive,
/// finite and at most [`MAX_SAMPLES`] samples.
pub fn check_seconds(seconds: f64, period_s: f64) -> Result<(), String> {
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(format!(
            "--seconds {seconds:?} must be a positive number of seconds"
        ));
    }
    let samples = seconds / period_s;
    if samples > MAX_SAMPLES {
        return Err(format!(
            "--seconds {seconds:?}: {samples:e} samples at a sample period of {period_s} s is more than \
             {MAX_SAMPLES:.0} samples (an hour at 1 kHz) in one run"
        ));
    }
    Ok(())
}

/// Builds the simulator for a request.
pub fn build(cfg: &Config, req: &SimulateRequest) -> Result<(Simulator, f64), String> {
    build_with_sensor_faults(cfg, req, &[])
}

/// Builds the simulator for a request with the sensor faults `sensor_faults`
/// (specs `CHANNEL:KIND@ONSET`, [`model::sensor_fault::SensorFault::parse`]; `none` is skipped).
pub fn build_with_sensor_faults(
    cfg: &Config,
    req: &SimulateRequest,
    sensor_faults: &[String],
) -> Result<(Simulator, f64), String> {
    let sensor_schedule = SensorFaultSchedule::parse_all(sensor_faults).map_err(|e| e.to_string())?;
    if let Some(s) = req.seconds {
        check_seconds(s, cfg.sim.sample_period_s)?;
    }
    let seconds_max = req.seconds.unwrap_or(60.0);
    let scenario = Scenario::by_name(&req.scenario, req.seed, seconds_max).map_err(|e| e.to_string())?;
    let seconds = req.seconds.unwrap_or(scenario.default_seconds);
    check_seconds(seconds, cfg.sim.sample_period_s)?;
    let mut rig = cfg.rig_params();
    if let Some(v) = req.rig_variant {
        rig = rig.with_friction_preset(v);
    }
    let mut schedule = FaultSchedule::default();
    // (`--fault none` asks for a healthy run, as in `run`)
    for spec in req.faults.iter().filter(|f| f.as_str() != "none") {
        schedule
            .faults
            .push(Fault::parse(spec, &rig).map_err(|e| e.to_string())?);
    }
    let sim = Simulator::new(rig, cfg.sensors, cfg.sim, scenario, schedule, req.seed)
        .and_then(|sim| sim.with_sensor_faults(sensor_schedule))
        .map_err(|e| e.to_string())?;
    Ok((sim, seconds))
}

/// Runs the request and writes the CSV to `out` (`-`: standard output; an existing
/// file only if `force`, never the `config` file or through a symbolic link);
/// returns the number of samples.
pub fn run(
    cfg: &Config,
    req: &SimulateRequest,
    out: &Path,
    force: bool,
    config: Option<&Path>,
) -> Result<usize, String> {
    write_run(build(cfg, req)?, out, force, config)
}

/// Runs the simulator `sim` for `seconds` (s) and writes the CSV to `out`, as [`run`].
fn write_run(
    (mut sim, seconds): (Simulator, f64),
    out: &Path,
    force: bool,
    config: Option<&Path>,
) -> Result<usize, String> {
    if out == Path::new("-") {
        let samples = sim.run(seconds);
        let mut w = std::io::BufWriter::new(std::io::stdout().lock());
        return write_csv(&mut w, &samples)
            .map_err(|e| format!("cannot write the CSV to standard output: {e}"));
    }
    // fail on an unwritable or refused path before spending time simulating
    let inputs: Vec<&Path> = config.into_iter().collect();
    let file = crate::out::create(out, force, &inputs)?;
    let samples = sim.run(seconds);
    let mut w = std::io::BufWriter::new(file);
    write_csv(&mut w, &samples).map_err(|e| dataset::output::message(out, &e))
}

/// `leakwatch simulate`: simulates `req` with the sensor faults `sensor_faults`
/// and the configuration `config` (or ./leakwatch.toml, or the defaults), writes
/// the CSV to `out` and says how much.
pub fn command(
    config: Option<PathBuf>,
    req: SimulateRequest,
    sensor_faults: &[String],
    out: &Path,
    force: bool,
) -> Result<(), String> {
    let config = Config::pick(config);
    let cfg = Config::load_or_default(config.as_deref())?;
    let built = build_with_sensor_faults(&cfg, &req, sensor_faults)?;
    let n = write_run(built, out, force, config.as_deref())?;
    if out.as_os_str() == "-" {
        eprintln!("wrote {n} samples to standard output");
    } else {
        eprintln!("wrote {n} samples to {}", out.display());
    }
    Ok(())
}

/// Writes `samples` as a leakwatch CSV (header and rows) to `w` and flushes it;
/// returns the number of samples.
pub fn write_csv(w: &mut impl std::io::Write, samples: &[model::Sample]) -> std::io::Result<usize> {
    dataset::write_header(&mut *w)?;
    for s in samples {
        dataset::write_row(&mut *w, s)?;
    }
    w.flush()?;
    Ok(samples.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_lengths_that_would_exhaust_memory_or_never_end_are_refused() {
        assert_eq!(check_seconds(3600.0, 1e-3), Ok(()));
        let e = check_seconds(3601.0, 1e-3).unwrap_err();
        assert!(e.contains("--seconds 3601.0: 3.601e6 samples"), "{e}");
        for s in [1e308, f64::INFINITY, f64::NAN, 0.0, -1.0] {
            assert!(check_seconds(s, 1e-3).is_err(), "{s}");
        }
        // the random scenario's levels are not drawn for 1e308 s
        let req = SimulateRequest {
            scenario: "closed-loop-random".into(),
            seconds: Some(1e308),
            seed: 1,
            faults: vec![],
            rig_variant: None,
        };
        let e = build(&Config::default(), &req).err().unwrap();
        assert!(e.starts_with("--seconds 1e308: inf samples"), "{e}");
    }
}
