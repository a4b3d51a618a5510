//! Commissioning measures how far the leak filter's oil stiffness θ moves
//! per unit of error in the model's laminar flows (docs/plant.md, "The null
//! leakage's pull on θ").

mod common;

use config::Config;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::SensorParams;

/// The pull measured on a recording of the press whose model (and rig)
/// has null leakage `c_l` (m³/(s·Pa)).
fn pull(c_l: f64) -> Option<f64> {
    let rig = ActuatorParams {
        valve_null_leakage_m3_s_pa: c_l,
        ..ActuatorParams::press()
    };
    let dir = scratch::ScratchDir::new("laminar-pull");
    let csv = dir.join("press.csv");
    let scenario = Scenario::by_name("press", 5, 60.0).expect("scenario");
    common::record(&rig, SensorParams::plant(), scenario, 5, &csv);
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
