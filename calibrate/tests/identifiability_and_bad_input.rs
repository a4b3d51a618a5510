//! Inputs that do not excite an effect get "not identifiable from this
//! data"; bad inputs (too little data, missing columns, a model file that
//! does not load, unknown effects, non-finite values) get clear messages.

use calibrate::suite::{nominal_model, nuisance};
use calibrate::{fit_effect, load_measured, run, CalibrateError, CalibrateOptions, NOT_IDENTIFIABLE};
use model::scenario::Drive;
use model::{FaultSchedule, Sample, Scenario, Simulator};

/// 10 s of a rod held at 0.3 m by the position controller: nothing moves.
fn held_rod() -> Vec<Sample> {
    let mut sc = match Scenario::by_name("closed-loop-random", 1, 10.0) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    sc.drive = Drive::ClosedLoopSteps {
        levels: vec![(0.0, 0.3)],
    };
    let mut sim =
        Simulator::with_default_sensors(nuisance(&nominal_model()), sc, FaultSchedule::default(), 5)
            .expect("valid rig");
    sim.run(10.0)
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("calibrate-tests");
    std::fs::create_dir_all(&d).expect("tmp dir");
    d.join(name)
}

#[test]
fn a_held_rod_does_not_excite_motion_effects() {
    let data = held_rod();
    let opts = CalibrateOptions::default();
    for name in [
        "friction-asymmetry",
        "valve-bandwidth",
        "supply-sag",
        "bulk-modulus",
    ] {
        match fit_effect(&data, &nominal_model(), name, &opts) {
            Err(e @ CalibrateError::NotIdentifiable { .. }) => {
                let msg = e.to_string();
                eprintln!("{msg}");
                assert!(msg.contains(NOT_IDENTIFIABLE) && msg.contains(name), "{msg}");
            }
            other => panic!("{name}: expected not identifiable, got {other:?}"),
        }
    }
    // the whole workflow names nothing and says why, candidate by candidate
    let cal = run(&data, &nominal_model(), &opts).expect("runs");
    assert!(cal.effects.is_empty(), "{:?}", cal.names());
    let round = &cal.rounds[0];
    let fr = round
        .candidates
        .iter()
        .find(|c| c.name == "friction-asymmetry")
        .expect("scored");
    assert!(!fr.identifiable, "{fr:?}");
}

#[test]
fn a_rod_that_only_extends_does_not_show_retracting_friction() {
    // open loop, constant +0.4 V: the rod creeps out and never retracts
    let mut sc = Scenario::by_name("open-loop-sine", 2, 8.0).expect("scenario");
    sc.drive = Drive::OpenLoopSine {
        amplitude_v: 0.4,
        freq_hz: 0.0,
        phase_rad: std::f64::consts::FRAC_PI_2,
    };
    let rig = calibrate::Effect::FrictionAsymmetry.apply(&nuisance(&nominal_model()), &[1600.0]);
    let mut sim = Simulator::with_default_sensors(rig, sc, FaultSchedule::default(), 6).expect("valid rig");
    let data = sim.run(8.0);
    assert!(
        data.windows(2).all(|w| w[1].x_m >= w[0].x_m - 1e-4),
        "the rod retracted"
    );
    let e = fit_effect(
        &data,
        &nominal_model(),
        "friction-asymmetry",
        &CalibrateOptions::default(),
    )
    .unwrap_err();
    eprintln!("{e}");
    assert!(e.to_string().contains(NOT_IDENTIFIABLE), "{e}");
}

/// Asserts that `fit_effect` refuses each of `names` on `data` with
/// "not identifiable from this data", and that the whole workflow names
/// nothing and marks those candidates as not identifiable.
fn assert_not_identifiable(data: &[Sample], names: &[&str]) {
    let opts = CalibrateOptions::default();
    for name in names {
        match fit_effect(data, &nominal_model(), name, &opts) {
            Err(e @ CalibrateError::NotIdentifiable { .. }) => {
                let msg = e.to_string();
                eprintln!("{msg}");
                assert!(msg.contains(NOT_IDENTIFIABLE) && msg.contains(name), "{msg}");
            }
            other => panic!("{name}: expected not identifiable, got {other:?}"),
        }
    }
    let cal = run(data, &nominal_model(), &opts).expect("runs");
    assert!(cal.effects.is_empty(), "{:?}", cal.names());
    for name in names {
        for c in cal.rounds[0].candidates.iter().filter(|c| c.name == *name) {
            assert!(!c.identifiable, "{c:?}");
            assert!(c.status.starts_with(NOT_IDENTIFIABLE), "{c:?}");
        }
    }
}

