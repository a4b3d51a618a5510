//! The one TOML configuration file of leakwatch: every section and field has
//! a default, so nothing is needed to start (`leakwatch config --print-default`).

use std::path::{Path, PathBuf};

use detect::ClassifierConfig;
use filter::Tuning;
use model::params::ActuatorParams;
use model::sensors::SensorParams;
use model::sim::SimSettings;
use serde::{Deserialize, Serialize};

pub mod init;
pub mod live;
pub mod opcua;
mod reference;
mod run_settings;
pub mod udp;
pub use reference::{reference_markdown, REGENERATE};
pub use run_settings::RunSettings;
use udp::UdpScaling;

/// The config file `run`, `replay`, `simulate`, `calibrate` and `commission` pick
/// up from the working directory when no `--config` is given.
pub const WORKING_DIR_CONFIG: &str = "leakwatch.toml";

schema::config_struct! {
    /// The whole configuration: each section with its defaults (the rig facts
    /// of `[classifier]` equal `[model]`'s and `[sensors]`' defaults, so the
    /// default needs no [`Config::derive_rig_facts`]).
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct Config {
        /// The rig in its datasheets' terms (docs/rig.md); when given, the rig facts
        /// of `[model]`, `[sensors]` and `[leak_filter]` are derived from it
        /// ([`model::datasheet::DERIVED_FIELDS`]) and are not written there.
        pub datasheet: Option<model::Datasheet> = None,
        /// The actuator model the estimator and calibration believe in.
        pub model: ActuatorParams = ActuatorParams::default(),
        /// The simulated rig's own parameters; when absent the rig equals `[model]`.
        pub rig: Option<ActuatorParams> = None,
        /// Sensors of the simulated rig.
        pub sensors: SensorParams = SensorParams::default(),
        /// Integration settings of the simulated rig.
        pub sim: SimSettings = SimSettings::default(),
        /// The thesis filter (baseline detector): by default the thesis' 7-state tuning
        /// (docs/model.md#tuning).
        pub estimator: Tuning = Tuning::thesis(),
        /// The leak filter (leakwatch's detector): by default 12 states, tuning from the sensors.
        pub leak_filter: Tuning = Tuning::sensor_derived(),
        /// The detectors.
        pub classifier: ClassifierConfig = ClassifierConfig::default(),
        /// The UDP sensor stream of a real rig (`run --source udp://...`): per-channel
        /// scaling of raw values to SI, `SI = gain·raw + offset` (default: SI as sent),
        /// and the expected sender, `sender = "IP:PORT"` (default: the first one).
        pub udp: UdpScaling = UdpScaling::default(),
        /// How `run` places its stage processes: CPU pinning, the low-latency spin.
        pub run: RunSettings = RunSettings::default(),
        /// The Foxglove WebSocket live view (`run --live-view`), off by default.
        pub live_view: live::LiveViewConfig = live::LiveViewConfig::default(),
        /// The Zenoh fleet gateway (`run --zenoh`) and `leakwatch watch`, off by default.
        pub zenoh: live::ZenohConfig = live::ZenohConfig::default(),
        /// The OPC UA server for a plant's SCADA (`run --opcua`), off by default.
        pub opcua: opcua::OpcuaConfig = opcua::OpcuaConfig::default(),
    }
}

