//! A leak's size as the flow it passes where the rig works: the coefficient
//! that makes a leak of `size_lpm` pass that flow at the mean drop its path
//! saw before it opened (the plant recordings' truth states its leaks so:
//! `coef = size / √(mean Δp)`). A press holds its chambers near each other,
//! so an internal leak sized at the nominal drop p_s/2 passes a third of its
//! size there.

use model::{LeakLaw, LeakPath, Sample};

/// The start of the window the mean drop is taken over, s (the simulation's
/// first second holds its start-up).
pub const CALIBRATION_START_S: f64 = 1.0;

/// The smallest mean drop a leak is sized at, Pa: below it the coefficient
/// for a flow grows without bound.
pub const MIN_MEAN_DROP_PA: f64 = 1e4;

/// The leak path a kind names (`ext1`, `ext2`, `int`), or an error naming the kind.
pub fn leak_path(kind: &str) -> Result<LeakPath, String> {
    LeakPath::from_name(kind).ok_or_else(|| format!("unknown leak kind `{kind}`"))
}

/// A square-root leak of `size_lpm` L/min on `path`, opening at `onset_s`,
/// sized at the mean |drop| (Pa) its path sees in the healthy `samples`
/// between [`CALIBRATION_START_S`] and `onset_s`, with the return at
/// `return_pa` (Pa).
#[derive(Debug, Clone, PartialEq)]
pub struct OperatingLeak {
    /// The `simulate` fault spec: `KIND:k=COEF@ONSETs`.
    pub spec: String,
    /// The coefficient, m³/(s·√Pa).
    pub coefficient: f64,
    /// The mean |drop| over the window, Pa.
    pub mean_drop_pa: f64,
}

impl OperatingLeak {
    /// The leak on `path` of `size_lpm` (L/min) opening at `onset_s` (s),
    /// sized on the healthy twin `samples` with the return at `return_pa`
    /// (Pa); an error when the window holds no sample or the drop is below
    /// [`MIN_MEAN_DROP_PA`].
    pub fn size(
        path: LeakPath,
        size_lpm: f64,
        onset_s: f64,
        samples: &[Sample],
        return_pa: f64,
    ) -> Result<OperatingLeak, String> {
        let (sum, n) = samples
            .iter()
            .filter(|s| s.t_s >= CALIBRATION_START_S && s.t_s < onset_s)
            .map(|s| path.pressure_drop_pa(s.p1_pa, s.p2_pa, return_pa).abs())
            .filter(|d| d.is_finite())
            .fold((0.0, 0usize), |(sum, n), d| (sum + d, n + 1));
        if n == 0 {
            return Err(format!(
                "a {path} leak at {onset_s} s: no healthy sample between {CALIBRATION_START_S} s and its onset to size it at"
            ));
        }
        let mean_drop_pa = sum / n as f64;
        if mean_drop_pa < MIN_MEAN_DROP_PA {
            return Err(format!(
                "a {path} leak at {onset_s} s: its path's mean drop before it, {mean_drop_pa:.0} Pa, is below {MIN_MEAN_DROP_PA} Pa"
            ));
        }
        let coefficient =
            LeakLaw::SquareRoot.coefficient_for(model::units::lpm_to_m3_s(size_lpm), mean_drop_pa);
        Ok(OperatingLeak {
            spec: format!("{path}:k={coefficient:e}@{onset_s}s"),
            coefficient,
            mean_drop_pa,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t_s: f64, p1_pa: f64, p2_pa: f64) -> Sample {
        Sample::new(t_s, 0.0, 0.0, p1_pa, p2_pa)
    }

    #[test]
    fn a_leak_passes_its_size_at_the_mean_drop_before_it_opens() {
        // p1 − p2 alternates 1 and 3 MPa before the onset, then 20 MPa (not counted)
        let samples: Vec<Sample> = (0..5000)
            .map(|i| {
                let t = i as f64 * 1e-3;
                let dp = if t >= 4.0 {
                    20e6
                } else if i % 2 == 0 {
                    1e6
                } else {
                    3e6
                };
                at(t, 5e6 + dp, 5e6)
            })
            .collect();
        let leak = OperatingLeak::size(LeakPath::Internal, 0.25, 4.0, &samples, 0.0).unwrap();
        assert!((leak.mean_drop_pa - 2e6).abs() < 1e3, "{}", leak.mean_drop_pa);
        let q = LeakLaw::SquareRoot.flow_m3_s(leak.coefficient, 2e6);
        assert!((model::units::m3_s_to_lpm(q) - 0.25).abs() < 1e-9);
        // the spec is what `simulate` parses back to the same coefficient
        let params = model::ActuatorParams::default();
        let f = model::fault::Fault::parse(&leak.spec, &params).unwrap();
        assert_eq!(f.path, LeakPath::Internal);
        assert!((f.coefficient / leak.coefficient - 1.0).abs() < 1e-12);
        assert_eq!(f.onset_s, 4.0);
        // an external leak's drop is the chamber's over the return
        let ext = OperatingLeak::size(LeakPath::External2, 0.1, 4.0, &samples, 1e5).unwrap();
        assert!((ext.mean_drop_pa - 4.9e6).abs() < 1e3);
    }

    #[test]
    fn a_leak_with_no_window_or_no_drop_is_refused() {
        let flat: Vec<Sample> = (0..3000).map(|i| at(i as f64 * 1e-3, 5e6, 5e6)).collect();
        let err = OperatingLeak::size(LeakPath::Internal, 0.1, 2.0, &flat, 0.0).unwrap_err();
        assert!(err.contains("below"), "{err}");
        let err = OperatingLeak::size(LeakPath::External1, 0.1, 0.5, &flat, 0.0).unwrap_err();
        assert!(err.contains("no healthy sample"), "{err}");
    }
}
