//! `leakwatch config --reference`: the configuration reference in Markdown,
//! made from the config types' declarations ([`schema`]), so it cannot
//! disagree with them.
//!
//! - Sections and fields: [`Config::SCHEMA`] and the sections it holds, in
//!   the order they are declared.
//! - Meaning: the first sentence of each field's doc comment.
//! - Unit and range: as each field declares them (and as its check states them).
//! - Default: `Config::default()` serialized.

use schema::{Field, Kind, Section};

use super::Config;

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

/// The range column of a field: its declared range, `true or false`, or its names.
fn range_cell(f: &Field) -> String {
    match f.kind {
        Kind::Flag => "true or false".into(),
        Kind::Choice(names) => {
            let names: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
            match names.split_last() {
                Some((last, rest)) if rest.len() == 1 => format!("{} or {last}", rest[0]),
                Some((last, rest)) if !rest.is_empty() => format!("one of {}, {last}", rest.join(", ")),
                _ => names.concat(),
            }
        }
        Kind::Tables(_) => String::new(),
        _ => f.expected(),
    }
}

/// A table cell: `—` when empty, `|` escaped.
fn cell(s: &str) -> String {
    if s.is_empty() {
        "—".to_string()
    } else {
        s.replace('|', "\\|")
    }
}

/// Writes the reference of one section and, after it, of its sub-sections.
struct Writer {
    /// `Config::default()` serialized.
    defaults: toml::Table,
    /// Sections written so far: (type, defaults, heading), to refer to instead of repeating.
    written: Vec<(&'static str, Option<toml::Table>, String)>,
    /// The page so far.
    out: String,
}

impl Writer {
    /// The section at `path`, of type `section`, that the field documented `about` holds.
    fn section(&mut self, path: &[String], section: &'static Section, about: &str, optional: bool) {
        let heading = format!("[{}]", path.join("."));
        let defaults = section_defaults(&self.defaults, path);
        let mut intro = first_sentence(about);
        if optional {
            intro.push_str(" Optional: absent by default.");
        }
        if let Some((_, _, same)) = self
            .written
            .iter()
            .find(|(t, d, _)| *t == section.name && *d == defaults)
        {
            self.out.push_str(&format!(
                "## {heading}\n\n{intro} The fields, ranges and defaults of {same}.\n\n"
            ));
            return;
        }
        self.written
            .push((section.name, defaults.clone(), heading.clone()));
        self.out.push_str(&format!(
            "## {heading}\n\n{intro} (`{}` in {})\n\n",
            section.name, section.file
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
        for f in section.settings() {
            if let Kind::Table(sub) = f.kind {
                subsections.push((f, sub));
                continue;
            }
            let default = match defaults.as_ref().and_then(|d| d.get(f.key)) {
                Some(v) => format!("`{}`", shown(v)),
                None if f.optional => "absent".into(),
                None => "—".into(),
            };
            let meaning = first_sentence(&f.doc_text());
            self.out.push_str(&format!(
                "| `{}` | {} | {} | {default} | {meaning} |\n",
                f.key,
                cell(f.unit_shown()),
                cell(&range_cell(f)),
            ));
            if let Kind::Tables(element) = f.kind {
                subsections.push((f, element));
            }
        }
        self.out.push('\n');
        for (f, sub) in subsections {
            let mut path = path.to_vec();
            path.push(f.key.to_string());
            if matches!(f.kind, Kind::Tables(_)) {
                self.list(&path, sub, &f.doc_text());
            } else {
                self.section(&path, sub, &f.doc_text(), f.optional);
            }
        }
    }

    /// A list of tables (`[[model.leaks]]`): its element's fields, no defaults.
    fn list(&mut self, path: &[String], section: &'static Section, about: &str) {
        self.out.push_str(&format!(
            "## [[{}]]\n\n{} Each entry has every field below. (`{}` in {})\n\n| field | meaning |\n|---|---|\n",
            path.join("."),
            first_sentence(about),
            section.name,
            section.file
        ));
        for f in section.settings() {
            self.out
                .push_str(&format!("| `{}` | {} |\n", f.key, first_sentence(&f.doc_text())));
        }
        self.out.push('\n');
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
         This page is generated from the config types' declarations (each field declared once, with its unit, range, default and doc comment: the `schema` crate): meanings from the doc comments, units and ranges as declared (and checked), defaults from `Config::default()`.\n\
         Do not edit it; regenerate it with `{REGENERATE}`.\n\
         A test (`leakwatch/tests/reference.rs`) fails when it differs from what the command prints.\n\n"
    ));
    w.out.push_str("## The five that matter first\n\n");
    for (fields, why) in FIRST {
        w.out.push_str(&format!("- {fields}: {why}\n"));
    }
    w.out.push('\n');
    for f in Config::SCHEMA.settings() {
        let Kind::Table(section) = f.kind else {
            return Err(format!("Config::{} is not a section", f.key));
        };
        w.section(
            std::slice::from_ref(&f.key.to_string()),
            section,
            &f.doc_text(),
            f.optional,
        );
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
    }
}
