//! Friction parameters: the presets, one direction's Stribeck curve, and the
//! rod's friction with an optional own retracting curve.

use schema::{num, Range};
use serde::{Deserialize, Serialize};

/// Which friction preset a rig uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrictionPreset {
    /// The thesis' friction as published (f_st = 2.4 kN, f_sl = 1.1 kN): the
    /// rod falls into a stick-slip cycle (docs/model.md#stick-slip).
    Thesis,
    /// A smoother rig: no Stribeck drop (f_st = f_sl = 1.1 kN), so no stick-slip.
    Smooth,
}

/// Declares [`FrictionParams`] and [`Friction`] with the same curve fields,
/// written once (`$curve`).
macro_rules! friction_structs {
    ($($curve:tt)*) => {
        schema::config_struct! {
            /// Friction parameters of one direction of motion (Karnopp with the LaVal
            /// Stribeck form, docs/model.md#friction).
            #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
            #[serde(default, deny_unknown_fields)]
            pub struct FrictionParams {
                $($curve)*
            }
        }

        schema::config_struct! {
            /// Friction of the rod seal in both directions. The top-level values apply
            /// while extending and, unless `retract` is given, in both directions.
            #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
            #[serde(default, deny_unknown_fields)]
            pub struct Friction {
                $($curve)*
                /// Velocity treated as zero (the stick band half-width) u_z, m/s.
                pub zero_velocity_m_s: f64 = 1.0e-3 => ["m/s", num!("a velocity", 1e-9, 1)],
                /// Friction while retracting (v < 0), when it differs from extending (asymmetric seals).
                pub retract: Option<FrictionParams> = None,
            }
        }
    };
}

friction_structs! {
    /// Static (stiction) friction f_st, N.
    pub static_n: f64 = 2.4e3 => ["N", Range::Stated("a force from slip_n to 1e6 N")],
    /// Slip (Coulomb) friction f_sl, N.
    pub slip_n: f64 = 1.1e3 => ["N", num!("a force", 0, 1e6)],
    /// Stribeck decay velocity α, m/s.
    pub stribeck_velocity_m_s: f64 = 0.04 => ["m/s", num!("a velocity", 1e-6, 10)],
    /// Viscous friction coefficient d, N·s/m.
    pub viscous_n_s_per_m: f64 = 350.0 => ["N·s/m", num!("a viscous coefficient", 0, 1e7)],
}

impl FrictionParams {
    /// The parameters of a friction preset.
    pub fn preset(preset: FrictionPreset) -> Self {
        match preset {
            FrictionPreset::Thesis => FrictionParams::default(),
            FrictionPreset::Smooth => FrictionParams {
                static_n: 1.1e3,
                ..FrictionParams::default()
            },
        }
    }
}

impl Friction {
    /// The same friction in both directions, with the thesis' stick band (1 mm/s)
    /// (the default: [`FrictionParams::default`] both ways).
    pub fn symmetric(p: FrictionParams) -> Self {
        Friction {
            static_n: p.static_n,
            slip_n: p.slip_n,
            stribeck_velocity_m_s: p.stribeck_velocity_m_s,
            viscous_n_s_per_m: p.viscous_n_s_per_m,
            zero_velocity_m_s: 1.0e-3,
            retract: None,
        }
    }

    /// The friction while extending.
    #[inline]
    pub fn extend(&self) -> FrictionParams {
        FrictionParams {
            static_n: self.static_n,
            slip_n: self.slip_n,
            stribeck_velocity_m_s: self.stribeck_velocity_m_s,
            viscous_n_s_per_m: self.viscous_n_s_per_m,
        }
    }

    /// Sets the friction while extending (and in both directions if `retract` is none).
    pub fn set_extend(&mut self, p: FrictionParams) {
        self.static_n = p.static_n;
        self.slip_n = p.slip_n;
        self.stribeck_velocity_m_s = p.stribeck_velocity_m_s;
        self.viscous_n_s_per_m = p.viscous_n_s_per_m;
    }

    /// The parameters that apply when moving with velocity sign `sign` (>= 0 extends).
    #[inline]
    pub fn for_direction(&self, sign: f64) -> FrictionParams {
        match (sign < 0.0, self.retract) {
            (true, Some(r)) => r,
            _ => self.extend(),
        }
    }
}
