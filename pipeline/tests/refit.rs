//! The calibrate workflow with the rig identified first: a spring in front of
//! the rod that the search corrects is taken into a refit of the mass and the
//! friction, and the search is repeated until it adds no such effect.

mod common;

use config::Config;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::SensorParams;
use pipeline::calibration::{refits_mechanics, search_with_refit};

/// The press rig on its press cycle (a workpiece of 2e6 N/m at 0.20 m), with
/// a model whose spring is half as stiff and touches 1 cm early. The first
/// identification fits the mass and friction against the wrong spring (mass
/// not identifiable, Coulomb friction 2.8 kN against 1 kN). The search adds a
/// spring (stiffness and contact trade over the short penetration: 0.9e6 N/m
/// at 198 mm). The refit of the spring, the mass and the friction together
/// puts the spring within 10 % (contact within 1 cm), the Coulomb friction and
/// the mass within 5 % of the rig's; the validation gap falls tenfold.
#[test]
fn a_spring_the_search_corrects_is_refitted_into_the_mechanics() {
    let rig = ActuatorParams::press();
    let scenario = Scenario::by_name("press", 3, 60.0).expect("scenario");
    let workpiece = scenario.spring;
    let dir = scratch::ScratchDir::new("refit");
    let csv = dir.join("press.csv");
    common::record(&rig, SensorParams::default(), scenario, 7, &csv);

    let mut cfg = Config {
        model: rig.clone(),
        ..Config::default()
    };
    cfg.model.load.stiffness_n_per_m = 0.5 * workpiece.stiffness_n_per_m;
    cfg.model.load.contact_m = workpiece.contact_m - 0.01;
    let first = pipeline::commission::identify_rig(&csv, &cfg).expect("identified");
    let measured = calibrate::load_measured(&csv).expect("read");
    let opts = calibrate::CalibrateOptions::default();
    let cal = search_with_refit(&csv, &first, &measured, &opts, &|_| {}).expect("calibrated");

    assert!(cal.effects.iter().any(refits_mechanics), "{:?}", cal.names());
    let m = &cal.model_after;
    assert!(
        (m.load.stiffness_n_per_m / workpiece.stiffness_n_per_m - 1.0).abs() < 0.1,
        "stiffness {} N/m (the workpiece's {})",
        m.load.stiffness_n_per_m,
        workpiece.stiffness_n_per_m
    );
    assert!(
        (m.load.contact_m - workpiece.contact_m).abs() < 0.01,
        "contact {} m",
        m.load.contact_m
    );
    let coulomb = m.friction.extend().slip_n / rig.friction.extend().slip_n - 1.0;
    let mass = m.mass_kg / rig.mass_kg - 1.0;
    assert!(
        coulomb.abs() < 0.05 && mass.abs() < 0.05,
        "Coulomb off by {coulomb}, mass by {mass}"
    );
    // the gap before is the first model's, and every round's effects are kept
    assert!(
        cal.gap_after.normalised < 0.1 * cal.gap_before.normalised,
        "{cal:?}"
    );
    assert!(cal.gap_reduction > 0.0 && cal.gap_reduction <= 1.0);
}
