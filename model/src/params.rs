//! Physical parameters of the actuator (MODEL.md §2), with every field
//! defaulted to the thesis' value and named with its unit.
//!
//! The same type describes the model the estimator believes in and the
//! simulated rig; a rig may differ from the model (friction asymmetry, air in
//! the oil, a spool null bias, supply sag, a spring load, built-in leaks), and
//! each such effect has a neutral default so the nominal model has none.

use serde::{Deserialize, Serialize};

use crate::leakage::{LeakLaw, LeakPath};

/// Which friction preset a rig uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrictionPreset {
    /// The thesis' friction as published (f_st = 2.4 kN, f_sl = 1.1 kN): the
    /// rod falls into a 30–40 Hz stick-slip cycle (MODEL.md §8).
    Thesis,
    /// A smoother rig: no Stribeck drop (f_st = f_sl = 1.1 kN), so no stick-slip.
    Smooth,
}

/// Friction parameters of one direction of motion (Karnopp with the LaVal
/// Stribeck form, MODEL.md §3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionParams {
    /// Static (stiction) friction f_st, N.
    pub static_n: f64,
    /// Slip (Coulomb) friction f_sl, N.
    pub slip_n: f64,
    /// Stribeck decay velocity α, m/s.
    pub stribeck_velocity_m_s: f64,
    /// Viscous friction coefficient d, N·s/m.
    pub viscous_n_s_per_m: f64,
}

impl Default for FrictionParams {
    fn default() -> Self {
        FrictionParams {
            static_n: 2.4e3,
            slip_n: 1.1e3,
            stribeck_velocity_m_s: 0.04,
            viscous_n_s_per_m: 350.0,
        }
    }
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

/// Friction of the rod seal in both directions. The top-level values apply
/// while extending and, unless `retract` is given, in both directions.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Friction {
    /// Static (stiction) friction f_st, N.
    pub static_n: f64,
    /// Slip (Coulomb) friction f_sl, N.
    pub slip_n: f64,
    /// Stribeck decay velocity α, m/s.
    pub stribeck_velocity_m_s: f64,
    /// Viscous friction coefficient d, N·s/m.
    pub viscous_n_s_per_m: f64,
    /// Velocity treated as zero (the stick band half-width) u_z, m/s.
    pub zero_velocity_m_s: f64,
    /// Friction while retracting (v < 0), when it differs from extending (asymmetric seals).
    pub retract: Option<FrictionParams>,
}

impl Default for Friction {
    fn default() -> Self {
        Friction::symmetric(FrictionParams::default())
    }
}

impl Friction {
    /// The same friction in both directions, with the thesis' stick band (1 mm/s).
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

/// A spring in front of the rod: F_l = k·max(0, x − x_c) + preload + damping
/// while in contact (MODEL.md §2, Chapters 6 and 7).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpringLoad {
    /// Spring stiffness K_env, N/m (0 = no load).
    pub stiffness_n_per_m: f64,
    /// Rod position at which the rod touches the spring, m.
    pub contact_m: f64,
    /// Force added as soon as the spring is touched, N.
    pub preload_n: f64,
    /// Damping while in contact, N·s/m.
    pub damping_n_s_per_m: f64,
}

impl Default for SpringLoad {
    fn default() -> Self {
        SpringLoad {
            stiffness_n_per_m: 0.0,
            contact_m: 0.22,
            preload_n: 0.0,
            damping_n_s_per_m: 0.0,
        }
    }
}

impl SpringLoad {
    /// The spring of the thesis' loaded simulation: 2e4 N/m touching at 0.22 m.
    pub fn thesis_simulation() -> Self {
        SpringLoad {
            stiffness_n_per_m: 2.0e4,
            contact_m: 0.22,
            ..SpringLoad::default()
        }
    }

    /// The load force on the rod at position `x_m` and velocity `v_m_s`, N (pushes back, i.e. positive opposes extension).
    #[inline]
    pub fn force_n(&self, x_m: f64, v_m_s: f64) -> f64 {
        if self.stiffness_n_per_m == 0.0 && self.preload_n == 0.0 {
            return 0.0;
        }
        let compression = x_m - self.contact_m;
        if compression <= 0.0 {
            0.0
        } else {
            self.stiffness_n_per_m * compression + self.preload_n + self.damping_n_s_per_m * v_m_s
        }
    }
}

/// A leak that is part of the plant itself (as opposed to a scheduled fault).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuiltInLeak {
    /// Where the oil leaks.
    pub path: LeakPath,
    /// Which law the flow follows.
    pub law: LeakLaw,
    /// The coefficient: m³/(s·Pa) for the linear law, m³/(s·√Pa) for the square-root law.
    pub coefficient: f64,
}

