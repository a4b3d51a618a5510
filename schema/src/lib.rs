//! The config schema: every field of a config section declared once, with its
//! key, unit, range, default and doc comment ([`config_struct!`]). From that one
//! declaration come the struct itself (its doc comments real `#[doc]`s), its
//! `Default`, its table ([`Section`]: what `leakwatch config --reference`
//! prints) and its range checks ([`Section`]'s fields, checked by
//! `check_ranges`, the error naming the field's dotted key, range and unit).
//!
//! Plain Rust, no dependencies: the pure crates (model, filter, detect)
//! declare their own sections with it.

#![forbid(unsafe_code)]

mod declare;

use std::fmt;

/// The values a field may take (checked by `check_ranges`, shown by the reference).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Range {
    /// Any value of the field's type (a flag, text, a list, a section), or
    /// none stated.
    Any,
    /// A finite number from `lo` to `hi`, both included, in the field's unit:
    /// shown `{what} from {lo} to {hi} {unit} {note}` with the bounds as declared.
    Number {
        /// What the number is (`a mass`); empty: the bounds alone.
        what: &'static str,
        /// The least value, in the field's unit.
        lo: f64,
        /// The largest value, in the field's unit.
        hi: f64,
        /// `lo` as declared (`1e-3`).
        lo_text: &'static str,
        /// `hi` as declared (`1e5`).
        hi_text: &'static str,
        /// A remark after the unit (`(0 = none)`), or empty.
        note: &'static str,
    },
    /// A finite number from `lo` (included) up to `hi` (excluded), in the
    /// field's unit: shown `{what} in [{lo}, {hi})`.
    Below {
        /// What the number is (`a fraction`).
        what: &'static str,
        /// The least value, in the field's unit.
        lo: f64,
        /// The bound it stays below, in the field's unit.
        hi: f64,
        /// `lo` as declared.
        lo_text: &'static str,
        /// `hi` as declared.
        hi_text: &'static str,
    },
    /// An integer from `lo` to `hi`, both included, in the field's unit:
    /// shown `{lo} to {hi} {unit} {note}`.
    Integer {
        /// The least value.
        lo: u64,
        /// The largest value.
        hi: u64,
        /// A remark after the unit, or empty.
        note: &'static str,
    },
    /// One of these integers (`6, 7, 10, 11 or 12`).
    OneOf(&'static [u64]),
    /// A range that depends on other fields or on more than a number
    /// (`a force from slip_n to 1e6 N`), as stated here and checked by hand
    /// next to the struct.
    Stated(&'static str),
}

impl Range {
    /// The range as the reference and the errors state it, with `unit`
    /// (`a mass from 1e-3 to 1e5 kg`); empty for [`Range::Any`].
    pub fn text(&self, unit: &str) -> String {
        let with = |mut s: String, parts: &[&str]| {
            for p in parts.iter().filter(|p| !p.is_empty()) {
                s.push(' ');
                s.push_str(p);
            }
            s
        };
        match *self {
            Range::Any => String::new(),
            Range::Number {
                what,
                lo_text,
                hi_text,
                note,
                ..
            } => {
                let bounds = format!("{lo_text} to {hi_text}");
                let head = if what.is_empty() {
                    bounds
                } else {
                    format!("{what} from {bounds}")
                };
                with(head, &[unit, note])
            }
            Range::Below {
                what,
                lo_text,
                hi_text,
                ..
            } => with(format!("{what} in [{lo_text}, {hi_text})"), &[unit]),
            Range::Integer { lo, hi, note } => with(format!("{lo} to {hi}"), &[unit, note]),
            Range::OneOf(values) => {
                let shown: Vec<String> = values.iter().map(u64::to_string).collect();
                match shown.split_last() {
                    Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
                    Some((last, _)) => last.clone(),
                    None => String::new(),
                }
            }
            Range::Stated(text) => text.to_string(),
        }
    }

    /// Whether the number `v` is within the range (a stated range is checked
    /// by hand: always true here).
    pub fn holds_number(&self, v: f64) -> bool {
        match *self {
            Range::Number { lo, hi, .. } => v.is_finite() && (lo..=hi).contains(&v),
            Range::Below { lo, hi, .. } => v.is_finite() && (lo..hi).contains(&v),
            Range::Integer { lo, hi, .. } => v.is_finite() && v >= lo as f64 && v <= hi as f64,
            Range::OneOf(values) => values.iter().any(|x| *x as f64 == v),
            Range::Any | Range::Stated(_) => true,
        }
    }

    /// Whether the integer `v` is within the range.
    pub fn holds_integer(&self, v: u64) -> bool {
        match *self {
            Range::Integer { lo, hi, .. } => (lo..=hi).contains(&v),
            Range::OneOf(values) => values.contains(&v),
            _ => self.holds_number(v as f64),
        }
    }
}

/// What kind of value a field holds (from its Rust type, [`FieldType`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A floating-point number.
    Number,
    /// An integer.
    Integer,
    /// `true` or `false`.
    Flag,
    /// Text (a name, an address, a path).
    Text,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// A list (or a fixed-size array) of values of this kind.
    List(&'static Kind),
    /// A table of names to values.
    Map,
    /// A sub-section (a TOML table).
    Table(&'static Section),
    /// A list of tables (`[[model.leaks]]`).
    Tables(&'static Section),
}

/// One field of a section, as declared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Field {
    /// The TOML key.
    pub key: &'static str,
    /// The doc comment's lines.
    pub doc: &'static [&'static str],
    /// The unit (`kg`, `m²/s²`), empty for none.
    pub unit: &'static str,
    /// The values it may take.
    pub range: Range,
    /// The kind of value.
    pub kind: Kind,
    /// Whether it may be absent (`Option`).
    pub optional: bool,
    /// Whether it is kept out of the file (`#[serde(skip)]`): set by the loader, not a setting.
    pub skipped: bool,
}

impl Field {
    /// The doc comment as one line (its lines trimmed and joined with spaces).
    pub fn doc_text(&self) -> String {
        join_doc(self.doc)
    }

    /// The range as the reference and the errors state it, with the unit.
    pub fn expected(&self) -> String {
        self.range.text(self.unit)
    }

    /// The unit as a column shows it: a unit in parentheses (`(thresholds)`) without them.
    pub fn unit_shown(&self) -> &'static str {
        match self.unit.strip_prefix('(').and_then(|u| u.strip_suffix(')')) {
            Some(inner) if !inner.contains(['(', ')']) => inner,
            _ => self.unit,
        }
    }

    /// The error for `value` (shown as `shown`) at `key`.
    pub fn out_of_range(&self, key: &str, value: f64, shown: String) -> OutOfRange {
        OutOfRange {
            key: key.to_string(),
            value,
            shown,
            expected: self.expected(),
        }
    }
}

