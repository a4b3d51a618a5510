//! What the leaks do to the rod: external drift, internal stroke loss, the leak-flow column.

use model::dynamics::I_X;
use model::fault::Fault;
use model::leakage::{LeakLaw, LeakPath};
use model::params::{ActuatorParams, FrictionPreset};
use model::sensors::SensorParams;
use model::sim::SimSettings;
use model::units::m3_s_to_lpm;

use crate::{run_truth, sim};

fn mean_position(name: &str, faults: Vec<Fault>, seconds: f64, from_s: f64) -> (f64, f64) {
    let mut s = sim(
        name,
        ActuatorParams::default(),
        faults,
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let states = run_truth(&mut s, seconds);
    let tail = &states[(from_s * 1000.0) as usize..];
    let mean = tail.iter().map(|s| s[I_X]).sum::<f64>() / tail.len() as f64;
    let xmin = tail.iter().map(|s| s[I_X]).fold(f64::MAX, f64::min);
    let xmax = tail.iter().map(|s| s[I_X]).fold(f64::MIN, f64::max);
    (mean, (xmax - xmin) / 2.0)
}

#[test]
fn external_leaks_drift_the_rod_towards_the_leaking_chamber() {
    let p = ActuatorParams::default();
    let leak = |path| vec![Fault::from_lpm(path, LeakLaw::SquareRoot, 0.5, 1.0, &p)];
    let (healthy, _) = mean_position("open-loop-sine", vec![], 5.0, 3.0);
    let (ext1, _) = mean_position("open-loop-sine", leak(LeakPath::External1), 5.0, 3.0);
    let (ext2, _) = mean_position("open-loop-sine", leak(LeakPath::External2), 5.0, 3.0);
    // chamber 1 is on the retracted side: losing oil there retracts the rod
    assert!(ext1 < healthy - 5e-3, "ext1 {ext1} vs healthy {healthy}");
    assert!(ext2 > healthy + 5e-3, "ext2 {ext2} vs healthy {healthy}");
}

/// Half the rod's peak-to-peak travel after the first 3 s of an ideal-sensor
/// open-loop sine run of `seconds` on rig `p` with `faults`, m.
fn sine_amplitude(p: &ActuatorParams, faults: Vec<Fault>, seconds: f64) -> f64 {
    let mut s = sim(
        "open-loop-sine",
        p.clone(),
        faults,
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let st = run_truth(&mut s, seconds);
    let tail = &st[3000..];
    let xmin = tail.iter().map(|s| s[I_X]).fold(f64::MAX, f64::min);
    let xmax = tail.iter().map(|s| s[I_X]).fold(f64::MIN, f64::max);
    (xmax - xmin) / 2.0
}

#[test]
fn internal_leak_shrinks_the_stroke() {
    let p = ActuatorParams::default().with_friction_preset(FrictionPreset::Smooth);
    let mk = |faults| sine_amplitude(&p, faults, 6.0);
    let healthy = mk(vec![]);
    let leaky = mk(vec![Fault::from_lpm(
        LeakPath::Internal,
        LeakLaw::SquareRoot,
        2.0,
        0.0,
        &p,
    )]);
    assert!(
        leaky < 0.97 * healthy,
        "internal leak amplitude {leaky} vs healthy {healthy}"
    );

    // The thesis friction (stick-slip), a 0.5 L/min internal leak.
    let thesis = ActuatorParams::default();
    let mk = |faults| sine_amplitude(&thesis, faults, 10.0);
    let healthy = mk(vec![]);
    let leaky = mk(vec![Fault::from_lpm(
        LeakPath::Internal,
        LeakLaw::SquareRoot,
        0.5,
        0.0,
        &thesis,
    )]);
    eprintln!(
        "thesis friction, 0.5 L/min internal leak: amplitude {:.3} mm vs healthy {:.3} mm ({:+.2} %)",
        leaky * 1e3,
        healthy * 1e3,
        (leaky / healthy - 1.0) * 100.0
    );
    // Measured: 28.89 mm against 30.61 mm, a 5.6 % shrink (2.0 % at 0.25 L/min,
    // 11.2 % at 1 L/min); the stick-slip cycle repeats exactly, so the figure is not noise.
    assert!(
        leaky < 0.97 * healthy && leaky > 0.90 * healthy,
        "thesis friction: internal leak amplitude {leaky} vs healthy {healthy} (measured -5.6 %)"
    );
}

#[test]
fn leak_flow_column_reports_the_delivered_flow() {
    let p = ActuatorParams::default();
    let f = Fault::from_lpm(LeakPath::External1, LeakLaw::SquareRoot, 0.5, 1.0, &p);
    let mut s = sim(
        "closed-loop-sine",
        p,
        vec![f],
        SensorParams::ideal(),
        SimSettings::default(),
    );
    let samples = s.run(3.0);
    assert!(samples[..1000].iter().all(|s| s.q_leak_lpm == 0.0));
    for smp in &samples[1000..] {
        let expect = m3_s_to_lpm(f.coefficient * smp.p1_pa.sqrt());
        assert!((smp.q_leak_lpm - expect).abs() < 1e-9);
    }
    // delivered flow: 0.56..1.25 of the nominal 0.5 L/min (docs/model.md#delivered-leak-flow)
    let mean = samples[1000..].iter().map(|s| s.q_leak_lpm).sum::<f64>() / 2000.0;
    assert!((0.28..0.63).contains(&mean), "{mean}");
}
