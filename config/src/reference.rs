//! `leakwatch config --reference`: the configuration reference in Markdown,
//! made from the config types themselves, so it cannot disagree with them.
//!
//! - Sections and fields: the structs [`Config`] holds, read from their source
//!   (compiled in with `include_str!`), in the order they are declared.
//! - Meaning: the first sentence of each field's doc comment.
//! - Range and unit: the field's own validation ([`probe_range`]).
//! - Default: `Config::default()` serialized.

mod structs;

use super::{probe_range, Config};
use structs::{find_struct, struct_head};

/// The sources of the structs that make up the configuration (path from the
/// workspace root, text). A section whose type is in none of them is an error
/// that names the type.
const SOURCES: [(&str, &str); 14] = [
    ("config/src/lib.rs", include_str!("lib.rs")),
    ("config/src/run_settings.rs", include_str!("run_settings.rs")),
    ("model/src/params.rs", include_str!("../../model/src/params.rs")),
    (
        "model/src/params/friction.rs",
        include_str!("../../model/src/params/friction.rs"),
    ),
    (
        "model/src/params/oil.rs",
        include_str!("../../model/src/params/oil.rs"),
    ),
    (
        "model/src/datasheet.rs",
        include_str!("../../model/src/datasheet.rs"),
    ),
    ("model/src/sensors.rs", include_str!("../../model/src/sensors.rs")),
    ("model/src/sim.rs", include_str!("../../model/src/sim.rs")),
    ("model/src/leakage.rs", include_str!("../../model/src/leakage.rs")),
    ("filter/src/tuning.rs", include_str!("../../filter/src/tuning.rs")),
    ("detect/src/config.rs", include_str!("../../detect/src/config.rs")),
    ("config/src/udp.rs", include_str!("udp.rs")),
    ("config/src/live.rs", include_str!("live.rs")),
    ("config/src/opcua.rs", include_str!("opcua.rs")),
];

/// The command that writes the committed reference (named in the page and by its test).
pub const REGENERATE: &str = "cargo run -p leakwatch -- config --reference > docs/config.md";

/// The settings a user sets first, with why; each is in its section's table below.
pub const FIRST: [(&str, &str); 5] = [
    (
        "`[datasheet]`",
        "your rig in its datasheets' terms; the model, the sensors and the filters' noise are derived from it ([rig.md](rig.md)).",
    ),
    (
        "`[classifier] false_alarms_per_hour`",
        "the false-alarm rate you accept; the detector's thresholds follow from it and the healthy spreads commissioning learns.",
    ),
    (
        "`[classifier] min_size_lpm`, `min_internal_size_lpm`",
        "the smallest leak ever declared, external and internal.",
    ),
    (
        "`[udp] sender`, `[udp.<channel>] gain`, `offset`",
        "a real rig's stream: the only device that may send, and its raw values to SI.",
    ),
    (
        "`[live_view] enabled`, `[zenoh] enabled`",
        "watching from Foxglove on this PC, or from another PC with `leakwatch watch`.",
    ),
];

/// `Option<T>` → (true, `T`); `T` → (false, `T`).
fn unwrap_option(ty: &str) -> (bool, &str) {
    match ty.strip_prefix("Option<").and_then(|t| t.strip_suffix('>')) {
        Some(inner) => (true, inner),
        None => (false, ty),
    }
}

/// The type's name without its module path (`live::ZenohConfig` → `ZenohConfig`).
fn bare(ty: &str) -> &str {
    ty.rsplit("::").next().unwrap_or(ty)
}

/// Whether `ty` names a struct of the sources (a TOML table).
fn is_struct(ty: &str) -> bool {
    let head = struct_head(bare(ty));
    SOURCES
        .iter()
        .any(|(_, text)| text.lines().any(|l| l.trim() == head))
}

/// The first sentence of a doc comment: up to the first `. ` before a capital
/// letter outside parentheses, or the whole of it. Rustdoc links (`` [`x`] ``)
/// become code; table cells escape `|`.
fn first_sentence(doc: &str) -> String {
    let mut end = doc.len();
    let mut depth = 0i32;
    for (i, c) in doc.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            '.' if depth == 0
                && doc[i + 1..].starts_with(' ')
                && doc[i + 2..].chars().next().is_some_and(char::is_uppercase) =>
            {
                end = i + 1;
                break;
            }
            _ => {}
        }
    }
    let mut text = doc[..end].to_string();
    while let Some(open) = text.find("[`") {
        let Some(close) = text[open..].find("`]").map(|c| open + c) else {
            break;
        };
        text.replace_range(close + 1..close + 2, "");
        text.replace_range(open..open + 1, "");
    }
    text.replace('|', "\\|")
}

