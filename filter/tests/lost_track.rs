//! A filter kicked off its track re-anchors (`filter::track`): a sample whose
//! position and p2 are far off on both channels (no lone outlier) throws its
//! state off, the next reading is far off that state, and the filter takes
//! its fast states from the reading after; its leak sizes end where the clean
//! recording's end. A lone outlier, left out of the update, does not.

use filter::{Estimator, Tuning, FLAG_REANCHORED};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

/// Leak sizes (L/min) at the end, and the samples flagged re-anchored, with
/// samples `kicked` moved by `dx_m` on x and `dp2_pa` on p2.
fn run(samples: &[model::Sample], kicked: &[usize], dx_m: f64, dp2_pa: f64) -> ([f64; 3], Vec<usize>) {
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let mut reanchored = Vec::new();
    let mut last = None;
    for (i, s) in samples.iter().enumerate() {
        let mut s = *s;
        if kicked.contains(&i) {
            s.x_m += dx_m;
            s.p2_pa += dp2_pa;
        }
        let e = est.on_sample(&s);
        if e.flags & FLAG_REANCHORED != 0 {
            reanchored.push(i);
        }
        last = Some(e);
    }
    let e = last.unwrap();
    (std::array::from_fn(|k| e.state[7 + k] * 6e4), reanchored)
}

#[test]
fn a_filter_kicked_off_its_track_re_anchors_and_keeps_its_leak_sizes() {
    let scenario = Scenario::by_name("closed-loop-sine", 7, 30.0).unwrap();
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), scenario, FaultSchedule::default(), 7)
            .unwrap();
    let samples: Vec<model::Sample> = (0..30_000).map(|_| sim.step()).collect();
    let (clean, none) = run(&samples, &[], 0.0, 0.0);
    assert!(none.is_empty(), "a clean recording re-anchors at {none:?}");
    // 5 mm spikes on x, one every 2 s: lone outliers
    let spikes: Vec<usize> = (5_000..30_000).step_by(2_000).collect();
    let (_, lone) = run(&samples, &spikes, 5e-3, 0.0);
    assert!(lone.is_empty(), "lone outliers re-anchor at {lone:?}");
    let (sizes, kicked) = run(&samples, &[15_000], 3e-3, 2e6);
    assert_eq!(
        kicked,
        vec![15_002],
        "re-anchored on the second sample after the kick"
    );
    for k in 0..3 {
        assert!(
            (sizes[k] - clean[k]).abs() < 0.01,
            "size {k}: {} L/min against {} L/min clean",
            sizes[k],
            clean[k]
        );
    }
}
