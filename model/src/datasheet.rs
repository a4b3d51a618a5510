//! A rig described in its datasheets' own terms (`[datasheet]` of the config):
//! bore and rod, hoses, oil, the valve's rated flow, the transducers. The
//! model's, the sensors' and the leak filter's rig facts are derived from it
//! once ([`Datasheet::model`], [`Datasheet::sensors`],
//! [`Datasheet::measurement_noise`]); docs/rig.md gives each formula.

use serde::{Deserialize, Serialize};

use crate::params::{ActuatorParams, OilTemperature};
use crate::sensors::SensorParams;

mod sheets;
mod validate;

pub use sheets::{
    CylinderKind, CylinderSheet, HoseSheet, OilSheet, PositionSensorSheet, SupplySheet, TransducerLocation,
    TransducerSheet, ValveSheet,
};

schema::config_struct! {
    /// A rig in its datasheets' terms: every rig fact in one place.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Datasheet {
        /// The cylinder and what it moves.
        pub cylinder: CylinderSheet,
        /// The lines between valve and cylinder.
        pub hoses: HoseSheet,
        /// The oil.
        pub oil: OilSheet,
        /// The servovalve.
        pub valve: ValveSheet,
        /// The hydraulic supply.
        pub supply: SupplySheet,
        /// The chamber-pressure transducers.
        pub pressure_transducers: TransducerSheet,
        /// The rod's position sensor.
        pub position_sensor: PositionSensorSheet,
    }
}

/// The config fields a datasheet derives: (section, field, the datasheet fact
/// it comes from). Written once: a config with a `[datasheet]` may not set them.
pub const DERIVED_FIELDS: [(&str, &str, &str); 30] = [
    ("model", "piston_area_m2", "cylinder.bore_m and rod_m"),
    ("model", "rod_side_area_m2", "cylinder.kind, bore_m and rod_m"),
    ("model", "mounting_angle_rad", "cylinder.mounting_angle_deg"),
    ("model", "mass_kg", "cylinder.moving_mass_kg"),
    ("model", "x_min_m", "cylinder.stroke_m"),
    ("model", "x_max_m", "cylinder.stroke_m"),
    ("model", "dead_volume_1_m3", "hoses"),
    ("model", "dead_volume_2_m3", "hoses"),
    ("model", "bulk_modulus_pa", "oil.bulk_modulus_pa"),
    ("model", "oil_density_kg_m3", "oil.density_kg_m3"),
    (
        "model",
        "oil_temperature.viscosity_40c_mm2_s",
        "oil.viscosity_40c_mm2_s",
    ),
    (
        "model",
        "oil_temperature.viscosity_100c_mm2_s",
        "oil.viscosity_100c_mm2_s",
    ),
    (
        "model",
        "oil_temperature.bulk_modulus_per_k",
        "oil.bulk_modulus_per_k",
    ),
    ("model", "oil_temperature.operating_min_c", "oil.operating_min_c"),
    ("model", "oil_temperature.operating_max_c", "oil.operating_max_c"),
    ("model", "area_gradient_m2_per_m", "valve.rated_flow_l_min"),
    ("model", "area_gradient_b_m2_per_m", "valve.rated_flow_b_l_min"),
    (
        "model",
        "spool_gain_m_per_v",
        "valve.spool_stroke_m and rated_signal_v",
    ),
    ("model", "spool_natural_freq_rad_s", "valve.phase_90_hz"),
    ("model", "supply_pressure_pa", "supply.pressure_pa"),
    ("model", "valve_null_leakage_m3_s_pa", "valve.null_leakage_l_min"),
    ("sensors", "encoder_resolution_m", "position_sensor.resolution_m"),
    ("sensors", "position_noise_m", "position_sensor.noise_m"),
    (
        "sensors",
        "pressure_full_scale_pa",
        "pressure_transducers.full_scale_pa",
    ),
    ("sensors", "adc_bits", "pressure_transducers.adc_bits"),
    ("sensors", "pressure_noise_pa", "pressure_transducers.noise_pa"),
    (
        "sensors",
        "pressure_zero_offset_max_pa",
        "pressure_transducers.zero_offset_max_pa",
    ),
    (
        "sensors",
        "pressure_span_error_max",
        "pressure_transducers.span_error_max_fraction",
    ),
    ("leak_filter", "r_x_m2", "position_sensor"),
    ("leak_filter", "r_p_pa2", "pressure_transducers"),
];

