//! The hidden-effect suite on the stick-slip rig (thesis friction as
//! published, rig and nominal model alike; docs/model.md#stick-slip): every single effect
//! under the open-loop sine, the open-loop chirp and the closed-loop
//! pseudorandom steps (the spring under the loaded sine and the steps), and
//! three clean controls, 15 s each. A freely simulated window diverges on
//! this rig within tens of ms; the default equation-error comparison must
//! still name every effect first and alone, fit what it states as
//! identifiable within 10 %, shrink the validation gap by ≥ 70 % in at least
//! 90 % of the cases, and name nothing on the controls.

use calibrate::suite::{bench_cases, thesis_cases};
use calibrate::CalibrateOptions;

#[test]
fn every_effect_is_named_on_the_stick_slip_rig() {
    let list = thesis_cases();
    assert_eq!(list.len(), 32);
    let rep = bench_cases(&list, &CalibrateOptions::default(), 2);
    eprintln!("{}", rep.markdown());
    let mut failures = Vec::new();
    let mut shrunk = 0;
    let mut effect_cases = 0;
    for r in &rep.cases {
        if let Some(e) = &r.error {
            failures.push(format!("{}: error {e}", r.case));
            continue;
        }
        if r.hidden.is_empty() {
            if !r.named.is_empty() {
                failures.push(format!("{}: clean data named {:?}", r.case, r.named));
            }
            continue;
        }
        effect_cases += 1;
        if !r.right_first || !r.all_found {
            failures.push(format!("{}: named {:?}, hidden {:?}", r.case, r.named, r.hidden));
        }
        for p in &r.parameters {
            if p.relative_error.is_nan() || p.relative_error > 0.10 {
                failures.push(format!(
                    "{}: {} fitted {:.4e} vs truth {:.4e} ({:.1} %)",
                    r.case,
                    p.parameter,
                    p.fitted,
                    p.truth,
                    100.0 * p.relative_error
                ));
            }
        }
        if r.gap_shrink >= 0.70 {
            shrunk += 1;
        }
    }
    assert_eq!(effect_cases, 29);
    assert!(
        shrunk as f64 >= 0.9 * effect_cases as f64,
        "gap shrank by ≥ 70 % in only {shrunk} of {effect_cases} cases"
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn small_effects_are_named_and_more_controls_stay_quiet() {
    use calibrate::suite::{SuiteCase, MATRIX_SCENARIOS};
    use calibrate::Effect;
    use model::params::FrictionPreset;
    // near the detection limit on the stick-slip rig (the development set's
    // effects are 2-10 times larger): 1 µm of spool offset (1.2 % of a 3 V
    // amplitude), 3 % entrained air (β 4 % lower at 6.9 MPa), 0.1 L/min
    // leaking from chamber 2, retracting friction 15 % lower, a spool 20 %
    // slower under a 1 Hz sine
    let small: [(&str, &'static str, Effect, Vec<f64>); 5] = [
        (
            "spool bias 1 µm",
            "closed-loop-random",
            Effect::SpoolBias,
            vec![-1.0e-6],
        ),
        ("air 3 %", "open-loop-chirp", Effect::EntrainedAir, vec![0.03]),
        (
            "ext2 0.1 L/min",
            "open-loop-sine",
            Effect::LeakExt2,
            vec![0.64e-9],
        ),
        (
            "friction retracting x0.85",
            "open-loop-sine",
            Effect::FrictionAsymmetryViscous,
            vec![935.0, 385.0],
        ),
        // judged on the spool channel: the extra lag moves the spool by
        // about 0.3 µm at 1 Hz, its noise is 0.2 µm
        (
            "spool 20 % slower",
            "open-loop-sine",
            Effect::ValveBandwidth,
            vec![0.8 * 200.0 * std::f64::consts::PI],
        ),
    ];
    let mut list: Vec<SuiteCase> = small
        .iter()
        .enumerate()
        .map(|(i, (name, sc, e, theta))| SuiteCase {
            name: name.to_string(),
            scenario: sc,
            seconds: 15.0,
            seed: 600 + i as u64,
            hidden: vec![(*e, theta.clone())],
            friction: FrictionPreset::Thesis,
        })
        .collect();
    for (i, sc) in MATRIX_SCENARIOS.iter().chain(MATRIX_SCENARIOS.iter()).enumerate() {
        list.push(SuiteCase {
            name: format!("clean {sc} #{i}"),
            scenario: sc,
            seconds: 15.0,
            seed: 620 + i as u64,
            hidden: vec![],
            friction: FrictionPreset::Thesis,
        });
    }
    let rep = bench_cases(&list, &CalibrateOptions::default(), 2);
    eprintln!("{}", rep.markdown());
    for r in &rep.cases {
        assert!(r.error.is_none(), "{}: {:?}", r.case, r.error);
        if r.hidden.is_empty() {
            assert!(r.named.is_empty(), "{}: clean data named {:?}", r.case, r.named);
        } else {
            assert!(r.right_first && r.all_found, "{}: named {:?}", r.case, r.named);
            for p in &r.parameters {
                assert!(
                    p.relative_error <= 0.10,
                    "{}: {} {:.4e} vs {:.4e}",
                    r.case,
                    p.parameter,
                    p.fitted,
                    p.truth
                );
            }
        }
    }
}

#[test]
fn friction_per_direction_is_fitted_on_request() {
    use calibrate::suite::{generate, nominal_model_for, thesis_cases};
    // the stick-slip rig with the retracting static and Coulomb friction
    // 1600/1100 times the extending ones: `friction` fits both directions
    let case = thesis_cases()
        .into_iter()
        .find(|c| c.name == "friction-asymmetry / closed-loop-random [thesis]")
        .expect("case");
    let data = generate(&case);
    let model = nominal_model_for(case.friction);
    let fit = calibrate::fit_effect(&data, &model, "friction", &CalibrateOptions::default()).expect("fits");
    eprintln!("{fit:?}");
    let p = |k: &str| fit.parameters[k];
    assert!(
        (p("friction.slip_n") - 1100.0).abs() < 110.0,
        "{:?}",
        fit.parameters
    );
    assert!(
        (p("friction.retract.slip_n") - 1600.0).abs() < 160.0,
        "{:?}",
        fit.parameters
    );
    assert!(fit.gap_reduction > 0.5, "{}", fit.gap_reduction);
}
