//! What commissioning says of the identification: the flow balance's
//! parameters against the model, and the force balance's.

use config::Config;

use super::{Identified, Param};

/// What an identified transducer lag `e` (s) says against the longest lag the
/// datasheet's response time allows, `bound_s` (s; `None`: not given): a lag
/// beyond it by more than 2 σ holds another delay.
pub(super) fn lag_against_datasheet(e: &identify::Estimate, bound_s: Option<f64>) -> String {
    match bound_s {
        None => String::new(),
        Some(b) if e.value > b + 2.0 * e.sigma => format!(
            "; above the {:.2} ms the datasheet's response time allows: another delay is in it (the hose, \
             the DAQ's timing); the NIS counts {:.2} ms",
            b * 1e3,
            b * 1e3
        ),
        Some(b) => format!(
            "; within the {:.2} ms the datasheet's response time allows",
            b * 1e3
        ),
    }
}

/// What the flow balance identified (`id`) against the model of `cfg`, and
/// what the recording cannot tell apart; `tolerance`: how far the
/// transducers' tolerances move the null leakage, if measured.
pub(super) fn flow_balance(
    id: &identify::Identification,
    tolerance: Option<identify::NullLeakageTolerance>,
    cfg: &Config,
    out: &mut Identified,
) {
    let dt = cfg.leak_filter.sample_period_s;
    let m = &cfg.model;
    let (wa, wb) = m.area_gradients_m2_per_m();
    out.windows = (
        id.windows,
        identify::WINDOW_SAMPLES as f64 * dt * 1e3,
        id.moving_windows,
    );
    out.gap_lpm = (id.gap_before_lpm, id.gap_after_lpm, id.sensor_floor_lpm);
    let ga = &id.valve_gain_a;
    let two_ports = !(m.rod_side_area_m2.is_none() && m.area_gradient_b_m2_per_m.is_none());
    let port_a = if two_ports {
        "port A area gradient"
    } else {
        "valve area gradient"
    };
    out.flow
        .push(Param::new(port_a, &ga.scaled(wa), "mm²/mm", 1e3, wa));
    if two_ports {
        out.flow.push(Param::new(
            "port B area gradient",
            &id.valve_gain_b.scaled(wb),
            "mm²/mm",
            1e3,
            wb,
        ));
    }
    let two_pi = 2.0 * std::f64::consts::PI;
    out.flow.extend([
        Param::new(
            "effective bulk modulus",
            &id.bulk_modulus_pa,
            "MPa",
            1e-6,
            m.bulk_modulus_pa,
        ),
        Param::new(
            "valve null leakage C_L",
            &id.null_leakage_m3_s_pa,
            "1e-13 m³/(s·Pa)",
            1e13,
            m.valve_null_leakage_m3_s_pa,
        ),
        Param::new(
            "supply sag",
            &id.supply_sag_pa_per_m3_s,
            "MPa per m³/s",
            1e-6,
            m.supply_sag_pa_per_m3_s,
        ),
        Param::new(
            "spool -90° frequency",
            &id.spool_natural_freq_rad_s.scaled(1.0 / two_pi),
            "Hz",
            1.0,
            m.spool_natural_freq_rad_s / two_pi,
        ),
    ]);
    let transducers = cfg.datasheet.as_ref().map(|d| d.pressure_transducers);
    // (calibrate's model.toml carries no datasheet: calibrate said it)
    if let Some(t) = transducers {
        out.notes.push(null_leakage_tolerance(id, tolerance, t));
    }
    for (channel, found) in ["p1", "p2"].iter().zip(&id.pressure_lag_s) {
        out.notes.push(match found {
            identify::Found::Identified(e) => format!(
                "  {channel} transducer lag: {:.3} ± {:.3} ms (apparent; the leak filter's NIS counts it, \
                 [leak_filter] pressure_lag_s){}",
                e.value * 1e3,
                e.sigma * 1e3,
                lag_against_datasheet(e, transducers.and_then(|t| t.lag_bound_s()))
            ),
            identify::Found::NotIdentifiable(why) => {
                format!("  {channel} transducer lag: not identifiable from this recording: {why}")
            }
        });
    }
    out.notes.push(match &id.line_resistance_pa_s_per_m3 {
        identify::Found::Identified(e) => format!(
            "  line resistance, transducers to chambers: {:.0} ± {:.0} MPa per m³/s (the line's drop, \
             fitted beside the null leakage; in the model: the leak filter predicts its readings with it)",
            e.value * 1e-6,
            e.sigma * 1e-6
        ),
        identify::Found::NotIdentifiable(why) => {
            format!(
                "  line resistance, transducers to chambers: not identifiable from this recording: {why}; \
                 the model reads the chambers at the transducers (0)"
            )
        }
    });
    out.notes.push(match &id.sample_jitter_s {
        identify::Found::Identified(e) => format!(
            "  DAQ sample timing: {:.1} ± {:.1} µs jitter (RMS; from the position's noise, which grows with \
             the rod's speed; counted in the sensor floor and, as [leak_filter] sample_jitter_s, in the \
             leak filter's measurement noise)",
            e.value * 1e6,
            e.sigma * 1e6
        ),
        identify::Found::NotIdentifiable(why) => {
            format!("  DAQ sample timing: no jitter counted in the sensor floor: {why}")
        }
    });
    out.notes.push(match id.oil_temp_c {
        Some(t) => format!(
            "  oil temperature: {t:.1} °C (the recording's temp_c): the identified values hold there, \
             and a live temp_c moves the model from it"
        ),
        None => format!(
            "  oil temperature: not recorded (no temp_c column): the identified values hold at the \
             recording's temperature, taken as [model.oil_temperature] reference_c = {:.1} °C; set it \
             to the oil's temperature during the recording (the tank's thermometer): the live model \
             moves from it, with temp_c or with the temperature the leak filter reads from the oil's stiffness",
            m.oil_temperature.reference_c
        ),
    });
    // what this recording cannot tell apart, said rather than guessed
    out.notes.push(
        "  transducer offsets: not separable in the balances: the flow balance uses pressure \
         changes (an offset cancels); in the force balance an offset difference reads as a static \
         load and a common offset as supply pressure; a reading at zero pressure (pump off) gives them \
         (commissioning fits their misreading at the working point to the leak filter, below)"
            .to_string(),
    );
}

