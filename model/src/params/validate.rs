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
    pub expected: String,
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

impl From<schema::OutOfRange> for InvalidParam {
    fn from(e: schema::OutOfRange) -> Self {
        InvalidParam {
            field: e.key,
            value: e.value,
            expected: e.expected,
        }
    }
}

/// `Ok` if `ok` and `value` is finite, else the error naming `field` with `expected`.
pub(crate) fn check(field: &str, value: f64, ok: bool, expected: &str) -> Result<(), InvalidParam> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(InvalidParam {
            field: field.to_string(),
            value,
            expected: expected.to_string(),
        })
    }
}

/// The declared range of `field` (a key of [`ActuatorParams::SCHEMA`], dotted), as stated.
fn stated(field: &[&str]) -> String {
    ActuatorParams::SCHEMA
        .find(field)
        .map(schema::Field::expected)
        .unwrap_or_default()
}

impl ActuatorParams {
    /// Checks that every value can describe a real actuator: each field must be
    /// finite and within its declared physical range (named, with its unit, in
    /// the error), then the ranges that depend on other fields. Names the first
    /// bad field.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        self.check_ranges("")?;
        self.validate_cross_fields()
    }

    /// Checks the ranges that depend on other fields: the stroke (m), the
    /// operating temperatures (°C) and viscosities (mm²/s), the supply (Pa,
    /// Pa per m³/s) and each direction's static friction (N).
    fn validate_cross_fields(&self) -> Result<(), InvalidParam> {
        check(
            "x_max_m",
            self.x_max_m,
            self.x_max_m >= self.x_min_m + 1e-3 && self.x_max_m <= 10.0,
            &stated(&["x_max_m"]),
        )?;
        let oil = &self.oil_temperature;
        check(
            "oil_temperature.operating_max_c",
            oil.operating_max_c,
            oil.operating_max_c > oil.operating_min_c,
            "a temperature above operating_min_c (the operating range's top)",
        )?;
        check(
            "oil_temperature.viscosity_100c_mm2_s",
            oil.viscosity_100c_or_default_mm2_s(),
            oil.viscosity_100c_or_default_mm2_s() < oil.viscosity_40c_mm2_s,
            "a viscosity below the one at 40 °C (oil thins as it warms)",
        )?;
        check(
            "supply_pressure_pa",
            self.supply_pressure_pa,
            self.supply_pressure_pa >= self.return_pressure_pa + 1e4 && self.supply_pressure_pa <= 1.0e9,
            &stated(&["supply_pressure_pa"]),
        )?;
        check(
            "supply_sag_pa_per_m3_s",
            self.supply_sag_pa_per_m3_s,
            self.supply_sag_pa_per_m3_s == 0.0 || (1.0..=1e14).contains(&self.supply_sag_pa_per_m3_s),
            &stated(&["supply_sag_pa_per_m3_s"]),
        )?;
        let mut dirs = vec![("friction", self.friction.extend())];
        if let Some(r) = self.friction.retract {
            dirs.push(("friction.retract", r));
        }
        for (name, fp) in dirs {
            check(
                &format!("{name}.static_n"),
                fp.static_n,
                fp.static_n >= fp.slip_n && fp.static_n <= 1e6,
                &stated(&["friction", "static_n"]),
            )?;
        }
        Ok(())
    }
}
