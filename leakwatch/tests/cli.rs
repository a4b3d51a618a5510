//! The command line as a user meets it: real runs of the built binary.

mod common;
use common::*;

#[path = "cli/bench_plant_folder.rs"]
mod bench_plant_folder;
#[path = "cli/commissioning.rs"]
mod commissioning;
#[path = "cli/config_and_input.rs"]
mod config_and_input;
#[path = "cli/lift.rs"]
mod lift;
#[path = "cli/log_readers.rs"]
mod log_readers;
#[path = "cli/logs.rs"]
mod logs;
#[path = "cli/misreading.rs"]
mod misreading;
#[path = "cli/outputs.rs"]
mod outputs;
#[path = "cli/run.rs"]
mod run;
#[path = "cli/simulate.rs"]
mod simulate;

/// A config as a user writes it for a rig: its `sheet` in `[datasheet]`, and
/// in `[model]` only what no datasheet gives (`model` less the derived fields).
fn datasheet_config(sheet: model::Datasheet, model: &model::ActuatorParams) -> toml::Table {
    let mut rest = toml::Table::try_from(model).unwrap();
    for (section, field, _) in model::datasheet::DERIVED_FIELDS {
        if section == "model" {
            rest.remove(field);
        }
    }
    let mut cfg = toml::Table::new();
    cfg.insert("datasheet".into(), toml::Value::try_from(sheet).unwrap());
    cfg.insert("model".into(), toml::Value::Table(rest));
    cfg
}

/// `seconds` of `scenario` on the config `config`'s rig, with `fault`, to `out`.
fn simulate_scenario(
    scenario: &str,
    config: &std::path::Path,
    seconds: &str,
    seed: &str,
    fault: &str,
    out: &std::path::Path,
) {
    let o = leakwatch(&[
        "simulate",
        "--config",
        config.to_str().unwrap(),
        "--scenario",
        scenario,
        "--seconds",
        seconds,
        "--seed",
        seed,
        "--fault",
        fault,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `simulate --scenario closed-loop-random` of the rig in `config` into `out`.
fn simulate_random(config: &std::path::Path, seconds: &str, seed: &str, fault: &str, out: &std::path::Path) {
    simulate_scenario("closed-loop-random", config, seconds, seed, fault, out);
}
