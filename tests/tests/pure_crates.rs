//! The workspace's layering rule: the pure crates (the model, the
//! EKF, the detectors, the calibration and what they build on) depend on no
//! process machinery: not on iceoryx2 (nor `bus` or `frames`, which carry it),
//! clap or toml. The process shells live in the stage crates (`estimator`,
//! `classifier`, ...) and in `leakwatch`. The `config` crate (the config
//! file's schema) is pure but for `toml`: every stage loads it.
//!
//! Read from each pure crate's Cargo.toml (normal and build dependencies; dev
//! dependencies may be anything): a forbidden name fails, and so does a
//! workspace crate that is not itself on the pure list, which keeps the rule
//! transitive without running `cargo tree`.

use std::path::{Path, PathBuf};

/// The crates that must stay pure.
const PURE: [&str; 7] = [
    "schema",
    "model",
    "dataset",
    "plot",
    "filter",
    "detect",
    "calibrate",
];

/// Dependencies no pure crate may have.
const FORBIDDEN: [&str; 5] = ["iceoryx2", "bus", "frames", "clap", "toml"];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the workspace root")
        .to_path_buf()
}

/// The names of the normal and build dependencies in a Cargo.toml (a renamed
/// dependency counts under both names).
fn dependencies(manifest: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_deps = false;
    for line in manifest.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.starts_with('[') {
            let header = line.trim_matches(|c| c == '[' || c == ']');
            let last = |s: &str| s.rsplit('.').next().unwrap_or("").to_string();
            // [dependencies], [build-dependencies], [target.'cfg(..)'.dependencies],
            // or [dependencies.NAME]
            let is_deps = |s: &str| s == "dependencies" || s == "build-dependencies";
            if let Some(name) = header
                .strip_prefix("dependencies.")
                .or_else(|| header.strip_prefix("build-dependencies."))
            {
                out.push(name.trim().to_string());
                in_deps = false;
            } else {
                in_deps = is_deps(&last(header));
            }
            continue;
        }
        if !in_deps || line.is_empty() {
            continue;
        }
        let name: String = line
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
            .collect();
        if !name.is_empty() {
            out.push(name);
        }
        if let Some(rest) = line.split("package").nth(1) {
            if let Some(pkg) = rest.split('"').nth(1) {
                out.push(pkg.to_string());
            }
        }
    }
    out
}

fn workspace_members() -> Vec<String> {
    let text = std::fs::read_to_string(root().join("Cargo.toml")).expect("workspace Cargo.toml");
    let members = text.split("members").nth(1).expect("members");
    let list = members.split(']').next().expect("member list");
    list.split('"').skip(1).step_by(2).map(str::to_string).collect()
}

#[test]
fn pure_crates_depend_on_no_process_machinery() {
    let members = workspace_members();
    let mut problems = Vec::new();
    for krate in PURE {
        assert!(
            members.iter().any(|m| m == krate),
            "{krate} is not a workspace member: update PURE"
        );
        let path = root().join(krate).join("Cargo.toml");
        let text = std::fs::read_to_string(&path).expect("Cargo.toml");
        for dep in dependencies(&text) {
            if FORBIDDEN.contains(&dep.as_str()) {
                problems.push(format!("{krate} depends on {dep}"));
            } else if members.contains(&dep) && !PURE.contains(&dep.as_str()) {
                problems.push(format!("{krate} depends on {dep}, which is not a pure crate"));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "pure crates must not depend on iceoryx2, clap or toml: {problems:?}"
    );
}

#[test]
fn the_reader_sees_what_a_manifest_lists() {
    let text = "[package]\nname = \"x\"\n\n[dependencies]\nmodel.workspace = true\n\
                serde = { version = \"1\" }  # note\nargs = { package = \"clap\", version = \"4\" }\n\n\
                [dev-dependencies]\ntoml.workspace = true\n\n\
                [target.'cfg(unix)'.dependencies]\nlibc = \"0.2\"\n\n[dependencies.iceoryx2]\nversion = \"0.10\"\n";
    assert_eq!(
        dependencies(text),
        ["model", "serde", "args", "clap", "libc", "iceoryx2"]
    );
}

/// A type has one path: the stage crates do not re-export the pure crates they wrap.
#[test]
fn the_stage_crates_do_not_reexport_the_pure_ones() {
    for (stage, pure) in [("estimator", "filter"), ("classifier", "detect")] {
        let lib = std::fs::read_to_string(root().join(stage).join("src/lib.rs")).expect("lib.rs");
        assert!(
            !lib.contains(&format!("pub use {pure}::")),
            "{stage} re-exports {pure}: use {pure}'s own path"
        );
    }
}

#[test]
fn the_config_crate_needs_no_process_machinery_but_toml() {
    let members = workspace_members();
    let text = std::fs::read_to_string(root().join("config/Cargo.toml")).expect("config/Cargo.toml");
    let deps = dependencies(&text);
    assert!(deps.iter().any(|d| d == "toml"), "{deps:?}");
    let problems: Vec<&String> = deps
        .iter()
        .filter(|d| {
            (FORBIDDEN.contains(&d.as_str()) && d.as_str() != "toml")
                || (members.contains(d) && !PURE.contains(&d.as_str()))
        })
        .collect();
    assert!(
        problems.is_empty(),
        "config may depend on pure crates and toml only: {problems:?}"
    );
}
