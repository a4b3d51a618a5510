//! `leakwatch replay` end to end on real files: wiring-independent results,
//! detection written to events.json, and bad input reported line by line
//! without poisoning the filter.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::*;

#[path = "replay/bad_input.rs"]
mod bad_input;
#[path = "replay/recorded_logs.rs"]
mod recorded_logs;
#[path = "replay/reporting.rs"]
mod reporting;
#[path = "replay/results.rs"]
mod results;

fn simulate(dir: &Path, scenario: &str, seconds: &str, fault: &str) -> PathBuf {
    let out = dir.join("in.csv");
    let o = leakwatch(&[
        "simulate",
        "--scenario",
        scenario,
        "--seconds",
        seconds,
        "--fault",
        fault,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn replay(input: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["replay", input.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    leakwatch(&args)
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The command ran: exit status 0, or 3 when its detector never armed (a short file).
fn ran(o: &std::process::Output) -> bool {
    matches!(o.status.code(), Some(0) | Some(3))
}
