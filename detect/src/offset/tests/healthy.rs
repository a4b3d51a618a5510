//! The healthy rises' own misreading: learned over a whole recording, and
//! taken off the rises before the watch fits.

use super::*;

/// The rises an offset of `b_mpa` on p2 makes through [`cycle_responses`],
/// from a baseline following at 15 s (the detector's default).
fn p2_reading_off(watch: OffsetWatch, b_mpa: f64) -> (OffsetWatch, Option<OffsetChange>) {
    let (watch, first) = drive_watch(watch, 60.0, 15.0, false, (f64::INFINITY, 0.0), |t| {
        let [d1, d2] = cycle_responses(t);
        (d2.map(|d| b_mpa * d), [d1, d2], [0.0; 2])
    });
    (watch, first.map(|(_, change)| change))
}

#[test]
fn the_healthy_rises_misreading_is_learned_over_all_they_read() {
    // the model's error swings as p2 reading 90 kPa high would: under the least named
    let (watch, change) = p2_reading_off(OffsetWatch::new(25e6).learning_healthy_misreading(), 0.09);
    assert_eq!(change, None);
    let m = watch.healthy_misreading().expect("a healthy misreading");
    assert_eq!(m.channel, 1, "{m:?}");
    assert!((m.offset_mpa - 0.09).abs() < 0.01, "{m:?}");
    assert!(m.span_error.is_nan() && m.share > 0.9, "{m:?}");
    // without learning there is none
    let (watch, _) = p2_reading_off(OffsetWatch::new(25e6), 0.09);
    assert_eq!(watch.healthy_misreading(), None);
}

#[test]
fn a_healthy_misreading_taken_off_names_the_fault_it_would_hide() {
    // healthy rises as p2 reading 150 kPa high; p2 then reads 200 kPa low of the truth:
    // the sum, 50 kPa low, is under every floor
    let (_, hidden) = p2_reading_off(OffsetWatch::new(25e6), 0.15 - 0.2);
    assert_eq!(hidden, None);
    let healthy = HealthyMisreading::from_kept([0.0, 150.0], [0.0; 2]);
    assert_eq!(healthy.map(|m| (m.channel, m.offset_mpa)), Some((1, 0.15)));
    let (_, named) = p2_reading_off(
        OffsetWatch::new(25e6).with_healthy_misreading(healthy),
        0.15 - 0.2,
    );
    let Some(OffsetChange::Raised(s)) = named else {
        panic!("the fault not named with the healthy misreading taken off: {named:?}");
    };
    assert_eq!(s.channel, 1, "{s:?}");
    assert!((s.offset_mpa + 0.2).abs() < 0.03, "{s:?}");
    // and a healthy run, its own misreading taken off, names nothing
    let (_, healthy_run) = p2_reading_off(OffsetWatch::new(25e6).with_healthy_misreading(healthy), 0.15);
    assert_eq!(healthy_run, None);
}

#[test]
fn a_kept_healthy_misreading_is_its_first_non_zero_value() {
    assert_eq!(HealthyMisreading::from_kept([0.0; 2], [0.0; 2]), None);
    let span = HealthyMisreading::from_kept([0.0; 2], [0.0117, 0.0]).expect("a span error");
    assert_eq!((span.channel, span.span_error), (0, 0.0117));
    assert!(span.offset_mpa.is_nan());
}
