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
    assert_eq!(summary.schemas.len(), 6, "one schema per channel");
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
