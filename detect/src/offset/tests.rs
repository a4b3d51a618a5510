//! Tests of the offset watch: naming an offset and a span error, the reverse
//! internal part, a steady leak left alone.

use super::fit::{is_drift, FIRST_DRIFT_HYPOTHESIS};
use super::*;

mod floors;
mod healthy;
mod position;
mod rival;

/// What the filter gives the watch at one sample: the leak sizes' flows
/// (q_e1, q_e2, q_i, L/min), the offset responses (per MPa on p1 and on p2)
/// and the pressures read (MPa).
type Sample = ([f64; 3], [[f64; 3]; 2], [f64; 2]);

/// The responses of a filter whose offset responses `d` (L/min per MPa on p1
/// and on p2) have been the same while the pressures read `reading` (MPa)
/// stood: a span error's is then the offset's times the pressure.
fn steady(d: [[f64; 3]; 2], reading: [f64; 2]) -> MisreadingResponse {
    MisreadingResponse {
        offset_lpm_per_mpa: d,
        span_lpm: [0, 1].map(|c| d[c].map(|v| v * reading[c])),
        position_lpm_per_mm: [0.0; 3],
    }
}

/// Feeds `seconds` of the samples `at(t)` every 10 ms, the rises measured
/// from a baseline that follows the sizes with time constant `tau_s` (0:
/// fixed); returns the watch and the first change of the named misreading.
fn drive(seconds: f64, tau_s: f64, at: impl Fn(f64) -> Sample) -> (OffsetWatch, Option<OffsetChange>) {
    drive_beside_a_leak(seconds, tau_s, false, at)
}

/// [`drive`], a leak of a named kind standing throughout where `leak_named`.
fn drive_beside_a_leak(
    seconds: f64,
    tau_s: f64,
    leak_named: bool,
    at: impl Fn(f64) -> Sample,
) -> (OffsetWatch, Option<OffsetChange>) {
    let (watch, first) = drive_pausing(seconds, tau_s, leak_named, (f64::INFINITY, 0.0), at);
    (watch, first.map(|(_, change)| change))
}

/// [`drive_beside_a_leak`] with a pause: from `pause.0` (s) for `pause.1`
/// (s) the watch is not fed (a gap, or estimates it may not read), and after
/// it the samples go on where they stopped, their times later by the pause.
/// Returns the watch, and the first change of the named misreading with its time, s.
fn drive_pausing(
    seconds: f64,
    tau_s: f64,
    leak_named: bool,
    pause: (f64, f64),
    at: impl Fn(f64) -> Sample,
) -> (OffsetWatch, Option<(f64, OffsetChange)>) {
    drive_watch(OffsetWatch::new(25e6), seconds, tau_s, leak_named, pause, at)
}

/// [`drive_pausing`] with the watch `watch` (25 MPa transducers).
fn drive_watch(
    mut watch: OffsetWatch,
    seconds: f64,
    tau_s: f64,
    leak_named: bool,
    pause: (f64, f64),
    at: impl Fn(f64) -> Sample,
) -> (OffsetWatch, Option<(f64, OffsetChange)>) {
    let dt = 0.01;
    let factors = crate::NOMINAL_INTERNAL_FACTORS;
    let mut baseline = [0.0; 3];
    let mut first = None;
    let mut id = 1;
    for n in 0..(seconds / dt) as usize {
        let fed_t = n as f64 * dt;
        let t = if fed_t < pause.0 { fed_t } else { fed_t + pause.1 };
        let (q, responses, reading) = at(fed_t);
        let sizes = crate::signatures_with(q, factors);
        let share = if tau_s > 0.0 { dt / tau_s } else { 0.0 };
        for k in 0..3 {
            baseline[k] += share * (sizes[k] - baseline[k]);
        }
        let rise: [f64; 3] = std::array::from_fn(|k| sizes[k] - baseline[k]);
        watch.follow_baseline(share);
        watch.leak_named(leak_named);
        let response = steady(responses, reading);
        let change = watch.on_rise(t, dt, rise, &response, reading, factors, [0.05; 3], &mut id);
        first = first.or(change.map(|c| (t, c)));
    }
    (watch, first)
}

