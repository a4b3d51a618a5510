//! Tests of the oil's temperature read from θ.
use super::*;
use model::params::{CATALOGUE_LAW_UNCERTAINTY, STATED_LAW_UNCERTAINTY};

#[test]
fn a_stiffness_13_percent_down_reads_as_30_k_above_the_reference() {
    let oil = OilTemperature {
        reference_c: 30.0,
        ..OilTemperature::default()
    };
    let mut o = OilFromStiffness::new(&oil, 1.0).expect("k_β −0.0045");
    assert_eq!(o.observe(1.0, 1e-3), None);
    // unsettled, the temperature is as unsure as half the span
    assert!(o.sigma_k(0.0) >= 0.5 * OIL_ESTIMATE_SPAN_K);
    let theta = 1.0 - 0.0045 * 30.0;
    let mut last = None;
    for _ in 0..200_000 {
        last = o.observe(theta, 1e-3).or(last);
    }
    let t = last.expect("moved");
    assert!((t - 60.0).abs() < OIL_ESTIMATE_STEP_K, "{t}");
    assert!((o.temperature_c() - 60.0).abs() < 1e-6);
    assert!(o.settled());
    // θ's σ of 0.0045 is 1 K; k_β's share of the 30 K is 6 K
    assert!((o.sigma_k(0.0045) - 1f64.hypot(0.2 * (o.applied_c() - 30.0))).abs() < 1e-9);
    // θ spreading by 0.9 % at one temperature reads as 2 K more, at the reference too
    let spread = OilTemperature {
        reference_stiffness_sigma_share: Some(0.009),
        ..oil
    };
    assert!((stiffness_spread_k(&spread) - 2.0).abs() < 1e-12);
    assert!((settled_sigma_k(&spread, 30.0) - 2.0).abs() < 1e-12);
    assert!((settled_sigma_k(&spread, 45.0) - 3f64.hypot(2.0)).abs() < 1e-12);
    assert_eq!(settled_sigma_k(&oil, 30.0), 0.0);
    // a stiffness far below the law's range is held at the operating range's top (60 °C) and its margin
    for _ in 0..200_000 {
        o.observe(0.3, 1e-3);
    }
    assert!((o.applied_c() - (60.0 + OIL_RANGE_MARGIN_K)).abs() < OIL_ESTIMATE_STEP_K);
    assert_eq!(o.observe(f64::NAN, 1e-3), None);
    // and far above it, at the range's bottom (20 °C) and its margin
    for _ in 0..200_000 {
        o.observe(1.5, 1e-3);
    }
    assert!((o.applied_c() - (20.0 - OIL_RANGE_MARGIN_K)).abs() < OIL_ESTIMATE_STEP_K);
}

#[test]
fn the_temperature_read_from_theta_stays_within_the_span_and_takes_in_the_reference() {
    // a wide operating range: the span about the reference binds
    let wide = OilTemperature {
        reference_c: 30.0,
        operating_min_c: -30.0,
        operating_max_c: 120.0,
        ..OilTemperature::default()
    };
    let mut o = OilFromStiffness::new(&wide, 1.0).expect("k_β");
    for _ in 0..200_000 {
        o.observe(0.3, 1e-3);
    }
    assert!((o.applied_c() - (30.0 + OIL_ESTIMATE_SPAN_K)).abs() < OIL_ESTIMATE_STEP_K);
    // commissioned warmer than the operating range's top: the reference stays readable
    let warm = OilTemperature {
        reference_c: 75.0,
        ..OilTemperature::default()
    };
    let mut o = OilFromStiffness::new(&warm, 1.0).expect("k_β");
    for _ in 0..20_000 {
        o.observe(1.0, 1e-3);
    }
    assert!((o.temperature_c() - 75.0).abs() < 1e-9, "{}", o.temperature_c());
    for _ in 0..200_000 {
        o.observe(0.3, 1e-3);
    }
    assert!((o.temperature_c() - 75.0).abs() < 1e-9, "{}", o.temperature_c());
}

