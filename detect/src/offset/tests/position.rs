//! An offset on x: named in mm, not fitted where x is not watched, and
//! told from a steady leak and from the pressures' misreadings.

use super::*;

/// The rises an offset of `b_mm` on x makes (the model reading one chamber
/// too large and the other too small), with the filter's response to it
/// swinging with the cycle (`scale` times a thesis-like one), and those of
/// a steady ext2 leak of `steady_leak_lpm`; 60 s from a fixed baseline.
/// Returns the first change.
fn watch_position(b_mm: f64, scale: f64, steady_leak_lpm: f64) -> (OffsetWatch, Option<OffsetChange>) {
    watch_position_in(OffsetWatch::new(25e6), b_mm, scale, steady_leak_lpm)
}

/// [`watch_position`] through `watch`.
fn watch_position_in(
    watch: OffsetWatch,
    b_mm: f64,
    scale: f64,
    steady_leak_lpm: f64,
) -> (OffsetWatch, Option<OffsetChange>) {
    watch_growing_position(watch, |_| b_mm, 60.0, false, scale, steady_leak_lpm)
}

/// [`watch_position`] with the offset `b_mm(t)` (t in s) over `seconds`, a
/// leak of a named kind standing throughout where `leak_named`.
fn watch_growing_position(
    mut watch: OffsetWatch,
    b_mm: impl Fn(f64) -> f64,
    seconds: f64,
    leak_named: bool,
    scale: f64,
    steady_leak_lpm: f64,
) -> (OffsetWatch, Option<OffsetChange>) {
    let (mut id, mut first) = (1, None);
    let factors = crate::NOMINAL_INTERNAL_FACTORS;
    for n in 0..(seconds * 100.0) as usize {
        let t = n as f64 * 0.01;
        let swing = (std::f64::consts::PI * t / 2.0).sin().abs().powi(2);
        let xi = [0.009 * (1.0 + swing), -0.012 * (1.0 + 0.5 * swing), 0.001].map(|v| scale * v);
        let b_mm = b_mm(t);
        let q = [b_mm * xi[0], b_mm * xi[1] + steady_leak_lpm, b_mm * xi[2]];
        let rise = crate::signatures_with(q, factors);
        let response = MisreadingResponse {
            offset_lpm_per_mpa: [[-0.05 - 0.2 * swing, 0.0, 0.0], [0.0, -0.1 - 0.4 * swing, 0.02]],
            span_lpm: [[-0.4, 0.0, 0.0], [0.0, -0.3, 0.1]],
            position_lpm_per_mm: xi,
        };
        watch.leak_named(leak_named);
        let change = watch.on_rise(t, 0.01, rise, &response, [8.0, 3.0], factors, [0.05; 3], &mut id);
        first = first.or(change);
    }
    (watch, first)
}

#[test]
fn an_offset_on_x_is_named_in_mm() {
    let (watch, change) = watch_position(3.0, 1.0, 0.0);
    let Some(OffsetChange::Raised(s)) = change else {
        panic!("no offset on x named: {change:?}");
    };
    assert_eq!(OFFSET_CHANNEL_NAMES[s.channel], "x", "{s:?}");
    assert!((s.offset_mm - 3.0).abs() < 0.1, "{s:?}");
    assert!(s.offset_mpa.is_nan() && s.span_error.is_nan(), "{s:?}");
    assert!(watch.vetoes());
    let detail = offset_event(OffsetChange::Raised(s), 20.0, "leak-size").detail;
    assert!(detail.starts_with("x reads 3.0 mm high (an offset"), "{detail}");
    // under the least offset named on x (1 mm), nothing is named
    assert_eq!(watch_position(0.6, 1.0, 0.0).1, None);
    // the same rises where the response is a tenth: 30 mm, past the
    // largest offset fitted on x (15 mm); neither named nor a veto
    let (watch, change) = watch_position(30.0, 0.1, 0.0);
    assert_eq!(change, None);
    assert!(!watch.vetoes());
}

