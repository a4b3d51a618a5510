//! Tests of the commissioning's statements.

use super::*;

/// The smallest detectable leaks are stated at the ends and the middle of
/// the model's operating range: the thresholds themselves at the
/// commissioning's temperature, wider away from it; a commissioning
/// outside the range says so.
#[test]
fn the_detectable_leaks_are_stated_over_the_operating_range() {
    let mut m = model::ActuatorParams {
        valve_null_leakage_m3_s_pa: 1e-13,
        ..model::ActuatorParams::default()
    };
    m.oil_temperature.operating_min_c = 10.0;
    m.oil_temperature.operating_max_c = 50.0;
    m.oil_temperature.reference_c = 30.0;
    let thr = [0.03, 0.03, 0.04];
    let line = detectable_over_temperature(&m, thr, [0.01, -0.01, 0.02]);
    let at = |t: &str| -> Vec<f64> {
        let rest = line.split(&format!("{t} °C ")).nth(1).expect(t);
        let v = rest.split([',', ' ']).next().expect("values");
        v.split('/').map(|x| x.parse().expect("a number")).collect()
    };
    let (cold, mid, warm) = (at("10"), at("30"), at("50"));
    for k in 0..3 {
        assert!((mid[k] - thr[k]).abs() < 1e-3, "{line}");
        assert!(cold[k] > mid[k] + 1e-3 && warm[k] > mid[k] + 1e-3, "{line}");
    }
    assert!(!line.contains("outside"), "{line}");
    // a tank thermometer's reading just below the range is not outside it
    m.oil_temperature.reference_c = 9.0;
    assert!(!detectable_over_temperature(&m, thr, [0.0; 3]).contains("outside"));
    m.oil_temperature.reference_c = 55.0;
    let line = detectable_over_temperature(&m, thr, [0.01, -0.01, 0.02]);
    assert!(line.contains("outside the operating range 10-50 °C"), "{line}");
}

/// θ's spread at one temperature widens the smallest detectable leak at
/// the commissioning's temperature by the band a temperature that
/// uncertain leaves.
#[test]
fn thetas_spread_widens_the_detectable_leaks_at_the_reference() {
    let mut m = model::ActuatorParams {
        valve_null_leakage_m3_s_pa: 1e-13,
        ..model::ActuatorParams::default()
    };
    m.oil_temperature.reference_c = 40.0;
    let thr = [0.03, 0.03, 0.04];
    let offsets = [0.01, -0.01, 0.02];
    let [_, (_, plain), _] = detectable_at(&m, thr, offsets);
    assert_eq!(plain, thr);
    // 0.9 % over k_β's 0.45 %/K: 2 K
    m.oil_temperature.reference_stiffness_sigma_share = Some(0.009);
    let [_, (t, spread), _] = detectable_at(&m, thr, offsets);
    assert_eq!(t, 40.0);
    let (sigma, band) = filter::oil::null_leakage_band(&m, 40.0, 2.0);
    let widen = detect::oil_band_lpm(sigma, band, offsets);
    for k in 0..3 {
        assert!(widen[k] > 1e-3, "{widen:?}");
        assert!((spread[k] - thr[k] - widen[k]).abs() < 1e-12, "{spread:?}");
    }
}

/// θ's spread is read from its means over blocks of the reading's low-pass:
/// blocks alternating by ±0.01 about 0.89; none from fewer than four.
#[test]
fn thetas_spread_is_its_block_means_standard_deviation_over_its_mean() {
    let feed = |blocks: usize| {
        let mut theta = theta::ThetaMean::default();
        let mut e = filter::Estimate::default();
        for i in 0..blocks * 10_000 {
            e.t_s = i as f64 * 1e-3;
            let block = (e.t_s / filter::oil::OIL_STIFFNESS_TAU_S).floor() as usize;
            e.bulk_scale = if block.is_multiple_of(2) { 0.88 } else { 0.90 };
            theta.push(&e);
        }
        theta
    };
    let theta = feed(10);
    assert!((theta.mean().expect("a mean") - 0.89).abs() < 1e-9);
    let share = theta.block_spread_share().expect("a spread");
    let expected = 0.01 * (10.0f64 / 9.0).sqrt() / 0.89;
    assert!((share - expected).abs() < 1e-9, "{share} against {expected}");
    assert_eq!(feed(3).block_spread_share(), None);
}

#[test]
fn a_lag_is_held_against_the_datasheets_response_time() {
    let lag = |value: f64, sigma: f64| identify::Estimate { value, sigma };
    // plant_dev/double's p1: 1.64 ± 0.02 ms against 2.5 ms / ln 9 = 1.14 ms
    let bound = Some(2.5e-3 / 9f64.ln());
    let above = lag_against_datasheet(&lag(1.643e-3, 0.016e-3), bound);
    assert!(
        above.contains("above the 1.14 ms") && above.contains("another delay"),
        "{above}"
    );
    let within = lag_against_datasheet(&lag(0.51e-3, 0.014e-3), bound);
    assert!(within.contains("within the 1.14 ms"), "{within}");
    // within 2 σ of the bound is within
    assert!(lag_against_datasheet(&lag(1.16e-3, 0.02e-3), bound).contains("within"));
    assert_eq!(lag_against_datasheet(&lag(1.643e-3, 0.016e-3), None), "");
}

/// The null leakage's σ share is the tolerances' σ over the identified null
/// leakage, held to the field's range; none without tolerances or a null leakage.
#[test]
fn the_null_leakages_sigma_share_is_its_tolerances_sigma_over_it() {
    let tol = |sigma_m3_s_pa: f64| {
        Some(identify::NullLeakageTolerance {
            sigma_m3_s_pa,
            worst_m3_s_pa: 3.0 * sigma_m3_s_pa,
        })
    };
    let share = balances::null_leakage_sigma_share(tol(0.34e-13), 1.0e-13).expect("a share");
    assert!((share - 0.34).abs() < 1e-12, "{share}");
    assert_eq!(balances::null_leakage_sigma_share(None, 1.0e-13), None);
    assert_eq!(balances::null_leakage_sigma_share(tol(0.34e-13), 0.0), None);
    assert_eq!(balances::null_leakage_sigma_share(tol(f64::NAN), 1.0e-13), None);
    // a null leakage next to none: the share is held at the field's largest
    assert_eq!(
        balances::null_leakage_sigma_share(tol(1e-13), 1e-30),
        Some(1000.0)
    );
    // a config that carries the largest reads back; one past it is refused by name
    let mut cfg = config::Config::default();
    cfg.model.oil_temperature.null_leakage_sigma_share = Some(1000.0);
    let text = toml::to_string(&cfg).expect("serialise");
    assert_eq!(config::Config::parse(&text).expect("in range"), cfg);
    let e = config::Config::parse(&text.replace(
        "null_leakage_sigma_share = 1000.0",
        "null_leakage_sigma_share = 1001.0",
    ))
    .unwrap_err();
    assert!(e.contains("null_leakage_sigma_share"), "{e}");
}
