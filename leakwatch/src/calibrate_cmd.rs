//! `leakwatch calibrate`: find where the model and the measured data disagree,
//! fit the missing effects and print the gap before and after.

use crate::logs::export_log;
use crate::out::{self, outln};
use pipeline::calibrate_report::{self, CalibrationRecord, Identification};

/// `leakwatch calibrate`: calibrates the model of `config` (or the built-in one)
/// against `input` (a CSV or a recorded log) and writes the outputs into `out`.
/// With `identify`, or a config with a `[datasheet]`, the rig is identified on
/// `input` first and the search starts from the identified model.
pub fn run(
    input: &std::path::Path,
    config: Option<&std::path::Path>,
    identify: bool,
    out: &std::path::Path,
    effects: Vec<String>,
    force: bool,
) -> Result<(), String> {
    let original = input;
    let mut model = match config {
        Some(p) => crate::model_file::load_model(p).map_err(|e| e.to_string())?,
        None => model::ActuatorParams::default(),
    };
    // A recorded log is read through its frames, exported as dataset.csv.
    let input = if input.extension().is_some_and(|e| e == "mcap") {
        out::dir(out)?;
        let dir = out.join("log-export");
        export_log(input, &dir, force, true)?;
        dir.join("dataset.csv")
    } else {
        input.to_path_buf()
    };
    let datasheet = config.is_some_and(crate::model_file::has_datasheet);
    // a datasheet's sensors and noise go on into model.toml with the calibrated model
    let mut whole = None;
    // the config the rig was identified with: the search refits with it
    let mut identified = None;
    // what the identification found, for the report
    let mut identification = Identification::NotAsked;
    if identify || datasheet {
        // A datasheet's model is a prior within its tolerances: its values are
        // identified first, so that the search names what the rig has beyond them.
        let cfg = config::Config::load_or_default(config)?;
        match crate::commission::identify_rig_said(&input, &cfg) {
            Ok((rig, said)) => {
                eprintln!("the search for missing effects starts from the identified model");
                model = rig.model.clone();
                identified = Some(rig);
                identification = Identification::Found(said);
            }
            Err(e) => {
                eprintln!("note: {e}; the search starts from the config's model");
                identification = Identification::Failed(e);
            }
        }
        if datasheet {
            whole = Some(cfg);
        }
    }
    let measured = calibrate::load_measured(&input).map_err(|e| e.to_string())?;
    let opts = calibrate::CalibrateOptions {
        candidates: effects,
        position_noise_m: config::Config::load_or_default(config)?.sensors.position_noise_m,
        ..calibrate::CalibrateOptions::default()
    };
    let span = match (measured.first(), measured.last()) {
        (Some(a), Some(b)) => b.t_s - a.t_s,
        _ => 0.0,
    };
    eprintln!(
        "read {} samples ({span:.1} s) from {}; the whole record is used, no decimation: \
         {} comparison windows of {:.0} ms{}, started from the measured state, 70 % fit / 30 % validate",
        measured.len(),
        input.display(),
        (span / opts.window_s) as usize,
        opts.window_s * 1e3,
        if span / opts.window_s > opts.max_windows as f64 {
            format!(
                " (for speed {} of them, spread over the whole record)",
                opts.max_windows
            )
        } else {
            String::new()
        }
    );
    let progress = |m: &str| eprintln!("  {m}");
    let cal = match &identified {
        Some(rig) => pipeline::calibration::search_with_refit(&input, rig, &measured, &opts, &progress)?,
        None => {
            calibrate::run_with_progress(&measured, &model, &opts, &progress).map_err(|e| e.to_string())?
        }
    };
    say_stick_band(&opts, cal.data.sample_period_s);
    for w in &cal.warnings {
        eprintln!("note: {w}");
    }
    let mut inputs = vec![original, input.as_path()];
    inputs.extend(config);
    let model_file = match whole {
        Some(cfg) => crate::model_file::config_toml(&config::Config {
            datasheet: None,
            model: cal.model_after.clone(),
            ..cfg
        }),
        None => crate::model_file::model_toml(&cal.model_after),
    }
    .map_err(|e| e.to_string())?;
    // the report is refused with the other outputs, before any is written
    let report = out.join(calibrate_report::FILE_NAME);
    out::dir(out)?;
    out::check(&report, force, &inputs)?;
    let files =
        calibrate::write_outputs(&cal, out, force, &inputs, &model_file).map_err(|e| e.to_string())?;
    let record = CalibrationRecord {
        input: original.display().to_string(),
        identification,
        cal: &cal,
    };
    out::write(&report, record.html()?.as_bytes(), force, &inputs)?;
    say_result(&cal, &files, &report)?;
    Ok(())
}

