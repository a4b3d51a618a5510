//! The model as a TOML file: reading the `[model]` table of a config file for
//! `leakwatch calibrate` and `leakwatch bench calibration --data`, and writing the
//! calibrated model as `model.toml` (the `calibrate` library is pure and writes no
//! TOML: it takes this file's text).

use std::path::Path;

use calibrate::CalibrateError;
use model::ActuatorParams;
use serde::Serialize;

/// Reads the `[model]` table of a leakwatch config file (other sections are
/// ignored here, except a `[datasheet]`, from which the model is derived); a
/// missing table gives the default model. The model is validated.
pub fn load_model(path: &Path) -> Result<ActuatorParams, CalibrateError> {
    let err = |message: String| CalibrateError::ModelFile {
        path: path.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let table: toml::Table = toml::from_str(&text).map_err(|e| err(format!("not valid TOML: {e}")))?;
    if table.contains_key("datasheet") {
        // the model's rig facts are derived from the datasheet: the whole config is read
        let cfg = config::Config::parse(&text).map_err(err)?;
        return Ok(cfg.model);
    }
    let params = match table.get("model") {
        Some(v) => {
            let t = toml::to_string(v).map_err(|e| err(e.to_string()))?;
            toml::from_str::<ActuatorParams>(&t).map_err(|e| err(format!("[model]: {e}")))?
        }
        None => ActuatorParams::default(),
    };
    params.validate().map_err(|e| err(format!("[model] {e}")))?;
    Ok(params)
}

/// Whether the config file at `path` describes the rig by a `[datasheet]`
/// (false for a file that cannot be read or parsed: loading it says why).
pub fn has_datasheet(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| toml::from_str::<toml::Table>(&t).ok())
        .is_some_and(|t| t.contains_key("datasheet"))
}

#[derive(Serialize)]
struct ModelFile<'a> {
    model: &'a ActuatorParams,
}

/// The calibrated model as TOML under a `[model]` table (the leakwatch config
/// format): the text of `model.toml`.
pub fn model_toml(params: &ActuatorParams) -> Result<String, CalibrateError> {
    let body = toml::to_string(&ModelFile { model: params })
        .map_err(|e| CalibrateError::Serialize(e.to_string()))?;
    Ok(format!(
        "# Written by `leakwatch calibrate`: the calibrated actuator model, a leakwatch\n\
         # configuration file with only its [model] table (SI units); every other\n\
         # section keeps its default. Use it as it is:\n\
         #   leakwatch replay MEASURED.csv --config model.toml --out replay-out\n\
         #   leakwatch run --config model.toml\n\
         #   leakwatch calibrate MEASURED.csv --config model.toml --out cal-out   (calibrate further)\n\
         # (the stage binaries take the same `--config model.toml`), or paste the [model]\n\
         # table into your own configuration file in place of its [model].\n\n{body}"
    ))
}

