//! The chain on a seeded simulated run: a leak is found and named, and the
//! thesis filter runs only where something reads it.

use detect::{EventKind, Phase};
use model::{Fault, FaultSchedule, Scenario, Simulator};
use pipeline::{Chain, ChainSettings};

/// 40 s of the loaded sine on the built-in rig, an external leak of chamber 1
/// (0.5 L/min) from 20 s, seed 7: the demonstration's defaults.
fn samples() -> Vec<model::Sample> {
    let rig = model::ActuatorParams::default();
    let schedule = FaultSchedule {
        faults: vec![Fault::parse("ext1:0.5lpm@20s", &rig).expect("fault")],
    };
    let scenario = Scenario::by_name("loaded-sine", 7, 40.0).expect("scenario");
    let mut sim = Simulator::with_default_sensors(rig, scenario, schedule, 7).expect("rig");
    sim.run(40.0)
}

#[test]
fn the_default_chain_names_an_external_leak_after_its_onset() {
    let mut chain = Chain::new(&ChainSettings::default()).expect("chain");
    assert!(!chain.stage().thesis_runs());
    let mut raised = Vec::new();
    for s in &samples() {
        let e = chain.step(s, |ev| {
            if ev.phase == Phase::Raised && ev.kind.is_leak_alarm() && ev.detector == "leak-size" {
                raised.push(ev)
            }
        });
        assert!(e.thesis.state[0].is_nan(), "the thesis filter does not run");
    }
    let named = raised
        .iter()
        .find(|ev| ev.kind == EventKind::Ext1)
        .unwrap_or_else(|| panic!("no ext1 alarm: {raised:?}"));
    assert!(raised.iter().all(|ev| ev.t_detect_s > 20.0), "{raised:?}");
    assert!(named.t_detect_s < 25.0, "{named:?}");
    assert!((named.size_lpm - 0.5).abs() < 0.1, "{named:?}");
}

#[test]
fn the_thesis_filter_runs_with_its_baseline_or_when_asked() {
    let mut set = ChainSettings::default();
    set.classifier.thesis_baseline = true;
    let s = &samples()[..200];
    let mut with_baseline = Chain::new(&set).expect("chain");
    let mut asked = Chain::new(&ChainSettings::default())
        .expect("chain")
        .with_thesis(true);
    for s in s {
        let (a, b) = (with_baseline.step(s, |_| {}), asked.step(s, |_| {}));
        assert!(a.thesis.state[0].is_finite() && b.thesis.state[0].is_finite());
        assert_eq!(a.leak.state.map(f64::to_bits), b.leak.state.map(f64::to_bits));
    }
    // the leak stage alone: the same leak filter, bit for bit
    let mut leak = ChainSettings::default().leak_stage().expect("stage");
    let mut chain = Chain::new(&ChainSettings::default()).expect("chain");
    for s in s {
        let (a, b) = (leak.on_sample(s), chain.step(s, |_| {}));
        assert_eq!(a.leak.state.map(f64::to_bits), b.leak.state.map(f64::to_bits));
    }
}
