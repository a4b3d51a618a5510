//! The ROS 2 interface package `leakwatch_msgs/` at the repository's root
//! holds exactly the message definitions the recorder writes into a log's
//! schemas, one `.msg` file per type, so the two cannot drift.

use std::collections::BTreeMap;
use std::path::PathBuf;

use recorder::{LogWriter, WriterOptions};

/// The rosbag2 separator before each dependency of a concatenated ros2msg schema.
const SEPARATOR: &str =
    "\n================================================================================\nMSG: ";

/// The repository's `leakwatch_msgs/` folder.
fn package_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(recorder::msg::PACKAGE)
}

/// Every `.msg` file of the package: type name → text.
fn msg_files() -> BTreeMap<String, String> {
    let dir = package_dir().join("msg");
    let mut files = BTreeMap::new();
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) == Some("msg") {
            let name = path.file_stem().unwrap().to_str().unwrap().to_string();
            let text = std::fs::read_to_string(&path).unwrap();
            files.insert(name, text);
        }
    }
    files
}

/// Every message type in the schemas of a log the recorder writes, each with
/// its definition as written (the top-level types and their dependencies).
fn written_definitions() -> BTreeMap<String, String> {
    let dir = scratch::ScratchDir::new("recorder-ros2-package");
    let path = dir.join("run.mcap");
    let w = LogWriter::create(&path, WriterOptions::default()).unwrap();
    w.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    assert_eq!(summary.schemas.len(), 7, "one schema per channel");
    let package = recorder::msg::PACKAGE;
    let mut defs = BTreeMap::new();
    let mut add = |name: &str, text: &str| {
        if let Some(old) = defs.insert(name.to_string(), text.to_string()) {
            assert_eq!(old, text, "{name} is written with two definitions");
        }
    };
    for schema in summary.schemas.values() {
        assert_eq!(schema.encoding, "ros2msg", "{}", schema.name);
        let name = schema
            .name
            .strip_prefix(&format!("{package}/msg/"))
            .unwrap_or_else(|| panic!("{} is not a type of {package}", schema.name));
        let data = std::str::from_utf8(&schema.data).unwrap();
        let mut parts = data.split(SEPARATOR);
        add(name, parts.next().unwrap());
        for dep in parts {
            let (dep_name, text) = dep.split_once('\n').unwrap();
            let dep_name = dep_name
                .strip_prefix(&format!("{package}/"))
                .unwrap_or_else(|| panic!("{dep_name} (in {name}) is not a type of {package}"));
            add(dep_name, text);
        }
    }
    defs
}

#[test]
fn each_msg_file_is_the_definition_the_recorder_writes() {
    let files = msg_files();
    let written = written_definitions();
    assert_eq!(
        files.keys().collect::<Vec<_>>(),
        written.keys().collect::<Vec<_>>(),
        "the .msg files of {} and the types in a log's schemas",
        package_dir().display()
    );
    for (name, text) in &written {
        assert_eq!(
            &files[name], text,
            "{name}.msg differs from its schema in the log"
        );
    }
}

#[test]
fn the_package_builds_every_msg_file() {
    let dir = package_dir();
    let xml = std::fs::read_to_string(dir.join("package.xml")).unwrap();
    let package = recorder::msg::PACKAGE;
    assert!(
        xml.contains(&format!("<name>{package}</name>")),
        "package.xml names {package}"
    );
    assert!(xml.contains("<member_of_group>rosidl_interface_packages</member_of_group>"));
    let cmake = std::fs::read_to_string(dir.join("CMakeLists.txt")).unwrap();
    assert!(cmake.contains(&format!("project({package})")));
    let listed: Vec<&str> = cmake
        .lines()
        .filter_map(|l| l.trim().strip_prefix("\"msg/")?.strip_suffix(".msg\""))
        .collect();
    let files = msg_files();
    assert_eq!(
        listed,
        files.keys().map(String::as_str).collect::<Vec<_>>(),
        "rosidl_generate_interfaces in CMakeLists.txt lists every .msg file, sorted"
    );
}

/// Every line of every `.msg` file is one rosidl accepts: a comment, or a field
/// `TYPE name` / constant `TYPE NAME=VALUE` (then an optional comment), with a
/// primitive type or a message of the package, and names as rosidl's parser
/// requires them (lower snake case fields, upper snake case constants; no
/// double or trailing underscore); message names are CamelCase.
#[test]
fn the_msg_files_follow_rosidls_rules() {
    const PRIMITIVES: [&str; 5] = ["uint32", "uint64", "float64", "string", "uint8"];
    let files = msg_files();
    let package = recorder::msg::PACKAGE;
    let snake = |s: &str, upper: bool| {
        let first_ok = s.chars().next().is_some_and(|c| {
            if upper {
                c.is_ascii_uppercase()
            } else {
                c.is_ascii_lowercase()
            }
        });
        let rest_ok = s.chars().all(|c| {
            c == '_'
                || c.is_ascii_digit()
                || if upper {
                    c.is_ascii_uppercase()
                } else {
                    c.is_ascii_lowercase()
                }
        });
        first_ok && rest_ok && !s.contains("__") && !s.ends_with('_')
    };
    for (name, text) in &files {
        assert!(
            name.chars().next().is_some_and(|c| c.is_ascii_uppercase())
                && name.chars().all(|c| c.is_ascii_alphanumeric()),
            "{name}: a message name is CamelCase"
        );
        for (i, line) in text.lines().enumerate() {
            let code = line.split('#').next().unwrap_or("").trim();
            if code.is_empty() {
                continue;
            }
            let at = format!("{name}.msg line {}: {line:?}", i + 1);
            let mut parts = code.split_whitespace();
            let (ty, rest) = (parts.next().unwrap(), parts.collect::<Vec<_>>().join(" "));
            // an unbounded array of a primitive: `float64[]`
            let ty = ty.strip_suffix("[]").unwrap_or(ty);
            let known = PRIMITIVES.contains(&ty)
                || ty
                    .strip_prefix(&format!("{package}/"))
                    .is_some_and(|m| files.contains_key(m));
            assert!(known, "{at}: type {ty}");
            match rest.split_once('=') {
                Some((constant, value)) => {
                    assert!(snake(constant.trim(), true), "{at}: constant name");
                    assert!(PRIMITIVES[..3].contains(&ty), "{at}: a constant is a number");
                    assert!(value.trim().parse::<u64>().is_ok(), "{at}: value");
                }
                None => assert!(snake(&rest, false), "{at}: field name"),
            }
        }
    }
}