const L_MIN: f64 = 1.0 / 60_000.0;

impl Datasheet {
    /// The areas (A1, A2) chambers 1 and 2 push on, m²: π/4·D² and π/4·(D² − d²)
    /// for a single-rod cylinder, π/4·(D² − d²) both for a double-rod one.
    pub fn areas_m2(&self) -> (f64, f64) {
        let bore = std::f64::consts::FRAC_PI_4 * self.cylinder.bore_m * self.cylinder.bore_m;
        let annulus = bore - std::f64::consts::FRAC_PI_4 * self.cylinder.rod_m * self.cylinder.rod_m;
        match self.cylinder.kind {
            CylinderKind::DoubleRod => (annulus, annulus),
            CylinderKind::SingleRod => (bore, annulus),
        }
    }

    /// The dead volumes (V10, V20) of the port-A and port-B sides, m³: each
    /// hose's π/4·ID²·L plus its extra volume.
    pub fn dead_volumes_m3(&self) -> (f64, f64) {
        let h = &self.hoses;
        let bore = std::f64::consts::FRAC_PI_4 * h.inner_diameter_m * h.inner_diameter_m;
        (
            bore * h.length_a_m + h.extra_volume_a_m3,
            bore * h.length_b_m + h.extra_volume_b_m3,
        )
    }

    /// The area gradient of a port whose rated flow is `rated_l_min`, m²/m:
    /// Q = C_d·w·x_max·√(Δp_valve/ρ) (each land drops half the valve drop, so
    /// √(2·Δp_land/ρ) = √(Δp_valve/ρ)), with the model's C_d.
    fn area_gradient_m2_per_m(&self, rated_l_min: f64, discharge_coefficient: f64) -> f64 {
        let v = &self.valve;
        rated_l_min * L_MIN
            / (discharge_coefficient
                * v.spool_stroke_m
                * (v.rated_pressure_drop_pa / self.oil.density_kg_m3).sqrt())
    }

    /// `base` with every model fact of the datasheet set ([`DERIVED_FIELDS`]);
    /// what a datasheet does not give (C_d, damping, friction, load, end stops)
    /// stays as in `base`.
    pub fn model(&self, base: &ActuatorParams) -> ActuatorParams {
        let (a1, a2) = self.areas_m2();
        let (v1, v2) = self.dead_volumes_m3();
        let c = &self.cylinder;
        let v = &self.valve;
        let cd = base.discharge_coefficient;
        ActuatorParams {
            piston_area_m2: a1,
            rod_side_area_m2: match c.kind {
                CylinderKind::DoubleRod => None,
                CylinderKind::SingleRod => Some(a2),
            },
            mounting_angle_rad: c.mounting_angle_deg.to_radians(),
            mass_kg: c.moving_mass_kg,
            x_min_m: 0.0,
            x_max_m: c.stroke_m,
            dead_volume_1_m3: v1,
            dead_volume_2_m3: v2,
            bulk_modulus_pa: self.oil.bulk_modulus_pa,
            oil_density_kg_m3: self.oil.density_kg_m3,
            area_gradient_m2_per_m: self.area_gradient_m2_per_m(v.rated_flow_l_min, cd),
            area_gradient_b_m2_per_m: v.rated_flow_b_l_min.map(|q| self.area_gradient_m2_per_m(q, cd)),
            spool_gain_m_per_v: v.spool_stroke_m / v.rated_signal_v,
            // a second-order spool lags 90° at its natural frequency, whatever its damping
            spool_natural_freq_rad_s: 2.0 * std::f64::consts::PI * v.phase_90_hz,
            supply_pressure_pa: self.supply.pressure_pa,
            valve_null_leakage_m3_s_pa: v.null_leakage_l_min * L_MIN / self.supply.pressure_pa,
            oil_temperature: OilTemperature {
                viscosity_40c_mm2_s: self.oil.viscosity_40c_mm2_s,
                viscosity_100c_mm2_s: self.oil.viscosity_100c_mm2_s,
                bulk_modulus_per_k: self.oil.bulk_modulus_per_k,
                operating_min_c: self.oil.operating_min_c,
                operating_max_c: self.oil.operating_max_c,
                ..base.oil_temperature
            },
            ..base.clone()
        }
    }