/// The offset responses (L/min per MPa on p1 and on p2) at `t` (s): δ on p2
/// moves ext2 with the valve's flow, small at rest and large in the moves of
/// a 3-s cycle; δ on p1 moves ext1 in another rhythm.
fn cycle_responses(t: f64) -> [[f64; 3]; 2] {
    let swing = (std::f64::consts::PI * t / 1.5).sin().abs().powi(4);
    let d2 = [0.0, -0.1 - 0.4 * swing, 0.02];
    let d1 = [
        -0.05 - 0.2 * (std::f64::consts::PI * t / 2.5).cos().powi(2),
        0.0,
        0.0,
    ];
    [d1, d2]
}

/// Feeds `seconds` of rises that an offset `b_mpa` on p2 makes, measured
/// from a baseline that follows the sizes with time constant `tau_s`
/// (0: fixed), with the model's own reverse internal flow of
/// `artefact_lpm` for 2 s of every 10 (a rest under load after a fast
/// move); returns the watch and the first change of the named offset.
fn watch_offset_on_p2(
    b_mpa: f64,
    tau_s: f64,
    seconds: f64,
    artefact_lpm: f64,
) -> (OffsetWatch, Option<OffsetChange>) {
    drive(seconds, tau_s, |t| {
        let [d1, d2] = cycle_responses(t);
        let reverse = if t % 10.0 >= 8.0 { -artefact_lpm } else { 0.0 };
        let q = [b_mpa * d2[0], b_mpa * d2[1], b_mpa * d2[2] + reverse];
        (q, [d1, d2], [0.0; 2])
    })
}

#[test]
fn an_offset_is_named_from_rises_measured_from_a_following_baseline() {
    for tau_s in [0.0, 15.0] {
        let (watch, change) = watch_offset_on_p2(-0.5, tau_s, 60.0, 0.0);
        let Some(OffsetChange::Raised(s)) = change else {
            panic!("no offset named with baseline_tau_s {tau_s}: {change:?}");
        };
        assert_eq!(s.channel, 1, "{s:?}");
        assert!(
            (s.offset_mpa + 0.5).abs() < 0.05,
            "offset {} MPa, truth -0.5 (tau {tau_s})",
            s.offset_mpa
        );
        assert!(watch.vetoes(), "tau {tau_s}");
    }
}

#[test]
fn a_pause_in_the_samples_does_not_count_towards_naming() {
    // p2 reading 0.5 MPa low, the rises measured from a fixed baseline
    let offset_on_p2 = |t: f64| {
        let [d1, d2] = cycle_responses(t);
        ([-0.5 * d2[0], -0.5 * d2[1], -0.5 * d2[2]], [d1, d2], [0.0; 2])
    };
    let (_, named) = drive_pausing(60.0, 0.0, false, (f64::INFINITY, 0.0), offset_on_p2);
    let Some((named_s, OffsetChange::Raised(_))) = named else {
        panic!("no offset named: {named:?}");
    };
    // 3 s without samples, 1 s before it was named (its conditions had held
    // for 1 of the OFFSET_CONFIRM_S): named after 1 s more of samples
    let pause = (named_s - 1.0, 3.0);
    let (_, later) = drive_pausing(60.0, 0.0, false, pause, offset_on_p2);
    let Some((later_s, OffsetChange::Raised(s))) = later else {
        panic!("no offset named across the pause: {later:?}");
    };
    assert_eq!(s.channel, 1, "{s:?}");
    assert!(
        (later_s - (named_s + pause.1)).abs() < 0.015,
        "named at {later_s} s across the pause, at {named_s} s without it"
    );
}

#[test]
fn the_models_reverse_internal_flow_does_not_hide_an_offset() {
    // an offset of −0.4 MPa on p2 among stretches of the reverse flow that
    // no leak makes, each several times the offset's own part of the rises
    let (watch, change) = watch_offset_on_p2(-0.4, 15.0, 90.0, 0.3);
    let Some(OffsetChange::Raised(s)) = change else {
        panic!("no offset named beside the reverse flow: {change:?}");
    };
    assert_eq!(s.channel, 1, "{s:?}");
    assert!(
        (s.offset_mpa + 0.4).abs() < 0.04,
        "offset {} MPa, truth -0.4",
        s.offset_mpa
    );
    assert!(watch.standing().is_some());
}