#[test]
fn the_laminar_factor_is_sure_at_the_reference_and_less_so_away_from_it() {
    let oil = OilTemperature {
        reference_c: 30.0,
        ..OilTemperature::default()
    };
    let (f, s) = laminar_factor_with_sigma(&oil, 30.0, 0.0);
    assert!((f - 1.0).abs() < 1e-12 && s.abs() < 1e-12);
    let (f, s) = laminar_factor_with_sigma(&oil, 55.0, 0.0);
    // ν(30)/ν(55) of an HLP 46 of VI 100 is about 3
    assert!((2.8..3.3).contains(&f), "{f}");
    assert!((s - CATALOGUE_LAW_UNCERTAINTY * (f - 1.0)).abs() < 1e-12);
    // an oil whose data sheet gives ν at 100 °C, a null leakage known to 6 %:
    // the law's share narrows to 0.15 + 0.06
    let stated = OilTemperature {
        viscosity_100c_mm2_s: Some(6.8),
        null_leakage_sigma_share: Some(0.06),
        ..oil
    };
    let (f_stated, s_stated) = laminar_factor_with_sigma(&stated, 55.0, 0.0);
    assert_eq!(f_stated, f);
    assert!((s_stated - (STATED_LAW_UNCERTAINTY + 0.06) * (f - 1.0)).abs() < 1e-12);
    assert!(s_stated < 0.6 * s);
    let (_, s2) = laminar_factor_with_sigma(&oil, 55.0, 2.0);
    // about 4 % a kelvin at 55 °C
    assert!((s2 - s) / f > 0.06 && (s2 - s) / f < 0.1, "{}", (s2 - s) / f);
}

#[test]
fn an_oil_law_without_a_stiffness_slope_infers_nothing() {
    let oil = OilTemperature {
        bulk_modulus_per_k: 0.0,
        ..OilTemperature::default()
    };
    assert!(OilFromStiffness::new(&oil, 1.0).is_none());
    let oil = OilTemperature::default();
    assert!(OilFromStiffness::new(&oil, f64::NAN).is_none());
    // relative to the commissioning's θ: 0.9 there, 0.9·(1 − 0.0045·10) is 10 K warmer
    let mut o = OilFromStiffness::new(&oil, 0.9).expect("a stiffness");
    for _ in 0..100_000 {
        o.observe(0.9 * (1.0 - 0.0045 * 10.0), 1e-3);
    }
    assert!((o.temperature_c() - 50.0).abs() < 1e-6, "{}", o.temperature_c());
}

/// θ as the filter gives it for oil at `true_c` (°C) with the model set
/// to `applied_c`: the stiffness' change and the pull `pull` of the
/// laminar flows' error.
fn theta_seen(oil: &OilTemperature, theta_ref: f64, pull: f64, true_c: f64, applied_c: f64) -> f64 {
    let l = |t: f64| oil.factors(t).laminar_flow;
    theta_ref * (1.0 + oil.bulk_modulus_per_k * (true_c - oil.reference_c))
        + pull * (l(applied_c) - l(true_c))
}

/// Follows θ (1 ms steps over 300 s) for oil at `true_c` (°C); returns
/// the temperature the model was set to at the end.
fn follow(o: &mut OilFromStiffness, oil: &OilTemperature, pull: f64, true_c: f64) -> f64 {
    for _ in 0..300_000 {
        let theta = theta_seen(oil, o.theta_ref, pull, true_c, o.applied_c());
        o.observe(theta, 1e-3);
    }
    o.applied_c()
}

#[test]
fn with_the_laminar_pull_taken_out_the_reading_settles_on_the_oils_temperature() {
    let mut oil = OilTemperature {
        reference_c: 45.0,
        ..OilTemperature::default()
    };
    // a pull that leaves about two thirds of the stiffness' own signal
    let pull = -0.04;
    oil.stiffness_per_laminar_factor = Some(pull);
    let mut o = OilFromStiffness::new(&oil, 0.97).expect("k_β");
    assert!(o.readable());
    // a start-up transient first kicks θ to the soft (warm) side
    for _ in 0..2_000 {
        o.observe(0.90, 1e-3);
    }
    assert!(o.applied_c() > 50.0, "{}", o.applied_c());
    let read = follow(&mut o, &oil, pull, 35.0);
    assert!((read - 35.0).abs() <= OIL_ESTIMATE_STEP_K, "{read}");
    // θ tells the temperature from the range's cold end to where L
    // steepens: beyond it the reading stops, as uncertain as the rest
    let (lo, hi) = o.readable_range_c();
    assert!(
        lo == 20.0 - OIL_RANGE_MARGIN_K && (50.0..60.0).contains(&hi),
        "{lo}..{hi}"
    );
    let warm = follow(&mut o, &oil, pull, 62.0);
    assert!((warm - hi).abs() <= OIL_ESTIMATE_STEP_K, "{warm}");
    assert!(
        o.sigma_k(0.0) >= 60.0 + OIL_RANGE_MARGIN_K - hi,
        "{}",
        o.sigma_k(0.0)
    );
}

