//! Outliers on one transducer are kept out of the filter's update
//! (`filter::outlier`): a recording with 2 MPa spikes on p2 (or 5 mm on x)
//! twice a second leaves the leak sizes and the oil's stiffness where the
//! clean recording leaves them.

use filter::{Estimator, Tuning};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

/// Leak sizes (L/min) and θ at the end of `samples`, with every 500th reading
/// of channel `ch` (0: x, 2: p2) moved by `spike`; and the readings left out.
fn run(samples: &[model::Sample], ch: usize, spike: f64) -> ([f64; 3], f64, u64) {
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let mut last = None;
    for (i, s) in samples.iter().enumerate() {
        let mut s = *s;
        if i % 500 == 250 {
            match ch {
                0 => s.x_m += spike,
                _ => s.p2_pa += spike,
            }
        }
        last = Some(est.on_sample(&s));
    }
    let e = last.unwrap();
    (
        std::array::from_fn(|k| e.state[7 + k] * 6e4),
        e.bulk_scale,
        est.counters().outliers,
    )
}

#[test]
fn spikes_on_one_transducer_leave_the_leak_sizes_and_the_oils_stiffness() {
    let rig = ActuatorParams::default();
    let scenario = Scenario::by_name("loaded-random", 4, 40.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, FaultSchedule::default(), 4).unwrap();
    let samples: Vec<model::Sample> = (0..40_000).map(|_| sim.step()).collect();
    let (clean, theta, none) = run(&samples, 2, 0.0);
    assert_eq!(none, 0, "no reading of a clean recording is an outlier");
    for (ch, spike) in [(2, 2.0e6), (0, 5.0e-3)] {
        let (sizes, th, left_out) = run(&samples, ch, spike);
        eprintln!(
            "channel {ch}: sizes {sizes:?} against {clean:?}, θ {th} against {theta}, {left_out} left out"
        );
        assert!(left_out >= 72, "{left_out} of 80 spikes left out");
        for k in 0..3 {
            assert!(
                (sizes[k] - clean[k]).abs() < 0.005,
                "size {k}: {} against {}",
                sizes[k],
                clean[k]
            );
        }
        assert!((th / theta - 1.0).abs() < 0.002, "θ {th} against {theta}");
    }
}
