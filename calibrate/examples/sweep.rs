//! Detection limits on the stick-slip rig: each effect at smaller sizes
//! under the three inputs, and clean controls over many seeds.
//! `cargo run --release -p calibrate --example sweep`
use calibrate::suite::{bench_cases, SuiteCase, MATRIX_SCENARIOS};
use calibrate::{CalibrateOptions, Effect};
use model::params::FrictionPreset;

fn main() {
    let sizes: Vec<(&str, Effect, Vec<f64>)> = vec![
        (
            "friction ret x1.2",
            Effect::FrictionAsymmetryViscous,
            vec![1320.0, 385.0],
        ),
        (
            "friction ret x0.85",
            Effect::FrictionAsymmetryViscous,
            vec![935.0, 385.0],
        ),
        ("spool bias 2 um", Effect::SpoolBias, vec![2.0e-6]),
        ("spool bias 1 um", Effect::SpoolBias, vec![-1.0e-6]),
        ("spring 10 kN/m @0.30", Effect::SpringLoad, vec![1.0e4, 0.30]),
        ("beta x0.85", Effect::BulkModulus, vec![0.85 * 6.89e8]),
        ("air 3 %", Effect::EntrainedAir, vec![0.03]),
        ("sag 3e9", Effect::SupplySag, vec![3.0e9]),
        ("valve x0.8", Effect::ValveBandwidth, vec![0.8 * 628.3]),
        ("valve x0.9", Effect::ValveBandwidth, vec![0.9 * 628.3]),
        ("ext1 0.15 lpm", Effect::LeakExt1, vec![0.95e-9]),
        ("ext2 0.1 lpm", Effect::LeakExt2, vec![0.64e-9]),
        ("int 0.3 lpm", Effect::LeakInt, vec![1.9e-9]),
    ];
    let mut list = Vec::new();
    let mut seed = 500;
    for (name, e, theta) in &sizes {
        for sc in MATRIX_SCENARIOS {
            seed += 1;
            list.push(SuiteCase {
                name: format!("{name} / {sc}"),
                scenario: sc,
                seconds: 15.0,
                seed,
                hidden: vec![(*e, theta.clone())],
                friction: FrictionPreset::Thesis,
            });
        }
    }
    for sc in MATRIX_SCENARIOS {
        for _ in 0..4 {
            seed += 1;
            list.push(SuiteCase {
                name: format!("clean {sc} seed {seed}"),
                scenario: sc,
                seconds: 15.0,
                seed,
                hidden: vec![],
                friction: FrictionPreset::Thesis,
            });
        }
    }
    if let Ok(f) = std::env::var("SPOOL") {
        for c in list.iter().filter(|c| c.name.contains(&f)) {
            let data = calibrate::suite::generate(c);
            let m = calibrate::suite::nominal_model_for(c.friction);
            for e in ["valve-bandwidth", "spool-bias"] {
                if let Ok(r) = calibrate::fit_effect(&data, &m, e, &CalibrateOptions::default()) {
                    println!(
                        "{} {e}: spool {:.3} -> {:.3} um, total {:.3} -> {:.3}, {:?}",
                        c.name,
                        r.gap_before.spool_m * 1e6,
                        r.gap_after.spool_m * 1e6,
                        r.gap_before.normalised,
                        r.gap_after.normalised,
                        r.parameters
                    );
                }
            }
        }
        return;
    }
    if let Ok(f) = std::env::var("FILTER") {
        for c in list.iter().filter(|c| c.name.contains(&f)) {
            let data = calibrate::suite::generate(c);
            let m = calibrate::suite::nominal_model_for(c.friction);
            if let Ok(cal) = calibrate::run(&data, &m, &CalibrateOptions::default()) {
                println!("{}: gap {:.3}", c.name, cal.gap_before.normalised);
                for r in &cal.rounds {
                    for k in r.candidates.iter().take(4) {
                        println!(
                            "  {} {} {:.1} % {:?} {}",
                            k.name,
                            k.form,
                            100.0 * k.gap_reduction,
                            k.parameters,
                            k.status
                        );
                    }
                }
            }
        }
        return;
    }
    let rep = bench_cases(&list, &CalibrateOptions::default(), 2);
    println!("{}", rep.markdown());
}
