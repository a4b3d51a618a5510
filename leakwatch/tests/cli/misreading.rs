//! Commissioning fits the transducers' misreading at the working point.

use crate::common::*;

use crate::{datasheet_config, simulate_scenario};

/// The press's datasheet config (`Datasheet::press` and the `[model]` facts
/// no datasheet gives), its simulated transducers reading off by
/// `installation` (a `[sensors]` table).
fn press_config(installation: &str) -> String {
    let mut cfg = datasheet_config(model::Datasheet::press(), &model::ActuatorParams::press());
    cfg.insert(
        "sensors".into(),
        toml::Value::Table(toml::from_str(installation).unwrap()),
    );
    toml::to_string(&cfg).unwrap()
}

/// `leakwatch commission` of a simulated healthy minute of the press under
/// the config `sheet`, in `d` with names from `name`: its stderr, the
/// config it wrote, and the recording's mean p1 and p2 readings (Pa).
fn commission_press(
    d: &std::path::Path,
    sheet: &std::path::Path,
    name: &str,
) -> (String, toml::Table, [f64; 2]) {
    let rec = d.join(format!("{name}.csv"));
    simulate_scenario("press", sheet, "60", "11", "none", &rec);
    let means = [column_mean(&rec, "p1"), column_mean(&rec, "p2")];
    let out = d.join(format!("{name}.toml"));
    let o = leakwatch(&[
        "commission",
        rec.to_str().unwrap(),
        "--config",
        sheet.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let written = toml::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    (err, written, means)
}

/// The mean of CSV column `name` of `csv`.
fn column_mean(csv: &std::path::Path, name: &str) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = header.iter().position(|h| *h == name).unwrap();
    let v: Vec<f64> = lines.filter_map(|l| l.split(',').nth(i)?.parse().ok()).collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The press's transducers read p1 90 kPa high and p2 80 kPa low on its
/// pressing cycle (offsets and span errors within its datasheet's 50 kPa and
/// 0.5 %). Commissioning fits that misreading within 25 kPa per channel,
/// takes it (its healthy spreads fall) and writes it into `[model]`; on
/// transducers that read true it finds less than 25 kPa.
#[test]
fn commissioning_fits_a_transducers_misreading_and_takes_it_off() {
    let d = tmpdir("misreading");
    let sheet = d.join("datasheet.toml");
    std::fs::write(
        &sheet,
        press_config("pressure_offset_pa = [45e3, -40e3]\npressure_gain_error = [0.004, -0.004]\n"),
    )
    .unwrap();
    let (err, written, means) = commission_press(&d, &sheet, "healthy");
    let truth = [45e3 + 0.004 * means[0], -40e3 - 0.004 * means[1]];
    let line = err
        .lines()
        .find(|l| l.starts_with("transducers' misreading"))
        .unwrap_or_else(|| panic!("no misreading line in {err}"));
    assert!(line.contains("taken off each reading"), "{line}");
    let fitted: Vec<f64> = written["model"]["pressure_misreading_pa"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_float())
        .collect();
    for ch in 0..2 {
        assert!(
            (fitted[ch] - truth[ch]).abs() < 25e3,
            "p{}: fitted {:.0} Pa against {:.0} Pa: {line}",
            ch + 1,
            fitted[ch],
            truth[ch]
        );
    }
    // spreads before -> after: each sum of squares falls
    let spreads: Vec<Vec<f64>> = line
        .split("healthy spreads ")
        .nth(1)
        .unwrap()
        .split(" -> ")
        .map(|s| {
            s.split(['/', ' '])
                .take(3)
                .filter_map(|x| x.parse().ok())
                .collect()
        })
        .collect();
    let energy = |v: &Vec<f64>| v.iter().map(|s| s * s).sum::<f64>();
    assert!(energy(&spreads[1]) < energy(&spreads[0]), "{line}");
    // transducers that read true: nothing much to fit
    let true_sheet = d.join("true.toml");
    std::fs::write(&true_sheet, press_config("pressure_offset_pa = [0.0, 0.0]\n")).unwrap();
    let (err, written, _) = commission_press(&d, &true_sheet, "healthy_true");
    let fitted = written["model"]["pressure_misreading_pa"].as_array().unwrap();
    assert!(
        fitted.iter().all(|v| v.as_float().unwrap().abs() < 25e3),
        "{fitted:?}: {err}"
    );
}
