//! A sensor stream that restarts (a sender's reboot: its sample time back to 0)
//! re-anchors both filters of the stage on the first new sample, as a gap too
//! long to bridge does; a flagged gap the time does not show is a restart too;
//! forward gaps are decided from the time alone, flag or not.

use filter::{
    stage::StreamRestart, EstimatorStage, StageEstimate, Tuning, FLAG_AFTER_GAP, FLAG_CONVERGING,
    FLAG_REANCHORED, FLAG_RESET, FLAG_SKIPPED,
};
use model::{ActuatorParams, FaultSchedule, Sample, Scenario, Simulator};

/// `seconds` of the closed-loop sine on the default rig (default sensors,
/// seed `seed`), sample times from 0.
fn record(seconds: f64, seed: u64) -> Vec<Sample> {
    let sc = Scenario::by_name("closed-loop-sine", 3, seconds).expect("scenario");
    let mut sim =
        Simulator::with_default_sensors(ActuatorParams::default(), sc, FaultSchedule::default(), seed)
            .expect("rig");
    sim.run(seconds)
}

fn stage() -> EstimatorStage {
    EstimatorStage::new(
        ActuatorParams::default(),
        Tuning::sensor_derived(),
        Tuning::thesis(),
    )
    .expect("stage")
}

/// Rod position the estimate gives, m (state 3).
fn x_m(e: &filter::Estimate) -> f64 {
    e.state[3]
}

/// The same estimate, NaNs included (`PartialEq` says no to NaN fields).
fn same(a: &StageEstimate, b: &StageEstimate) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

#[test]
fn a_stream_whose_time_goes_back_restarts_and_both_filters_reanchor_on_its_first_sample() {
    let old = record(3.0, 7);
    let new = record(2.0, 11);
    assert_eq!(new[0].t_s, 0.0);
    let mut st = stage();
    let mut last = None;
    for s in &old {
        last = Some(st.on_sample(s));
    }
    let before = last.expect("estimates");
    assert_eq!(
        before.leak.flags & (FLAG_CONVERGING | FLAG_RESET | FLAG_SKIPPED),
        0
    );
    let t_last_s = old[old.len() - 1].t_s;
    let resets = (st.leak().counters().resets, st.thesis().counters().resets);

    // the reboot: the sender's first sample again at t = 0 s, flagged after a gap
    let s0 = &new[0];
    let e = st.on_sample_flagged(s0, true);
    for (name, f) in [("leak", &e.leak), ("thesis", &e.thesis)] {
        assert_eq!(
            f.flags & (FLAG_REANCHORED | FLAG_AFTER_GAP),
            FLAG_REANCHORED | FLAG_AFTER_GAP,
            "{name}: {:#x}",
            f.flags
        );
        // a re-anchoring, not a reset; the convergence time does not start again
        assert_eq!(
            f.flags & (FLAG_RESET | FLAG_SKIPPED | FLAG_CONVERGING),
            0,
            "{name}: {:#x}",
            f.flags
        );
        assert!(
            (x_m(f) - s0.x_m).abs() < 5e-6,
            "{name}: x {} m vs measured {} m",
            x_m(f),
            s0.x_m
        );
        assert!(f
            .state
            .iter()
            .take(f.n_states.min(11) as usize)
            .all(|v| v.is_finite()));
    }
    // the leak filter keeps its leak sizes across the restart (one update moves them a little)
    for i in 7..10 {
        assert!(
            (e.leak.state[i] - before.leak.state[i]).abs() < 0.05 / 60_000.0,
            "leak state {i}: {} vs {}",
            e.leak.state[i],
            before.leak.state[i]
        );
    }
    assert_eq!(e.missing_before, 0);
    assert_eq!(st.stream_restarts(), 1);
    assert_eq!(
        st.missing_samples(),
        0,
        "a restart is no count of missing samples"
    );
    assert_eq!(
        (st.leak().counters().resets, st.thesis().counters().resets),
        resets
    );
    let restart = st.last_restart().expect("restart kept");
    assert_eq!(
        restart,
        StreamRestart {
            t_before_s: t_last_s,
            t_after_s: 0.0
        }
    );
    assert_eq!(
        restart.to_string(),
        format!("sensor stream restarted at t = 0 s (time went back from {t_last_s} s): filters re-anchored")
    );

    // the new stream goes on as a stream: no further restart, gap or flag, and it is tracked
    for s in &new[1..] {
        let e = st.on_sample(s);
        assert_eq!(
            e.leak.flags & (FLAG_REANCHORED | FLAG_AFTER_GAP | FLAG_RESET | FLAG_SKIPPED),
            0
        );
        assert!(
            e.leak.nis.is_finite() && e.leak.nis < 1e4,
            "NIS {} at {} s",
            e.leak.nis,
            s.t_s
        );
        assert!((x_m(&e.leak) - s.x_m).abs() < 1e-3, "x at {} s", s.t_s);
    }
    assert_eq!((st.stream_restarts(), st.missing_samples()), (1, 0));

    // unflagged, a time that goes back is a restart all the same
    let e = st.on_sample(&old[0]);
    assert_eq!(
        e.leak.flags & (FLAG_REANCHORED | FLAG_AFTER_GAP),
        FLAG_REANCHORED | FLAG_AFTER_GAP
    );
    assert_eq!(st.stream_restarts(), 2);
}