#[test]
fn beside_a_named_leak_only_an_offset_on_x_grown_at_a_drift_is_named() {
    // 3 mm from 5 s on, at once: named alone, not while a leak is named (it
    // would have grown at 4 mm a minute for 45 s)
    let step = |t: f64| if t >= 5.0 { 3.0 } else { 0.0 };
    let watch = || OffsetWatch::new(25e6);
    let alone = watch_growing_position(watch(), step, 40.0, false, 1.0, 0.0).1;
    assert!(
        matches!(alone, Some(OffsetChange::Raised(s)) if s.channel == 2),
        "{alone:?}"
    );
    assert_eq!(
        watch_growing_position(watch(), step, 40.0, true, 1.0, 0.0).1,
        None
    );
    // the same offset reached at 2 mm a minute is named beside the leak
    let drift = |t: f64| 2.0 / 60.0 * (t - 5.0).clamp(0.0, 90.0);
    let beside = watch_growing_position(watch(), drift, 150.0, true, 1.0, 0.0).1;
    let Some(OffsetChange::Raised(s)) = beside else {
        panic!("a drift of x beside a leak not named: {beside:?}");
    };
    assert_eq!(OFFSET_CHANNEL_NAMES[s.channel], "x", "{s:?}");
    assert!(s.offset_mm > 1.0 && s.offset_mm < 3.1, "{s:?}");
}

#[test]
fn an_offset_on_x_is_not_fitted_where_commissioning_said_x_is_not_watched() {
    // the rises of 3 mm on x, named above; a watch without x names nothing
    // and holds no leak back, also after a restart of the filter
    let mut restarted = OffsetWatch::new(25e6).without_position();
    restarted.restart();
    for without_x in [OffsetWatch::new(25e6).without_position(), restarted] {
        let (watch, change) = watch_position_in(without_x, 3.0, 1.0, 0.0);
        assert_eq!(change, None);
        assert!(!watch.vetoes());
    }
}

#[test]
fn a_steady_leak_beside_a_position_response_is_no_offset() {
    let (watch, change) = watch_position(0.0, 1.0, 0.1);
    assert_eq!(change, None);
    assert!(!watch.vetoes());
}

#[test]
fn an_offset_on_x_must_fit_clearly_better_than_the_pressures() {
    // an offset of −0.5 MPa on p2 and a swing of its own in ext2; the
    // response to x is p2's pattern with a fifth of that swing: it fits the
    // rises somewhat better than p2's, not twice as well
    let factors = crate::NOMINAL_INTERNAL_FACTORS;
    let (mut watch, mut id, mut first) = (OffsetWatch::new(25e6), 1, None);
    let b_mpa = -0.5;
    for n in 0..6000 {
        let t = n as f64 * 0.01;
        let swing = (std::f64::consts::PI * t / 1.5).sin().abs().powi(4);
        let d2 = [0.0, -0.1 - 0.4 * swing, 0.02];
        let extra = 0.02 * (t / 0.9).cos();
        let q = [0.0, b_mpa * d2[1] + extra, b_mpa * d2[2]];
        let xi = [0.0, (d2[1] + 0.2 * extra / b_mpa) / 5.0, d2[2] / 5.0];
        let response = MisreadingResponse {
            offset_lpm_per_mpa: [[-0.05 - 0.2 * (t / 1.7).cos().powi(2), 0.0, 0.0], d2],
            span_lpm: [[-0.4, 0.0, 0.0], [0.0, -0.3, 0.1]],
            position_lpm_per_mm: xi,
        };
        let rise = crate::signatures_with(q, factors);
        let change = watch.on_rise(t, 0.01, rise, &response, [8.0, 3.0], factors, [0.05; 3], &mut id);
        first = first.or(change);
    }
    let Some(OffsetChange::Raised(s)) = first else {
        panic!("nothing named: {first:?}");
    };
    assert_eq!(OFFSET_CHANNEL_NAMES[s.channel], "p2", "{s:?}");
}