/// The keys `[classifier]` had for rig facts that now live in `[model]` and
/// `[sensors]` (`supply_pressure_pa`, `pressure_full_scale_pa`), taken out of
/// `table`: (key, value given, where the fact lives). A file written by an
/// older leakwatch (a commissioning's config) still loads when they agree.
fn derived_classifier_keys(
    table: &mut toml::Table,
) -> Result<Vec<(&'static str, f64, &'static str)>, ParseError> {
    let mut out = Vec::new();
    let Some(cls) = table.get_mut("classifier").and_then(|v| v.as_table_mut()) else {
        return Ok(out);
    };
    for (key, from) in [
        ("supply_pressure_pa", "[model] supply_pressure_pa"),
        ("pressure_full_scale_pa", "[sensors] pressure_full_scale_pa"),
    ] {
        if let Some(v) = cls.remove(key) {
            let given = match v {
                toml::Value::Float(f) => f,
                toml::Value::Integer(i) => i as f64,
                other => {
                    return Err(ParseError::Invalid(format!(
                        "[classifier] {key} = {}: not a number (and no longer a setting: the detector takes it from {from})",
                        dataset::shown(&other.to_string())
                    )))
                }
            };
            out.push((key, given, from));
        }
    }
    Ok(out)
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
        let mut stripped: toml::Table = toml::from_str(text).map_err(ParseError::Toml)?;
        let derived = derived_classifier_keys(&mut stripped)?;
        // From the text when it can be (errors then point at a line).
        let mut cfg: Config = if derived.is_empty() {
            toml::from_str(text).map_err(ParseError::Toml)?
        } else {
            Config::deserialize(stripped).map_err(ParseError::Toml)?
        };
        // A partial [leak_filter] fills its missing fields from the leak filter's own
        // defaults (sensor-derived, 12 states), not from the thesis tuning that
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
        if let Some(sheet) = cfg.datasheet {
            cfg.apply_datasheet(&sheet, &table).map_err(ParseError::Invalid)?;
        }
        cfg.derive_rig_facts();
        for (key, given, from) in derived {
            let used = match key {
                "supply_pressure_pa" => cfg.classifier.supply_pressure_pa,
                _ => cfg.classifier.pressure_full_scale_pa,
            };
            if given != used {
                return Err(ParseError::Invalid(format!(
                    "[classifier] {key} = {given:?} differs from {from} = {used:?}: the detector now takes \
                     this rig fact from {from} (written once); remove the line from [classifier]"
                )));
            }
        }
        cfg.validate().map_err(ParseError::Invalid)?;
        Ok(cfg)
    }

    /// Derives the rig facts of `[model]`, `[sensors]` and `[leak_filter]` from
    /// `sheet`. `written` is the file's table: a derived field written there too
    /// is refused unless it holds the derived value (a config this program
    /// wrote, with its values spelled out, reads back).
    fn apply_datasheet(&mut self, sheet: &model::Datasheet, written: &toml::Table) -> Result<(), String> {
        sheet.validate().map_err(|e| format!("[datasheet] {e}"))?;
        let mut derived = self.clone();
        derived.model = sheet.model(&self.model);
        derived.sensors = sheet.sensors(&self.sensors);
        (derived.leak_filter.r_x_m2, derived.leak_filter.r_p_pa2) = sheet.measurement_noise();
        let derived_table = toml::Table::try_from(&derived).map_err(|e| e.to_string())?;
        let number = |v: Option<&toml::Value>| match v {
            Some(toml::Value::Float(f)) => Some(*f),
            Some(toml::Value::Integer(i)) => Some(*i as f64),
            _ => None,
        };
        // a field may be dotted (`oil_temperature.viscosity_40c_mm2_s`): a table's field
        let lookup = |table: &'_ toml::Table, section: &str, field: &str| -> Option<toml::Value> {
            let mut at = table.get(section)?;
            for key in field.split('.') {
                at = at.as_table()?.get(key)?;
            }
            Some(at.clone())
        };
        for (section, field, from) in model::datasheet::DERIVED_FIELDS {
            let Some(given) = lookup(written, section, field) else {
                continue;
            };
            let value = lookup(&derived_table, section, field);
            let (given, value) = (&given, value.as_ref());
            let (given_n, value_n) = (number(Some(given)), number(value));
            if given_n.is_none() || given_n != value_n {
                let derived_text = value.map_or("none".to_string(), |v| v.to_string());
                return Err(format!(
                    "[{section}] {field} = {} is a rig fact the datasheet gives: [datasheet] {from} makes it {derived_text}. \
                     Write it once: remove the line from [{section}] (or correct the datasheet)",
                    dataset::shown(&given.to_string())
                ));
            }
        }
        self.model = derived.model;
        self.sensors = derived.sensors;
        self.leak_filter.r_x_m2 = derived.leak_filter.r_x_m2;
        self.leak_filter.r_p_pa2 = derived.leak_filter.r_p_pa2;
        Ok(())
    }

    /// Sets the detector's rig facts from where they are written: the supply
    /// pressure from `[model]`, the transducers' full scale, zero and span
    /// tolerances and the position reading's noise in counts from `[sensors]`.
    pub fn derive_rig_facts(&mut self) {
        self.classifier.supply_pressure_pa = self.model.supply_pressure_pa;
        self.classifier.pressure_full_scale_pa = self.sensors.pressure_full_scale_pa;
        self.classifier.pressure_zero_offset_max_pa = self.sensors.pressure_zero_offset_max_pa;
        self.classifier.pressure_span_error_max = self.sensors.pressure_span_error_max;
        self.classifier.position_noise_counts =
            self.sensors.position_noise_m / self.sensors.encoder_resolution_m;
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
        self.udp.validate()?;
        self.run.validate()?;
        self.live_view.validate()?;
        self.zenoh.validate()?;
        self.opcua.validate()
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

    /// Says on stderr that no description of the rig was found (`missing`:
    /// what was looked for), so the built-in rig stands in for it.
    pub fn note_builtin_rig(missing: &str) {
        eprintln!(
            "note: no --config and no {missing}: the rig is taken to be the built-in one (the thesis \
             rig, double-rod: \"the datasheet's\" values are its); describe your rig with `leakwatch init`"
        );
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
             # [model]: the actuator as the estimator believes it (docs/model.md).\n\
             # [rig]: optional, the simulated rig's own parameters (same fields as [model]);\n\
             #        when absent the simulated rig equals [model].\n\
             # [sensors]: the simulated rig's sensors; [sim]: its integrator.\n\
             # [estimator]: the thesis filter (Q, R, P0 in SI squared units per step; see README).\n\
             # [leak_filter]: the filter that estimates leak sizes; [classifier]: the detectors.\n\
             # [udp.<channel>]: a real rig's UDP stream (u, x, p1, p2, x_sp, f_load), SI = gain * raw + offset\n\
             #        (gain 1, offset 0: the sender sends SI); [udp] sender = \"IP:PORT\": optional, the only\n\
             #        address datagrams are taken from (default: the first sender).\n\
             # [live_view]: the Foxglove WebSocket live view (run --live-view), rates in Hz.\n\
             # [zenoh]: the fleet gateway (run --zenoh) and `watch`: Zenoh endpoints, estimates rate in Hz.\n\
             # [opcua]: the OPC UA server for a plant's SCADA (run --opcua), read-only.\n\n{body}"
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
/// must be an integer: 1 to 24 bits)`, the range and unit as the field
/// declares them ([`Config::SCHEMA`]); empty for any other error.
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
    // an element of a list (`leaks[0]`) has its list's field
    let path: Vec<&str> = keys
        .split('.')
        .map(|k| k.split('[').next().unwrap_or(k))
        .collect();
    let Some(field) = Config::SCHEMA.find(&path) else {
        return String::new();
    };
    // a channel of `[udp]` states its range in the channel's own unit
    let range = match path.as_slice() {
        ["udp", channel, key] => UdpScaling::range_text(channel, key).unwrap_or_default(),
        _ => field.expected(),
    };
    match field.kind {
        _ if range.is_empty() => String::new(),
        schema::Kind::Integer => format!(" (`{keys}` must be an integer: {range})"),
        schema::Kind::Number | schema::Kind::List(schema::Kind::Number) if range.starts_with("a number ") => {
            format!(" (`{keys}` must be {range})")
        }
        schema::Kind::Number | schema::Kind::List(schema::Kind::Number) => {
            format!(" (`{keys}` must be a number: {range})")
        }
        _ => String::new(),
    }
}

#[cfg(test)]
mod fuzz;
#[cfg(test)]
mod tests;
