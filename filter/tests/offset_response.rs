//! The filter's response to a pressure transducer's offset
//! (`Estimate::offset_response_lpm_per_mpa`) against finite differences: the
//! same recording run twice, once with a small offset added to p1 (p2) from
//! the start, moves the leak sizes by the response times the offset.

use filter::{Estimator, Tuning};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

/// Leak sizes (L/min) of each estimate over a recording, with `offset_pa` added to channel `ch` (1: p1, 2: p2).
fn run(samples: &[model::Sample], ch: usize, offset_pa: f64) -> (Vec<[f64; 3]>, Vec<[[f64; 3]; 2]>) {
    let mut est = Estimator::new(ActuatorParams::default(), Tuning::sensor_derived()).unwrap();
    let (mut sizes, mut responses) = (Vec::new(), Vec::new());
    for s in samples {
        let mut s = *s;
        match ch {
            1 => s.p1_pa += offset_pa,
            _ => s.p2_pa += offset_pa,
        }
        let e = est.on_sample(&s);
        sizes.push(std::array::from_fn(|k| e.state[7 + k] * 6e4));
        responses.push(e.offset_response_lpm_per_mpa);
    }
    (sizes, responses)
}

#[test]
fn an_offset_moves_the_leak_sizes_as_the_response_predicts() {
    let rig = ActuatorParams::default();
    let scenario = Scenario::by_name("loaded-random", 4, 40.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, FaultSchedule::default(), 4).unwrap();
    let samples: Vec<model::Sample> = (0..40_000).map(|_| sim.step()).collect();
    let offset_pa = 2.0e4;
    for ch in [1, 2] {
        let (base, response) = run(&samples, ch, 0.0);
        let (moved, _) = run(&samples, ch, offset_pa);
        // From 10 s on (the filter has converged): the change of each size
        // against the response's prediction, over every sample.
        let (mut err2, mut pred2) = (0.0, 0.0);
        for i in 10_000..samples.len() {
            for k in 0..3 {
                let predicted = response[i][ch - 1][k] * offset_pa * 1e-6;
                let seen = moved[i][k] - base[i][k];
                err2 += (seen - predicted).powi(2);
                pred2 += predicted.powi(2);
            }
        }
        let rel = (err2 / pred2).sqrt();
        assert!(pred2 > 0.0, "p{ch}: the response is zero");
        assert!(
            rel < 0.1,
            "p{ch}: the response misses the change by {:.0} % (RMS)",
            100.0 * rel
        );
    }
}