/// A section (a config struct): its fields in declaration order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// The Rust type's name (`ActuatorParams`).
    pub name: &'static str,
    /// Where it is declared (path from the workspace root).
    pub file: &'static str,
    /// The struct's doc comment's lines.
    pub doc: &'static [&'static str],
    /// Every field, skipped ones included, in order.
    pub fields: &'static [Field],
}

impl Section {
    /// The fields that are config keys (those not `#[serde(skip)]`), in order.
    pub fn settings(&self) -> impl Iterator<Item = &'static Field> {
        self.fields.iter().filter(|f| !f.skipped)
    }

    /// The setting at the dotted `path` below this section (`["friction",
    /// "static_n"]`), through sub-sections and lists of tables.
    pub fn find(&self, path: &[&str]) -> Option<&'static Field> {
        let (first, rest) = path.split_first()?;
        let field = self.fields.iter().find(|f| f.key == *first && !f.skipped)?;
        if rest.is_empty() {
            return Some(field);
        }
        match field.kind {
            Kind::Table(s) | Kind::Tables(s) => s.find(rest),
            _ => None,
        }
    }
}

/// The doc comment's lines as one line, trimmed and joined with spaces.
pub fn join_doc(lines: &[&str]) -> String {
    lines
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// `prefix.key`, or `key` when `prefix` is empty.
pub fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// A value outside its field's declared range.
#[derive(Debug, Clone, PartialEq)]
pub struct OutOfRange {
    /// The field's dotted key below the section checked (`friction.static_n`).
    pub key: String,
    /// The value as a number (NaN for one that is not).
    pub value: f64,
    /// The value as shown in the error (`1e308`, `64`).
    pub shown: String,
    /// The range, with the unit (`a mass from 1e-3 to 1e5 kg`).
    pub expected: String,
}

impl fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}: must be {}", self.key, self.shown, self.expected)
    }
}

