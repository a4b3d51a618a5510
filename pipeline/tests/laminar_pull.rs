//! Commissioning measures how far the leak filter's oil stiffness θ moves
//! per unit of error in the model's laminar flows (docs/plant.md, "The null
//! leakage's pull on θ").

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use config::Config;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::sim::{SimSettings, Simulator};
use model::{FaultSchedule, SensorParams};

/// A 60 s press recording of the rig `rig`, written to `csv`.
fn record(rig: &ActuatorParams, csv: &Path) {
    let scenario = Scenario::by_name("press", 5, 60.0).expect("scenario");
    let mut sim = Simulator::new(
        rig.clone(),
        SensorParams::plant(),
        SimSettings::default(),
        scenario,
        FaultSchedule::default(),
        5,
    )
    .expect("rig");
    let samples = sim.run(60.0);
    let mut w = BufWriter::new(File::create(csv).expect("csv"));
    pipeline::simulate::write_csv(&mut w, &samples).expect("written");
}

/// The pull measured on a recording of the press whose model (and rig)
/// has null leakage `c_l` (m³/(s·Pa)).
fn pull(c_l: f64) -> Option<f64> {
    let rig = ActuatorParams {
        valve_null_leakage_m3_s_pa: c_l,
        ..ActuatorParams::press()
    };
    let dir = scratch::ScratchDir::new("laminar-pull");
    let csv = dir.join("press.csv");
    record(&rig, &csv);
    let cfg = Config {
        model: rig,
        sensors: SensorParams::plant(),
        ..Config::default()
    };
    let (_, theta) = pipeline::commission::learn(&csv, &cfg).expect("learned");
    pipeline::commission::laminar_pull(&csv, &cfg, theta.expect("a θ state")).expect("replayed")
}

/// Laminar flows set too large pull θ down, as a warmer oil does; twice the
/// null leakage pulls about twice as hard; a model without laminar flows has none.
#[test]
fn a_leaky_valve_pulls_the_oil_stiffness_down_in_proportion_to_its_null_leakage() {
    let c_l = ActuatorParams::press().valve_null_leakage_m3_s_pa;
    assert!(c_l > 0.0);
    let one = pull(c_l).expect("a pull");
    assert!(one < -0.01, "{one}");
    let two = pull(2.0 * c_l).expect("a pull");
    assert!((1.4..2.6).contains(&(two / one)), "{one} then {two}");
    assert_eq!(pull(0.0), None);
}