#[test]
fn a_pull_that_cancels_the_stiffness_signal_leaves_the_temperature_unread() {
    // a press whose valve leaks at the catalogue's maximum: θ −0.137 per unit of L
    let mut oil = OilTemperature {
        reference_c: 49.4,
        ..OilTemperature::default()
    };
    oil.stiffness_per_laminar_factor = Some(-0.137);
    let mut o = OilFromStiffness::new(&oil, 0.974).expect("k_β");
    assert!(!o.readable());
    assert_eq!(o.pull(), -0.137);
    // whatever θ says, the model stays at the reference
    for _ in 0..20_000 {
        // (it says so once, as it settles)
        assert!(o.observe(0.85, 1e-3).is_none_or(|t| t == 49.4));
    }
    assert_eq!(o.temperature_c(), 49.4);
    // as uncertain as the farthest end of the range θ is read in (20 °C less the margin)
    let widest = 49.4 - (20.0 - OIL_RANGE_MARGIN_K);
    assert!((o.sigma_k(0.001) - widest).abs() < 1e-9, "{}", o.sigma_k(0.001));
    // without the pull the same θ reads as warm oil
    oil.stiffness_per_laminar_factor = None;
    let mut plain = OilFromStiffness::new(&oil, 0.974).expect("k_β");
    for _ in 0..20_000 {
        plain.observe(0.85, 1e-3);
    }
    assert!(plain.temperature_c() > 60.0, "{}", plain.temperature_c());
}

#[test]
fn the_oil_stiffness_line_names_theta_the_modulus_and_a_soft_rig() {
    assert_eq!(oil_stiffness_line(f64::NAN, f64::NAN, 6.89e8), None);
    assert_eq!(
        oil_stiffness_line(0.98, 0.004, 6.89e8).unwrap(),
        "oil stiffness: 0.980 ± 0.004 of the model's bulk modulus (675 of 689 MPa)"
    );
    let soft = oil_stiffness_line(0.74, 0.01, 6.89e8).unwrap();
    assert!(
        soft.starts_with("oil stiffness: 0.740 ± 0.010 of the model's bulk modulus (510 of 689 MPa): softer"),
        "{soft}"
    );
    assert!(soft.contains("leakwatch calibrate"), "{soft}");
    assert!(soft.ends_with("or a pressure transducer that reads off (the filter takes part of its misreading into the stiffness)"), "{soft}");
}

#[test]
fn a_stiffness_read_past_the_range_widens_the_temperatures_sigma_by_the_distance() {
    let oil = OilTemperature {
        reference_c: 30.0,
        ..OilTemperature::default()
    };
    let mut o = OilFromStiffness::new(&oil, 1.0).expect("k_β −0.0045");
    // θ says 30 K above the reference: inside the range, nothing past it
    let at_60 = 1.0 - 0.0045 * 30.0;
    for _ in 0..200_000 {
        o.observe(at_60, 1e-3);
    }
    assert_eq!(o.past_range_k(), 0.0);
    let inside = o.sigma_k(0.0);
    // θ says 50 K above (80 °C): the model is held at 65 °C, 15 K short
    let at_80 = 1.0 - 0.0045 * 50.0;
    let mut moved = None;
    for _ in 0..200_000 {
        moved = o.observe(at_80, 1e-3).or(moved);
    }
    assert!((o.applied_c() - (60.0 + OIL_RANGE_MARGIN_K)).abs() < OIL_ESTIMATE_STEP_K);
    assert!((o.past_range_k() - 15.0).abs() < 1e-6, "{}", o.past_range_k());
    // what σ_T took, and what flags the estimates (FLAG_OIL_PAST_RANGE)
    assert!(
        (o.past_applied_k() - 15.0).abs() < OIL_ESTIMATE_STEP_K,
        "{}",
        o.past_applied_k()
    );
    assert!(moved.is_some());
    // the σ of θ's own (0) and the slope's 20 % of 35 K, with the 15 K past added to θ's part
    let slope = 0.2 * (o.applied_c() - 30.0);
    assert!(
        (o.sigma_k(0.0) - 15f64.hypot(slope)).abs() < OIL_ESTIMATE_STEP_K,
        "{} {inside}",
        o.sigma_k(0.0)
    );
    // back inside: nothing past
    for _ in 0..200_000 {
        o.observe(at_60, 1e-3);
    }
    assert_eq!(o.past_range_k(), 0.0);
    assert_eq!(o.past_applied_k(), 0.0);
    assert!((o.sigma_k(0.0) - inside).abs() < 0.2 * OIL_ESTIMATE_STEP_K);
}