    /// `base` with the transducers' and the position sensor's facts set.
    pub fn sensors(&self, base: &SensorParams) -> SensorParams {
        let t = &self.pressure_transducers;
        SensorParams {
            encoder_resolution_m: self.position_sensor.resolution_m,
            position_noise_m: self.position_sensor.noise_m,
            pressure_full_scale_pa: t.full_scale_pa,
            adc_bits: t.adc_bits,
            pressure_noise_pa: t.noise_pa,
            pressure_zero_offset_max_pa: t.zero_offset_max_pa,
            pressure_span_error_max: t.span_error_max_fraction,
            ..*base
        }
    }

    /// The measurement noise variances (r_x m², r_p Pa²) of one reading: noise²
    /// plus the quantisation's LSB²/12 (the position sensor's resolution, the
    /// ADC's step, full scale / (2^bits − 1), as [`SensorParams`] quantises).
    pub fn measurement_noise(&self) -> (f64, f64) {
        let p = &self.position_sensor;
        let t = &self.pressure_transducers;
        let lsb = t.full_scale_pa / ((1u64 << t.adc_bits) - 1) as f64;
        (
            p.noise_m * p.noise_m + p.resolution_m * p.resolution_m / 12.0,
            t.noise_pa * t.noise_pa + lsb * lsb / 12.0,
        )
    }

