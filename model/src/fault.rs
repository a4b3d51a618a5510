//! Scheduled leak faults and their command-line spec
//! `KIND:SIZE@ONSET[,ramp=SECONDS][,law=sqrt|linear]`.

use crate::dynamics::LeakSet;
use crate::leakage::{LeakLaw, LeakPath};
use crate::params::ActuatorParams;
use crate::units::lpm_to_m3_s;

/// A leak that opens at a scheduled time, as a step or a ramp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fault {
    /// Where the oil leaks.
    pub path: LeakPath,
    /// The flow law.
    pub law: LeakLaw,
    /// Final coefficient: m³/(s·Pa) (linear) or m³/(s·√Pa) (square root).
    pub coefficient: f64,
    /// Time the leak starts to open, s.
    pub onset_s: f64,
    /// Time over which it opens linearly to full size, s (0 = step).
    pub ramp_s: f64,
    /// The size the user asked for, L/min at the nominal pressure, if given that way.
    pub nominal_lpm: Option<f64>,
}

impl Fault {
    /// The coefficient in force at time `t_s`.
    #[inline]
    pub fn coefficient_at(&self, t_s: f64) -> f64 {
        if t_s < self.onset_s {
            0.0
        } else if self.ramp_s > 0.0 {
            self.coefficient * ((t_s - self.onset_s) / self.ramp_s).min(1.0)
        } else {
            self.coefficient
        }
    }

    /// The nominal pressure drop of a path at which L/min sizes are stated, Pa:
    /// the mean chamber pressure (p_s + p_r)/2 for every path.
    pub fn nominal_drop_pa(params: &ActuatorParams) -> f64 {
        params.nominal_chamber_pressure_pa() - params.return_pressure_pa
    }

    /// A fault of `size_lpm` L/min at the nominal pressure drop.
    pub fn from_lpm(
        path: LeakPath,
        law: LeakLaw,
        size_lpm: f64,
        onset_s: f64,
        params: &ActuatorParams,
    ) -> Fault {
        Fault {
            path,
            law,
            coefficient: law.coefficient_for(lpm_to_m3_s(size_lpm), Self::nominal_drop_pa(params)),
            onset_s,
            ramp_s: 0.0,
            nominal_lpm: Some(size_lpm),
        }
    }

    /// Parses `KIND:SIZE@ONSET[,ramp=SECONDS][,law=sqrt|linear]`, e.g.
    /// `ext1:0.3lpm@20s`, `int:0.5lpm@18s,ramp=5`, `ext2:k=2e-12@20s,law=linear`.
    /// Sizes in L/min are converted at the nominal chamber pressure of `params`.
    pub fn parse(spec: &str, params: &ActuatorParams) -> Result<Fault, FaultSpecError> {
        let err = |msg: String| FaultSpecError {
            spec: spec.to_string(),
            message: msg,
        };
        let (kind, rest) = spec
            .split_once(':')
            .ok_or_else(|| err("expected KIND:SIZE@ONSET, e.g. ext1:0.3lpm@20s".into()))?;
        let path = LeakPath::from_name(kind.trim())
            .ok_or_else(|| err(format!("unknown leak kind `{kind}`: expected ext1, ext2 or int")))?;
        let mut parts = rest.split(',');
        let head = parts.next().unwrap_or("");
        let (size, onset) = head
            .split_once('@')
            .ok_or_else(|| err("missing `@ONSET` (e.g. @20s)".into()))?;
        let onset = onset.trim();
        let onset_s: f64 = onset
            .strip_suffix('s')
            .unwrap_or(onset)
            .parse()
            .map_err(|_| err(format!("onset `{onset}` is not a time in seconds")))?;
        if !onset_s.is_finite() || onset_s < 0.0 {
            return Err(err(format!("onset {onset_s} s must be >= 0")));
        }
        let mut law = LeakLaw::SquareRoot;
        let mut ramp_s = 0.0;
        for opt in parts {
            let (key, value) = opt.split_once('=').ok_or_else(|| {
                err(format!(
                    "option `{opt}` should be key=value (ramp=SECONDS or law=sqrt|linear)"
                ))
            })?;
            match key.trim() {
                "ramp" => {
                    let v = value.trim();
                    ramp_s = v
                        .strip_suffix('s')
                        .unwrap_or(v)
                        .parse()
                        .map_err(|_| err(format!("ramp `{value}` is not a time in seconds")))?;
                    if !(ramp_s >= 0.0 && f64::is_finite(ramp_s)) {
                        return Err(err(format!("ramp {ramp_s} s must be >= 0")));
                    }
                }
                "law" => {
                    law = match value.trim() {
                        "sqrt" => LeakLaw::SquareRoot,
                        "linear" => LeakLaw::Linear,
                        other => return Err(err(format!("unknown law `{other}`: expected sqrt or linear"))),
                    }
                }
                other => return Err(err(format!("unknown option `{other}`: expected ramp or law"))),
            }
        }
        let size = size.trim();
        let (coefficient, nominal_lpm) = if let Some(k) = size.strip_prefix("k=") {
            let k: f64 = k
                .parse()
                .map_err(|_| err(format!("coefficient `{k}` is not a number")))?;
            if !(k >= 0.0 && k.is_finite()) {
                return Err(err(format!("coefficient {k} must be >= 0")));
            }
            (k, None)
        } else if let Some(q) = size.strip_suffix("lpm") {
            let q: f64 = q
                .trim()
                .parse()
                .map_err(|_| err(format!("size `{q}` is not a number of L/min")))?;
            if !(q >= 0.0 && q.is_finite()) {
                return Err(err(format!("size {q} L/min must be >= 0")));
            }
            (
                law.coefficient_for(lpm_to_m3_s(q), Self::nominal_drop_pa(params)),
                Some(q),
            )
        } else {
            return Err(err(format!(
                "size `{size}` needs a unit: e.g. 0.3lpm (L/min at the nominal pressure) or k=2e-12 (raw coefficient)"
            )));
        };
        Ok(Fault {
            path,
            law,
            coefficient,
            onset_s,
            ramp_s,
            nominal_lpm,
        })
    }
}

