//! docs/config.md is what `leakwatch config --reference` prints: the committed
//! configuration reference cannot fall behind the config types.

use std::path::Path;
use std::process::Command;

/// The command that regenerates docs/config.md (named in the failure).
const REGENERATE: &str = "cargo run -p leakwatch -- config --reference > docs/config.md";

#[test]
fn docs_config_md_is_what_config_reference_prints() {
    let out = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["config", "--reference"])
        .output()
        .expect("leakwatch runs");
    assert!(
        out.status.success(),
        "config --reference failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8(out.stdout).expect("UTF-8");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/config.md");
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if printed == committed {
        return;
    }
    let (n, (was, is)) = committed
        .lines()
        .map(Some)
        .chain(std::iter::repeat(None))
        .zip(printed.lines().map(Some).chain(std::iter::repeat(None)))
        .enumerate()
        .find(|(_, (a, b))| a != b)
        .unwrap_or((0, (None, None)));
    panic!(
        "docs/config.md differs from what `leakwatch config --reference` prints, first at line {}:\n  \
         docs/config.md: {}\n  the command:    {}\nRegenerate it: {REGENERATE}",
        n + 1,
        was.unwrap_or("(end of file)"),
        is.unwrap_or("(end of output)"),
    );
}

#[test]
fn the_reference_names_the_command_that_regenerates_it() {
    let out = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["config", "--reference"])
        .output()
        .expect("leakwatch runs");
    let printed = String::from_utf8(out.stdout).expect("UTF-8");
    assert!(printed.starts_with("# Configuration reference\n"), "{printed}");
    assert!(printed.contains(REGENERATE), "{printed}");
    assert!(printed.contains("\n## [classifier]\n"), "{printed}");
    assert!(
        printed.contains("| `false_alarms_per_hour` | per hour |"),
        "{printed}"
    );
}
