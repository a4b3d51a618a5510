//! `leakwatch init`'s template: a config whose `[datasheet]` describes an example
//! rig, each fact commented with its unit, for the user to overwrite with their
//! rig's (docs/rig.md).

use model::datasheet::{
    CylinderKind, CylinderSheet, Datasheet, HoseSheet, OilSheet, PositionSensorSheet, SupplySheet,
    TransducerLocation, TransducerSheet, ValveSheet,
};

/// The example rig of the template: a horizontal double-rod press, or with
/// `single_rod` a vertical single-rod lift of 200 kg with a matched valve.
pub fn example(single_rod: bool) -> Datasheet {
    let mut sheet = Datasheet {
        cylinder: CylinderSheet {
            kind: CylinderKind::DoubleRod,
            bore_m: 0.05,
            rod_m: 0.032,
            stroke_m: 0.3,
            mounting_angle_deg: 0.0,
            moving_mass_kg: 30.0,
        },
        hoses: HoseSheet {
            inner_diameter_m: 0.0127,
            length_a_m: 0.5,
            length_b_m: 0.5,
            extra_volume_a_m3: 0.0,
            extra_volume_b_m3: 0.0,
        },
        oil: OilSheet::mineral(870.0, 1.6e9),
        valve: ValveSheet {
            rated_flow_l_min: 30.0,
            rated_flow_b_l_min: None,
            rated_pressure_drop_pa: 7.0e6,
            rated_signal_v: 10.0,
            spool_stroke_m: 3.0e-4,
            phase_90_hz: 120.0,
            null_leakage_l_min: 0.0,
        },
        supply: SupplySheet { pressure_pa: 21.0e6 },
        pressure_transducers: TransducerSheet {
            full_scale_pa: 25.0e6,
            adc_bits: 16,
            noise_pa: 8.0e3,
            location: TransducerLocation::Manifold,
            response_time_s: 2.0e-3,
            zero_offset_max_pa: 50.0e3,
            span_error_max_fraction: 0.005,
        },
        position_sensor: PositionSensorSheet {
            resolution_m: 2.0e-6,
            noise_m: 3.0e-6,
        },
    };
    if single_rod {
        sheet.cylinder = CylinderSheet {
            kind: CylinderKind::SingleRod,
            stroke_m: 0.4,
            mounting_angle_deg: 90.0,
            moving_mass_kg: 200.0,
            ..sheet.cylinder
        };
        sheet.hoses.length_a_m = 0.9;
        sheet.hoses.length_b_m = 0.9;
        sheet.valve.rated_flow_b_l_min = Some(18.0);
    }
    sheet
}

/// A number as TOML: the shortest text that reads back to the same f64, with
/// an exponent from 1e5 up (`1.6e9`, not `1600000000.0`).
fn num(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:e}")
    } else {
        format!("{v:?}")
    }
}

/// One line of the template: key, value (empty: commented out), comment.
type Line = (&'static str, String, &'static str);

/// The comment at the top of the template: what the file is and what to do with it.
const HEADER: &str = "# leakwatch configuration: your rig in its datasheets' terms (docs/rig.md).\n\
     # The values below are an example rig: replace each with yours.\n\
     # leakwatch derives the model, the sensors and the leak filter's noise from\n\
     # them; do not write those facts again in [model], [sensors] or [leak_filter].\n\
     # Check it:  leakwatch config --check leakwatch.toml\n\
     # Then:      leakwatch commission HEALTHY.csv --config leakwatch.toml --out rig.toml\n";

