//! [`Datasheet::validate`]: the range of every datasheet fact, one check per sheet.

use super::{CylinderKind, Datasheet};
use crate::params::InvalidParam;

/// Checks `value` is finite and in `lo..=hi`; otherwise names it `datasheet.{field}` with `expected`.
fn check(field: &str, value: f64, lo: f64, hi: f64, expected: &'static str) -> Result<(), InvalidParam> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(InvalidParam {
            field: format!("datasheet.{field}"),
            value,
            expected,
        })
    }
}

impl Datasheet {
    /// Checks every fact is finite and physical, naming the first bad one
    /// (`datasheet.cylinder.rod_m`) with its range and unit.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        self.validate_cylinder()?;
        self.validate_hoses()?;
        self.validate_oil()?;
        self.validate_valve()?;
        self.validate_supply()?;
        self.validate_pressure_transducers()?;
        self.validate_position_sensor()
    }

    /// Checks the cylinder: bore, rod and stroke (m), mounting angle (degrees) and moving mass (kg).
    fn validate_cylinder(&self) -> Result<(), InvalidParam> {
        let c = &self.cylinder;
        check("cylinder.bore_m", c.bore_m, 1e-3, 2.0, "a bore from 1e-3 to 2 m")?;
        check(
            "cylinder.rod_m",
            c.rod_m,
            0.0,
            0.99 * c.bore_m,
            "a rod diameter below 0.99 of the bore: from 0 m",
        )?;
        if c.kind == CylinderKind::DoubleRod {
            check(
                "cylinder.rod_m",
                c.rod_m,
                1e-4,
                0.99 * c.bore_m,
                "a rod diameter below 0.99 of the bore: from 1e-4 m (a double-rod cylinder has a rod)",
            )?;
        }
        check(
            "cylinder.stroke_m",
            c.stroke_m,
            1e-3,
            20.0,
            "a stroke from 1e-3 to 20 m",
        )?;
        check(
            "cylinder.mounting_angle_deg",
            c.mounting_angle_deg,
            -90.0,
            90.0,
            "an angle from -90 to 90 degrees",
        )?;
        check(
            "cylinder.moving_mass_kg",
            c.moving_mass_kg,
            1e-3,
            1e6,
            "a mass from 1e-3 to 1e6 kg",
        )?;
        Ok(())
    }

    /// Checks the hoses: diameter and lengths (m), extra volumes and the resulting dead volumes (m³).
    fn validate_hoses(&self) -> Result<(), InvalidParam> {
        let h = &self.hoses;
        check(
            "hoses.inner_diameter_m",
            h.inner_diameter_m,
            1e-3,
            0.2,
            "a diameter from 1e-3 to 0.2 m",
        )?;
        for (name, v) in [
            ("hoses.length_a_m", h.length_a_m),
            ("hoses.length_b_m", h.length_b_m),
        ] {
            check(name, v, 0.0, 100.0, "a length from 0 to 100 m")?;
        }
        for (name, v) in [
            ("hoses.extra_volume_a_m3", h.extra_volume_a_m3),
            ("hoses.extra_volume_b_m3", h.extra_volume_b_m3),
        ] {
            check(name, v, 0.0, 1.0, "a volume from 0 to 1 m³")?;
        }
        let (v1, v2) = self.dead_volumes_m3();
        for (name, v) in [("hoses (port A)", v1), ("hoses (port B)", v2)] {
            check(
                name,
                v,
                1e-9,
                1.0,
                "a dead volume of 1e-9 to 1 m³ (hose length or extra volume)",
            )?;
        }
        Ok(())
    }

    /// Checks the oil: density (kg/m³), bulk modulus (Pa) and its temperature coefficient (1/K), viscosities (mm²/s), operating range (°C).
    fn validate_oil(&self) -> Result<(), InvalidParam> {
        check(
            "oil.density_kg_m3",
            self.oil.density_kg_m3,
            500.0,
            2000.0,
            "a density from 500 to 2000 kg/m³",
        )?;
        check(
            "oil.bulk_modulus_pa",
            self.oil.bulk_modulus_pa,
            1e7,
            1e10,
            "a bulk modulus from 1e7 to 1e10 Pa",
        )?;
        check(
            "oil.viscosity_40c_mm2_s",
            self.oil.viscosity_40c_mm2_s,
            1.0,
            10_000.0,
            "a kinematic viscosity from 1 to 10000 mm²/s",
        )?;
        check(
            "oil.viscosity_100c_mm2_s",
            self.oil.viscosity_100c_mm2_s,
            0.5,
            10_000.0,
            "a kinematic viscosity from 0.5 to 10000 mm²/s",
        )?;
        if self.oil.viscosity_100c_mm2_s >= self.oil.viscosity_40c_mm2_s {
            return Err(InvalidParam {
                field: "datasheet.oil.viscosity_100c_mm2_s".into(),
                value: self.oil.viscosity_100c_mm2_s,
                expected: "a viscosity below the one at 40 °C (oil thins as it warms)",
            });
        }
        check(
            "oil.bulk_modulus_per_k",
            self.oil.bulk_modulus_per_k,
            -0.02,
            0.0,
            "a relative change per kelvin from -0.02 to 0 (1/K)",
        )?;
        for (field, value) in [
            ("oil.operating_min_c", self.oil.operating_min_c),
            ("oil.operating_max_c", self.oil.operating_max_c),
        ] {
            check(
                field,
                value,
                -40.0,
                150.0,
                "an oil temperature from -40 to 150 °C",
            )?;
        }
        if self.oil.operating_max_c <= self.oil.operating_min_c {
            return Err(InvalidParam {
                field: "datasheet.oil.operating_max_c".into(),
                value: self.oil.operating_max_c,
                expected: "a temperature above operating_min_c (the operating range's top)",
            });
        }
        Ok(())
    }

    /// Checks the valve ratings: flows (L/min), pressure drop (Pa), signal (V), spool stroke (m), bandwidth (Hz), null leakage (L/min).
    fn validate_valve(&self) -> Result<(), InvalidParam> {
        let v = &self.valve;
        check(
            "valve.rated_flow_l_min",
            v.rated_flow_l_min,
            0.01,
            1e5,
            "a flow from 0.01 to 1e5 L/min",
        )?;
        if let Some(qb) = v.rated_flow_b_l_min {
            check(
                "valve.rated_flow_b_l_min",
                qb,
                0.01,
                1e5,
                "a flow from 0.01 to 1e5 L/min",
            )?;
        }
        check(
            "valve.rated_pressure_drop_pa",
            v.rated_pressure_drop_pa,
            1e4,
            1e8,
            "a pressure drop from 1e4 to 1e8 Pa (both lands together)",
        )?;
        check(
            "valve.rated_signal_v",
            v.rated_signal_v,
            1e-3,
            1e3,
            "a signal from 1e-3 to 1e3 V",
        )?;
        check(
            "valve.spool_stroke_m",
            v.spool_stroke_m,
            1e-6,
            0.05,
            "a spool stroke from 1e-6 to 0.05 m",
        )?;
        check(
            "valve.phase_90_hz",
            v.phase_90_hz,
            0.1,
            1e4,
            "a frequency from 0.1 to 1e4 Hz",
        )?;
        check(
            "valve.null_leakage_l_min",
            v.null_leakage_l_min,
            0.0,
            100.0,
            "a flow from 0 to 100 L/min",
        )?;
        Ok(())
    }

    /// Checks the supply pressure (Pa).
    fn validate_supply(&self) -> Result<(), InvalidParam> {
        check(
            "supply.pressure_pa",
            self.supply.pressure_pa,
            1e5,
            1e9,
            "a pressure from 1e5 to 1e9 Pa",
        )?;
        Ok(())
    }

    /// Checks the pressure transducers: full scale (Pa), ADC bits, noise (Pa) and response time (s).
    fn validate_pressure_transducers(&self) -> Result<(), InvalidParam> {
        let t = &self.pressure_transducers;
        check(
            "pressure_transducers.full_scale_pa",
            t.full_scale_pa,
            1e5,
            1e9,
            "a full scale from 1e5 to 1e9 Pa",
        )?;
        check(
            "pressure_transducers.adc_bits",
            t.adc_bits as f64,
            1.0,
            24.0,
            "1 to 24 bits",
        )?;
        check(
            "pressure_transducers.noise_pa",
            t.noise_pa,
            0.0,
            1e7,
            "a noise from 0 to 1e7 Pa",
        )?;
        check(
            "pressure_transducers.response_time_s",
            t.response_time_s,
            0.0,
            1.0,
            "a time from 0 to 1 s",
        )?;
        Ok(())
    }

    /// Checks the position sensor: resolution and noise (m).
    fn validate_position_sensor(&self) -> Result<(), InvalidParam> {
        let p = &self.position_sensor;
        check(
            "position_sensor.resolution_m",
            p.resolution_m,
            1e-9,
            1e-2,
            "a resolution from 1e-9 to 1e-2 m",
        )?;
        check(
            "position_sensor.noise_m",
            p.noise_m,
            0.0,
            1e-2,
            "a noise from 0 to 1e-2 m",
        )
    }
}
