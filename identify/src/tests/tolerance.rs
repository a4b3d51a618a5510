//! The null leakage's σ from the transducers' tolerances.

use super::*;

/// The lift with a null leakage of 0.35·10⁻¹³ m³/(s·Pa), read by transducers
/// 25 kPa low and 39 kPa high, with span errors of −0.14 % and +0.49 %
/// (within a datasheet's 50 kPa and 0.5 %): the fit's C_L is off the rig's by
/// more than five of its own σ and more than the σ the tolerances give, and
/// by less than the most they can move it (all four adding up). Without
/// tolerances nothing is measured.
#[test]
fn the_transducers_tolerances_bound_the_null_leakage() {
    let c_l = 0.35e-13;
    let rig = ActuatorParams {
        valve_null_leakage_m3_s_pa: c_l,
        ..ActuatorParams::vertical_lift()
    };
    let sensors = model::SensorParams {
        pressure_offset_pa: [-25e3, 39e3],
        pressure_gain_error: [-0.0014, 0.0049],
        ..model::SensorParams::default()
    };
    let rows = record_with(&rig, sensors, "lift", 60.0, 0);
    let id = identify(&rig, 1e-3, &rows, noise()).expect("identified");
    let fit = id.null_leakage_m3_s_pa.estimate().expect("C_L identified");
    let tol = TransducerTolerance {
        zero_offset_max_pa: 50e3,
        span_error_max_fraction: 0.005,
    };
    let moved = null_leakage_tolerance(&rig, 1e-3, &rows, noise(), &id, tol).expect("measured");
    let off = (fit.value - c_l).abs();
    eprintln!(
        "C_L {:.3e} ± {:.1e} (fit); the tolerances: σ {:.1e}, at most {:.1e}; the rig's {c_l:.3e}",
        fit.value, fit.sigma, moved.sigma_m3_s_pa, moved.worst_m3_s_pa
    );
    assert!(off > 5.0 * fit.sigma, "off by {off:e}, σ {:e}", fit.sigma);
    assert!(off > moved.sigma_m3_s_pa, "off by {off:e}, {moved:?}");
    assert!(off < moved.worst_m3_s_pa, "off by {off:e}, {moved:?}");
    let none = TransducerTolerance {
        zero_offset_max_pa: 0.0,
        span_error_max_fraction: 0.0,
    };
    assert_eq!(
        null_leakage_tolerance(&rig, 1e-3, &rows, noise(), &id, none),
        None
    );
}