/// Whether a word of a range is a number (`1e-3`, `0.5)`, `-π/2`).
fn is_number(word: &str) -> bool {
    let w = word.trim_matches(|c: char| "[](),;:".contains(c));
    w.parse::<f64>().is_ok() || (w.contains('π') && w.chars().all(|c| "0123456789.π/-+".contains(c)))
}

/// `text` without its remarks in parentheses: a ` (` group closed by a `)`
/// that ends a word (`(0 = off)`, not `m³/(s·Pa)` nor `(dimensionless)²`).
fn without_remarks(text: &str) -> String {
    let mut out = text.to_string();
    while let Some(open) = out.find(" (") {
        let Some(close) = out[open..].find(')').map(|c| open + c) else {
            break;
        };
        let after = out[close + 1..].chars().next();
        if after.is_some_and(|c| !(c.is_whitespace() || ",;.".contains(c))) {
            break;
        }
        out.replace_range(open..close + 1, "");
    }
    out
}

/// The unit of a field, from its range (`a mass from 1e-3 to 1e5 kg` → `kg`):
/// the words after its last number, remarks in parentheses left out; else a
/// remark right after the last number (`from 0.01 to 1 (dimensionless)`);
/// else the short last part of the meaning (`Window of ..., samples.` →
/// `samples`); else empty.
fn unit_of(range: &str, meaning: &str) -> String {
    let plain = without_remarks(range);
    let words: Vec<&str> = plain.split_whitespace().collect();
    if let Some(last) = words.iter().rposition(|w| is_number(w)) {
        let rest = words[last + 1..].join(" ");
        if !rest.is_empty() {
            return rest;
        }
        let words: Vec<&str> = range.split_whitespace().collect();
        if let Some(last) = words.iter().rposition(|w| is_number(w)) {
            let rest = words[last + 1..].join(" ");
            if let Some(inner) = rest.strip_prefix('(').and_then(|r| r.strip_suffix(')')) {
                if !inner.chars().any(|c| c.is_ascii_digit()) {
                    return inner.to_string();
                }
            }
        }
    }
    match meaning.trim_end_matches('.').rsplit_once(", ") {
        Some((_, tail)) if tail.chars().count() <= 12 && !tail.contains(['(', ')', ' ']) => tail.to_string(),
        _ => String::new(),
    }
}

/// A default value as it is written in the file (numbers in their shortest
/// form, large and small ones with an exponent).
fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) if *f != 0.0 && (f.abs() >= 1e5 || f.abs() < 1e-3) => format!("{f:e}"),
        toml::Value::Float(f) => format!("{f}"),
        toml::Value::Table(t) if t.is_empty() => "{}".into(),
        other => other.to_string(),
    }
}

/// The value at `path` in a table.
fn at<'a>(t: &'a toml::Table, path: &[String]) -> Option<&'a toml::Value> {
    let (first, rest) = path.split_first()?;
    let v = t.get(first)?;
    match v {
        toml::Value::Table(sub) if !rest.is_empty() => at(sub, rest),
        _ if rest.is_empty() => Some(v),
        _ => None,
    }
}

