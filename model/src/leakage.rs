//! Leakage laws for the three leak paths (docs/model.md#leak-paths).

use serde::{Deserialize, Serialize};

use crate::units::signed_sqrt;

/// Where oil leaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LeakPath {
    /// External leak from chamber 1 to return (tank).
    #[serde(rename = "ext1")]
    External1,
    /// External leak from chamber 2 to return (tank).
    #[serde(rename = "ext2")]
    External2,
    /// Internal (cross-port) leak from chamber 1 to chamber 2 across the piston.
    #[serde(rename = "int")]
    Internal,
}

impl LeakPath {
    /// All three paths in a fixed order (ext1, ext2, int).
    pub const ALL: [LeakPath; 3] = [LeakPath::External1, LeakPath::External2, LeakPath::Internal];

    /// The short name used on the command line and in events: `ext1`, `ext2`, `int`.
    pub fn name(self) -> &'static str {
        match self {
            LeakPath::External1 => "ext1",
            LeakPath::External2 => "ext2",
            LeakPath::Internal => "int",
        }
    }

    /// Parses a short name (`ext1`, `ext2`, `int`).
    pub fn from_name(name: &str) -> Option<LeakPath> {
        match name {
            "ext1" => Some(LeakPath::External1),
            "ext2" => Some(LeakPath::External2),
            "int" => Some(LeakPath::Internal),
            _ => None,
        }
    }

    /// The pressure drop across this path, Pa: p1 − p_r, p2 − p_r or p1 − p2.
    #[inline]
    pub fn pressure_drop_pa(self, p1_pa: f64, p2_pa: f64, return_pa: f64) -> f64 {
        match self {
            LeakPath::External1 => p1_pa - return_pa,
            LeakPath::External2 => p2_pa - return_pa,
            LeakPath::Internal => p1_pa - p2_pa,
        }
    }
}

impl std::fmt::Display for LeakPath {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl schema::FieldType for LeakPath {
    const KIND: schema::Kind = schema::Kind::Choice(&["ext1", "ext2", "int"]);
}

impl schema::FieldType for LeakLaw {
    const KIND: schema::Kind = schema::Kind::Choice(&["linear", "sqrt"]);
}

/// The flow law of a leak.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LeakLaw {
    /// Laminar: q = k·Δp, k in m³/(s·Pa).
    Linear,
    /// Turbulent (orifice): q = k·sgn(Δp)·√|Δp|, k in m³/(s·√Pa). Fits the rig better (thesis).
    #[serde(rename = "sqrt")]
    SquareRoot,
}

impl LeakLaw {
    /// Leak flow for coefficient `k` and pressure drop `dp_pa`, m³/s (positive along the path).
    #[inline]
    pub fn flow_m3_s(self, k: f64, dp_pa: f64) -> f64 {
        match self {
            LeakLaw::Linear => k * dp_pa,
            LeakLaw::SquareRoot => k * signed_sqrt(dp_pa),
        }
    }

    /// The coefficient that gives `flow_m3_s` at pressure drop `dp_pa` (> 0).
    pub fn coefficient_for(self, flow_m3_s: f64, dp_pa: f64) -> f64 {
        match self {
            LeakLaw::Linear => flow_m3_s / dp_pa,
            LeakLaw::SquareRoot => flow_m3_s / dp_pa.sqrt(),
        }
    }

    /// The name used in fault specs: `linear` or `sqrt`.
    pub fn name(self) -> &'static str {
        match self {
            LeakLaw::Linear => "linear",
            LeakLaw::SquareRoot => "sqrt",
        }
    }
}

/// The leak flows of the three paths at one instant, m³/s.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LeakFlows {
    /// Chamber 1 to return, m³/s.
    pub ext1_m3_s: f64,
    /// Chamber 2 to return, m³/s.
    pub ext2_m3_s: f64,
    /// Chamber 1 to chamber 2, m³/s.
    pub int_m3_s: f64,
}

impl LeakFlows {
    /// Adds the flow of one leak.
    #[inline]
    pub fn add(&mut self, path: LeakPath, flow_m3_s: f64) {
        match path {
            LeakPath::External1 => self.ext1_m3_s += flow_m3_s,
            LeakPath::External2 => self.ext2_m3_s += flow_m3_s,
            LeakPath::Internal => self.int_m3_s += flow_m3_s,
        }
    }

    /// The flow along one path, m³/s.
    pub fn get(&self, path: LeakPath) -> f64 {
        match path {
            LeakPath::External1 => self.ext1_m3_s,
            LeakPath::External2 => self.ext2_m3_s,
            LeakPath::Internal => self.int_m3_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::{lpm_to_m3_s, m3_s_to_lpm};

    #[test]
    fn thesis_reference_linear_leak() {
        // docs/model.md#sizes-in-lmin: at p1 ≈ 6.9 MPa, 2e-12 m³/(s·Pa) is about 0.83 L/min.
        let q = LeakLaw::Linear.flow_m3_s(2e-12, 6.9e6);
        assert!((m3_s_to_lpm(q) - 0.828).abs() < 0.005, "{}", m3_s_to_lpm(q));
    }

    #[test]
    fn square_root_law_and_inverse() {
        let k = LeakLaw::SquareRoot.coefficient_for(lpm_to_m3_s(0.5), 6.9e6);
        assert!((k - 3.1724e-9).abs() < 1e-13, "{k}");
        let q = LeakLaw::SquareRoot.flow_m3_s(k, 6.9e6);
        assert!((m3_s_to_lpm(q) - 0.5).abs() < 1e-12);
        // quadrupling the drop doubles the flow; a reversed drop reverses it
        let q4 = LeakLaw::SquareRoot.flow_m3_s(k, 4.0 * 6.9e6);
        assert!((q4 / q - 2.0).abs() < 1e-12);
        assert!((LeakLaw::SquareRoot.flow_m3_s(k, -6.9e6) + q).abs() < 1e-20);
        assert!((LeakLaw::Linear.flow_m3_s(1e-12, -2e6) + 2e-6).abs() < 1e-20);
    }

    #[test]
    fn path_pressure_drops() {
        assert_eq!(LeakPath::External1.pressure_drop_pa(7e6, 5e6, 1e5), 6.9e6);
        assert_eq!(LeakPath::External2.pressure_drop_pa(7e6, 5e6, 1e5), 4.9e6);
        assert_eq!(LeakPath::Internal.pressure_drop_pa(7e6, 5e6, 1e5), 2e6);
        for p in LeakPath::ALL {
            assert_eq!(LeakPath::from_name(p.name()), Some(p));
        }
    }
}