impl std::error::Error for OutOfRange {}

/// A Rust type a config field may have: its [`Kind`], and how a value of it
/// is checked against the field's declared range.
pub trait FieldType {
    /// The kind of value.
    const KIND: Kind;
    /// Whether the field may be absent (`Option`).
    const OPTIONAL: bool = false;
    /// Checks the value against `field`'s range; `key` is its dotted key.
    fn check(&self, key: &str, field: &'static Field) -> Result<(), OutOfRange> {
        let _ = (key, field);
        Ok(())
    }
}

impl FieldType for f64 {
    const KIND: Kind = Kind::Number;
    fn check(&self, key: &str, field: &'static Field) -> Result<(), OutOfRange> {
        if field.range.holds_number(*self) {
            Ok(())
        } else {
            Err(field.out_of_range(key, *self, format!("{self:?}")))
        }
    }
}

macro_rules! integer_field {
    ($($t:ty),*) => {$(
        impl FieldType for $t {
            const KIND: Kind = Kind::Integer;
            fn check(&self, key: &str, field: &'static Field) -> Result<(), OutOfRange> {
                if field.range.holds_integer(*self as u64) {
                    Ok(())
                } else {
                    Err(field.out_of_range(key, *self as f64, self.to_string()))
                }
            }
        }
    )*};
}
integer_field!(u8, u16, u32, u64, usize);

impl FieldType for bool {
    const KIND: Kind = Kind::Flag;
}

impl FieldType for String {
    const KIND: Kind = Kind::Text;
}

impl FieldType for std::path::PathBuf {
    const KIND: Kind = Kind::Text;
}

impl FieldType for std::net::SocketAddr {
    const KIND: Kind = Kind::Text;
}

impl<K, V> FieldType for std::collections::BTreeMap<K, V> {
    const KIND: Kind = Kind::Map;
}

impl<T: FieldType> FieldType for Option<T> {
    const KIND: Kind = T::KIND;
    const OPTIONAL: bool = true;
    fn check(&self, key: &str, field: &'static Field) -> Result<(), OutOfRange> {
        match self {
            Some(v) => v.check(key, field),
            None => Ok(()),
        }
    }
}

impl<T: FieldType, const N: usize> FieldType for [T; N] {
    const KIND: Kind = Kind::List(&T::KIND);
    fn check(&self, key: &str, field: &'static Field) -> Result<(), OutOfRange> {
        self.iter().try_for_each(|v| v.check(key, field))
    }
}

impl<T: FieldType> FieldType for Vec<T> {
    const KIND: Kind = match T::KIND {
        Kind::Table(s) => Kind::Tables(s),
        _ => Kind::List(&T::KIND),
    };
    /// Each element, a table's fields under `key[i]`.
    fn check(&self, key: &str, field: &'static Field) -> Result<(), OutOfRange> {
        for (i, v) in self.iter().enumerate() {
            v.check(&format!("{key}[{i}]"), field)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
