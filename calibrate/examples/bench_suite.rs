//! Runs the hidden-effect suite and prints its table (docs/calibration/README.md#results).
//!
//! `cargo run -p calibrate --example bench_suite [CASE-SUBSTRING]`; with
//! `MATRIX=1` every effect under every input (`suite::matrix_cases`); with
//! `THESIS=1` the stick-slip rig (`suite::thesis_cases`).
fn main() {
    let opts = calibrate::CalibrateOptions::default();
    let filter = std::env::args().nth(1).unwrap_or_default();
    let all = if std::env::var("MATRIX").is_ok() {
        calibrate::suite::matrix_cases()
    } else if std::env::var("THESIS").is_ok() {
        calibrate::suite::thesis_cases()
    } else {
        calibrate::suite::cases()
    };
    let list: Vec<_> = all.into_iter().filter(|c| c.name.contains(&filter)).collect();
    let rep = calibrate::suite::bench_cases(&list, &opts, 2);
    println!("{}", rep.markdown());
    if let Ok(dir) = std::env::var("OUT") {
        match rep.write(std::path::Path::new(&dir), true) {
            Ok(p) => eprintln!("wrote {} and {}", p[0].display(), p[1].display()),
            Err(e) => eprintln!("{e}"),
        }
    }
}
