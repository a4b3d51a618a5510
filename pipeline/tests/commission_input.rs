//! Commissioning refuses a recording it cannot read as SI before it
//! identifies anything: pressures written in bar, positions in mm (every row
//! outside the stroke), each error naming the file, the reading and the unit.

mod common;

use config::Config;
use model::params::ActuatorParams;
use model::scenario::Scenario;
use model::{Sample, SensorParams};

/// A 60 s lift recording (in a scratch folder, kept while it lives) with
/// every sample passed through `unit`, and the lift's config.
fn lift_written_as(unit: fn(Sample) -> Sample) -> (scratch::ScratchDir, std::path::PathBuf, Config) {
    let rig = ActuatorParams::vertical_lift();
    let scenario = Scenario::by_name("lift", 3, 60.0).expect("scenario");
    let dir = scratch::ScratchDir::new("commission_input");
    let si = dir.join("lift_si.csv");
    common::record(&rig, SensorParams::plant(), scenario, 7, &si);
    let samples: Vec<Sample> = dataset::read_csv(&si, dataset::Limits::for_model(&rig, 1e-3))
        .expect("read")
        .samples
        .into_iter()
        .map(unit)
        .collect();
    let csv = dir.join("lift.csv");
    dataset::write_csv(&csv, &samples, false).expect("write");
    let cfg = Config {
        model: rig,
        ..Config::default()
    };
    (dir, csv, cfg)
}

/// Why commissioning refuses the lift recording written through `unit`, and the file.
fn refused(unit: fn(Sample) -> Sample) -> (String, std::path::PathBuf) {
    let (_dir, csv, cfg) = lift_written_as(unit);
    let e = pipeline::commission::identify_rig(&csv, &cfg).expect_err("refused");
    (e, csv)
}

#[test]
fn a_recording_with_its_pressures_in_bar_is_refused_naming_the_unit() {
    let (e, csv) = refused(|s| Sample {
        p1_pa: s.p1_pa / 1e5,
        p2_pa: s.p2_pa / 1e5,
        ..s
    });
    assert!(
        e.starts_with(&format!("{}: p1 and p2 never read above ", csv.display())),
        "{e}"
    );
    // the lift's 21 MPa supply
    assert!(e.contains("under 1 % of the supply pressure (21 MPa)"), "{e}");
    assert!(e.contains("1 bar = 100000 Pa"), "{e}");
}

#[test]
fn a_recording_with_its_positions_in_mm_is_refused_naming_the_first_row() {
    let (e, csv) = refused(|s| Sample {
        x_m: s.x_m * 1e3,
        ..s
    });
    assert!(
        e.starts_with(&format!("{}: no usable samples (", csv.display())),
        "{e}"
    );
    assert!(
        e.contains("rows skipped; first: line 2, column `x`: position "),
        "{e}"
    );
}

#[test]
fn the_same_recording_in_si_is_identified() {
    let (_dir, csv, cfg) = lift_written_as(|s| s);
    let id = pipeline::commission::identify_rig(&csv, &cfg).expect("identified");
    let (a, b) = (id.model.area_gradient_m2_per_m, cfg.model.area_gradient_m2_per_m);
    assert!(
        (a / b - 1.0).abs() < 0.05,
        "area gradient {a} identified, {b} simulated"
    );
}
