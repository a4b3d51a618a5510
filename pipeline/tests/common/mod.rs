//! What the pipeline's integration tests share: a simulated healthy recording.

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::sim::{SimSettings, Simulator};
use model::{FaultSchedule, SensorParams};

/// Simulates 60 s of `scenario` on `rig` read by `sensors` (the simulator's
/// seed `seed`), healthy, and writes it to `csv` as a leakwatch CSV.
pub fn record(rig: &ActuatorParams, sensors: SensorParams, scenario: Scenario, seed: u64, csv: &Path) {
    let mut sim = Simulator::new(
        rig.clone(),
        sensors,
        SimSettings::default(),
        scenario,
        FaultSchedule::default(),
        seed,
    )
    .expect("rig");
    let samples = sim.run(60.0);
    let mut w = BufWriter::new(File::create(csv).expect("csv"));
    pipeline::simulate::write_csv(&mut w, &samples).expect("written");
}