/// The template: `sheet` as a `[datasheet]` with one comment per fact.
pub fn template(sheet: &Datasheet) -> String {
    let mut out = String::from(HEADER);
    let sections: [(&str, Vec<Line>); 7] = [
        ("cylinder", cylinder_lines(&sheet.cylinder)),
        ("hoses", hose_lines(&sheet.hoses)),
        ("oil", oil_lines(&sheet.oil)),
        ("valve", valve_lines(&sheet.valve)),
        ("supply", supply_lines(&sheet.supply)),
        (
            "pressure_transducers",
            transducer_lines(&sheet.pressure_transducers),
        ),
        ("position_sensor", position_sensor_lines(&sheet.position_sensor)),
    ];
    for (section, fields) in sections {
        out.push_str(&format!("\n[datasheet.{section}]\n"));
        for (key, value, note) in fields {
            let line = if value.is_empty() {
                format!("# {key} = ...")
            } else {
                format!("{key} = {value}")
            };
            out.push_str(&format!("{line:<32}# {note}\n"));
        }
    }
    out
}

/// The `[datasheet.cylinder]` lines: kind, bore, rod and stroke (m), mounting angle (degrees), moving mass (kg).
fn cylinder_lines(c: &CylinderSheet) -> Vec<Line> {
    let kind = match c.kind {
        CylinderKind::DoubleRod => "\"double-rod\"".to_string(),
        CylinderKind::SingleRod => "\"single-rod\"".to_string(),
    };
    vec![
        (
            "kind",
            kind,
            "\"double-rod\" (a rod through both ends) or \"single-rod\" (port A feeds the cap side)",
        ),
        ("bore_m", num(c.bore_m), "piston diameter, m"),
        ("rod_m", num(c.rod_m), "rod diameter, m"),
        ("stroke_m", num(c.stroke_m), "m"),
        (
            "mounting_angle_deg",
            num(c.mounting_angle_deg),
            "extension above the horizontal, degrees: 0 horizontal, 90 lifts, -90 lowers",
        ),
        (
            "moving_mass_kg",
            num(c.moving_mass_kg),
            "piston, rod, tool and payload, kg",
        ),
    ]
}

/// The `[datasheet.hoses]` lines: diameter and lengths (m), extra volumes (m³).
fn hose_lines(h: &HoseSheet) -> Vec<Line> {
    vec![
        ("inner_diameter_m", num(h.inner_diameter_m), "m"),
        ("length_a_m", num(h.length_a_m), "valve port A to the cylinder, m"),
        ("length_b_m", num(h.length_b_m), "valve port B to the cylinder, m"),
        (
            "extra_volume_a_m3",
            num(h.extra_volume_a_m3),
            "manifold bores and the cylinder's end volume on the port A side, m³",
        ),
        (
            "extra_volume_b_m3",
            num(h.extra_volume_b_m3),
            "the same on the port B side, m³",
        ),
    ]
}

/// The `[datasheet.oil]` lines: density (kg/m³), bulk modulus (Pa), viscosities (mm²/s), temperature coefficient (1/K) and range (°C).
fn oil_lines(oil: &OilSheet) -> Vec<Line> {
    vec![
        ("density_kg_m3", num(oil.density_kg_m3), "kg/m³"),
        (
            "bulk_modulus_pa",
            num(oil.bulk_modulus_pa),
            "without air, Pa (commissioning finds the effective one)",
        ),
        (
            "viscosity_40c_mm2_s",
            num(oil.viscosity_40c_mm2_s),
            "at 40 °C, mm²/s (the ISO VG grade)",
        ),
        (
            "viscosity_100c_mm2_s",
            oil.viscosity_100c_mm2_s.map(num).unwrap_or_default(),
            "at 100 °C, mm²/s, where the oil's data sheet gives it (omit: its grade's at viscosity index 100, known less well)",
        ),
        (
            "bulk_modulus_per_k",
            num(oil.bulk_modulus_per_k),
            "relative change per kelvin, 1/K (mineral oil about -0.0045)",
        ),
        (
            "operating_min_c",
            num(oil.operating_min_c),
            "the lowest oil temperature the rig runs at, °C",
        ),
        (
            "operating_max_c",
            num(oil.operating_max_c),
            "the highest, °C (commissioning states the smallest detectable leaks over the range)",
        ),
    ]
}

