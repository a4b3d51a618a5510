//! The one TOML configuration file of leakwatch: every section and field has
//! a default, so nothing is needed to start (`leakwatch config --print-default`).

use std::path::{Path, PathBuf};

use acquisition::UdpScaling;
use classifier::ClassifierConfig;
use estimator::Tuning;
use model::params::ActuatorParams;
use model::sensors::SensorParams;
use model::sim::SimSettings;
use serde::{Deserialize, Serialize};

/// The config file `run`, `replay`, `simulate`, `calibrate` and `commission` pick
/// up from the working directory when no `--config` is given.
pub const WORKING_DIR_CONFIG: &str = "leakwatch.toml";

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// The actuator model the estimator and calibration believe in.
    pub model: ActuatorParams,
    /// The simulated rig's own parameters; when absent the rig equals `[model]`.
    pub rig: Option<ActuatorParams>,
    /// Sensors of the simulated rig.
    pub sensors: SensorParams,
    /// Integration settings of the simulated rig.
    pub sim: SimSettings,
    /// The thesis filter (baseline detector): by default the thesis' 7-state tuning (MODEL.md §4).
    pub estimator: Tuning,
    /// The leak filter (leakwatch's detector): by default 11 states, tuning from the sensors.
    pub leak_filter: Tuning,
    /// The detectors.
    pub classifier: ClassifierConfig,
    /// The UDP sensor stream of a real rig (`run --source udp://...`): per-channel
    /// scaling of raw values to SI, `SI = gain·raw + offset` (default: SI as sent).
    pub udp: UdpScaling,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            model: ActuatorParams::default(),
            rig: None,
            sensors: SensorParams::default(),
            sim: SimSettings::default(),
            estimator: Tuning::thesis(),
            leak_filter: Tuning::sensor_derived(),
            classifier: ClassifierConfig::default(),
            udp: UdpScaling::default(),
        }
    }
}

impl Config {
    /// Loads and validates a config file; the error names the file and the problem.
    pub fn load(path: &Path) -> Result<Config, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read config {}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| format!("config {}: {e}", path.display()))
    }

    /// Parses and validates config text. A value of the wrong type for a
    /// numeric field (`adc_bits = 12.5`, `= -1` or too large for the field)
    /// is named with the field's type, range and unit ([`range_hint`]).
    pub fn parse(text: &str) -> Result<Config, String> {
        Self::parse_or_toml_error(text).map_err(|e| match e {
            ParseError::Toml(e) => toml_error_line(text, &e) + &range_hint(&e),
            ParseError::Invalid(msg) => msg,
        })
    }

    fn parse_or_toml_error(text: &str) -> Result<Config, ParseError> {
        let mut cfg: Config = toml::from_str(text).map_err(ParseError::Toml)?;
        // A partial [leak_filter] fills its missing fields from the leak filter's own
        // defaults (sensor-derived, 11 states), not from the thesis tuning that
        // `Tuning::default()` gives to a partial [estimator].
        let table: toml::Table = toml::from_str(text).map_err(ParseError::Toml)?;
        if let Some(given) = table.get("leak_filter").and_then(|v| v.as_table()) {
            let mut merged = toml::Table::try_from(Tuning::sensor_derived())
                .map_err(|e| ParseError::Invalid(e.to_string()))?;
            for (k, v) in given {
                merged.insert(k.clone(), v.clone());
            }
            cfg.leak_filter = Tuning::deserialize(merged).map_err(|e| {
                ParseError::Invalid(format!("[leak_filter] {}", dataset::escaped(&e.to_string())))
            })?;
        }
        cfg.validate().map_err(ParseError::Invalid)?;
        Ok(cfg)
    }

    /// Checks every section, naming the first bad field with its range and unit.
    fn validate(&self) -> Result<(), String> {
        self.model.validate().map_err(|e| format!("[model] {e}"))?;
        if let Some(rig) = &self.rig {
            rig.validate().map_err(|e| format!("[rig] {e}"))?;
        }
        self.sensors.validate().map_err(|e| format!("[sensors] {e}"))?;
        self.sim.validate().map_err(|e| format!("[sim] {e}"))?;
        self.estimator.validate()?;
        self.leak_filter
            .validate()
            .map_err(|e| e.replace("[estimator]", "[leak_filter]"))?;
        self.classifier.validate()?;
        self.udp.validate()
    }

    /// The config file a command uses: `explicit` (`--config`) if given, else
    /// [`WORKING_DIR_CONFIG`] when the working directory has one (said on stderr),
    /// else none (the defaults).
    pub fn pick(explicit: Option<PathBuf>) -> Option<PathBuf> {
        if explicit.is_some() {
            return explicit;
        }
        let here = Path::new(WORKING_DIR_CONFIG);
        if here.is_file() {
            eprintln!(
                "leakwatch: using ./{WORKING_DIR_CONFIG} from the working directory (--config FILE to use another)"
            );
            return Some(here.to_path_buf());
        }
        None
    }

    /// Loads `path` if given, else the defaults.
    pub fn load_or_default(path: Option<&Path>) -> Result<Config, String> {
        match path {
            Some(p) => Self::load(p),
            None => Ok(Config::default()),
        }
    }

    /// The simulated rig's parameters.
    pub fn rig_params(&self) -> ActuatorParams {
        self.rig.clone().unwrap_or_else(|| self.model.clone())
    }

    /// The default configuration as commented TOML.
    pub fn default_toml() -> String {
        let body = toml::to_string(&Config::default()).unwrap_or_default();
        format!(
            "# leakwatch configuration: SI units everywhere (m, s, Pa, m³/s, N, V);\n\
             # every field is optional and defaults to the value shown.\n\
             # [model]: the actuator as the estimator believes it (MODEL.md §2).\n\
             # [rig]: optional, the simulated rig's own parameters (same fields as [model]);\n\
             #        when absent the simulated rig equals [model].\n\
             # [sensors]: the simulated rig's sensors; [sim]: its integrator.\n\
             # [estimator]: the thesis filter (Q, R, P0 in SI squared units per step; see README).\n\
             # [leak_filter]: the filter that estimates leak sizes; [classifier]: the detectors.\n\
             # [udp.<channel>]: a real rig's UDP stream (u, x, p1, p2, x_sp, f_load), SI = gain * raw + offset\n\
             #        (gain 1, offset 0: the sender sends SI).\n\n{body}"
        )
    }
}

