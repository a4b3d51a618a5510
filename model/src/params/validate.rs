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

/// [`check`] of a value that must lie in `lo..=hi` (inclusive, in the field's unit).
fn in_range(field: &str, v: f64, lo: f64, hi: f64, expected: &'static str) -> Result<(), InvalidParam> {
    check(field, v, (lo..=hi).contains(&v), expected)
}

impl ActuatorParams {
    /// Checks that every value can describe a real actuator: each field must be
    /// finite and within a physical range (named, with its unit, in the error).
    /// Names the first bad field.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        self.validate_geometry()?;
        self.validate_oil()?;
        self.validate_spool()?;
        self.validate_pressures()?;
        self.validate_valve_leakage()?;
        self.validate_asymmetry()?;
        self.validate_friction()?;
        self.validate_load()?;
        self.validate_end_stops()?;
        self.validate_leaks()?;
        Ok(())
    }

    /// Checks the cylinder geometry (m², m, m³), the moving mass (kg) and the oil bulk modulus (Pa).
    fn validate_geometry(&self) -> Result<(), InvalidParam> {
        in_range(
            "piston_area_m2",
            self.piston_area_m2,
            1e-6,
            1.0,
            "an area from 1e-6 to 1 m²",
        )?;
        in_range("mass_kg", self.mass_kg, 1e-3, 1e5, "a mass from 1e-3 to 1e5 kg")?;
        in_range(
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
        in_range(
            "dead_volume_1_m3",
            self.dead_volume_1_m3,
            1e-9,
            1.0,
            "a volume from 1e-9 to 1 m³",
        )?;
        in_range(
            "dead_volume_2_m3",
            self.dead_volume_2_m3,
            1e-9,
            1.0,
            "a volume from 1e-9 to 1 m³",
        )?;
        in_range(
            "bulk_modulus_pa",
            self.bulk_modulus_pa,
            1e6,
            1e11,
            "a bulk modulus from 1e6 to 1e11 Pa",
        )?;
        Ok(())
    }

    /// Checks the oil: its temperature range (°C), viscosities (mm²/s), entrained air and density (kg/m³).
    fn validate_oil(&self) -> Result<(), InvalidParam> {
        let oil = &self.oil_temperature;
        in_range(
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
            in_range(
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
        in_range(
            "oil_temperature.viscosity_40c_mm2_s",
            oil.viscosity_40c_mm2_s,
            1.0,
            10_000.0,
            "a kinematic viscosity from 1 to 10000 mm²/s",
        )?;
        in_range(
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
        in_range(
            "oil_temperature.bulk_modulus_per_k",
            oil.bulk_modulus_per_k,
            -0.02,
            0.0,
            "a relative change per kelvin from -0.02 to 0 (1/K)",
        )?;
        if let Some(theta) = oil.reference_stiffness {
            in_range(
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
        in_range(
            "oil_density_kg_m3",
            self.oil_density_kg_m3,
            100.0,
            5000.0,
            "a density from 100 to 5000 kg/m³",
        )?;
        Ok(())
    }

    /// Checks the servovalve spool: discharge coefficient, area gradient (m²/m), gain (m/V), dynamics (rad/s) and null bias (m).
    fn validate_spool(&self) -> Result<(), InvalidParam> {
        check(
            "discharge_coefficient",
            self.discharge_coefficient,
            self.discharge_coefficient >= 0.01 && self.discharge_coefficient <= 1.0,
            "a value from 0.01 to 1 (dimensionless)",
        )?;
        in_range(
            "area_gradient_m2_per_m",
            self.area_gradient_m2_per_m,
            1e-6,
            10.0,
            "an area gradient from 1e-6 to 10 m²/m",
        )?;
        in_range(
            "spool_gain_m_per_v",
            self.spool_gain_m_per_v,
            1e-9,
            0.1,
            "a spool gain from 1e-9 to 0.1 m/V",
        )?;
        in_range(
            "spool_natural_freq_rad_s",
            self.spool_natural_freq_rad_s,
            1.0,
            2e4,
            "a natural frequency from 1 to 2e4 rad/s",
        )?;
        in_range(
            "spool_damping_ratio",
            self.spool_damping_ratio,
            0.01,
            10.0,
            "a damping ratio from 0.01 to 10 (dimensionless)",
        )?;
        in_range(
            "spool_null_bias_m",
            self.spool_null_bias_m,
            -0.01,
            0.01,
            "a spool offset from -0.01 to 0.01 m",
        )?;
        Ok(())
    }

    /// Checks the return and supply pressures (Pa) and the supply sag (Pa per m³/s).
    fn validate_pressures(&self) -> Result<(), InvalidParam> {
        in_range(
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
        Ok(())
    }

    /// Checks the valve null leakage (m³/(s·Pa)) and the spool underlap (m).
    fn validate_valve_leakage(&self) -> Result<(), InvalidParam> {
        check(
            "valve_null_leakage_m3_s_pa",
            self.valve_null_leakage_m3_s_pa,
            (0.0..=1e-9).contains(&self.valve_null_leakage_m3_s_pa),
            "a conductance from 0 to 1e-9 m³/(s·Pa) (0 = no null leakage; 1e-9 passes 1260 L/min at 21 MPa)",
        )?;
        in_range(
            "valve_underlap_m",
            self.valve_underlap_m,
            1e-8,
            1e-3,
            "a spool travel from 1e-8 to 1e-3 m",
        )?;
        Ok(())
    }

    /// Checks the optional rod-side area (m²), port-B area gradient (m²/m) and the mounting angle (rad).
    fn validate_asymmetry(&self) -> Result<(), InvalidParam> {
        if let Some(a2) = self.rod_side_area_m2 {
            in_range(
                "rod_side_area_m2",
                a2,
                1e-6,
                1.0,
                "an area from 1e-6 to 1 m² (or absent: a double-rod cylinder)",
            )?;
        }
        if let Some(w) = self.area_gradient_b_m2_per_m {
            in_range(
                "area_gradient_b_m2_per_m",
                w,
                1e-6,
                10.0,
                "an area gradient from 1e-6 to 10 m²/m (or absent: the port-A gradient)",
            )?;
        }
        in_range(
            "mounting_angle_rad",
            self.mounting_angle_rad,
            -std::f64::consts::FRAC_PI_2,
            std::f64::consts::FRAC_PI_2,
            "an angle from -π/2 to π/2 rad (0: horizontal, π/2: vertical, extension lifts)",
        )?;
        Ok(())
    }

    /// Checks the friction curve of each direction (N, m/s, N·s/m) and the zero-velocity band (m/s).
    fn validate_friction(&self) -> Result<(), InvalidParam> {
        let mut dirs = vec![("friction", self.friction.extend())];
        if let Some(r) = self.friction.retract {
            dirs.push(("friction.retract", r));
        }
        for (name, fp) in dirs {
            in_range(
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
            in_range(
                &format!("{name}.stribeck_velocity_m_s"),
                fp.stribeck_velocity_m_s,
                1e-6,
                10.0,
                "a velocity from 1e-6 to 10 m/s",
            )?;
            in_range(
                &format!("{name}.viscous_n_s_per_m"),
                fp.viscous_n_s_per_m,
                0.0,
                1e7,
                "a viscous coefficient from 0 to 1e7 N·s/m",
            )?;
        }
        in_range(
            "friction.zero_velocity_m_s",
            self.friction.zero_velocity_m_s,
            1e-9,
            1.0,
            "a velocity from 1e-9 to 1 m/s",
        )?;
        Ok(())
    }

    /// Checks the external load: stiffness (N/m), contact position (m), preload (N) and damping (N·s/m).
    fn validate_load(&self) -> Result<(), InvalidParam> {
        in_range(
            "load.stiffness_n_per_m",
            self.load.stiffness_n_per_m,
            0.0,
            1e10,
            "a stiffness from 0 to 1e10 N/m",
        )?;
        in_range(
            "load.contact_m",
            self.load.contact_m,
            -10.0,
            10.0,
            "a position from -10 to 10 m",
        )?;
        in_range(
            "load.preload_n",
            self.load.preload_n,
            0.0,
            1e7,
            "a force from 0 to 1e7 N",
        )?;
        Ok(())
    }

    /// Checks the end stops: stiffness (N/m) and damping (N·s/m).
    fn validate_end_stops(&self) -> Result<(), InvalidParam> {
        in_range(
            "load.damping_n_s_per_m",
            self.load.damping_n_s_per_m,
            0.0,
            1e8,
            "a damping from 0 to 1e8 N·s/m",
        )?;
        in_range(
            "end_stop_stiffness_n_per_m",
            self.end_stop_stiffness_n_per_m,
            1.0,
            1e10,
            "a stiffness from 1 to 1e10 N/m",
        )?;
        in_range(
            "end_stop_damping_n_s_per_m",
            self.end_stop_damping_n_s_per_m,
            0.0,
            1e8,
            "a damping from 0 to 1e8 N·s/m",
        )?;
        Ok(())
    }

    /// Checks each leak's coefficient (m³/s per √Pa, or per Pa for the linear law).
    fn validate_leaks(&self) -> Result<(), InvalidParam> {
        for (i, leak) in self.leaks.iter().enumerate() {
            in_range(
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