#[test]
fn only_the_part_against_the_internal_leak_is_taken_out() {
    let responses = [[0.3, 0.1], [0.0, -0.4], [0.1, 0.0], [0.2, 0.2]];
    for factors in [[1.0, 1.0], [0.6, 1.3]] {
        // what leaks make (ext1, ext2, an internal leak and mixes): untouched
        for rise in [[0.2, 0.0], [0.0, 0.2], [0.2, -0.1], [0.1, 0.3]] {
            let mut h = responses;
            assert_eq!(without_reverse_internal(rise, factors, &mut h), rise);
            assert_eq!(h, responses);
        }
        // an ext2 rise of 0.05 with 0.1 of reverse internal flow: the ext2 part stays
        let [r1, r2] = factors;
        let rise = [-0.1 * r1, 0.05 + 0.1 * r2];
        let mut h = responses;
        let left = without_reverse_internal(rise, factors, &mut h);
        assert!(
            left[0].abs() < 1e-12 && (left[1] - 0.05).abs() < 1e-12,
            "{left:?}"
        );
        // each response loses its own part along the internal leak
        for (got, was) in h.iter().zip(responses) {
            let c = was[0] / r1;
            assert!((got[0] - (was[0] - c * r1)).abs() < 1e-12, "{got:?} from {was:?}");
            assert!((got[1] - (was[1] + c * r2)).abs() < 1e-12, "{got:?} from {was:?}");
        }
    }
    // the internal leak feeding chamber 1 (p2 > p1): ext1 bounds the other side
    let factors = [-1.0, -1.0];
    let mut h = responses;
    assert_eq!(without_reverse_internal([0.0, 0.2], factors, &mut h), [0.0, 0.2]);
    let left = without_reverse_internal([0.15, -0.1], factors, &mut h);
    assert!(
        (left[0] - 0.05).abs() < 1e-12 && left[1].abs() < 1e-12,
        "{left:?}"
    );
}

#[test]
fn a_steady_leak_is_no_offset() {
    let mut watch = OffsetWatch::new(25e6);
    let mut id = 1;
    let factors = crate::NOMINAL_INTERNAL_FACTORS;
    for n in 0..6000 {
        let t = n as f64 * 0.01;
        let swing = (std::f64::consts::PI * t / 1.5).sin().abs().powi(4);
        let d2 = [0.0, -0.1 - 0.4 * swing, 0.02];
        let d1 = [-0.05, 0.0, 0.0];
        watch.follow_baseline(0.01 / 15.0);
        let change = watch.on_rise(
            t,
            0.01,
            [0.0, 0.2, -0.1],
            &steady([d1, d2], [0.0; 2]),
            [0.0; 2],
            factors,
            [0.05; 3],
            &mut id,
        );
        assert_eq!(change, None, "at {t} s");
    }
    assert!(!watch.vetoes());
}

/// Feeds `seconds` of the rises a span error `gain_error` (1) on p1 makes
/// while p1 reads `p1_mpa(t)`, measured from a baseline that follows the
/// sizes with a time constant of 15 s; returns the first change.
fn watch_span_on_p1(gain_error: f64, seconds: f64, p1_mpa: impl Fn(f64) -> f64) -> Option<OffsetChange> {
    let (_, first) = drive(seconds, 15.0, |t| {
        let d1 = [
            -0.1 - 0.4 * (std::f64::consts::PI * t / 2.5).cos().powi(2),
            0.0,
            0.01,
        ];
        let d2 = [0.0, -0.1, 0.02];
        let p1 = p1_mpa(t);
        (d1.map(|d| gain_error * p1 * d), [d1, d2], [p1, 3.0])
    });
    first
}