/// Why config text was refused.
enum ParseError {
    /// Not TOML, or a value the sections' types cannot hold (wrong type, unknown field).
    Toml(toml::de::Error),
    /// A value outside its range (the message names field, range and unit).
    Invalid(String),
}

/// One line describing a TOML error: line, column and the parser's message.
/// Text from the file (the line, names and values in the message) is shown
/// with its control characters escaped ([`dataset::escaped`]).
pub fn toml_error_line(text: &str, e: &toml::de::Error) -> String {
    let msg = dataset::escaped(&e.message().trim().replace('\n', "; "));
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
            let src = dataset::shown(text.lines().nth(line - 1).unwrap_or("").trim());
            format!("line {line}, column {col} (`{src}`): {msg}")
        }
        None => msg,
    }
}

/// For a TOML error at a numeric field of the config (a value of the wrong
/// type, negative for an unsigned field, or too large for it): ` (`section.field`
/// must be an integer: 1 to 24 bits)`, the range and unit from the field's own
/// validation; empty for any other error.
///
/// The range is the validation's own message (no second table to keep in
/// step): the field is set, in the default config, to values outside every
/// range (NaN for a number; 0, then the largest u8, u16, u32 for an integer)
/// until the validation refuses it by name.
pub fn range_hint(e: &toml::de::Error) -> String {
    // the dotted key path of the value the error is about (toml shows it when
    // the error has no input text to point into)
    let mut bare = e.clone();
    bare.set_input(None);
    let bare = bare.to_string();
    let Some(keys) = bare
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("in `").and_then(|l| l.strip_suffix('`')))
    else {
        return String::new();
    };
    let mut path: Vec<&str> = keys.split('.').collect();
    if path.first() == Some(&"rig") {
        path[0] = "model"; // [rig] has [model]'s fields and ranges (not in the default config)
    }
    let Ok(base) = toml::Table::try_from(Config::default()) else {
        return String::new();
    };
    let (integer, candidates) = match leaf(&base, &path) {
        Some(toml::Value::Integer(_)) => (
            true,
            [0, 255, 65_535, 4_294_967_295].map(toml::Value::Integer).to_vec(),
        ),
        Some(toml::Value::Float(_)) => (false, vec![toml::Value::Float(f64::NAN)]),
        _ => return String::new(),
    };
    let last = path[path.len() - 1];
    for v in candidates {
        let mut t = base.clone();
        if let Some(slot) = leaf_mut(&mut t, &path) {
            *slot = v;
        }
        let Ok(text) = toml::to_string(&t) else { continue };
        let Err(ParseError::Invalid(msg)) = Config::parse_or_toml_error(&text) else {
            continue;
        };
        if !(msg.contains(&format!("{last}` =")) || msg.contains(&format!("{last} ="))) {
            continue;
        }
        let range = msg
            .split_once("is invalid: expected ")
            .or_else(|| msg.split_once(": must be "))
            .map(|(_, r)| r);
        let path = keys;
        match range {
            Some(r) if !integer && r.starts_with("a number ") => return format!(" (`{path}` must be {r})"),
            Some(r) if integer => return format!(" (`{path}` must be an integer: {r})"),
            Some(r) => return format!(" (`{path}` must be a number: {r})"),
            None => {}
        }
    }
    String::new()
}