/// The defaults of a section: from the default config, or, for an optional
/// section absent there, the values its fields take when it is given empty
/// (`None` when it cannot be given empty: it has required fields).
fn section_defaults(defaults: &toml::Table, path: &[String]) -> Option<toml::Table> {
    if let Some(toml::Value::Table(t)) = at(defaults, path) {
        return Some(t.clone());
    }
    let mut given = defaults.clone();
    let mut t = &mut given;
    for key in path {
        t = t
            .entry(key.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()?;
    }
    let text = toml::to_string(&given).ok()?;
    let cfg = Config::parse(&text).ok()?;
    let filled = toml::Table::try_from(cfg).ok()?;
    match at(&filled, path) {
        Some(toml::Value::Table(t)) => Some(t.clone()),
        _ => None,
    }
}

/// Writes the reference of one section and, after it, of its sub-sections.
struct Writer {
    /// `Config::default()` serialized.
    defaults: toml::Table,
    /// Sections written so far: (type, defaults, heading), to refer to instead of repeating.
    written: Vec<(String, Option<toml::Table>, String)>,
    /// The page so far.
    out: String,
}

impl Writer {
    fn section(&mut self, path: &[String], ty: &str, about: &str, optional: bool) -> Result<(), String> {
        let heading = format!("[{}]", path.join("."));
        let defaults = section_defaults(&self.defaults, path);
        let mut intro = first_sentence(about);
        if optional {
            intro.push_str(" Optional: absent by default.");
        }
        if let Some((_, _, same)) = self
            .written
            .iter()
            .find(|(t, d, _)| t == bare(ty) && *d == defaults)
        {
            self.out.push_str(&format!(
                "## {heading}\n\n{intro} The fields, ranges and defaults of {same}.\n\n"
            ));
            return Ok(());
        }
        self.written
            .push((bare(ty).to_string(), defaults.clone(), heading.clone()));
        let doc = find_struct(bare(ty))?;
        self.out.push_str(&format!(
            "## {heading}\n\n{intro} (`{}` in {})\n\n",
            bare(ty),
            doc.file
        ));
        match (optional, defaults.is_some()) {
            (true, true) => self
                .out
                .push_str("A field left out of it takes the default shown.\n\n"),
            (_, false) => self
                .out
                .push_str("It has required fields, so no defaults are shown.\n\n"),
            _ => {}
        }
        self.out
            .push_str("| field | unit | range | default | meaning |\n|---|---|---|---|---|\n");
        let mut subsections = Vec::new();
        for f in &doc.fields {
            let (opt, inner) = unwrap_option(&f.ty);
            if is_struct(inner) {
                subsections.push((f, opt, inner));
                continue;
            }
            let mut field_path = path.to_vec();
            field_path.push(f.name.clone());
            let keys: Vec<&str> = field_path.iter().map(String::as_str).collect();
            let list_of_tables = inner
                .strip_prefix("Vec<")
                .and_then(|t| t.strip_suffix('>'))
                .is_some_and(is_struct);
            let range = if inner == "bool" {
                "true or false".to_string()
            } else if list_of_tables {
                String::new()
            } else {
                probe_range(&keys).map(|(_, r)| r).unwrap_or_default()
            };
            let default = match defaults.as_ref().and_then(|d| d.get(&f.name)) {
                Some(v) => format!("`{}`", shown(v)),
                None if opt => "absent".into(),
                None => "—".into(),
            };
            let cell = |s: &str| {
                if s.is_empty() {
                    "—".to_string()
                } else {
                    s.replace('|', "\\|")
                }
            };
            self.out.push_str(&format!(
                "| `{}` | {} | {} | {} | {} |\n",
                f.name,
                cell(&unit_of(&range, &first_sentence(&f.doc))),
                cell(&range),
                default,
                first_sentence(&f.doc)
            ));
            if let Some(element) = inner.strip_prefix("Vec<").and_then(|t| t.strip_suffix('>')) {
                if is_struct(element) {
                    subsections.push((f, false, element));
                }
            }
        }
        self.out.push('\n');
        for (f, opt, inner) in subsections {
            let mut sub = path.to_vec();
            sub.push(f.name.clone());
            if f.ty.starts_with("Vec<") {
                self.list(&sub, inner, &f.doc)?;
            } else {
                self.section(&sub, inner, &f.doc, opt)?;
            }
        }
        Ok(())
    }

    /// A list of tables (`[[model.leaks]]`): its element's fields, no defaults.
    fn list(&mut self, path: &[String], ty: &str, about: &str) -> Result<(), String> {
        let doc = find_struct(bare(ty))?;
        self.out.push_str(&format!(
            "## [[{}]]\n\n{} Each entry has every field below. (`{}` in {})\n\n| field | meaning |\n|---|---|\n",
            path.join("."),
            first_sentence(about),
            bare(ty),
            doc.file
        ));
        for f in &doc.fields {
            self.out
                .push_str(&format!("| `{}` | {} |\n", f.name, first_sentence(&f.doc)));
        }
        self.out.push('\n');
        Ok(())
    }
}

/// The configuration reference in Markdown: per section, each field with its
/// unit, range, default and meaning (what `leakwatch config --reference` prints).
pub fn reference_markdown() -> Result<String, String> {
    let defaults = toml::Table::try_from(Config::default()).map_err(|e| e.to_string())?;
    let mut w = Writer {
        defaults,
        written: Vec::new(),
        out: String::new(),
    };
    w.out.push_str(&format!(
        "# Configuration reference\n\n\
         What each setting of a leakwatch config file means, in which unit, within which range, and its default.\n\n\
         Every field is optional: a field left out takes its default.\n\
         `leakwatch config --print-default` prints them all as TOML; `leakwatch config --check FILE` checks a file.\n\
         A value outside its range is refused at load, naming the field, the range and the unit.\n\n\
         This page is generated from the config types: meanings from their doc comments, ranges from their validation, defaults from `Config::default()`.\n\
         Do not edit it; regenerate it with `{REGENERATE}`.\n\
         A test (`leakwatch/tests/reference.rs`) fails when it differs from what the command prints.\n\n"
    ));
    w.out.push_str("## The five that matter first\n\n");
    for (fields, why) in FIRST {
        w.out.push_str(&format!("- {fields}: {why}\n"));
    }
    w.out.push('\n');
    let config = find_struct("Config")?;
    for f in &config.fields {
        let (opt, inner) = unwrap_option(&f.ty);
        if !is_struct(inner) {
            return Err(format!("Config::{} is not a section (type {})", f.name, f.ty));
        }
        w.section(std::slice::from_ref(&f.name), inner, &f.doc, opt)?;
    }
    Ok(w.out.trim_end().to_string() + "\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_five_first_are_fields_of_the_reference() {
        let page = reference_markdown().expect("the reference");
        for (fields, _) in FIRST {
            for name in fields.split('`').skip(1).step_by(2) {
                // `[section] field` or `field`: the field's own row, or the section's heading
                let field = name.rsplit(' ').next().unwrap_or(name);
                let found = if field.starts_with('[') {
                    page.contains(&format!("## {field}"))
                } else {
                    page.contains(&format!("| `{field}` |"))
                };
                assert!(found, "{name} of the five first is not in the reference");
            }
        }
    }

    #[test]
    fn a_field_has_its_unit_range_default_and_meaning() {
        let page = reference_markdown().expect("the reference");
        assert!(
            page.contains(
                "| `mass_kg` | kg | a mass from 1e-3 to 1e5 kg | `10` | Moving mass m (rod + piston), kg. |"
            ),
            "{page}"
        );
        assert!(page.contains(
            "| `false_alarms_per_hour` | per hour | a number from 1e-9 to 1000000.0 per hour | `0.05` | \
             Leak-size detector: the false-alarm rate asked for, per hour. |"
        ));
        assert!(
            page.contains("| `adc_bits` | bits | 1 to 24 bits | `12` |"),
            "{page}"
        );
        assert!(
            page.contains("| `init` | — | `thesis` or `measured` | `\"thesis\"` |"),
            "{page}"
        );
    }

    #[test]
    fn every_field_of_the_default_config_is_in_the_reference() {
        let page = reference_markdown().expect("the reference");
        let defaults = toml::Table::try_from(Config::default()).expect("the defaults");
        fn walk(t: &toml::Table, path: &str, page: &str, n: &mut usize) {
            for (k, v) in t {
                match v {
                    toml::Value::Table(sub) if k != "cpus" => walk(sub, &format!("{path}.{k}"), page, n),
                    _ => {
                        let heading = format!("## [{}]", path.trim_start_matches('.'));
                        let section = page
                            .split_once(&heading)
                            .map(|(_, rest)| rest.split("\n## ").next().unwrap_or(""))
                            .unwrap_or_else(|| panic!("no section {heading}"));
                        let row = format!("| `{k}` |");
                        let referred = section.contains("The fields, ranges and defaults of ");
                        assert!(referred || section.contains(&row), "{heading} has no row {row}");
                        *n += 1;
                    }
                }
            }
        }
        let mut n = 0;
        walk(&defaults, "", &page, &mut n);
        assert!(n > 150, "{n} fields");
    }

    #[test]
    fn the_rig_facts_the_loader_sets_are_not_settings() {
        // `#[serde(skip)]`: set from [model] and [sensors], never read from [classifier]
        let page = reference_markdown().expect("the reference");
        let classifier = page
            .split_once("## [classifier]")
            .map(|(_, r)| r.split("\n## ").next().unwrap_or(""))
            .expect("[classifier]");
        assert!(!classifier.contains("`supply_pressure_pa`"));
        assert!(!classifier.contains("`pressure_full_scale_pa`"));
        assert!(page.contains("| `supply_pressure_pa` | Pa |"));
    }

    #[test]
    fn the_first_sentence_stops_before_the_next_one() {
        assert_eq!(first_sentence("Sample period T, s."), "Sample period T, s.");
        assert_eq!(
            first_sentence("Number of states, e.g. 7. More follow. Not this."),
            "Number of states, e.g. 7."
        );
        assert_eq!(first_sentence("|gain| at most 1e12."), "\\|gain\\| at most 1e12.");
        assert_eq!(
            first_sentence("SI units per raw unit (e.g. Pa per count). More."),
            "SI units per raw unit (e.g. Pa per count)."
        );
        assert_eq!(
            first_sentence("Pressure factors ([`crate::f`]), 1."),
            "Pressure factors (`crate::f`), 1."
        );
        assert_eq!(unit_of("a mass from 1e-3 to 1e5 kg", ""), "kg");
        assert_eq!(unit_of("a fraction in [0, 0.5)", "A fraction."), "");
        assert_eq!(
            unit_of("a number from 0.0 to 10.0 (fraction of the size)", ""),
            "fraction of the size"
        );
        assert_eq!(
            unit_of("an angle from -π/2 to π/2 rad (0: horizontal)", ""),
            "rad"
        );
        assert_eq!(
            unit_of("a conductance from 0 to 1e-9 m³/(s·Pa) (0 = none)", ""),
            "m³/(s·Pa)"
        );
        assert_eq!(
            unit_of("a number from 0.0 to 1.0 (dimensionless)²", ""),
            "(dimensionless)²"
        );
        assert_eq!(
            unit_of("1 to 3600000 (an hour at 1 kHz)", "Window, samples."),
            "samples"
        );
    }
}