#[test]
fn a_span_error_is_named_where_it_moves_with_the_pressure() {
    // p1 swinging 2-14 MPa in a rhythm of its own: a 2 % span error makes
    // offsets of 40-280 kPa, 160 kPa on average
    let swinging = |t: f64| 8.0 + 6.0 * (2.0 * std::f64::consts::PI * t / 7.0).sin();
    let Some(OffsetChange::Raised(s)) = watch_span_on_p1(0.02, 90.0, swinging) else {
        panic!("no span error named");
    };
    assert_eq!(s.channel, 0, "{s:?}");
    assert!(
        (s.span_error - 0.02).abs() < 0.004,
        "span error {} against 0.02",
        s.span_error
    );
    // at a steady 8 MPa the same error is an offset of 160 kPa: a span fits
    // no better than an offset, and it is named as one (past the least
    // standing offset named, 125 kPa)
    let Some(OffsetChange::Raised(s)) = watch_span_on_p1(0.02, 90.0, |_| 8.0) else {
        panic!("no offset named");
    };
    assert!(s.span_error.is_nan(), "{s:?}");
    assert!((s.offset_mpa - 0.16).abs() < 0.01, "{s:?}");
    // 0.7 % at 8 MPa, 56 kPa: under the clean offset's floor (62.5 kPa)
    assert_eq!(watch_span_on_p1(0.007, 90.0, |_| 8.0), None);
}

#[test]
fn a_standing_offset_under_the_least_named_is_not_named_however_cleanly_it_fits() {
    // -0.1 MPa on p2 (0.4 % of 25 MPa): the fit leaves nothing, but a sound
    // transducer reads this far off at its working point
    let (_, change) = watch_offset_on_p2(-0.1, 0.0, 60.0, 0.0);
    assert_eq!(change, None);
    // -0.15 MPa, past the least standing offset (125 kPa): named 2 s after the window filled
    let (_, change) = watch_offset_on_p2(-0.15, 0.0, 13.0, 0.0);
    let Some(OffsetChange::Raised(s)) = change else {
        panic!("no offset named: {change:?}");
    };
    assert!((s.offset_mpa + 0.15).abs() < 0.01, "{s:?}");
}

#[test]
fn an_episode_is_judged_on_the_offsets_as_given_alone() {
    // rises that a span error's response on p1 makes exactly, while the
    // offsets' responses swing in other rhythms: the fit in all forms
    // finds the span; the episode's fit, offsets as given alone, does not
    let mut fit = Fit::default();
    for n in 0..2000 {
        let t = n as f64 * 0.01;
        let span = [1.0 + (t / 3.0).sin(), 0.2];
        let mut h = [[0.0; 2]; HYPOTHESES];
        h[0] = [(t / 0.7).cos(), 0.1];
        h[1] = [0.05, (t / 1.3).sin()];
        h[4] = span;
        let rise = [0.03 * span[0], 0.03 * span[1]];
        fit.add((-0.01f64 / OFFSET_WINDOW_S).exp(), 0.01, rise, &h);
    }
    let fit::BestOffset { h: all, left, .. } =
        fit.best_offset(true, true, &leak_directions(crate::NOMINAL_INTERNAL_FACTORS));
    assert_eq!(all, 4, "the span on p1 fits best");
    assert!(left < 1e-6 * fit.energy, "{left} of {}", fit.energy);
    let fit::BestOffset { h: given, left, .. } =
        fit.best_offset(false, false, &leak_directions(crate::NOMINAL_INTERNAL_FACTORS));
    assert!(given < 2 || is_drift(given), "hypothesis {given}");
    assert!(left > 0.1 * fit.energy, "{left} of {}", fit.energy);
}

/// The fit of `seconds` of rises `rise(t)` (w1, w2) against responses
/// where only the offsets on p1 and p2 as given move the sizes, `d1(t)` and
/// `d2(t)`, sampled every 10 ms.
fn fit_offsets(
    seconds: f64,
    rise: impl Fn(f64) -> [f64; 2],
    d1: impl Fn(f64) -> [f64; 2],
    d2: impl Fn(f64) -> [f64; 2],
) -> Fit {
    let mut fit = Fit::default();
    for n in 0..(seconds / 0.01) as usize {
        let t = n as f64 * 0.01;
        let mut h = [[0.0; 2]; HYPOTHESES];
        h[0] = d1(t);
        h[1] = d2(t);
        fit.add((-0.01f64 / OFFSET_WINDOW_S).exp(), 0.01, rise(t), &h);
    }
    fit
}