#[test]
fn a_flagged_gap_the_time_does_not_show_is_a_restart_and_forward_gaps_ignore_the_flag() {
    let samples = record(2.0, 5);
    let mut st = stage();
    for s in &samples[..1500] {
        st.on_sample(s);
    }

    // forward gaps: flag or not, bit for bit the same; bridged (3 missing) or re-anchored (50)
    for (k, missing, reanchored) in [(1503, 3u64, false), (1573, 50, true)] {
        let mut flagged = st.clone();
        let e = st.on_sample(&samples[k]);
        let f = flagged.on_sample_flagged(&samples[k], true);
        assert!(same(&e, &f), "flagged gap before sample {k} processed otherwise");
        assert_eq!(e.missing_before, missing);
        assert_eq!(e.leak.flags & FLAG_AFTER_GAP, FLAG_AFTER_GAP);
        assert_eq!(
            e.leak.flags & FLAG_REANCHORED != 0,
            reanchored,
            "{:#x}",
            e.leak.flags
        );
        assert_eq!(
            e.thesis.flags & FLAG_REANCHORED != 0,
            reanchored,
            "{:#x}",
            e.thesis.flags
        );
        for s in &samples[k + 1..k + 20] {
            let e = st.on_sample(s);
            let f = flagged.on_sample(s);
            assert!(same(&e, &f));
        }
        assert_eq!(flagged.stream_restarts(), 0);
    }
    assert_eq!((st.stream_restarts(), st.missing_samples()), (0, 53));

    // flagged, one period after the one before: the stream restarted
    let s = &samples[1593];
    let e = st.on_sample_flagged(s, true);
    assert_eq!(
        e.leak.flags & (FLAG_REANCHORED | FLAG_AFTER_GAP),
        FLAG_REANCHORED | FLAG_AFTER_GAP
    );
    assert_eq!(
        e.thesis.flags & (FLAG_REANCHORED | FLAG_AFTER_GAP),
        FLAG_REANCHORED | FLAG_AFTER_GAP
    );
    assert_eq!(e.leak.flags & FLAG_RESET, 0);
    assert!((x_m(&e.leak) - s.x_m).abs() < 5e-6);
    assert_eq!((st.stream_restarts(), st.missing_samples()), (1, 53));
    let restart = st.last_restart().expect("restart kept");
    assert!(restart.to_string().contains("flagged after a gap"), "{restart}");

    // unflagged, the next sample is just the next one
    let e = st.on_sample(&samples[1594]);
    assert_eq!(e.leak.flags & (FLAG_REANCHORED | FLAG_AFTER_GAP), 0);
    assert_eq!((st.stream_restarts(), st.missing_samples()), (1, 53));
}

/// A stream that restarts before the filter has started (every sample so far
/// unusable) starts it on its first full sample as usual; nothing panics.
#[test]
fn a_restart_before_the_filter_started_just_starts_it() {
    let samples = record(0.2, 3);
    let mut st = stage();
    for s in &samples[100..150] {
        let mut bad = *s;
        bad.x_m = f64::NAN;
        bad.p1_pa = f64::NAN;
        let e = st.on_sample(&bad);
        assert_ne!(e.leak.flags & FLAG_SKIPPED, 0);
    }
    let e = st.on_sample_flagged(&samples[0], true);
    assert_eq!(st.stream_restarts(), 1);
    assert_eq!(e.leak.flags & (FLAG_SKIPPED | FLAG_REANCHORED), 0);
    assert!((x_m(&e.leak) - samples[0].x_m).abs() < 5e-6);
}

/// Without its thesis filter the stage gives the leak filter's estimates bit
/// for bit, across a gap and a restart too, and each thesis estimate empty and
/// flagged skipped.
#[test]
fn a_stage_without_the_thesis_filter_gives_the_same_leak_estimates() {
    let mut samples = record(3.0, 5);
    samples.drain(1200..1250); // a gap of 50 samples: re-anchored
    let mut restarted = record(1.0, 6); // then the sender reboots: time back to 0
    samples.append(&mut restarted);
    let (mut both, mut leak_only) = (stage(), stage().with_thesis(false));
    assert!(both.thesis_runs() && !leak_only.thesis_runs());
    for s in &samples {
        let (a, b) = (both.on_sample(s), leak_only.on_sample(s));
        assert_eq!(
            format!("{:?}", a.leak),
            format!("{:?}", b.leak),
            "t = {} s",
            s.t_s
        );
        assert_eq!(a.missing_before, b.missing_before);
        assert!(b.thesis.flags & FLAG_SKIPPED != 0 && b.thesis.state[3].is_nan());
    }
    assert_eq!(leak_only.thesis().counters().samples, 0);
    assert_eq!(both.stream_restarts(), 1);
    assert_eq!(leak_only.stream_restarts(), 1);
}