    /// The in-repo vertical lift ([`ActuatorParams::vertical_lift`]) as its
    /// datasheet would give it: 50 mm bore, 32 mm rod, 0.4 m stroke, 200 kg,
    /// 1.1e-4 m³ per side, a valve of 29.06 L/min at 7 MPa with port B matched.
    pub fn vertical_lift() -> Self {
        let lift = ActuatorParams::vertical_lift();
        let q = |w: f64| {
            lift.discharge_coefficient * w * 3.0e-4 * (7.0e6 / lift.oil_density_kg_m3).sqrt() / L_MIN
        };
        let (wa, wb) = lift.area_gradients_m2_per_m();
        Datasheet {
            cylinder: CylinderSheet {
                kind: CylinderKind::SingleRod,
                bore_m: 0.05,
                rod_m: 0.032,
                stroke_m: 0.4,
                mounting_angle_deg: 90.0,
                moving_mass_kg: lift.mass_kg,
            },
            hoses: HoseSheet {
                inner_diameter_m: 0.0127,
                length_a_m: 0.0,
                length_b_m: 0.0,
                extra_volume_a_m3: lift.dead_volume_1_m3,
                extra_volume_b_m3: lift.dead_volume_2_m3,
            },
            oil: OilSheet::mineral(lift.oil_density_kg_m3, lift.bulk_modulus_pa),
            valve: ValveSheet {
                rated_flow_l_min: q(wa),
                rated_flow_b_l_min: Some(q(wb)),
                rated_pressure_drop_pa: 7.0e6,
                rated_signal_v: 3.0e-4 / lift.spool_gain_m_per_v,
                spool_stroke_m: 3.0e-4,
                phase_90_hz: lift.spool_natural_freq_rad_s / (2.0 * std::f64::consts::PI),
                null_leakage_l_min: 0.0,
            },
            supply: SupplySheet {
                pressure_pa: lift.supply_pressure_pa,
            },
            pressure_transducers: TransducerSheet {
                full_scale_pa: 25.0e6,
                adc_bits: 16,
                noise_pa: 8.0e3,
                location: TransducerLocation::CylinderPorts,
                response_time_s: 0.0,
                zero_offset_max_pa: 50.0e3,
                span_error_max_fraction: 0.005,
            },
            position_sensor: PositionSensorSheet {
                resolution_m: 2.0e-6,
                noise_m: 3.0e-6,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// plant_dev's double-rod press as its datasheet gives it.
    fn press() -> Datasheet {
        Datasheet {
            cylinder: CylinderSheet {
                kind: CylinderKind::DoubleRod,
                bore_m: 0.0505,
                rod_m: 0.032,
                stroke_m: 0.3,
                mounting_angle_deg: 0.0,
                moving_mass_kg: 27.5,
            },
            hoses: HoseSheet {
                inner_diameter_m: 0.0127,
                length_a_m: 0.55,
                length_b_m: 0.55,
                extra_volume_a_m3: 0.0,
                extra_volume_b_m3: 0.0,
            },
            oil: OilSheet::mineral(870.0, 1.6e9),
            valve: ValveSheet {
                rated_flow_l_min: 32.0,
                rated_flow_b_l_min: None,
                rated_pressure_drop_pa: 7.0e6,
                rated_signal_v: 10.0,
                spool_stroke_m: 3.0e-4,
                phase_90_hz: 130.0,
                null_leakage_l_min: 0.0,
            },
            supply: SupplySheet { pressure_pa: 21.0e6 },
            pressure_transducers: TransducerSheet {
                full_scale_pa: 25.0e6,
                adc_bits: 16,
                noise_pa: 8.0e3,
                location: TransducerLocation::CylinderPorts,
                response_time_s: 0.0,
                zero_offset_max_pa: 50.0e3,
                span_error_max_fraction: 0.005,
            },
            position_sensor: PositionSensorSheet {
                resolution_m: 2.0e-6,
                noise_m: 3.0e-6,
            },
        }
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs()
    }

    #[test]
    fn the_press_derives_what_its_simulator_derived_by_hand() {
        // references: the independent simulator's own derivation for this sheet
        // (plant_dev/double/datasheet.json, "derived_for_leakwatch"), to 12 digits
        let sheet = press();
        sheet.validate().expect("valid");
        let m = sheet.model(&ActuatorParams::default());
        for (got, want) in [
            (m.piston_area_m2, 0.00119871394689),
            (m.dead_volume_1_m3, 6.96722783759e-05),
            (m.dead_volume_2_m3, 6.96722783759e-05),
            (m.area_gradient_m2_per_m, 0.0330321490203),
            (m.spool_gain_m_per_v, 3e-05),
            (m.spool_natural_freq_rad_s, 816.814089933),
            (m.x_max_m, 0.3),
        ] {
            assert!(close(got, want, 1e-11), "{got} vs {want}");
        }
        assert_eq!(m.rod_side_area_m2, None);
        assert_eq!(m.area_gradient_b_m2_per_m, None);
        assert_eq!(m.mounting_angle_rad, 0.0);
        // what a datasheet does not give stays as it was
        assert_eq!(m.friction, ActuatorParams::default().friction);
        assert_eq!(m.discharge_coefficient, 0.6);
        let (r_x, r_p) = sheet.measurement_noise();
        assert!(close(r_x, 9.33333333333e-12, 1e-11), "{r_x}");
        assert!(close(r_p, 64012126.9661, 1e-11), "{r_p}");
        let s = sheet.sensors(&SensorParams::default());
        assert_eq!((s.adc_bits, s.pressure_full_scale_pa), (16, 25.0e6));
    }

    #[test]
    fn the_rated_flow_is_what_the_derived_valve_passes_at_the_rated_drop() {
        // Q = Cd·w·x·√(2Δp_land/ρ) at the full spool stroke and half the valve drop per land
        let sheet = press();
        let m = sheet.model(&ActuatorParams::default());
        let x = m.spool_gain_m_per_v * sheet.valve.rated_signal_v;
        let q = m.discharge_coefficient
            * m.area_gradient_m2_per_m
            * x
            * (2.0 * 3.5e6 / m.oil_density_kg_m3).sqrt();
        assert!(close(q * 60_000.0, 32.0, 1e-12), "{}", q * 60_000.0);
        // with another C_d the area gradient follows, the rated flow stays
        let cd = ActuatorParams {
            discharge_coefficient: 0.7,
            ..ActuatorParams::default()
        };
        let m7 = sheet.model(&cd);
        assert!(close(
            m7.area_gradient_m2_per_m * 0.7,
            m.area_gradient_m2_per_m * 0.6,
            1e-12
        ));
    }

    #[test]
    fn the_lift_sheet_derives_the_in_repo_lift() {
        let sheet = Datasheet::vertical_lift();
        sheet.validate().expect("valid");
        let lift = ActuatorParams::vertical_lift();
        let m = sheet.model(&lift);
        let pairs = [
            (m.piston_area_m2, lift.piston_area_m2),
            (
                m.rod_side_area_m2.unwrap_or(0.0),
                lift.rod_side_area_m2.unwrap_or(1.0),
            ),
            (m.mounting_angle_rad, lift.mounting_angle_rad),
            (m.dead_volume_1_m3, lift.dead_volume_1_m3),
            (m.area_gradient_m2_per_m, lift.area_gradient_m2_per_m),
            (
                m.area_gradient_b_m2_per_m.unwrap_or(0.0),
                lift.area_gradient_b_m2_per_m.unwrap_or(1.0),
            ),
            (m.spool_gain_m_per_v, lift.spool_gain_m_per_v),
            (m.spool_natural_freq_rad_s, lift.spool_natural_freq_rad_s),
        ];
        for (got, want) in pairs {
            assert!(close(got, want, 1e-12), "{got} vs {want}");
        }
        // A2/A1 for 50/32 mm: 1 − 0.64² = 0.5904
        assert!(close(
            m.rod_side_area_m2.unwrap_or(0.0) / m.piston_area_m2,
            0.5904,
            1e-12
        ));
    }

    #[test]
    fn a_bad_fact_is_named_with_its_range() {
        let mut s = press();
        s.cylinder.rod_m = 0.06;
        let e = s.validate().unwrap_err().to_string();
        assert!(
            e.contains("datasheet.cylinder.rod_m") && e.contains("0.99 of the bore"),
            "{e}"
        );
        let mut s = press();
        s.valve.phase_90_hz = f64::NAN;
        let e = s.validate().unwrap_err().to_string();
        assert!(
            e.contains("datasheet.valve.phase_90_hz") && e.contains("Hz"),
            "{e}"
        );
        let mut s = press();
        s.hoses.length_a_m = 0.0;
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("hoses (port A)"), "{e}");
        let mut s = press();
        s.cylinder.kind = CylinderKind::SingleRod;
        s.cylinder.rod_m = 0.0; // a plunger: allowed single-rod... with no annulus
        assert!(s.validate().is_ok());
        let mut s = press();
        s.pressure_transducers.response_time_s = -1e-3;
        let e = s.validate().unwrap_err().to_string();
        assert!(
            e.contains("datasheet.pressure_transducers.response_time_s"),
            "{e}"
        );
    }

    #[test]
    fn the_response_time_bounds_a_first_order_lag_and_the_location_reads_in_kebab_case() {
        let mut t = press().pressure_transducers;
        assert_eq!(t.lag_bound_s(), None);
        t.response_time_s = 2.5e-3;
        // a first-order lag of τ = 1.1378 ms reaches 10 % at 0.1199 ms and 90 % at 2.6198 ms
        let tau = t.lag_bound_s().expect("given");
        let at = |frac: f64| -tau * (1.0 - frac).ln();
        assert!((at(0.9) - at(0.1) - 2.5e-3).abs() < 1e-15);
        assert!((tau - 1.1378e-3).abs() < 1e-7);
        let read = |s: &str| {
            toml::from_str::<TransducerSheet>(&format!(
                "full_scale_pa = 25e6\nadc_bits = 16\nnoise_pa = 8000.0\n{s}"
            ))
        };
        assert_eq!(
            read("location = \"manifold\"").expect("reads").location,
            TransducerLocation::Manifold
        );
        assert_eq!(
            read("").expect("reads").location,
            TransducerLocation::CylinderPorts
        );
        let e = read("location = \"valve\"").unwrap_err().to_string();
        assert!(e.contains("cylinder-ports") && e.contains("manifold"), "{e}");
    }
}