#[test]
fn a_drifting_offset_is_fitted_with_its_rate() {
    // p1 drifting from 0 at 4 kPa/s (240 kPa a minute) for 20 s, its response
    // swinging with the valve's flow: the drifting offset on p1 leaves
    // nothing, a standing one leaves some, and the last sample's offset and
    // the rate are found
    let swing = |t: f64| [-0.5 * (1.0 + (std::f64::consts::PI * t / 2.0).sin().abs()), 0.1];
    let rate = 0.004;
    let fit = fit_offsets(
        20.0,
        |t| swing(t).map(|d| rate * t * d),
        swing,
        |t| [0.05, -0.4 - 0.2 * (t / 1.3).sin()],
    );
    let fit::BestOffset { h, left, .. } =
        fit.best_offset(false, false, &leak_directions(crate::NOMINAL_INTERNAL_FACTORS));
    assert_eq!(h, FIRST_DRIFT_HYPOTHESIS, "the drifting offset on p1");
    assert_eq!(channel_of(h), 0);
    assert!(left < 1e-9 * fit.energy, "{left} of {}", fit.energy);
    let standing = fit.energy - fit.explained_by_offset(0);
    assert!(standing > 0.01 * fit.energy, "{standing} of {}", fit.energy);
    assert!(
        (fit.coefficient(h) - rate * 19.99).abs() < 1e-6,
        "{}",
        fit.coefficient(h)
    );
    assert!((fit.drift_rate_mpa_per_s(h) - rate).abs() < 1e-9);
    assert_eq!(fit.drift_rate_mpa_per_s(0), 0.0);
}

#[test]
fn a_leaks_onset_is_no_drifting_offset() {
    // an ext1 leak opening over 5 s to 0.25 L/min, while p1's offset response
    // barely swings: an offset growing at 100 kPa/s would fit the ramp, one
    // within MOST_DRIFT_MPA_PER_S does not, and the episode is no veto
    let d1 = |t: f64| [-0.5 * (1.0 + 0.1 * (std::f64::consts::PI * t / 2.0).sin()), 0.0];
    let fit = fit_offsets(8.0, |t| [0.25 * (t / 5.0).min(1.0), 0.0], d1, |_| [0.0, -0.5]);
    let drift = FIRST_DRIFT_HYPOTHESIS;
    assert_eq!(fit.drift_rate_mpa_per_s(drift), -MOST_DRIFT_MPA_PER_S);
    let directions = leak_directions(crate::NOMINAL_INTERNAL_FACTORS);
    let best = fit.best_offset(false, false, &directions);
    assert!(!fit.offset_fits_better(&best, OFFSET_FIT_RATIO));
}

/// The rises of an offset on p2 of `b_mpa(t)` with p2's response swinging
/// with a 3-s cycle, from a fixed baseline, a leak of a named kind standing
/// where `leak_named`; the first change.
fn offset_on_p2_beside_a_leak(
    seconds: f64,
    leak_named: bool,
    b_mpa: impl Fn(f64) -> f64,
) -> Option<OffsetChange> {
    drive_beside_a_leak(seconds, 0.0, leak_named, |t| {
        let [d1, d2] = cycle_responses(t);
        let b = b_mpa(t);
        ([b * d2[0], b * d2[1], b * d2[2]], [d1, d2], [0.0; 2])
    })
    .1
}

#[test]
fn beside_a_named_leak_only_an_offset_grown_at_a_drift_is_named() {
    // -0.5 MPa from 5 s on, at once: named alone, not while a leak is named
    // (it would have grown at 10 kPa/s for 50 s)
    let step = |t: f64| if t >= 5.0 { -0.5 } else { 0.0 };
    let alone = offset_on_p2_beside_a_leak(40.0, false, step);
    assert!(
        matches!(alone, Some(OffsetChange::Raised(s)) if s.channel == 1),
        "{alone:?}"
    );
    assert_eq!(offset_on_p2_beside_a_leak(40.0, true, step), None);
    // the same offset reached at 5 kPa/s (300 kPa a minute) is named beside the leak
    let drift = |t: f64| -0.005 * (t - 5.0).clamp(0.0, 100.0);
    let beside = offset_on_p2_beside_a_leak(120.0, true, drift);
    let Some(OffsetChange::Raised(s)) = beside else {
        panic!("a drift beside a leak not named: {beside:?}");
    };
    assert_eq!(s.channel, 1);
    assert!((s.drift_mpa_per_s + 0.005).abs() < 0.0005, "{s:?}");
}