/// A whole calibrated configuration as `model.toml` (written when the starting
/// config described the rig by a `[datasheet]`: its sensors and noise are kept,
/// the datasheet itself is not, its model being now the calibrated one).
pub fn config_toml(cfg: &config::Config) -> Result<String, CalibrateError> {
    let body = toml::to_string(cfg).map_err(|e| CalibrateError::Serialize(e.to_string()))?;
    Ok(format!(
        "# Written by `leakwatch calibrate`: the configuration it started from (derived from its\n\
         # [datasheet]) with the identified and calibrated [model] (SI units). Use it as it is:\n\
         #   leakwatch commission HEALTHY.csv --config model.toml --out rig.toml\n\
         #   leakwatch replay MEASURED.csv --config model.toml --out replay-out\n\n{body}"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use calibrate::suite::{cases, generate, nominal_model};
    use calibrate::{run, write_outputs, CalibrateOptions};

    #[test]
    fn model_files_that_do_not_load_are_named() {
        let d = scratch::ScratchDir::new("model-file");
        let tmp = |name: &str| d.join(name);
        let cases = [
            (
                "unknown_field.toml",
                "[model]\nsupply_pressure_psi = 2000.0\n",
                "supply_pressure_psi",
            ),
            ("invalid_value.toml", "[model]\nmass_kg = -3.0\n", "mass_kg"),
            ("not_toml.toml", "[model\nmass_kg = 3\n", "not valid TOML"),
        ];
        for (file, text, needle) in cases {
            let p = tmp(file);
            std::fs::write(&p, text).expect("write");
            let e = load_model(&p).unwrap_err();
            let msg = e.to_string();
            assert!(matches!(e, CalibrateError::ModelFile { .. }), "{msg}");
            assert!(msg.contains(file) && msg.contains(needle), "{msg}");
        }
        let e = load_model(&tmp("absent.toml")).unwrap_err();
        assert!(e.to_string().contains("cannot read"), "{e}");
        // other sections are left to their owners; a file without [model] gives the default
        let p = tmp("other_sections.toml");
        std::fs::write(&p, "[sim]\nsubsteps_per_sample = 20\n").expect("write");
        assert_eq!(load_model(&p).expect("loads"), ActuatorParams::default());
    }

    #[test]
    fn the_written_model_loads_back() {
        let d = scratch::ScratchDir::new("model-file");
        let tmp = |name: &str| d.join(name);
        let c = cases().into_iter().find(|c| c.name == "leak-ext1").expect("case");
        let data = generate(&c);
        let cal = run(&data, &nominal_model(), &CalibrateOptions::default()).expect("runs");
        let dir = tmp("calibrate-outputs");
        let text = model_toml(&cal.model_after).expect("toml");
        let files = write_outputs(&cal, &dir, true, &[], &text).expect("written");
        let loaded = load_model(&files.model_toml).expect("model.toml loads");
        assert_eq!(loaded, cal.model_after);
        assert_eq!(loaded.leaks.len(), 1);
        let written = std::fs::read_to_string(&files.model_toml).expect("toml");
        assert_eq!(written, text);
        assert!(written.contains("[model]"), "{written}");
        assert!(
            written.contains("leakwatch replay MEASURED.csv --config model.toml")
                && written.contains("leakwatch run --config model.toml"),
            "{written}"
        );
    }

    #[test]
    fn the_model_toml_calibrate_writes_is_a_config() {
        // a calibrated model with every kind of effect the library adds
        let mut m = model::ActuatorParams::default();
        for (e, theta) in [
            (calibrate::Effect::FrictionAsymmetryViscous, vec![1500.0, 300.0]),
            (calibrate::Effect::SpoolBias, vec![-5.0e-6]),
            (calibrate::Effect::SpringLoad, vec![3.0e4, 0.3]),
            (calibrate::Effect::EntrainedAir, vec![0.01]),
            (calibrate::Effect::SupplySag, vec![5.0e9]),
            (calibrate::Effect::ValveBandwidth, vec![320.0]),
            (calibrate::Effect::LeakExt1, vec![4.0e-9]),
        ] {
            m = e.apply(&m, &theta);
        }
        let text = model_toml(&m).unwrap();
        // the file says how to use it, and `--config model.toml` takes it as it is
        assert!(
            text.contains("leakwatch replay MEASURED.csv --config model.toml"),
            "{text}"
        );
        let cfg = config::Config::parse(&text).unwrap();
        assert_eq!(cfg.model, m);
        assert_eq!(cfg.model.spool_null_bias_m, -5.0e-6);
        assert_eq!(cfg.model.leaks.len(), 1);
        let r = cfg.model.friction.for_direction(-1.0);
        assert_eq!((r.slip_n, r.viscous_n_s_per_m), (1500.0, 300.0));
        // everything else keeps its default
        assert_eq!(cfg.estimator, config::Config::default().estimator);
        assert_eq!(cfg.classifier, config::Config::default().classifier);
        assert!(cfg.rig.is_none());
    }
}