/// What the force balance identified (`mech`) against the model of `cfg`.
pub(super) fn force_balance(mech: &identify::Mechanics, cfg: &Config, out: &mut Identified) {
    let m = &cfg.model;
    let transducers = cfg.datasheet.as_ref().map(|d| d.pressure_transducers);
    let f = m.friction.extend();
    out.force_gap_n = Some((mech.equations, mech.gap_before_n, mech.gap_after_n));
    let viscous = match transducers.map(|t| t.location) {
        Some(model::datasheet::TransducerLocation::Manifold) => {
            "viscous friction (apparent: with the hoses' drop, the transducers being at the manifold)"
        }
        _ => "viscous friction (apparent)",
    };
    out.mechanics = vec![
        Param::new("moving mass", &mech.mass_kg, "kg", 1.0, m.mass_kg),
        Param::new("Coulomb friction", &mech.coulomb_n, "N", 1.0, f.slip_n),
        Param::new("static friction", &mech.static_n, "N", 1.0, f.static_n),
        Param::new(
            "Stribeck velocity",
            &mech.stribeck_velocity_m_s,
            "mm/s",
            1e3,
            f.stribeck_velocity_m_s,
        ),
        Param::new(
            viscous,
            &mech.viscous_n_s_per_m,
            "N·s/m",
            1.0,
            f.viscous_n_s_per_m,
        ),
        Param::new(
            "static force (weight and load)",
            &mech.static_force_n,
            "N",
            1.0,
            m.gravity_force_n(),
        ),
    ];
    if let Some((k, contact_m)) = mech.contact_spring {
        out.notes.push(format!(
            "  a workpiece: a contact spring of {:.4e} ± {:.1e} N/m from {:.1} mm on (in the force balance, and now in the model's load)",
            k.value,
            k.sigma,
            contact_m * 1e3
        ));
    }
}

/// The line that says how far the transducers' tolerances (the datasheet's
/// `t`) move the null leakage `id` found (`tolerance`, as
/// measured), against the fit's σ, or why it is not said.
fn null_leakage_tolerance(
    id: &identify::Identification,
    tolerance: Option<identify::NullLeakageTolerance>,
    t: model::datasheet::TransducerSheet,
) -> String {
    let head = "  valve null leakage C_L and the transducers' tolerances:";
    let Some(fit) = id.null_leakage_m3_s_pa.estimate() else {
        return format!("{head} no null leakage identified");
    };
    let percent = |v: f64| 100.0 * v / fit.value.abs();
    match tolerance {
        Some(moved) => format!(
            "{head} their zero offsets (±{:.0} kPa) and span errors (±{:.2} %) move C_L by up to \
             ±{:.4} 1e-13 m³/(s·Pa) ({:.0} %; σ {:.0} %, the fit's σ {:.0} %): a recording cannot tell them apart",
            t.zero_offset_max_pa * 1e-3,
            t.span_error_max_fraction * 100.0,
            moved.worst_m3_s_pa * 1e13,
            percent(moved.worst_m3_s_pa),
            percent(moved.sigma_m3_s_pa),
            percent(fit.sigma)
        ),
        None if t.zero_offset_max_pa > 0.0 || t.span_error_max_fraction > 0.0 => format!(
            "{head} not measured: with the readings moved by them the flow balance does not identify C_L"
        ),
        _ => format!(
            "{head} not given ([datasheet.pressure_transducers] zero_offset_max_pa, \
             span_error_max_fraction): how far they move C_L is not said"
        ),
    }
}

/// The largest share [`null_leakage_sigma_share`] gives (1): the range
/// `[model.oil_temperature] null_leakage_sigma_share` takes.
const MOST_NULL_LEAKAGE_SIGMA_SHARE: f64 = 1000.0;

/// The σ the transducers' tolerances `tolerance` give the null leakage
/// `null_leakage_m3_s_pa` (m³/(s·Pa)), as a share of it (1, at most
/// [`MOST_NULL_LEAKAGE_SIGMA_SHARE`]); None without them or without a null
/// leakage.
pub(super) fn null_leakage_sigma_share(
    tolerance: Option<identify::NullLeakageTolerance>,
    null_leakage_m3_s_pa: f64,
) -> Option<f64> {
    let sigma = tolerance?.sigma_m3_s_pa;
    (null_leakage_m3_s_pa > 0.0 && sigma.is_finite())
        .then(|| (sigma.abs() / null_leakage_m3_s_pa).min(MOST_NULL_LEAKAGE_SIGMA_SHARE))
}
