//! Physics of the rig simulator asserted against references (docs/model.md, "Known behaviour").

use model::fault::{Fault, FaultSchedule};
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::sensors::SensorParams;
use model::sim::{SimSettings, Simulator};

#[path = "physics/closed_loop.rs"]
mod closed_loop;
#[path = "physics/leaks.rs"]
mod leaks;
#[path = "physics/lift.rs"]
mod lift;
#[path = "physics/open_loop.rs"]
mod open_loop;
#[path = "physics/plant.rs"]
mod plant;
#[path = "physics/rest_and_balance.rs"]
mod rest_and_balance;

fn sim(
    name: &str,
    rig: ActuatorParams,
    faults: Vec<Fault>,
    sensors: SensorParams,
    settings: SimSettings,
) -> Simulator {
    let sc = Scenario::by_name(name, 1, 60.0).unwrap();
    Simulator::new(rig, sensors, settings, sc, FaultSchedule { faults }, 1).unwrap()
}

/// Runs and returns the true states after each sample.
fn run_truth(s: &mut Simulator, seconds: f64) -> Vec<[f64; 6]> {
    let n = (seconds * 1000.0).round() as usize;
    (0..n)
        .map(|_| {
            s.step();
            s.truth().state
        })
        .collect()
}