/// Says how wide the force balance's band of rest was at the sample period
/// `dt_s` (s) when the position sensor's noise widened it
/// ([`calibrate::equation::STICK_BAND_SIGMAS`]).
fn say_stick_band(opts: &calibrate::CalibrateOptions, dt_s: f64) {
    if opts.position_noise_m <= 0.0 || dt_s.is_nan() || dt_s <= 0.0 {
        return;
    }
    let sigma = calibrate::shoot::velocity_noise_m_s(opts.position_noise_m, dt_s, opts.velocity_half_width);
    eprintln!(
        "note: the position sensor's noise ({:.1} µm) leaves {:.1} mm/s of noise on the velocity: \
         the force balance read a rod within {:.1} mm/s as at rest",
        opts.position_noise_m * 1e6,
        sigma * 1e3,
        calibrate::equation::STICK_BAND_SIGMAS * sigma * 1e3
    );
}

/// Prints what calibration `cal` found: the gap before, each effect added
/// with its parameters, the gap after, and the files written (`files` and the
/// HTML report `report`); an error only when stdout cannot be written.
fn say_result(
    cal: &calibrate::Calibration,
    files: &calibrate::OutputFiles,
    report: &std::path::Path,
) -> Result<(), String> {
    // the numbers the report's gap table holds
    let g = |gap: &calibrate::Gap| {
        let [p1, p2, force, spool, normalised] = calibrate_report::gap_numbers(gap);
        format!(
            "chamber 1 {p1} kPa, chamber 2 {p2} kPa, force {force} N, spool {spool} µm per {:.0} ms window; normalised {normalised}",
            cal.data.window_s * 1e3,
        )
    };
    outln!("gap before (validation RMS): {}", g(&cal.gap_before));
    if cal.effects.is_empty() {
        if cal
            .warnings
            .iter()
            .any(|w| w.contains(calibrate::NOT_IDENTIFIABLE))
        {
            outln!("nothing identifiable from this data (see the note above); the model is left as it is");
        } else {
            outln!("no missing effect explains a significant part of the gap: the model stands as it is");
        }
    }
    if cal.gap_after.normalised > 1.0 {
        outln!(
            "the remaining gap ({:.2}) is well above the sensor floor (about {:.1}-{:.1}): the rig differs in \
             something the library does not have, or a channel is scaled or wired differently",
            cal.gap_after.normalised,
            calibrate_report::NORMALISED_SENSOR_FLOOR.0,
            calibrate_report::NORMALISED_SENSOR_FLOOR.1
        );
    }
    for (i, e) in cal.effects.iter().enumerate() {
        let params: Vec<String> = e
            .parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v:.4e}"))
            .collect();
        outln!(
            "{}. {} ({}), explains {:.0} % of the gap: {} (SI)",
            i + 1,
            e.name,
            e.form,
            e.gap_reduction * 100.0,
            params.join(", ")
        );
        for l in e.engineering.iter().chain(&e.not_identifiable) {
            outln!("   {l}");
        }
        if let Some(c) = &e.caveat {
            outln!("   {c}");
        }
    }
    outln!(
        "gap after: {} ({:.0} % smaller)",
        g(&cal.gap_after),
        cal.gap_reduction * 100.0
    );
    outln!(
        "wrote {}, {}, {}, {}",
        files.json.display(),
        files.model_toml.display(),
        files.report.display(),
        report.display()
    );
    Ok(())
}