/// The `[datasheet.valve]` lines: rated flows (L/min), drop (Pa) and signal (V), spool stroke (m), bandwidth (Hz), null leakage (L/min).
fn valve_lines(v: &ValveSheet) -> Vec<Line> {
    let rated_b = match v.rated_flow_b_l_min {
        Some(q) => num(q),
        None => String::new(),
    };
    vec![
        (
            "rated_flow_l_min",
            num(v.rated_flow_l_min),
            "port A at the rated signal and drop, L/min",
        ),
        (
            "rated_flow_b_l_min",
            rated_b,
            "port B's, for a valve matched to a single-rod area ratio (omit: port A's), L/min",
        ),
        (
            "rated_pressure_drop_pa",
            num(v.rated_pressure_drop_pa),
            "valve drop of the rated flow, both lands (7 MPa = 3.5 MPa per land), Pa",
        ),
        ("rated_signal_v", num(v.rated_signal_v), "V"),
        (
            "spool_stroke_m",
            num(v.spool_stroke_m),
            "spool travel at the rated signal, m",
        ),
        (
            "phase_90_hz",
            num(v.phase_90_hz),
            "frequency of 90° phase lag, Hz",
        ),
        (
            "null_leakage_l_min",
            num(v.null_leakage_l_min),
            "internal leakage at supply with the ports blocked, L/min (0: critical centre)",
        ),
    ]
}

/// The `[datasheet.supply]` line: the supply pressure (Pa).
fn supply_lines(supply: &SupplySheet) -> Vec<Line> {
    vec![("pressure_pa", num(supply.pressure_pa), "the pump's setting, Pa")]
}

/// The `[datasheet.pressure_transducers]` lines: full scale (Pa), ADC bits, noise (Pa), location, response time (s).
fn transducer_lines(t: &TransducerSheet) -> Vec<Line> {
    vec![
        (
            "full_scale_pa",
            num(t.full_scale_pa),
            "the range is 0 to this, Pa",
        ),
        (
            "adc_bits",
            t.adc_bits.to_string(),
            "the DAQ's resolution over the full scale, bits",
        ),
        (
            "noise_pa",
            num(t.noise_pa),
            "noise of a reading (standard deviation), Pa",
        ),
        (
            "location",
            match t.location {
                TransducerLocation::CylinderPorts => "\"cylinder-ports\"".to_string(),
                TransducerLocation::Manifold => "\"manifold\"".to_string(),
            },
            "\"cylinder-ports\" or \"manifold\" (at the valve: they read the hose's drop too)",
        ),
        (
            "response_time_s",
            num(t.response_time_s),
            "10-90 % response time, the datasheet's maximum, s (0: not given)",
        ),
        (
            "zero_offset_max_pa",
            num(t.zero_offset_max_pa),
            "each one's zero offset, the datasheet's maximum, Pa (0: not given)",
        ),
        (
            "span_error_max_fraction",
            num(t.span_error_max_fraction),
            "each one's span error, the datasheet's maximum (0.005: 0.5 %; 0: not given)",
        ),
    ]
}

