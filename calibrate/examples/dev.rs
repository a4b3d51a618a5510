//! Scores calibration on a directory of cases with truth (e.g. the dev set): `cargo run --release -p calibrate --example dev -- DIR [threads]`.
fn main() {
    let mut args = std::env::args().skip(1);
    let Some(dir) = args.next() else {
        eprintln!("usage: dev DIR [threads]");
        std::process::exit(2);
    };
    let threads = args.next().and_then(|t| t.parse().ok()).unwrap_or(1);
    let mut opts = calibrate::CalibrateOptions {
        keep_traces: false,
        ..Default::default()
    };
    if let Some(v) = std::env::var("VH").ok().and_then(|v| v.parse().ok()) {
        opts.velocity_half_width = v;
    }
    if let Some(v) = std::env::var("WS").ok().and_then(|v| v.parse().ok()) {
        opts.window_s = v;
    }
    if let Ok(c) = std::env::var("CASES") {
        opts.candidates = c.split(',').map(str::to_string).collect();
    }
    let r = calibrate::external::bench_dir(
        std::path::Path::new(&dir),
        &model::params::ActuatorParams::default(),
        &opts,
        threads,
        &|d, n| eprintln!("{d}/{n}"),
    );
    match r {
        Ok(r) => println!("{}", r.markdown()),
        Err(e) => eprintln!("{e}"),
    }
}
