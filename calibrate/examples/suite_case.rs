//! Runs one case of the hidden-effect suite, prints every round of the
//! selection and writes the outputs (json, model.toml, report.md, plots).
//!
//! `cargo run -p calibrate --example suite_case -- "leak-ext1" /tmp/cal-out`
fn main() {
    let name = std::env::args().nth(1).unwrap_or_else(|| "leak-ext1".into());
    let out = std::env::args()
        .nth(2)
        .unwrap_or_else(|| "/tmp/calibrate-case".into());
    let all = calibrate::suite::cases()
        .into_iter()
        .chain(calibrate::suite::matrix_cases());
    let Some(case) = all.into_iter().find(|c| c.name == name) else {
        eprintln!("no case `{name}`; cases:");
        for c in calibrate::suite::matrix_cases() {
            eprintln!("  {}", c.name);
        }
        std::process::exit(2);
    };
    let data = calibrate::suite::generate(&case);
    let cal = match calibrate::run(&data, &calibrate::suite::nominal_model(), &Default::default()) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    println!(
        "gap {:.3} -> {:.3} ({:.2} s)",
        cal.gap_before.normalised, cal.gap_after.normalised, cal.elapsed_s
    );
    for r in &cal.rounds {
        println!("round (gap {:.3})", r.gap_before);
        for c in &r.candidates {
            println!(
                "  {:20} {:48} {:7.1} % {:?} {}",
                c.name,
                c.form,
                100.0 * c.gap_reduction,
                c.parameters,
                c.status
            );
        }
    }
    // model.toml: the calibrated model as a config's [model] table (leakwatch adds a header)
    let mut table = toml::Table::new();
    table.insert(
        "model".into(),
        toml::Value::try_from(&cal.model_after).expect("the model is TOML"),
    );
    let model_file = toml::to_string(&table).expect("the model is TOML");
    match calibrate::write_outputs(&cal, std::path::Path::new(&out), true, &[], &model_file) {
        Ok(f) => println!("wrote {}", f.report.display()),
        Err(e) => eprintln!("{e}"),
    }
}
