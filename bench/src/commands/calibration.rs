//! `leakwatch bench calibration`: the calibration workflow's suites, or a
//! directory of cases with truth, scored.

use std::path::PathBuf;

use super::{identification_data, rig_files};
use pipeline::out::outln;

/// The calibration workflow's hidden-effect suites (smooth and stick-slip rig, or the smooth
/// matrix), or a directory of cases with truth (`--data`).
pub fn bench(
    matrix: bool,
    data: Option<PathBuf>,
    config: Option<PathBuf>,
    json: bool,
    out: Option<PathBuf>,
    force: bool,
) -> Result<(), String> {
    if let Some(dir) = &data {
        if let (_, Some(recording)) = rig_files(dir) {
            return identification_data(dir, &recording, config.as_deref(), json, out, force);
        }
    }
    let opts = calibrate::CalibrateOptions {
        keep_traces: false,
        ..calibrate::CalibrateOptions::default()
    };
    let threads = pipeline::batch::cores().min(2);
    let reports: Vec<(&str, calibrate::BenchReport)> = if let Some(dir) = data {
        let model = match config {
            Some(p) => pipeline::model_file::load_model(&p).map_err(|e| e.to_string())?,
            None => model::ActuatorParams::default(),
        };
        let bar = indicatif::ProgressBar::new(0);
        let r = calibrate::external::bench_dir(&dir, &model, &opts, threads, &|d, n| {
            bar.set_length(n as u64);
            bar.set_position(d as u64);
        })
        .map_err(|e| e.to_string())?;
        bar.finish_and_clear();
        vec![("data", r)]
    } else if matrix {
        let shooting = calibrate::CalibrateOptions::shooting();
        vec![(
            "matrix",
            suite_with_bar("smooth-rig matrix", &calibrate::suite::matrix_cases(), &shooting),
        )]
    } else {
        vec![
            (
                "smooth",
                suite_with_bar("smooth rig", &calibrate::suite::cases(), &opts),
            ),
            (
                "thesis",
                suite_with_bar("stick-slip rig", &calibrate::suite::thesis_cases(), &opts),
            ),
        ]
    };
    if json {
        let v: serde_json::Map<String, serde_json::Value> = reports
            .iter()
            .map(|(k, r)| (k.to_string(), serde_json::to_value(r).unwrap_or_default()))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&v).map_err(|e| e.to_string())?);
    } else {
        for (k, r) in &reports {
            outln!("## {k}\n\n{}", r.markdown());
        }
    }
    if let Some(dir) = out {
        for (k, r) in &reports {
            let d = if reports.len() > 1 {
                dir.join(k)
            } else {
                dir.clone()
            };
            let files = r.write(&d, force).map_err(|e| e.to_string())?;
            for f in files {
                eprintln!("wrote {}", f.display());
            }
        }
    }
    Ok(())
}

/// One calibration suite on two threads, with a progress bar of its cases on stderr.
fn suite_with_bar(
    name: &str,
    cases: &[calibrate::suite::SuiteCase],
    opts: &calibrate::CalibrateOptions,
) -> calibrate::BenchReport {
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg}: {bar:30} {pos}/{len} cases  {elapsed} (eta {eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(name.to_string());
    let r = calibrate::suite::bench_cases_with_progress(cases, opts, 2, &|d, _| bar.set_position(d as u64));
    bar.finish();
    r
}