/// The `[datasheet.position_sensor]` lines: resolution and noise (m).
fn position_sensor_lines(p: &PositionSensorSheet) -> Vec<Line> {
    vec![
        ("resolution_m", num(p.resolution_m), "one count, m"),
        (
            "noise_m",
            num(p.noise_m),
            "noise of a reading (standard deviation), m",
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Config;
    use model::ActuatorParams;

    #[test]
    fn each_template_reads_back_as_its_rig() {
        for single_rod in [false, true] {
            let sheet = example(single_rod);
            let text = template(&sheet);
            let cfg = Config::parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(cfg.datasheet, Some(sheet));
            assert_eq!(cfg.model, sheet.model(&ActuatorParams::default()));
            let (r_x, r_p) = sheet.measurement_noise();
            assert_eq!((cfg.leak_filter.r_x_m2, cfg.leak_filter.r_p_pa2), (r_x, r_p));
            // the detector's copies follow
            assert_eq!(cfg.classifier.supply_pressure_pa, 21.0e6);
            assert_eq!(cfg.classifier.pressure_full_scale_pa, 25.0e6);
            assert_eq!(cfg.model.rod_side_area_m2.is_some(), single_rod);
            // 30 L/min at 7 MPa through 0.3 mm with C_d 0.6 and 870 kg/m³: w = 0.03097 m²/m
            assert!((cfg.model.area_gradient_m2_per_m - 0.030968).abs() < 1e-6);
            // what `config --check` prints reads back to the same config
            let again = toml::to_string(&cfg).expect("serialise");
            assert_eq!(Config::parse(&again).expect("reads back"), cfg);
        }
    }

    #[test]
    fn the_oils_viscosity_at_100_c_is_left_out_until_its_data_sheet_gives_it() {
        let text = template(&example(false));
        assert!(text.contains("# viscosity_100c_mm2_s = ..."), "{text}");
        let cfg = Config::parse(&text).expect("valid");
        assert_eq!(cfg.model.oil_temperature.viscosity_100c_mm2_s, None);
        assert_eq!(
            cfg.model.oil_temperature.law_uncertainty(),
            model::params::CATALOGUE_LAW_UNCERTAINTY
        );
        // given, it reaches the model's law; the uncertainty narrows once
        // commissioning has measured how well it knows the null leakage
        let text = text.replace("# viscosity_100c_mm2_s = ...", "viscosity_100c_mm2_s = 6.5");
        let mut cfg = Config::parse(&text).expect("valid");
        assert_eq!(cfg.datasheet.map(|d| d.oil.viscosity_100c_mm2_s), Some(Some(6.5)));
        assert_eq!(cfg.model.oil_temperature.viscosity_100c_mm2_s, Some(6.5));
        assert_eq!(
            cfg.model.oil_temperature.law_uncertainty(),
            model::params::CATALOGUE_LAW_UNCERTAINTY
        );
        cfg.model.oil_temperature.null_leakage_sigma_share = Some(0.1);
        let again = Config::parse(&toml::to_string(&cfg).expect("serialise")).expect("reads back");
        assert_eq!(again, cfg);
        assert!(
            (again.model.oil_temperature.law_uncertainty() - model::params::STATED_LAW_UNCERTAINTY - 0.1)
                .abs()
                < 1e-12
        );
        // thicker at 100 °C than at 40 °C is refused, by its name
        let e = Config::parse(&text.replace("viscosity_100c_mm2_s = 6.5", "viscosity_100c_mm2_s = 50.0"))
            .unwrap_err();
        assert!(e.contains("viscosity_100c_mm2_s"), "{e}");
    }

    #[test]
    fn a_fact_written_twice_is_refused_by_both_names() {
        let text = template(&example(false)) + "\n[model]\nmass_kg = 31.0\ndischarge_coefficient = 0.65\n";
        let e = Config::parse(&text).unwrap_err();
        assert!(
            e.contains("[model] mass_kg = 31.0")
                && e.contains("cylinder.moving_mass_kg")
                && e.contains("30.0"),
            "{e}"
        );
        // a fact the datasheet does not give is the model's: C_d sets the area gradient
        let text = template(&example(false)) + "\n[model]\ndischarge_coefficient = 0.65\n";
        let cfg = Config::parse(&text).expect("valid");
        assert!((cfg.model.area_gradient_m2_per_m * 0.65 - 0.030968 * 0.6).abs() < 1e-6);
        // a bad fact is named in the datasheet's terms
        let text = template(&example(true)).replace("rod_m = 0.032", "rod_m = 0.07");
        let e = Config::parse(&text).unwrap_err();
        assert!(
            e.contains("datasheet.cylinder.rod_m") && e.contains("0.99 of the bore"),
            "{e}"
        );
        // a missing fact is named
        let text = template(&example(true)).replace("stroke_m = 0.4", "");
        let e = Config::parse(&text).unwrap_err();
        assert!(e.contains("stroke_m"), "{e}");
    }
}
