//! `commission`'s HTML record beside its TOML, and a replay on the rig it
//! commissioned.

use std::path::{Path, PathBuf};

use crate::common::html::{row, screenshot, self_contained};
use crate::common::{leakwatch, stderr, tmpdir};
use crate::simulate;
use scratch::ScratchDir;

/// A healthy recording of the built-in rig commissioned in a scratch folder
/// named `name`: the folder, the recording, rig.toml, rig.html, the record's
/// HTML and `commission`'s terminal.
struct Commissioned {
    dir: ScratchDir,
    healthy: PathBuf,
    toml_path: PathBuf,
    html_path: PathBuf,
    html: String,
    err: String,
}

fn commissioned(name: &str) -> Commissioned {
    let dir = tmpdir(name);
    let healthy = dir.join("healthy.csv");
    simulate(
        &[
            "--scenario",
            "closed-loop-random",
            "--seconds",
            "25",
            "--seed",
            "5",
        ],
        &healthy,
    );
    let toml_path = dir.join("rig.toml");
    let o = leakwatch(&[
        "commission",
        healthy.to_str().unwrap(),
        "--out",
        toml_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let html_path = dir.join("rig.html");
    assert!(
        err.contains(&format!(
            "wrote {} (the commissioning record)",
            html_path.display()
        )),
        "{err}"
    );
    let html = std::fs::read_to_string(&html_path).unwrap();
    Commissioned {
        dir,
        healthy,
        toml_path,
        html_path,
        html,
        err,
    }
}

/// A TOML array of numbers as the record prints them (3 decimals).
fn three_decimals(array: &toml::Value) -> Vec<String> {
    array
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{:.3}", v.as_float().unwrap()))
        .collect()
}

/// `replay` of `input` with `config` into `out`; its terminal.
fn replay(input: &Path, config: &Path, out: &Path) -> String {
    let o = leakwatch(&[
        "replay",
        input.to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    stderr(&o)
}

/// `commission` writes rig.html beside rig.toml: the thresholds, offsets,
/// smallest detectable leaks and mean NIS are the terminal's and the TOML's
/// (to their printed decimals); the page loads nothing from outside and opens
/// in headless Chromium (a screenshot is taken).
#[test]
fn the_commissioning_record_holds_the_terminals_and_the_tomls_numbers() {
    let Commissioned {
        dir: d,
        toml_path,
        html_path,
        html,
        err,
        ..
    } = commissioned("commission_report");
    // the thresholds, naming and on all rises: the terminal's line, the report's rows
    let line = err
        .lines()
        .find_map(|l| l.strip_prefix("the detector will name leaks from "))
        .expect("the thresholds are stated");
    let three = |s: &str| -> Vec<String> {
        s.split(' ')
            .next()
            .unwrap()
            .split('/')
            .map(str::to_string)
            .collect()
    };
    assert_eq!(row(&html, "threshold that names the kind"), three(line));
    let on_all = line
        .split("clearly, ")
        .nth(1)
        .expect("the thresholds on all rises");
    assert!(on_all.contains(" on all its rises"), "{line}");
    assert_eq!(row(&html, "threshold on all rises"), three(on_all));
    // the offsets: the TOML's values, the terminal's and the report's
    let t: toml::Table = toml::from_str(&std::fs::read_to_string(&toml_path).unwrap()).unwrap();
    let c = &t["classifier"]["commissioning"];
    let offsets = three_decimals(&c["offsets_lpm"]);
    assert_eq!(row(&html, "healthy offset"), offsets);
    assert!(
        err.contains(&format!("offsets ext1/ext2/int {} L/min", offsets.join("/"))),
        "{err}"
    );
    let spreads = three_decimals(&c["spreads_lpm"]);
    assert_eq!(row(&html, "healthy spread"), spreads);
    // the healthy misreading: the terminal's line where the TOML keeps one, else said none
    let kept = ["healthy_offsets_kpa", "healthy_span_errors"].iter().any(|f| {
        c.get(*f)
            .and_then(|v| v.as_array())
            .is_some_and(|a| a.iter().any(|v| v.as_float() != Some(0.0)))
    });
    match err.lines().find(|l| l.starts_with("the healthy rises swing as")) {
        Some(line) => {
            assert!(kept, "printed but not kept: {line}");
            assert!(html.contains(line), "{line}");
        }
        None => {
            assert!(!kept, "kept but not printed: {c:?}");
            assert!(html.contains("no healthy misreading taken"), "{html}");
        }
    }
    // the smallest detectable leaks per oil temperature
    for temp in ["20", "40", "60"] {
        let at = err.split(&format!("{temp} °C ")).nth(1).unwrap();
        let v: Vec<String> = at
            .split([',', ' ', '\n'])
            .next()
            .unwrap()
            .split('/')
            .map(str::to_string)
            .collect();
        assert_eq!(
            row(&html, &format!("smallest detectable at {temp} °C")),
            v,
            "{temp} °C"
        );
    }
    // the mean NIS: the TOML's, to the terminal's one decimal
    let nis = format!("{:.1}", c["nis_mean"].as_float().unwrap());
    assert!(
        err.contains(&format!("mean NIS on this recording is {nis} ")),
        "{err}"
    );
    assert!(html.contains(&format!("mean NIS on this recording: <b>{nis}</b>")));
    // an identified parameter's line: value and σ as the terminal prints them
    let bulk = err
        .lines()
        .find(|l| l.trim_start().starts_with("effective bulk modulus: "))
        .unwrap();
    let value = bulk.split(": ").nth(1).unwrap().split(' ').next().unwrap();
    assert!(
        html.contains(&format!(
            "<td>effective bulk modulus</td><td class=\"n\">{value}</td>"
        )),
        "{bulk}"
    );

    // self-contained: nothing fetched from outside
    self_contained(&html);
    assert!(html.contains("<svg"));

    screenshot(&html_path, &d);
}

/// A replay with the commissioned rig.toml states the record's thresholds and
/// smallest detectable leaks, its seconds without evidence by cause and the
/// transducers' reach; where commissioning found x not watched, the replay
/// says so at start and in its report.
#[test]
fn a_replay_on_the_commissioned_rig_states_its_record() {
    let Commissioned {
        dir: d,
        healthy,
        toml_path,
        html,
        err,
        ..
    } = commissioned("commission_report_replayed");
    // a replay with the commissioned config states the commissioning's thresholds
    // and smallest detectable leaks in its report
    let replayed = d.join("replayed");
    replay(&healthy, &toml_path, &replayed);
    let report = std::fs::read_to_string(replayed.join("report.html")).unwrap();
    assert!(report.contains("Replay of healthy.csv on the rig of rig.toml"));
    for name in [
        "threshold that names the kind",
        "smallest detectable at 20 °C",
        "smallest detectable at 60 °C",
    ] {
        assert_eq!(row(&report, name), row(&html, name), "{name}");
    }
    assert!(report.contains("Leak alarms (0)"), "a healthy recording");
    // the seconds without evidence by cause add up to the blind seconds, and
    // the report gives summary.json's
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(replayed.join("summary.json")).unwrap()).unwrap();
    let watch = &summary["watch"];
    let causes = watch["blind_by_cause"].as_object().unwrap();
    assert_eq!(causes.len(), 8, "{causes:?}");
    let total: f64 = causes.values().map(|v| v.as_f64().unwrap()).sum();
    assert!(
        (total - watch["blind_s"].as_f64().unwrap()).abs() < 1e-6,
        "{watch}"
    );
    let excursions = format!("{:.1}", causes["excursion_s"].as_f64().unwrap());
    assert_eq!(row(&report, "excursions"), vec![excursions]);
    // the record holds the transducers' reach as the terminal says it; on
    // this rig x is watched (the e2e commissioning test: from 4.1 mm)
    let reach = err
        .lines()
        .find(|l| l.starts_with("transducer offsets named"))
        .unwrap();
    assert!(html.contains(reach), "{reach}");
    assert!(!report.contains("is not watched"));
    // a commissioning that found x not watched (a plant rig's): the replay
    // says so at start and in its report
    let text = std::fs::read_to_string(&toml_path).unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with("least_offsets_named"))
        .unwrap();
    let plant = d.join("plant.toml");
    std::fs::write(
        &plant,
        text.replace(line, "least_offsets_named = [250.0, 250.0, inf]"),
    )
    .unwrap();
    let unwatched = d.join("unwatched");
    let said = replay(&healthy, &plant, &unwatched);
    assert!(said.contains("; an offset on x is not watched"), "{said}");
    let report = std::fs::read_to_string(unwatched.join("report.html")).unwrap();
    assert!(report.contains("<b>An offset on x is not watched (commissioning found"));
}