#[test]
fn a_growing_leak_is_fitted_with_its_rate() {
    // ext1 growing from 0.1 L/min at 0.02 L/min per s for 20 s: a growing
    // leak leaves nothing, a steady one leaves the ramp's spread
    let fit = fit_offsets(20.0, |t| [0.1 + 0.02 * t, 0.0], |_| [-0.5, 0.0], |_| [0.0, -0.5]);
    let directions = leak_directions(crate::NOMINAL_INTERNAL_FACTORS);
    let growing = fit.unexplained_by_growing_leak(&directions);
    assert!(growing.abs() < 1e-9 * fit.energy, "{growing} of {}", fit.energy);
    let steady = fit.unexplained_by_leak(&directions);
    assert!(steady > 0.01 * fit.energy, "{steady} of {}", fit.energy);
}

#[test]
fn a_leak_opening_late_in_the_window_is_no_drifting_offset() {
    // a 0.1 L/min ext1 step 15 s into 20 s, where p1's response is large and
    // barely swings: a drift within the bound fits it better than a steady
    // leak does, not better than a growing one; no veto
    let d1 = |t: f64| [-5.0 * (1.0 + 0.05 * (std::f64::consts::PI * t / 2.0).sin()), 0.0];
    let step = |t: f64| [if t >= 15.0 { 0.1 } else { 0.0 }, 0.0];
    let fit = fit_offsets(20.0, step, d1, |_| [0.0, -0.5]);
    let directions = leak_directions(crate::NOMINAL_INTERNAL_FACTORS);
    let drift = FIRST_DRIFT_HYPOTHESIS;
    let left = fit.energy - fit.explained_by_offset(drift);
    assert!(
        left < OFFSET_FIT_RATIO * fit.unexplained_by_leak(&directions),
        "{left}"
    );
    let best = fit.best_offset(false, false, &directions);
    assert!(
        !fit.offset_fits_better(&best, OFFSET_FIT_RATIO),
        "hypothesis {}",
        best.h
    );
}

#[test]
fn a_channels_explained_rms_is_its_largest_hypothesis_rms() {
    // p2 reading 0.3 MPa low: each channel's RMS is the largest of its
    // hypotheses' (each form), to the bit
    let w = watch_offset_on_p2(-0.3, 15.0, 30.0, 0.0).0;
    let rms = w.window.channels_explained_rms_lpm();
    for (c, rms) in rms.iter().enumerate() {
        let each = (0..fit::ALL_HYPOTHESES)
            .filter(|&h| fit::channel_of(h) == c)
            .map(|h| w.window.explained_rms_lpm(h))
            .fold(0.0, f64::max);
        assert_eq!(*rms, each, "channel {c}");
    }
    assert!(rms[1] > 0.01);
}

#[test]
fn a_named_offset_says_since_when_it_has_read_off() {
    // a drift of −4 kPa/s on p2 from 12 s: since its fitted line's zero
    let drift = |t: f64| -0.004 * (t - 12.0).max(0.0);
    let Some(OffsetChange::Raised(s)) = offset_on_p2_beside_a_leak(150.0, false, drift) else {
        panic!("the drift not named");
    };
    assert!(s.drift_mpa_per_s < 0.0, "{s:?}");
    assert!((s.since_s - 12.0).abs() < 3.0, "{s:?}");
    let detail = offset_event(OffsetChange::Raised(s), 60.0, "leak-size").detail;
    assert!(detail.contains(&format!("since {:.1} s", s.since_s)), "{detail}");
    // the other pressure channel, ranked second: its fit leaves more
    assert!(s.other_channel_left_ratio > 2.0, "{s:?}");
    let second = format!(
        "A misreading of p1 leaves {:.1} times as much of the rises unexplained: if p2 reads true, check p1",
        s.other_channel_left_ratio
    );
    assert!(detail.contains(&second), "{detail}");
    // an offset standing from the first sample: since the first sample read
    let Some(OffsetChange::Raised(s)) = offset_on_p2_beside_a_leak(60.0, false, |_| -0.5) else {
        panic!("the standing offset not named");
    };
    assert_eq!(s.since_s, 0.0, "{s:?}");
}