fn leaf<'a>(t: &'a toml::Table, path: &[&str]) -> Option<&'a toml::Value> {
    let (first, rest) = path.split_first()?;
    let v = t.get(*first)?;
    match v {
        toml::Value::Table(sub) if !rest.is_empty() => leaf(sub, rest),
        _ if rest.is_empty() => Some(v),
        _ => None,
    }
}

fn leaf_mut<'a>(t: &'a mut toml::Table, path: &[&str]) -> Option<&'a mut toml::Value> {
    let (first, rest) = path.split_first()?;
    let v = t.get_mut(*first)?;
    if rest.is_empty() {
        return Some(v);
    }
    match v {
        toml::Value::Table(sub) => leaf_mut(sub, rest),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_round_trips_and_errors_name_the_problem() {
        let text = Config::default_toml();
        assert_eq!(Config::parse(&text).unwrap(), Config::default());
        let e = Config::parse("[model]\nsupply_pressure_psi = 2000.0\n").unwrap_err();
        assert!(e.contains("supply_pressure_psi"), "{e}");
        let e = Config::parse("[model]\nsupply_pressure_pa = \"13.8 MPa\"\n").unwrap_err();
        assert!(e.contains("supply_pressure_pa"), "{e}");
        let e = Config::parse("[model]\nmass_kg = -3.0\n").unwrap_err();
        assert!(e.contains("mass_kg"), "{e}");
        // Values that would abort, hang or give NaN are refused by name.
        for (text, field) in [
            (
                "[estimator]\nmae_window_samples = 1000000000000\n",
                "mae_window_samples",
            ),
            ("[model]\nsupply_pressure_pa = 1e308\n", "supply_pressure_pa"),
            ("[estimator]\nsample_period_s = 1e-300\n", "sample_period_s"),
            ("[sensors]\nadc_bits = 0\n", "adc_bits"),
            ("[sensors]\nadc_bits = 64\n", "adc_bits"),
            ("[sim]\nsubsteps_per_sample = 4000000000\n", "substeps_per_sample"),
            ("[sim]\nsample_period_s = 1e-300\n", "sample_period_s"),
        ] {
            let e = Config::parse(text).unwrap_err();
            assert!(e.contains(field), "{text}: {e}");
        }
        let e = Config::parse("[modle]\n").unwrap_err();
        assert!(e.contains("modle"), "{e}");
        // A partial [leak_filter] keeps the leak filter's own defaults for the rest.
        let c = Config::parse("[leak_filter]\nsubsteps = 2\n").unwrap();
        assert_eq!(c.leak_filter.states, 11);
        assert_eq!(c.leak_filter.substeps, 2);
        assert_eq!(c.leak_filter.r_p_pa2, Tuning::sensor_derived().r_p_pa2);
        // [udp]: raw counts to SI per channel; an unknown channel or field is named
        let c = Config::parse("[udp.p1]\ngain = 250.0\noffset = -1.0e6\n").unwrap();
        assert_eq!((c.udp.p1.gain, c.udp.p1.offset), (250.0, -1.0e6));
        assert_eq!(c.udp.p2, acquisition::ChannelScale::default());
        let e = Config::parse("[udp.p3]\ngain = 2.0\n").unwrap_err();
        assert!(e.contains("p3"), "{e}");
        let e = Config::parse("[udp.x]\nscale = 2.0\n").unwrap_err();
        assert!(e.contains("scale"), "{e}");
        let c = Config::parse("[rig]\nbulk_modulus_pa = 5e8\n").unwrap();
        assert_eq!(c.rig_params().bulk_modulus_pa, 5e8);
        assert_eq!(c.model.bulk_modulus_pa, 6.89e8);
    }

    /// Every numeric leaf of `t` with its path (section names, then the key).
    fn numeric_leaves(t: &toml::Table, path: &mut Vec<String>, out: &mut Vec<(Vec<String>, toml::Value)>) {
        for (k, v) in t {
            path.push(k.clone());
            match v {
                toml::Value::Table(sub) => numeric_leaves(sub, path, out),
                toml::Value::Integer(_) | toml::Value::Float(_) => out.push((path.clone(), v.clone())),
                _ => {}
            }
            path.pop();
        }
    }

    fn set(t: &mut toml::Table, path: &[String], v: toml::Value) {
        if path.len() == 1 {
            t.insert(path[0].clone(), v);
        } else if let Some(toml::Value::Table(sub)) = t.get_mut(&path[0]) {
            set(sub, &path[1..], v);
        }
    }

    /// Runs 0.3 s of the loaded scenario on the configured rig through both filters and
    /// the classifier; every measurement and every filter state must stay finite.
    fn runs_finite(cfg: &Config, what: &str) -> Result<(), String> {
        let req = crate::simulate::SimulateRequest {
            scenario: "loaded-sine".into(),
            seconds: Some(0.3),
            seed: 1,
            faults: vec![],
            rig_variant: None,
        };
        let (mut sim, seconds) = crate::simulate::build(cfg, &req).unwrap();
        let samples = sim.run(seconds);
        let mut stage =
            estimator::EstimatorStage::new(cfg.model.clone(), cfg.leak_filter.clone(), cfg.estimator.clone())
                .unwrap();
        let mut cls = classifier::Classifier::new(cfg.classifier.clone()).unwrap();
        for s in &samples {
            if ![s.t_s, s.u_v, s.x_m, s.p1_pa, s.p2_pa]
                .iter()
                .all(|v| v.is_finite())
            {
                return Err(format!("{what}: sample {s:?}"));
            }
            let e = stage.on_sample(s);
            for f in [&e.leak, &e.thesis] {
                let n = f.n_states as usize;
                if !f.state[..n].iter().all(|v| v.is_finite()) {
                    return Err(format!("{what}: t = {} s, state {:?}", f.t_s, &f.state[..n]));
                }
            }
            cls.on_stage(&e, |_| {});
        }
        Ok(())
    }

    #[test]
    fn every_numeric_field_swept_with_absurd_values_is_refused_by_name_or_stays_finite() {
        let base: toml::Table = toml::from_str(&Config::default_toml()).unwrap();
        let mut leaves = Vec::new();
        numeric_leaves(&base, &mut Vec::new(), &mut leaves);
        assert_eq!(leaves.len(), 136, "numeric fields");
        let floats = [0.0, -1.0, 1e308, -1e308, 1e-300, -1e-300, 1e30];
        let ints = [0i64, -1, 4_000_000_000, 1_000_000_000_000, i64::MAX];
        let (mut refused, mut accepted) = (0, 0);
        let mut not_finite = Vec::new();
        for (path, v) in &leaves {
            let values: Vec<toml::Value> = match v {
                toml::Value::Float(_) => floats.iter().map(|f| toml::Value::Float(*f)).collect(),
                _ => ints.iter().map(|i| toml::Value::Integer(*i)).collect(),
            };
            for value in values {
                let mut t = base.clone();
                set(&mut t, path, value.clone());
                let text = toml::to_string(&t).unwrap();
                let what = format!("[{}] = {value}", path.join("."));
                let key = path.last().unwrap();
                let parsed = std::panic::catch_unwind(|| Config::parse(&text));
                match parsed {
                    Err(_) => panic!("{what}: Config::parse panicked"),
                    Ok(Err(e)) => {
                        refused += 1;
                        assert!(
                            e.contains(key.as_str()),
                            "{what}: the error does not name the field: {e}"
                        );
                    }
                    Ok(Ok(cfg)) => {
                        accepted += 1;
                        if let Err(e) = runs_finite(&cfg, &what) {
                            not_finite.push(e);
                        }
                    }
                }
            }
        }
        assert!(not_finite.is_empty(), "{not_finite:#?}");
        // most absurd values are refused; the rest (zeros of noises, offsets, ...) run finite
        assert!(refused > 3 * accepted, "{refused} refused, {accepted} accepted");
    }

    #[test]
    fn a_value_of_the_wrong_type_is_named_with_the_fields_range_and_unit() {
        for (text, expect) in [
            (
                "[sensors]\nadc_bits = -1\n",
                "line 2, column 12 (`adc_bits = -1`): invalid value: integer `-1`, expected u32 \
                 (`sensors.adc_bits` must be an integer: 1 to 24 bits)",
            ),
            (
                "[sensors]\nadc_bits = 12.5\n",
                "line 2, column 12 (`adc_bits = 12.5`): invalid type: floating point `12.5`, expected u32 \
                 (`sensors.adc_bits` must be an integer: 1 to 24 bits)",
            ),
            (
                "[sim]\nsubsteps_per_sample = 99999999999\n",
                "line 2, column 23 (`substeps_per_sample = 99999999999`): invalid value: integer \
                 `99999999999`, expected u32 (`sim.substeps_per_sample` must be an integer: 1 to 10000 \
                 sub-steps per sample)",
            ),
            (
                "[rig]\nmass_kg = true\n",
                "line 2, column 11 (`mass_kg = true`): invalid type: boolean `true`, expected f64 \
                 (`rig.mass_kg` must be a number: a mass from 1e-3 to 1e5 kg)",
            ),
            (
                "[leak_filter]\nq_p_pa2 = \"1e6 Pa²\"\n",
                "line 2, column 11 (`q_p_pa2 = \"1e6 Pa²\"`): invalid type: string \"1e6 Pa²\", \
                 expected f64 (`leak_filter.q_p_pa2` must be a number from 0.0 to 1e18 Pa²)",
            ),
            (
                "[estimator]\nmax_bridged_gap_samples = -3\n",
                "line 2, column 27 (`max_bridged_gap_samples = -3`): invalid value: integer `-3`, \
                 expected u32 (`estimator.max_bridged_gap_samples` must be an integer: 0 to 3600000 \
                 samples (an hour at 1 kHz))",
            ),
            (
                "[classifier]\nstuck_samples = 1e3\n",
                "line 2, column 17 (`stuck_samples = 1e3`): invalid type: floating point `1000.0`, \
                 expected u32 (`classifier.stuck_samples` must be an integer: 1 to 1000000000 samples)",
            ),
            (
                "[udp.p1]\noffset = \"0\"\n",
                "line 2, column 10 (`offset = \"0\"`): invalid type: string \"0\", expected f64 \
                 (`udp.p1.offset` must be a number from -1e9 to 1e9 Pa)",
            ),
            // not a numeric field: no range to give
            (
                "[model]\nfriction = 3\n",
                "line 2, column 12 (`friction = 3`): invalid type: integer `3`, expected struct Friction",
            ),
        ] {
            assert_eq!(Config::parse(text).unwrap_err(), expect, "{text}");
        }
    }

    #[test]
    fn every_numeric_field_of_the_wrong_type_is_named_with_its_range() {
        let base: toml::Table = toml::from_str(&Config::default_toml()).unwrap();
        let mut leaves = Vec::new();
        numeric_leaves(&base, &mut Vec::new(), &mut leaves);
        assert_eq!(leaves.len(), 136, "numeric fields");
        for (path, v) in &leaves {
            let wrong = match v {
                toml::Value::Integer(_) => [toml::Value::Float(0.5), toml::Value::Integer(-1)],
                _ => [toml::Value::String("1 unit".into()), toml::Value::Boolean(true)],
            };
            for value in wrong {
                let mut t = base.clone();
                set(&mut t, path, value.clone());
                let e = Config::parse(&toml::to_string(&t).unwrap()).unwrap_err();
                let kind = if v.is_integer() {
                    "an integer: "
                } else {
                    "a number"
                };
                let hint = format!("(`{}` must be {kind}", path.join("."));
                assert!(e.contains(&hint), "{} = {value}: {e}", path.join("."));
            }
        }
    }

    #[test]
    fn control_characters_from_the_file_are_escaped_in_messages() {
        for (text, expect) in [
            // an unknown key with ESC (written as a TOML escape)
            (
                "[model]\n\"\\u001b[31mx\" = 1\n",
                "line 2, column 1 (`\"\\u001b[31mx\" = 1`): unknown field `\\u{1b}[31mx`, expected one of",
            ),
            // raw ESC and NUL in the file
            (
                "[model]\nmass_kg = \"\u{1b}[31m\0\"\n",
                "line 2, column 12 (`mass_kg = \"\\u{1b}[31m\\0\"`): invalid basic string",
            ),
            (
                "[model]\nmass_kg = 1\0\u{1b}[2J\n",
                "line 2, column 14 (`mass_kg = 1\\0\\u{1b}[2J`): unexpected key or value",
            ),
        ] {
            let e = Config::parse(text).unwrap_err();
            assert!(e.starts_with(expect), "{text:?}: {e}");
            assert!(!e.chars().any(|c| c.is_control()), "{e:?}");
        }
    }

    #[test]
    fn ranges_name_the_unit() {
        for (text, expect) in [
            (
                "[model]\nmass_kg = 1e308\n",
                "[model] parameter `mass_kg` = 1e308 is invalid: expected a mass from 1e-3 to 1e5 kg",
            ),
            (
                "[sensors]\nadc_bits = 64\n",
                "parameter `sensors.adc_bits` = 64 is invalid: expected 1 to 24 bits",
            ),
            (
                "[sensors]\npressure_noise_pa = 1e308\n",
                "a noise from 0 to 1e8 Pa",
            ),
            (
                "[estimator]\nq_p_pa2 = 1e308\n",
                "q_p_pa2 = 1e308: must be a number from 0.0 to 1e18 Pa²",
            ),
            (
                "[leak_filter]\nr_x_m2 = 1e-300\n",
                "[leak_filter] r_x_m2 = 1e-300: must be a number from 1e-30 to 100.0 m²",
            ),
            (
                "[classifier]\nwarmup_s = 1e308\n",
                "[classifier] warmup_s = 1e308: must be a number from 0.0 to 1000000.0 s",
            ),
            (
                "[estimator]\nmax_bridged_gap_samples = 4000000000\n",
                "must be 0 to 3600000 samples",
            ),
            (
                "[udp.p1]\ngain = 0.0\n",
                "[udp] p1.gain = 0.0: must be a number of magnitude from 1e-12 to 1e12 Pa per raw unit",
            ),
            (
                "[udp.f_load]\noffset = 1e30\n",
                "[udp] f_load.offset = 1e30: must be a number from -1e9 to 1e9 N",
            ),
        ] {
            let e = Config::parse(text).unwrap_err();
            assert!(e.contains(expect), "{text}: {e}");
        }
    }

    #[test]
    fn the_model_toml_calibrate_writes_is_a_config() {
        // a calibrated model with every kind of effect the library adds
        let mut m = ActuatorParams::default();
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
        let text = crate::model_file::model_toml(&m).unwrap();
        // the file says how to use it, and `--config model.toml` takes it as it is
        assert!(
            text.contains("leakwatch replay MEASURED.csv --config model.toml"),
            "{text}"
        );
        let cfg = Config::parse(&text).unwrap();
        assert_eq!(cfg.model, m);
        assert_eq!(cfg.model.spool_null_bias_m, -5.0e-6);
        assert_eq!(cfg.model.leaks.len(), 1);
        let r = cfg.model.friction.for_direction(-1.0);
        assert_eq!((r.slip_n, r.viscous_n_s_per_m), (1500.0, 300.0));
        // everything else keeps its default
        assert_eq!(cfg.estimator, Config::default().estimator);
        assert_eq!(cfg.classifier, Config::default().classifier);
        assert!(cfg.rig.is_none());
    }
}