/// A fault spec that could not be parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultSpecError {
    /// The spec as given.
    pub spec: String,
    /// What is wrong with it.
    pub message: String,
}

impl std::fmt::Display for FaultSpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "bad fault spec `{}`: {}", self.spec, self.message)
    }
}

impl std::error::Error for FaultSpecError {}

/// The faults of a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultSchedule {
    /// The scheduled faults, in any order.
    pub faults: Vec<Fault>,
}

impl FaultSchedule {
    /// Adds the coefficients in force at `t_s` to `leaks`.
    #[inline]
    pub fn add_to(&self, t_s: f64, leaks: &mut LeakSet) {
        for f in &self.faults {
            let k = f.coefficient_at(t_s);
            if k != 0.0 {
                leaks.add(f.path, f.law, k);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::m3_s_to_lpm;

    #[test]
    fn parses_specs() {
        let p = ActuatorParams::default();
        let f = Fault::parse("ext1:0.3lpm@20s", &p).unwrap();
        assert_eq!(f.path, LeakPath::External1);
        assert_eq!(f.law, LeakLaw::SquareRoot);
        assert_eq!(f.onset_s, 20.0);
        let q = m3_s_to_lpm(f.law.flow_m3_s(f.coefficient, 6.9e6));
        assert!((q - 0.3).abs() < 1e-12);
        let f = Fault::parse("ext2:k=2e-12@18,law=linear,ramp=5s", &p).unwrap();
        assert_eq!((f.coefficient, f.law, f.ramp_s), (2e-12, LeakLaw::Linear, 5.0));
        assert_eq!(f.coefficient_at(17.9), 0.0);
        assert!((f.coefficient_at(20.5) - 1e-12).abs() < 1e-24);
        assert_eq!(f.coefficient_at(30.0), 2e-12);
        let f = Fault::parse("int:0.5lpm@0s,law=linear", &p).unwrap();
        assert!((m3_s_to_lpm(f.coefficient * 6.9e6) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn rejects_bad_specs_with_a_reason() {
        let p = ActuatorParams::default();
        for (spec, needle) in [
            ("ext3:0.3lpm@20s", "unknown leak kind"),
            ("ext1:-0.3lpm@20s", "must be >= 0"),
            ("ext1:0.3@20s", "needs a unit"),
            ("ext1:0.3lpm", "missing `@ONSET`"),
            ("ext1:0.3lpm@soon", "not a time"),
            ("ext1", "expected KIND:SIZE@ONSET"),
            ("ext1:0.3lpm@2s,law=cubic", "unknown law"),
            ("ext1:0.3lpm@2s,speed=3", "unknown option"),
            ("ext1:k=abc@2s", "not a number"),
        ] {
            let e = Fault::parse(spec, &p).unwrap_err();
            assert!(e.to_string().contains(needle), "{spec}: {e}");
        }
    }
}