#[test]
fn a_spring_the_rod_never_reaches_is_not_identifiable() {
    // a spring touching at 0.40 m; the position controller steps the rod
    // between 0.08 and 0.30 m, so the data never see it
    let mut sc = Scenario::by_name("closed-loop-random", 3, 10.0).expect("scenario");
    sc.drive = Drive::ClosedLoopSteps {
        levels: vec![
            (0.0, 0.15),
            (1.5, 0.28),
            (3.0, 0.08),
            (4.5, 0.22),
            (6.0, 0.12),
            (7.5, 0.30),
            (9.0, 0.18),
        ],
    };
    sc.initial_position_m = 0.2;
    let rig = calibrate::Effect::SpringLoad.apply(&nuisance(&nominal_model()), &[2.0e4, 0.40]);
    let mut sim = Simulator::with_default_sensors(rig, sc, FaultSchedule::default(), 7).expect("valid rig");
    let data = sim.run(10.0);
    let x_max = data.iter().map(|s| s.x_m).fold(f64::NEG_INFINITY, f64::max);
    let x_min = data.iter().map(|s| s.x_m).fold(f64::INFINITY, f64::min);
    assert!(x_max < 0.35 && x_max - x_min > 0.15, "stroke {x_min}..{x_max}");
    assert_not_identifiable(&data, &["spring-load"]);
}

#[test]
fn a_rod_on_its_end_stop_does_not_excite_leaks_or_spool_bias() {
    // open loop, constant −2 V: the rod retracts onto its end stop and stays
    // there with the valve open; chamber 1 sits at tank pressure (a chamber-1
    // leak has nothing to drive it), chamber 2 at supply (the open valve makes
    // up a chamber-2 leak without a measurable drop), and no flow goes
    // anywhere (a spool null offset changes nothing measured). The record
    // starts once the rod has settled.
    let mut sc = Scenario::by_name("open-loop-sine", 4, 10.0).expect("scenario");
    sc.drive = Drive::OpenLoopSine {
        amplitude_v: -2.0,
        freq_hz: 0.0,
        phase_rad: std::f64::consts::FRAC_PI_2,
    };
    let mut sim =
        Simulator::with_default_sensors(nuisance(&nominal_model()), sc, FaultSchedule::default(), 8)
            .expect("valid rig");
    let data: Vec<Sample> = sim.run(10.0).into_iter().filter(|s| s.t_s >= 4.0).collect();
    assert!(
        data.iter().all(|s| s.x_m.abs() < 1e-3 && s.p1_pa < 0.2e6),
        "the rod is not on its stop with chamber 1 at tank"
    );
    assert_not_identifiable(&data, &["leak-ext1", "leak-ext2"]);
    // without the spool channel nothing shows a spool null offset either (with
    // it, the measured spool shows the offset directly)
    let no_spool: Vec<Sample> = data
        .iter()
        .map(|s| Sample {
            x_sp_m: f64::NAN,
            ..*s
        })
        .collect();
    assert_not_identifiable(&no_spool, &["leak-ext1", "leak-ext2", "spool-bias"]);
}

#[test]
fn an_exciting_input_is_identifiable() {
    let c = calibrate::suite::cases()
        .into_iter()
        .find(|c| c.name == "friction-asymmetry")
        .expect("case");
    let data = calibrate::suite::generate(&c);
    let fit = fit_effect(
        &data,
        &nominal_model(),
        "friction-asymmetry",
        &CalibrateOptions::default(),
    )
    .expect("identifiable");
    let slip = fit.parameters["friction.retract.slip_n"];
    assert!((slip - 1600.0).abs() < 160.0, "{slip}");
    assert!(fit.gap_reduction > 0.7, "{fit:?}");
    let e = fit_effect(&data, &nominal_model(), "mass", &CalibrateOptions::default()).unwrap_err();
    assert!(e.to_string().contains("unknown effect `mass`"), "{e}");
}

#[test]
fn too_little_data_is_refused() {
    let data: Vec<Sample> = held_rod().into_iter().take(1500).collect();
    let e = run(&data, &nominal_model(), &CalibrateOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, CalibrateError::TooLittleData { .. }), "{msg}");
    assert!(
        msg.contains("too little data") && msg.contains("1500 samples"),
        "{msg}"
    );
    let e = run(&[], &nominal_model(), &CalibrateOptions::default()).unwrap_err();
    assert!(e.to_string().contains("too little data"), "{e}");
}

#[test]
fn non_finite_values_and_bad_models_are_named() {
    let mut data = held_rod();
    data[100].p2_pa = f64::NAN;
    let e = run(&data, &nominal_model(), &CalibrateOptions::default()).unwrap_err();
    assert!(e.to_string().contains("sample 100: column `p2`"), "{e}");
    let bad = model::ActuatorParams {
        bulk_modulus_pa: -1.0,
        ..nominal_model()
    };
    let e = run(&held_rod(), &bad, &CalibrateOptions::default()).unwrap_err();
    assert!(e.to_string().contains("bulk_modulus_pa"), "{e}");
    let opts = CalibrateOptions {
        candidates: vec!["seal-wear".into()],
        ..CalibrateOptions::default()
    };
    let e = run(&held_rod(), &nominal_model(), &opts).unwrap_err();
    assert!(e.to_string().contains("unknown effect `seal-wear`"), "{e}");
}

