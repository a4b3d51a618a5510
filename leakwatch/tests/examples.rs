//! The README's `calibrate` and `commission` outputs are made by
//! docs/examples.sh: this test runs the script with this build and compares
//! its outputs with the committed docs/examples/*.txt, and the README's
//! blocks (lines picked from them, `...` for those left out) with those.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{stderr, tmpdir};

/// The repository's root (the workspace).
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The lines of the README's ```text block that follows the line naming `file`,
/// without the block's three-space list indent.
fn readme_block(readme: &str, file: &str) -> Vec<String> {
    let start = readme
        .lines()
        .position(|l| l.contains(file))
        .unwrap_or_else(|| panic!("the README names {file}"));
    readme
        .lines()
        .skip(start + 1)
        .skip_while(|l| l.trim() != "```text")
        .skip(1)
        .take_while(|l| l.trim() != "```")
        .map(|l| l.strip_prefix("   ").unwrap_or(l).to_string())
        .collect()
}

/// The first of `shown` (a block's lines, `...` for lines left out) that is
/// not a line of `output` in order, if any.
fn first_not_in_order<'a>(shown: &'a [String], output: &str) -> Option<&'a str> {
    let mut lines = output.lines();
    shown
        .iter()
        .filter(|l| l.trim() != "...")
        .find(|l| !lines.any(|o| o == l.as_str()))
        .map(String::as_str)
}

#[test]
fn the_readmes_calibrate_and_commission_outputs_are_what_docs_examples_sh_makes() {
    let dir = tmpdir("examples");
    let o = Command::new("sh")
        .arg(repo().join("docs/examples.sh"))
        .arg(dir.path())
        .env("LEAKWATCH", env!("CARGO_BIN_EXE_leakwatch"))
        .output()
        .unwrap();
    assert!(o.status.success(), "docs/examples.sh: {}", stderr(&o));
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    for name in ["calibrate.txt", "commission.txt"] {
        let made = std::fs::read_to_string(dir.path().join(name)).unwrap();
        let committed = std::fs::read_to_string(repo().join("docs/examples").join(name)).unwrap();
        assert_eq!(
            made, committed,
            "docs/examples/{name} is not what this build prints: run `sh docs/examples.sh` and commit it"
        );
        let shown = readme_block(&readme, &format!("docs/examples/{name}"));
        assert!(shown.len() >= 5, "{name}: {shown:?}");
        if let Some(l) = first_not_in_order(&shown, &made) {
            panic!(
                "the README's block for {name} shows a line the output does not have (in that order): {l}"
            );
        }
    }
}

#[test]
fn a_block_line_out_of_order_or_changed_is_caught() {
    let output = "a\n  b 1.0\nc\n";
    let block = |ls: &[&str]| ls.iter().map(|l| l.to_string()).collect::<Vec<_>>();
    assert_eq!(first_not_in_order(&block(&["a", "...", "c"]), output), None);
    assert_eq!(first_not_in_order(&block(&["  b 1.0", "c"]), output), None);
    assert_eq!(first_not_in_order(&block(&["c", "a"]), output), Some("a"));
    assert_eq!(first_not_in_order(&block(&["  b 1.1"]), output), Some("  b 1.1"));
}
