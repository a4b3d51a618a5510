//! Reading a config struct from its source: its fields, their types and doc
//! comments, in the order they are declared (`#[serde(skip)]` ones left out).

use super::SOURCES;

/// One field of a config struct, as its source declares it.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Field {
    /// The TOML key.
    pub(super) name: String,
    /// The Rust type, as written (`f64`, `Option<Friction>`, `live::ZenohConfig`).
    pub(super) ty: String,
    /// The doc comment, its lines joined with spaces.
    pub(super) doc: String,
}

/// A struct of the configuration: its doc comment and its fields.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct StructDoc {
    /// Where it is declared (path from the workspace root).
    pub(super) file: &'static str,
    /// Its fields that are config keys (`#[serde(skip)]` ones left out).
    pub(super) fields: Vec<Field>,
}

/// The struct `name` from [`SOURCES`], or why not.
pub(super) fn find_struct(name: &str) -> Result<StructDoc, String> {
    for (file, text) in SOURCES {
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        let Some(start) = struct_start(&lines, name) else {
            continue;
        };
        let fields = read_fields(file, name, &lines[start + 1..])?;
        return Ok(StructDoc { file, fields });
    }
    Err(format!(
        "the config type {name} is in none of the reference's sources (add its file to SOURCES in config/src/reference.rs)"
    ))
}

/// The line that opens the struct `name` in its (trimmed) source.
pub(super) fn struct_head(name: &str) -> String {
    format!("pub struct {name} {{")
}

/// The index of the line that opens the struct `name`, if `lines` declare it.
fn struct_start(lines: &[&str], name: &str) -> Option<usize> {
    let head = struct_head(name);
    lines.iter().position(|l| *l == head)
}

/// The config fields of the struct `name` in `file`, from the (trimmed) lines after its
/// head up to its closing `}`: doc comments, attributes and `pub` fields, in order.
fn read_fields(file: &str, name: &str, body: &[&str]) -> Result<Vec<Field>, String> {
    let mut fields = Vec::new();
    let mut doc: Vec<&str> = Vec::new();
    let mut skip = false;
    let mut i = 0;
    while i < body.len() && body[i] != "}" {
        let line = body[i];
        if let Some(d) = line.strip_prefix("///") {
            doc.push(d.trim());
        } else if line.starts_with("#[") {
            let (attr, last) = read_attribute(body, i);
            i = last;
            skip |= skips_field(&attr);
        } else if let Some(decl) = line.strip_prefix("pub ") {
            let (key, ty) = field_decl(file, name, line, decl)?;
            if !skip {
                fields.push(documented_field(file, name, key, ty, &doc)?);
            }
            doc.clear();
            skip = false;
        } else if !line.is_empty() && !line.starts_with("//") {
            return Err(format!(
                "{file}: cannot read `{line}` in {name} (a private field?)"
            ));
        }
        i += 1;
    }
    Ok(fields)
}

/// The attribute that starts at `lines[i]`, its lines joined (it may span several),
/// and the index of its last line.
fn read_attribute(lines: &[&str], mut i: usize) -> (String, usize) {
    let mut attr = lines[i].to_string();
    while !attr.ends_with(']') && i + 1 < lines.len() {
        i += 1;
        attr.push_str(lines[i]);
    }
    (attr, i)
}

/// Whether an attribute keeps its field out of the config (`#[serde(skip)]`, `skip_deserializing`).
fn skips_field(attr: &str) -> bool {
    let compact: String = attr.chars().filter(|c| !c.is_whitespace()).collect();
    compact.contains("serde(skip)") || compact.contains("skip_deserializing")
}

/// A field's key and type, as written, from its `line` (`decl` is the line after `pub `).
fn field_decl<'a>(file: &str, name: &str, line: &str, decl: &'a str) -> Result<(&'a str, &'a str), String> {
    decl.split_once(':')
        .ok_or_else(|| format!("{file}: cannot read the field `{line}` of {name}"))
}

/// The field `key: ty` of the struct `name` with its doc comment's lines, or the error that it has none.
fn documented_field(file: &str, name: &str, key: &str, ty: &str, doc: &[&str]) -> Result<Field, String> {
    if doc.is_empty() {
        return Err(format!("{file}: {name}::{key} has no doc comment"));
    }
    Ok(Field {
        name: key.trim().to_string(),
        ty: ty.trim().trim_end_matches(',').trim().to_string(),
        doc: doc.join(" "),
    })
}
