//! Validation of the parameters: the physical range of every field
//! ([`ActuatorParams::validate`]) and the error naming the first bad one.

use super::ActuatorParams;

/// A parameter value that cannot describe a real actuator.
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidParam {
    /// Dotted name of the field, e.g. `friction.static_n`.
    pub field: String,
    /// The offending value.
    pub value: f64,
    /// What was expected.
    pub expected: &'static str,
}

impl std::fmt::Display for InvalidParam {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // whole numbers (bit counts, sub-steps) as integers, the rest in shortest form (1e308)
        let value = if self.value.fract() == 0.0 && self.value.abs() < 1e15 {
            format!("{:.0}", self.value)
        } else {
            format!("{:?}", self.value)
        };
        write!(
            f,
            "parameter `{}` = {} is invalid: expected {}",
            self.field, value, self.expected
        )
    }
}

impl std::error::Error for InvalidParam {}

fn check(field: &str, value: f64, ok: bool, expected: &'static str) -> Result<(), InvalidParam> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(InvalidParam {
            field: field.to_string(),
            value,
            expected,
        })
    }
}

impl ActuatorParams {
    /// Checks that every value can describe a real actuator: each field must be
    /// finite and within a physical range (named, with its unit, in the error).
    /// Names the first bad field.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        let r = |field: &str, v: f64, lo: f64, hi: f64, expected: &'static str| {
            check(field, v, (lo..=hi).contains(&v), expected)
        };
        r(
            "piston_area_m2",
            self.piston_area_m2,
            1e-6,
            1.0,
            "an area from 1e-6 to 1 m²",
        )?;
        r("mass_kg", self.mass_kg, 1e-3, 1e5, "a mass from 1e-3 to 1e5 kg")?;
        r(
            "x_min_m",
            self.x_min_m,
            -10.0,
            10.0,
            "a position from -10 to 10 m",
        )?;
        check(
            "x_max_m",
            self.x_max_m,
            self.x_max_m >= self.x_min_m + 1e-3 && self.x_max_m <= 10.0,
            "a position at least 1 mm above x_min_m and at most 10 m",
        )?;
        r(
            "dead_volume_1_m3",
            self.dead_volume_1_m3,
            1e-9,
            1.0,
            "a volume from 1e-9 to 1 m³",
        )?;
        r(
            "dead_volume_2_m3",
            self.dead_volume_2_m3,
            1e-9,
            1.0,
            "a volume from 1e-9 to 1 m³",
        )?;
        r(
            "bulk_modulus_pa",
            self.bulk_modulus_pa,
            1e6,
            1e11,
            "a bulk modulus from 1e6 to 1e11 Pa",
        )?;
        let oil = &self.oil_temperature;
        r(
            "oil_temperature.reference_c",
            oil.reference_c,
            -40.0,
            150.0,
            "an oil temperature from -40 to 150 °C",
        )?;
        for (field, value) in [
            ("oil_temperature.operating_min_c", oil.operating_min_c),
            ("oil_temperature.operating_max_c", oil.operating_max_c),
        ] {
            r(
                field,
                value,
                -40.0,
                150.0,
                "an oil temperature from -40 to 150 °C",
            )?;
        }
        check(
            "oil_temperature.operating_max_c",
            oil.operating_max_c,
            oil.operating_max_c > oil.operating_min_c,
            "a temperature above operating_min_c (the operating range's top)",
        )?;
        r(
            "oil_temperature.viscosity_40c_mm2_s",
            oil.viscosity_40c_mm2_s,
            1.0,
            10_000.0,
            "a kinematic viscosity from 1 to 10000 mm²/s",
        )?;
        r(
            "oil_temperature.viscosity_100c_mm2_s",
            oil.viscosity_100c_mm2_s,
            0.5,
            10_000.0,
            "a kinematic viscosity from 0.5 to 10000 mm²/s",
        )?;
        check(
            "oil_temperature.viscosity_100c_mm2_s",
            oil.viscosity_100c_mm2_s,
            oil.viscosity_100c_mm2_s < oil.viscosity_40c_mm2_s,
            "a viscosity below the one at 40 °C (oil thins as it warms)",
        )?;
        r(
            "oil_temperature.bulk_modulus_per_k",
            oil.bulk_modulus_per_k,
            -0.02,
            0.0,
            "a relative change per kelvin from -0.02 to 0 (1/K)",
        )?;
        if let Some(theta) = oil.reference_stiffness {
            r(
                "oil_temperature.reference_stiffness",
                theta,
                crate::process::BULK_SCALE_RANGE.0,
                crate::process::BULK_SCALE_RANGE.1,
                "a stiffness from 0.2 to 2 times the model's bulk modulus",
            )?;
        }
        check(
            "entrained_air_fraction",
            self.entrained_air_fraction,
            (0.0..0.5).contains(&self.entrained_air_fraction),
            "a fraction in [0, 0.5)",
        )?;
        r(
            "oil_density_kg_m3",
            self.oil_density_kg_m3,
            100.0,
            5000.0,
            "a density from 100 to 5000 kg/m³",
        )?;
        check(
            "discharge_coefficient",
            self.discharge_coefficient,
            self.discharge_coefficient >= 0.01 && self.discharge_coefficient <= 1.0,
            "a value from 0.01 to 1 (dimensionless)",
        )?;
        r(
            "area_gradient_m2_per_m",
            self.area_gradient_m2_per_m,
            1e-6,
            10.0,
            "an area gradient from 1e-6 to 10 m²/m",
        )?;
        r(
            "spool_gain_m_per_v",
            self.spool_gain_m_per_v,
            1e-9,
            0.1,
            "a spool gain from 1e-9 to 0.1 m/V",
        )?;
        r(
            "spool_natural_freq_rad_s",
            self.spool_natural_freq_rad_s,
            1.0,
            2e4,
            "a natural frequency from 1 to 2e4 rad/s",
        )?;
        r(
            "spool_damping_ratio",
            self.spool_damping_ratio,
            0.01,
            10.0,
            "a damping ratio from 0.01 to 10 (dimensionless)",
        )?;
        r(
            "spool_null_bias_m",
            self.spool_null_bias_m,
            -0.01,
            0.01,
            "a spool offset from -0.01 to 0.01 m",
        )?;
        r(
            "return_pressure_pa",
            self.return_pressure_pa,
            0.0,
            1e8,
            "a pressure from 0 to 1e8 Pa",
        )?;
        check(
            "supply_pressure_pa",
            self.supply_pressure_pa,
            self.supply_pressure_pa >= self.return_pressure_pa + 1e4 && self.supply_pressure_pa <= 1.0e9,
            "a pressure at least 1e4 Pa above return_pressure_pa and at most 1e9 Pa (1000 MPa)",
        )?;
        check(
            "supply_sag_pa_per_m3_s",
            self.supply_sag_pa_per_m3_s,
            self.supply_sag_pa_per_m3_s == 0.0 || (1.0..=1e14).contains(&self.supply_sag_pa_per_m3_s),
            "0 (no sag) or a pressure drop from 1 to 1e14 Pa per m³/s",
        )?;
        check(
            "valve_null_leakage_m3_s_pa",
            self.valve_null_leakage_m3_s_pa,
            (0.0..=1e-9).contains(&self.valve_null_leakage_m3_s_pa),
            "a conductance from 0 to 1e-9 m³/(s·Pa) (0 = no null leakage; 1e-9 passes 1260 L/min at 21 MPa)",
        )?;
        r(
            "valve_underlap_m",
            self.valve_underlap_m,
            1e-8,
            1e-3,
            "a spool travel from 1e-8 to 1e-3 m",
        )?;
        if let Some(a2) = self.rod_side_area_m2 {
            r(
                "rod_side_area_m2",
                a2,
                1e-6,
                1.0,
                "an area from 1e-6 to 1 m² (or absent: a double-rod cylinder)",
            )?;
        }
        if let Some(w) = self.area_gradient_b_m2_per_m {
            r(
                "area_gradient_b_m2_per_m",
                w,
                1e-6,
                10.0,
                "an area gradient from 1e-6 to 10 m²/m (or absent: the port-A gradient)",
            )?;
        }
        r(
            "mounting_angle_rad",
            self.mounting_angle_rad,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
            "an angle from -π/2 to π/2 rad (0: horizontal, π/2: vertical, extension lifts)",
        )?;
        let mut dirs = vec![("friction", self.friction.extend())];
        if let Some(r) = self.friction.retract {
            dirs.push(("friction.retract", r));
        }
        for (name, fp) in dirs {
            r(
                &format!("{name}.slip_n"),
                fp.slip_n,
                0.0,
                1e6,
                "a force from 0 to 1e6 N",
            )?;
            check(
                &format!("{name}.static_n"),
                fp.static_n,
                fp.static_n >= fp.slip_n && fp.static_n <= 1e6,
                "a force from slip_n to 1e6 N",
            )?;
            r(
                &format!("{name}.stribeck_velocity_m_s"),
                fp.stribeck_velocity_m_s,
                1e-6,
                10.0,
                "a velocity from 1e-6 to 10 m/s",
            )?;
            r(
                &format!("{name}.viscous_n_s_per_m"),
                fp.viscous_n_s_per_m,
                0.0,
                1e7,
                "a viscous coefficient from 0 to 1e7 N·s/m",
            )?;
        }
        r(
            "friction.zero_velocity_m_s",
            self.friction.zero_velocity_m_s,
            1e-9,
            1.0,
            "a velocity from 1e-9 to 1 m/s",
        )?;
        r(
            "load.stiffness_n_per_m",
            self.load.stiffness_n_per_m,
            0.0,
            1e10,
            "a stiffness from 0 to 1e10 N/m",
        )?;
        r(
            "load.contact_m",
            self.load.contact_m,
            -10.0,
            10.0,
            "a position from -10 to 10 m",
        )?;
        r(
            "load.preload_n",
            self.load.preload_n,
            0.0,
            1e7,
            "a force from 0 to 1e7 N",
        )?;
        r(
            "load.damping_n_s_per_m",
            self.load.damping_n_s_per_m,
            0.0,
            1e8,
            "a damping from 0 to 1e8 N·s/m",
        )?;
        r(
            "end_stop_stiffness_n_per_m",
            self.end_stop_stiffness_n_per_m,
            1.0,
            1e10,
            "a stiffness from 1 to 1e10 N/m",
        )?;
        r(
            "end_stop_damping_n_s_per_m",
            self.end_stop_damping_n_s_per_m,
            0.0,
            1e8,
            "a damping from 0 to 1e8 N·s/m",
        )?;
        for (i, leak) in self.leaks.iter().enumerate() {
            r(
                &format!("leaks[{i}].coefficient"),
                leak.coefficient,
                0.0,
                1e-4,
                "a coefficient from 0 to 1e-4 (m³/s per √Pa, or per Pa for the linear law)",
            )?;
        }
        Ok(())
    }
}