/// All physical parameters of the servovalve-driven double-rod cylinder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ActuatorParams {
    /// Effective piston area A, m².
    pub piston_area_m2: f64,
    /// Moving mass m (rod + piston), kg.
    pub mass_kg: f64,
    /// Fully retracted rod position X_min, m.
    pub x_min_m: f64,
    /// Fully extended rod position X_max, m.
    pub x_max_m: f64,
    /// Line (dead) volume on the chamber-1 side V10, m³.
    pub dead_volume_1_m3: f64,
    /// Line (dead) volume on the chamber-2 side V20, m³.
    pub dead_volume_2_m3: f64,
    /// Effective bulk modulus of the (air-free) oil β, Pa.
    pub bulk_modulus_pa: f64,
    /// Volume fraction of entrained air at atmospheric pressure (0 = none);
    /// makes the effective bulk modulus fall at low pressure.
    pub entrained_air_fraction: f64,
    /// Oil density ρ, kg/m³.
    pub oil_density_kg_m3: f64,
    /// Orifice discharge coefficient C_d, dimensionless.
    pub discharge_coefficient: f64,
    /// Orifice area gradient w, m²/m.
    pub area_gradient_m2_per_m: f64,
    /// Spool displacement per volt of command (DC gain) k_sp, m/V.
    pub spool_gain_m_per_v: f64,
    /// Spool natural frequency ω_n, rad/s.
    pub spool_natural_freq_rad_s: f64,
    /// Spool damping ratio ζ_n, dimensionless.
    pub spool_damping_ratio: f64,
    /// Spool null bias: spool position at zero command, m.
    pub spool_null_bias_m: f64,
    /// Supply pressure p_s at zero flow, Pa.
    pub supply_pressure_pa: f64,
    /// Supply pressure drop per unit of flow drawn from the supply, Pa/(m³/s) (0 = stiff supply).
    pub supply_sag_pa_per_m3_s: f64,
    /// Return (tank) pressure p_r, Pa (gauge).
    pub return_pressure_pa: f64,
    /// Friction of the rod and piston seals.
    pub friction: Friction,
    /// External load: a spring in front of the rod.
    pub load: SpringLoad,
    /// Stiffness of the end stops, N/m.
    pub end_stop_stiffness_n_per_m: f64,
    /// Damping of the end stops while pressed, N·s/m.
    pub end_stop_damping_n_s_per_m: f64,
    /// Leaks that are part of the plant (none in the healthy model).
    pub leaks: Vec<BuiltInLeak>,
}

impl Default for ActuatorParams {
    fn default() -> Self {
        ActuatorParams {
            piston_area_m2: 6.33e-4,
            mass_kg: 10.0,
            x_min_m: 0.0,
            x_max_m: 0.6069,
            dead_volume_1_m3: 2.14e-5,
            dead_volume_2_m3: 2.14e-5,
            bulk_modulus_pa: 6.89e8,
            entrained_air_fraction: 0.0,
            oil_density_kg_m3: 847.15,
            discharge_coefficient: 0.6,
            area_gradient_m2_per_m: 2.075e-2,
            spool_gain_m_per_v: 2.794e-5,
            spool_natural_freq_rad_s: 200.0 * std::f64::consts::PI,
            spool_damping_ratio: 0.7,
            spool_null_bias_m: 0.0,
            supply_pressure_pa: 13.8e6,
            supply_sag_pa_per_m3_s: 0.0,
            return_pressure_pa: 0.0,
            friction: Friction::default(),
            load: SpringLoad::default(),
            end_stop_stiffness_n_per_m: 1.0e8,
            end_stop_damping_n_s_per_m: 6.0e4,
            leaks: Vec::new(),
        }
    }
}

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
    /// The thesis' nominal parameters (same as `Default`).
    pub fn thesis() -> Self {
        Self::default()
    }

    /// Nominal parameters with the named friction preset.
    pub fn with_friction_preset(mut self, preset: FrictionPreset) -> Self {
        self.friction.set_extend(FrictionParams::preset(preset));
        self.friction.retract = None;
        self
    }

    /// The nominal operating pressure of a chamber, Pa: the mean of supply and
    /// return, where leak sizes given in L/min are converted to coefficients.
    pub fn nominal_chamber_pressure_pa(&self) -> f64 {
        0.5 * (self.supply_pressure_pa + self.return_pressure_pa)
    }

    /// Chamber volumes (V1, V2) at rod position `x_m`, m³, never below 1 % of the dead volume.
    #[inline]
    pub fn chamber_volumes_m3(&self, x_m: f64) -> (f64, f64) {
        let v1 = self.dead_volume_1_m3 + self.piston_area_m2 * (x_m - self.x_min_m);
        let v2 = self.dead_volume_2_m3 + self.piston_area_m2 * (self.x_max_m - x_m);
        (
            v1.max(0.01 * self.dead_volume_1_m3),
            v2.max(0.01 * self.dead_volume_2_m3),
        )
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_thesis_table() {
        let p = ActuatorParams::default();
        assert_eq!(p.piston_area_m2, 6.33e-4);
        assert_eq!(p.friction.static_n, 2.4e3);
        assert!((p.spool_natural_freq_rad_s - 628.3185).abs() < 1e-3);
        p.validate().unwrap();
    }

    #[test]
    fn toml_round_trip_and_unknown_field() {
        let p = ActuatorParams {
            leaks: vec![BuiltInLeak {
                path: LeakPath::External1,
                law: LeakLaw::SquareRoot,
                coefficient: 3.2e-9,
            }],
            ..ActuatorParams::default()
        };
        let text = toml::to_string(&p).unwrap();
        let back: ActuatorParams = toml::from_str(&text).unwrap();
        assert_eq!(p, back);
        let err = toml::from_str::<ActuatorParams>("supply_pressure_psi = 2000.0").unwrap_err();
        assert!(err.to_string().contains("supply_pressure_psi"), "{err}");
        let partial: ActuatorParams = toml::from_str("mass_kg = 12.0").unwrap();
        assert_eq!(partial.mass_kg, 12.0);
        assert_eq!(partial.piston_area_m2, 6.33e-4);
    }

    #[test]
    fn validate_names_the_field() {
        let mut p = ActuatorParams::default();
        p.friction.static_n = 500.0;
        let e = p.validate().unwrap_err();
        assert_eq!(e.field, "friction.static_n");
        let p = ActuatorParams {
            bulk_modulus_pa: -1.0,
            ..ActuatorParams::default()
        };
        assert_eq!(p.validate().unwrap_err().field, "bulk_modulus_pa");
    }
}