#[test]
fn missing_columns_are_named() {
    let p = tmp("missing_p2.csv");
    std::fs::write(&p, "t,u,x,p1\n0,0,0.3,6.9e6\n0.001,0,0.3,6.9e6\n").expect("write");
    let e = load_measured(&p).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("measured data") && msg.contains("`p2` is missing"),
        "{msg}"
    );
    let e = load_measured(&tmp("does_not_exist.csv")).unwrap_err();
    assert!(e.to_string().contains("does_not_exist.csv"), "{e}");
}

#[test]
fn a_held_rod_is_said_not_to_excite_motion() {
    let cal = run(&held_rod(), &nominal_model(), &CalibrateOptions::default()).expect("runs");
    assert!(cal.effects.is_empty(), "{:?}", cal.names());
    assert!(
        cal.warnings
            .iter()
            .any(|w| w.contains("the rod moved only") && w.contains(NOT_IDENTIFIABLE)),
        "{:?}",
        cal.warnings
    );
}

/// The calibration of the clean open-loop sine with every sample passed
/// through `reading`: the error that refuses it.
fn refused_reading(reading: fn(Sample) -> Sample) -> CalibrateError {
    let case = calibrate::suite::cases()
        .into_iter()
        .find(|c| c.name == "clean open-loop-sine")
        .expect("case");
    let data: Vec<Sample> = calibrate::suite::generate(&case)
        .into_iter()
        .map(reading)
        .collect();
    run(&data, &nominal_model(), &CalibrateOptions::default()).expect_err("refused")
}

#[test]
fn a_flat_pressure_channel_is_refused() {
    let e = refused_reading(|s| Sample { p2_pa: 6.9e6, ..s });
    assert!(
        matches!(e, CalibrateError::FlatChannel { column: "p2", .. }),
        "{e}"
    );
    assert!(e.to_string().contains("column `p2` is flat"), "{e}");
}

#[test]
fn pressures_written_in_bar_are_refused_naming_the_unit() {
    let e = refused_reading(|s| Sample {
        p1_pa: s.p1_pa / 1e5,
        p2_pa: s.p2_pa / 1e5,
        ..s
    });
    assert!(matches!(e, CalibrateError::Units(_)), "{e}");
    // the thesis rig's 13.8 MPa supply: no pressure read passes 138 kPa
    let m = e.to_string();
    assert!(m.starts_with("units: p1 and p2 never read above "), "{m}");
    assert!(m.contains("under 1 % of the supply pressure (13.8 MPa)"), "{m}");
    assert!(m.contains("1 bar = 100000 Pa"), "{m}");
}

#[test]
fn rows_missing_here_and_there_leave_the_rest_usable() {
    // a leak record with every 500th row dropped (what the reader does with
    // NaN rows): windows straddling a gap are left out, the leak is still
    // named and sized, and the gaps are reported
    let case = calibrate::suite::cases()
        .into_iter()
        .find(|c| c.name == "leak-ext1")
        .expect("case");
    let data: Vec<Sample> = calibrate::suite::generate(&case)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % 500 != 250)
        .map(|(_, s)| s)
        .collect();
    let cal = run(&data, &nominal_model(), &CalibrateOptions::default()).expect("runs");
    assert_eq!(cal.names(), vec!["leak-ext1".to_string()]);
    let k = cal.effects[0].parameters["leaks.ext1.sqrt_m3_s_sqrt_pa"];
    assert!((k - 3.0e-9).abs() < 0.3e-9, "{k}");
    assert!(
        cal.warnings.iter().any(|w| w.contains("24 gap(s)")),
        "{:?}",
        cal.warnings
    );
}

#[test]
fn a_long_record_is_thinned_evenly_and_says_so() {
    // max_windows below the record's 239 windows: whole blocks spread from
    // start to end are compared, the leak is still named and sized
    let case = calibrate::suite::cases()
        .into_iter()
        .find(|c| c.name == "leak-ext2")
        .expect("case");
    let data = calibrate::suite::generate(&case);
    let opts = CalibrateOptions {
        max_windows: 60,
        ..CalibrateOptions::default()
    };
    let cal = run(&data, &nominal_model(), &opts).expect("runs");
    let n = cal.data.fit_windows + cal.data.validation_windows;
    assert!((50..=70).contains(&n), "{n} windows");
    assert!(
        cal.warnings
            .iter()
            .any(|w| w.contains("for speed") && w.contains("of the 239 windows")),
        "{:?}",
        cal.warnings
    );
    assert!(
        cal.data.validation_start_s < 2.0,
        "{}",
        cal.data.validation_start_s
    );
    assert_eq!(cal.names(), vec!["leak-ext2".to_string()]);
    let k = cal.effects[0].parameters["leaks.ext2.sqrt_m3_s_sqrt_pa"];
    assert!((k - 3.0e-9).abs() < 0.3e-9, "{k}");
}
