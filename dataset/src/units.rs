//! Whether a recording's pressures are in Pa: a chamber pressure written in
//! bar, MPa or psi reads as a few Pa to a few thousand Pa, and passes every
//! row's range check ([`crate::Limits`]) unnoticed.

use crate::Sample;

/// The share of the supply pressure the larger chamber pressure passes at
/// least once in a recording of a working rig (1 %: 138 kPa at 13.8 MPa). A
/// recording in kPa, bar, MPa or psi stays under it.
pub const LEAST_PRESSURE_SHARE: f64 = 0.01;

/// The largest chamber pressure of a recording, read one sample at a time.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PressureReach {
    /// The largest |p1| or |p2| read so far, Pa.
    max_abs_pa: f64,
    /// Samples read.
    samples: u64,
}

impl PressureReach {
    /// Takes one sample's p1 and p2 (Pa); non-finite readings are passed over.
    pub fn add(&mut self, s: &Sample) {
        self.add_pressures(s.p1_pa, s.p2_pa);
    }

    /// Takes one sample's readings `p1_pa` and `p2_pa` (Pa); non-finite ones are passed over.
    pub fn add_pressures(&mut self, p1_pa: f64, p2_pa: f64) {
        for p in [p1_pa, p2_pa] {
            if p.is_finite() && p.abs() > self.max_abs_pa {
                self.max_abs_pa = p.abs();
            }
        }
        self.samples += 1;
    }

    /// The largest |p1| or |p2| read, Pa.
    pub fn max_abs_pa(&self) -> f64 {
        self.max_abs_pa
    }

    /// An error naming the readings and the units leakwatch reads when no
    /// chamber pressure passed [`LEAST_PRESSURE_SHARE`] of `supply_pa` (Pa);
    /// `Ok` for a recording without samples (its own error says so).
    pub fn check(&self, supply_pa: f64) -> Result<(), String> {
        let least = LEAST_PRESSURE_SHARE * supply_pa;
        if self.samples == 0 || self.max_abs_pa >= least {
            return Ok(());
        }
        Err(format!(
            "p1 and p2 never read above {} Pa in {} samples, under {} % of the supply pressure \
             ({} MPa): leakwatch reads pressures in Pa (1 bar = 100000 Pa, 1 MPa = 1000000 Pa, \
             1 psi = 6895 Pa); a recording with the supply off shows nothing to learn",
            shown_pa(self.max_abs_pa),
            self.samples,
            100.0 * LEAST_PRESSURE_SHARE,
            supply_pa / 1e6
        ))
    }
}

/// A pressure as a message shows it: four significant digits, Pa.
fn shown_pa(p: f64) -> String {
    if p == 0.0 {
        "0".into()
    } else {
        let digits = (3 - p.abs().log10().floor() as i32).max(0) as usize;
        format!("{p:.digits$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reach_of(p1: &[f64], p2: &[f64]) -> PressureReach {
        let mut r = PressureReach::default();
        for (&a, &b) in p1.iter().zip(p2) {
            r.add(&Sample::new(0.0, 0.0, 0.0, a, b));
        }
        r
    }

    #[test]
    fn pressures_in_bar_are_refused_naming_the_reading_and_the_unit() {
        // 69 and 48 bar written as numbers of bar, supply 138 bar
        let r = reach_of(&[69.1, 70.2, 68.0], &[48.0, 47.5, f64::NAN]);
        assert_eq!(r.max_abs_pa(), 70.2);
        let e = r.check(13.8e6).unwrap_err();
        assert!(
            e.starts_with("p1 and p2 never read above 70.20 Pa in 3 samples"),
            "{e}"
        );
        assert!(e.contains("under 1 % of the supply pressure (13.8 MPa)"), "{e}");
        assert!(e.contains("1 bar = 100000 Pa"), "{e}");
    }

    #[test]
    fn a_working_rigs_pressures_pass_and_the_bound_is_one_percent_of_supply() {
        // a lift's rod side at rest (2 MPa) on a 21 MPa supply
        assert_eq!(reach_of(&[0.0, 1.0e5], &[2.0e6, 1.9e6]).check(21.0e6), Ok(()));
        // just under and at 1 % of 10 MPa
        assert!(reach_of(&[99_999.0], &[-5.0e3]).check(10.0e6).is_err());
        assert_eq!(reach_of(&[-100_000.0], &[0.0]).check(10.0e6), Ok(()));
        // kPa: 6900 kPa written as 6900
        assert!(reach_of(&[6900.0], &[5000.0]).check(13.8e6).is_err());
        // nothing read: the recording's own error speaks
        assert_eq!(PressureReach::default().check(13.8e6), Ok(()));
    }
}
