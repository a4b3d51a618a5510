//! `leakwatch simulate`: run a scenario on the simulated rig and write the CSV.

use std::path::PathBuf;

use model::fault::{Fault, FaultSchedule};
use model::params::FrictionPreset;
use model::scenario::Scenario;
use model::sim::Simulator;

use crate::config::Config;

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

/// Builds the simulator for a request.
pub fn build(cfg: &Config, req: &SimulateRequest) -> Result<(Simulator, f64), String> {
    let seconds_max = req.seconds.unwrap_or(60.0);
    let scenario = Scenario::by_name(&req.scenario, req.seed, seconds_max).map_err(|e| e.to_string())?;
    let seconds = req.seconds.unwrap_or(scenario.default_seconds);
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(format!(
            "--seconds {seconds} must be a positive number of seconds"
        ));
    }
    let mut rig = cfg.rig_params();
    if let Some(v) = req.rig_variant {
        rig = rig.with_friction_preset(v);
    }
    let mut schedule = FaultSchedule::default();
    for spec in &req.faults {
        schedule
            .faults
            .push(Fault::parse(spec, &rig).map_err(|e| e.to_string())?);
    }
    let sim =
        Simulator::new(rig, cfg.sensors, cfg.sim, scenario, schedule, req.seed).map_err(|e| e.to_string())?;
    Ok((sim, seconds))
}

/// Runs the request and writes the CSV to `out`; returns the number of samples.
pub fn run(cfg: &Config, req: &SimulateRequest, out: &PathBuf) -> Result<usize, String> {
    let (mut sim, seconds) = build(cfg, req)?;
    // fail on an unwritable path before spending time simulating
    std::fs::File::create(out).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    let samples = sim.run(seconds);
    dataset::write_csv(out, &samples).map_err(|e| e.to_string())?;
    Ok(samples.len())
}
