//! The hot path's in-place forms (`Estimator::on_sample_into`,
//! `EstimatorStage::on_sample_flagged_into`) write the same estimates as the
//! forms that return them, whatever the buffer held before.

use filter::{Estimate, Estimator, EstimatorStage, StageEstimate, Tuning};
use model::{ActuatorParams, FaultSchedule, Sample, Scenario, Simulator};

/// 2 s of the closed-loop sine with what a stream brings: a sample without
/// pressures before the filter starts, a gap, a NaN command and a restart.
fn stream() -> Vec<Sample> {
    let sc = Scenario::by_name("closed-loop-sine", 3, 2.0).expect("scenario");
    let mut sim = Simulator::with_default_sensors(ActuatorParams::default(), sc, FaultSchedule::default(), 5)
        .expect("rig");
    let mut samples = sim.run(2.0);
    samples[0].p1_pa = f64::NAN;
    samples.drain(700..720);
    samples[900].u_v = f64::NAN;
    let restart = samples[..300].to_vec();
    samples.extend(restart);
    samples
}

/// The same estimate, NaNs included (`PartialEq` says no to NaN fields).
fn same<T: std::fmt::Debug>(a: &T, b: &T) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

#[test]
fn an_estimate_written_in_place_is_the_one_returned_whatever_the_buffer_held() {
    let samples = stream();
    for tuning in [Tuning::sensor_derived(), Tuning::thesis()] {
        let mut returned = Estimator::new(ActuatorParams::default(), tuning.clone()).expect("estimator");
        let mut in_place = Estimator::new(ActuatorParams::default(), tuning).expect("estimator");
        // a buffer holding another filter's estimate of a later sample
        let mut other = Estimator::new(ActuatorParams::default(), Tuning::thesis()).expect("estimator");
        let mut buffer = Estimate::default();
        for s in &samples[..50] {
            buffer = other.on_sample(s);
        }
        for (k, s) in samples.iter().enumerate() {
            let want = returned.on_sample(s);
            in_place.on_sample_into(s, &mut buffer);
            assert!(same(&want, &buffer), "sample {k}: {want:?}\nagainst {buffer:?}");
        }
    }
}

#[test]
fn a_stage_estimate_written_in_place_is_the_one_returned() {
    let samples = stream();
    for thesis in [false, true] {
        let stage = || {
            EstimatorStage::new(
                ActuatorParams::default(),
                Tuning::sensor_derived(),
                Tuning::thesis(),
            )
            .expect("stage")
            .with_thesis(thesis)
        };
        let (mut returned, mut in_place) = (stage(), stage());
        let mut buffer = StageEstimate::default();
        buffer.leak.state = [1.0; filter::MAX_STATES];
        buffer.thesis.nis = 1e9;
        buffer.missing_before = 99;
        for (k, s) in samples.iter().enumerate() {
            let want = returned.on_sample_flagged(s, k == 1000);
            in_place.on_sample_flagged_into(s, k == 1000, &mut buffer);
            assert!(same(&want, &buffer), "thesis {thesis}, sample {k}");
        }
        assert_eq!(
            returned.stream_restarts(),
            2,
            "the restart and the flagged sample"
        );
        assert_eq!(returned.missing_samples(), 20);
    }
}
