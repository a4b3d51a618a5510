//! [`Datasheet::validate`]: the range of every datasheet fact, one check per sheet.

use super::{CylinderKind, Datasheet};
use crate::params::validate::check;
use crate::params::{viscosity_100c_of_grade, InvalidParam};

impl Datasheet {
    /// Checks every fact is finite and within its declared range, then the
    /// ranges that depend on other facts, naming the first bad one
    /// (`datasheet.cylinder.rod_m`) with its range and unit.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        self.check_ranges("datasheet")?;
        self.validate_cylinder()?;
        self.validate_hoses()?;
        self.validate_oil()
    }

    /// Checks the rod (m): below 0.99 of the bore, and present on a double-rod cylinder.
    fn validate_cylinder(&self) -> Result<(), InvalidParam> {
        let c = &self.cylinder;
        let rod = |lo: f64, expected: &str| {
            check(
                "datasheet.cylinder.rod_m",
                c.rod_m,
                (lo..=0.99 * c.bore_m).contains(&c.rod_m),
                expected,
            )
        };
        rod(0.0, "a rod diameter below 0.99 of the bore: from 0 m")?;
        if c.kind == CylinderKind::DoubleRod {
            rod(
                1e-4,
                "a rod diameter below 0.99 of the bore: from 1e-4 m (a double-rod cylinder has a rod)",
            )?;
        }
        Ok(())
    }

    /// Checks the dead volumes the hoses give (m³).
    fn validate_hoses(&self) -> Result<(), InvalidParam> {
        let (v1, v2) = self.dead_volumes_m3();
        for (name, v) in [("hoses (port A)", v1), ("hoses (port B)", v2)] {
            check(
                &format!("datasheet.{name}"),
                v,
                (1e-9..=1.0).contains(&v),
                "a dead volume of 1e-9 to 1 m³ (hose length or extra volume)",
            )?;
        }
        Ok(())
    }

    /// Checks the oil's viscosities (mm²/s) and operating range (°C) against each other.
    fn validate_oil(&self) -> Result<(), InvalidParam> {
        let nu100 = self
            .oil
            .viscosity_100c_mm2_s
            .unwrap_or_else(|| viscosity_100c_of_grade(self.oil.viscosity_40c_mm2_s));
        check(
            "datasheet.oil.viscosity_100c_mm2_s",
            nu100,
            nu100 < self.oil.viscosity_40c_mm2_s,
            "a viscosity below the one at 40 °C (oil thins as it warms)",
        )?;
        check(
            "datasheet.oil.operating_max_c",
            self.oil.operating_max_c,
            self.oil.operating_max_c > self.oil.operating_min_c,
            "a temperature above operating_min_c (the operating range's top)",
        )
    }
}
