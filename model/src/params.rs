//! Physical parameters of the actuator (docs/model.md#parameters), with every field
//! defaulted to the thesis' value and named with its unit.
//!
//! The same type describes the model the estimator believes in and the
//! simulated rig; a rig may differ from the model (friction asymmetry, air in
//! the oil, a spool null bias, supply sag, a spring load, built-in leaks), and
//! each such effect has a neutral default so the nominal model has none.

use schema::{below, num, Range};
use serde::{Deserialize, Serialize};

use crate::leakage::{LeakLaw, LeakPath};

mod friction;
mod oil;
pub(crate) mod validate;

pub use friction::{Friction, FrictionParams, FrictionPreset};
pub use oil::{
    viscosity_100c_of_grade, OilFactors, OilTemperature, CATALOGUE_LAW_UNCERTAINTY, STATED_LAW_UNCERTAINTY,
    STATED_VISCOSITY_100C_TOLERANCE,
};
pub use validate::InvalidParam;

schema::config_struct! {
    /// A spring in front of the rod: F_l = k·max(0, x − x_c) + preload + damping
    /// while in contact (docs/model.md#load; the thesis' Chapters 6 and 7).
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct SpringLoad {
        /// Spring stiffness K_env, N/m (0 = no load).
        pub stiffness_n_per_m: f64 = 0.0 => ["N/m", num!("a stiffness", 0, 1e10)],
        /// Rod position at which the rod touches the spring, m.
        pub contact_m: f64 = 0.22 => ["m", num!("a position", -10, 10)],
        /// Force added as soon as the spring is touched, N.
        pub preload_n: f64 = 0.0 => ["N", num!("a force", 0, 1e7)],
        /// Damping while in contact, N·s/m.
        pub damping_n_s_per_m: f64 = 0.0 => ["N·s/m", num!("a damping", 0, 1e8)],
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

schema::config_struct! {
    /// A leak that is part of the plant itself (as opposed to a scheduled fault).
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct BuiltInLeak {
        /// Where the oil leaks.
        pub path: LeakPath,
        /// Which law the flow follows.
        pub law: LeakLaw,
        /// The coefficient: m³/(s·Pa) for the linear law, m³/(s·√Pa) for the square-root law.
        pub coefficient: f64 => [
            "(m³/s per √Pa, or per Pa for the linear law)",
            num!("a coefficient", 0, 1e-4)
        ],
    }
}

schema::config_struct! {
    /// All physical parameters of the servovalve-driven cylinder: double-rod
    /// (one piston area) or single-rod (`rod_side_area_m2`), at any mounting angle.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct ActuatorParams {
        /// Piston area chamber 1 (the cap side of a single-rod cylinder) pushes on, A1, m².
        pub piston_area_m2: f64 = 6.33e-4 => ["m²", num!("an area", 1e-6, 1)],
        /// Piston area chamber 2 pushes on, A2, m²: the annulus of a single-rod
        /// cylinder (π/4·(D² − d²)). Absent: A1 (a double-rod cylinder).
        pub rod_side_area_m2: Option<f64> = None => [
            "m²",
            num!("an area", 1e-6, 1, "(or absent: a double-rod cylinder)")
        ],
        /// Angle of the direction of extension above the horizontal, rad: π/2 is a
        /// vertical cylinder whose extension lifts the moving mass, −π/2 one whose
        /// extension lowers it; gravity then pulls on the rod with m·g·sin(angle).
        pub mounting_angle_rad: f64 = 0.0 => [
            "rad",
            Range::Number {
                what: "an angle",
                lo: -std::f64::consts::FRAC_PI_2,
                hi: std::f64::consts::FRAC_PI_2,
                lo_text: "-π/2",
                hi_text: "π/2",
                note: "(0: horizontal, π/2: vertical, extension lifts)",
            }
        ],
        /// Moving mass m (rod + piston), kg.
        pub mass_kg: f64 = 10.0 => ["kg", num!("a mass", 1e-3, 1e5)],
        /// Fully retracted rod position X_min, m.
        pub x_min_m: f64 = 0.0 => ["m", num!("a position", -10, 10)],
        /// Fully extended rod position X_max, m.
        pub x_max_m: f64 = 0.6069 => [
            "m",
            Range::Stated("a position at least 1 mm above x_min_m and at most 10 m")
        ],
        /// Line (dead) volume on the chamber-1 side V10, m³.
        pub dead_volume_1_m3: f64 = 2.14e-5 => ["m³", num!("a volume", 1e-9, 1)],
        /// Line (dead) volume on the chamber-2 side V20, m³.
        pub dead_volume_2_m3: f64 = 2.14e-5 => ["m³", num!("a volume", 1e-9, 1)],
        /// Effective bulk modulus of the (air-free) oil β, Pa.
        pub bulk_modulus_pa: f64 = 6.89e8 => ["Pa", num!("a bulk modulus", 1e6, 1e11)],
        /// How the oil's bulk modulus and viscosity follow its temperature (used
        /// only when the samples carry it, `temp_c`).
        pub oil_temperature: OilTemperature = OilTemperature::default(),
        /// Volume fraction of entrained air at atmospheric pressure (0 = none);
        /// makes the effective bulk modulus fall at low pressure.
        pub entrained_air_fraction: f64 = 0.0 => ["", below!("a fraction", 0, 0.5)],
        /// Oil density ρ, kg/m³.
        pub oil_density_kg_m3: f64 = 847.15 => ["kg/m³", num!("a density", 100, 5000)],
        /// Orifice discharge coefficient C_d, dimensionless.
        pub discharge_coefficient: f64 = 0.6 => ["(dimensionless)", num!("a value", 0.01, 1)],
        /// Orifice area gradient w of the port-A lands (P→A, A→T), m²/m.
        pub area_gradient_m2_per_m: f64 = 2.075e-2 => ["m²/m", num!("an area gradient", 1e-6, 10)],
        /// Orifice area gradient of the port-B lands (P→B, B→T), m²/m: a valve matched
        /// to a single-rod cylinder has w_B = w·A2/A1. Absent: the port-A gradient.
        pub area_gradient_b_m2_per_m: Option<f64> = None => [
            "m²/m",
            num!("an area gradient", 1e-6, 10, "(or absent: the port-A gradient)")
        ],
        /// Spool displacement per volt of command (DC gain) k_sp, m/V.
        pub spool_gain_m_per_v: f64 = 2.794e-5 => ["m/V", num!("a spool gain", 1e-9, 0.1)],
        /// Spool natural frequency ω_n, rad/s.
        pub spool_natural_freq_rad_s: f64 = 200.0 * std::f64::consts::PI => [
            "rad/s",
            num!("a natural frequency", 1, 2e4)
        ],
        /// Spool damping ratio ζ_n, dimensionless.
        pub spool_damping_ratio: f64 = 0.7 => ["(dimensionless)", num!("a damping ratio", 0.01, 10)],
        /// Spool null bias: spool position at zero command, m.
        pub spool_null_bias_m: f64 = 0.0 => ["m", num!("a spool offset", -0.01, 0.01)],
        /// Supply pressure p_s at zero flow, Pa.
        pub supply_pressure_pa: f64 = 13.8e6 => [
            "Pa",
            Range::Stated("a pressure at least 1e4 Pa above return_pressure_pa and at most 1e9 Pa (1000 MPa)")
        ],
        /// Supply pressure drop per unit of flow drawn from the supply, Pa/(m³/s) (0 = stiff supply).
        pub supply_sag_pa_per_m3_s: f64 = 0.0 => [
            "Pa per m³/s",
            Range::Stated("0 (no sag) or a pressure drop from 1 to 1e14 Pa per m³/s")
        ],
        /// What the p1 and p2 transducers read above the chamber pressures at the
        /// working point, Pa (their zero offsets and span errors there): the
        /// filters take it off each reading and a simulation adds it.
        /// `commission` fits it to the healthy leak estimates (docs/plant.md,
        /// "Commissioning fits the transducers' misreading").
        pub pressure_misreading_pa: [f64; 2] = [0.0; 2] => ["Pa", num!("misreadings", -1e7, 1e7)],
        /// Resistance of the lines between the chambers and the p1/p2
        /// transducers, Pa/(m³/s), held over the oil's temperature (0: the
        /// transducers read the chambers). Transducers at the valve's
        /// manifold read p1 + R·Q1 and p2 − R·Q2; the leak filter predicts its
        /// readings so. `commission` identifies it where the recording resolves it.
        pub line_resistance_pa_s_per_m3: f64 = 0.0 => [
            "Pa per m³/s",
            num!("a line resistance", 0, 1e12)
        ],
        /// Return (tank) pressure p_r, Pa (gauge).
        pub return_pressure_pa: f64 = 0.0 => ["Pa", num!("a pressure", 0, 1e8)],
        /// Laminar leakage conductance of each of the valve's four metering lands at
        /// null (spool underlap), m³/(s·Pa) (0 = a critical-centre valve without
        /// leakage). A catalogue's "internal leakage" Q_L at supply p_s (ports
        /// blocked, two paths P→A→T and P→B→T in parallel) is C_L = Q_L / p_s.
        pub valve_null_leakage_m3_s_pa: f64 = 0.0 => [
            "m³/(s·Pa)",
            num!("a conductance", 0, 1e-9, "(0 = no null leakage; 1e-9 passes 1260 L/min at 21 MPa)")
        ],
        /// Spool travel over which a closing land's null leakage fades to zero, m (the
        /// underlap x_u; used only with `valve_null_leakage_m3_s_pa` > 0).
        pub valve_underlap_m: f64 = 5.0e-6 => ["m", num!("a spool travel", 1e-8, 1e-3)],
        /// Friction of the rod and piston seals.
        pub friction: Friction = Friction::default(),
        /// External load: a spring in front of the rod.
        pub load: SpringLoad = SpringLoad::default(),
        /// Stiffness of the end stops, N/m.
        pub end_stop_stiffness_n_per_m: f64 = 1.0e8 => ["N/m", num!("a stiffness", 1, 1e10)],
        /// Damping of the end stops while pressed, N·s/m.
        pub end_stop_damping_n_s_per_m: f64 = 6.0e4 => ["N·s/m", num!("a damping", 0, 1e8)],
        /// Leaks that are part of the plant (none in the healthy model).
        pub leaks: Vec<BuiltInLeak> = Vec::new(),
    }
}

/// Standard gravity g_n, m/s² (the weight of a vertical cylinder's moving mass).
pub const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// How far below 0 Pa (gauge) a measured chamber pressure may read, as a
/// fraction of the supply pressure p_s (dimensionless): 2 %, 0.276 MPa at the
/// default 13.8 MPa. Sensor noise and offset around tank pressure read slightly
/// negative; see [`ActuatorParams::measured_pressure_range_pa`].
pub const PRESSURE_NEGATIVE_MARGIN: f64 = 0.02;

/// The highest a measured chamber pressure may read, as a multiple of the
/// supply pressure p_s (dimensionless): 1.5, 20.7 MPa at the default 13.8 MPa;
/// see [`ActuatorParams::measured_pressure_range_pa`].
pub const PRESSURE_MAX_PER_SUPPLY: f64 = 1.5;

impl ActuatorParams {
    /// These parameters at oil temperature `temp_c` (°C), from `base` (the
    /// parameters at the law's reference temperature): the bulk modulus, the
    /// seals' viscous and dry friction, the valve's null leakage and the linear
    /// leaks scaled by [`OilTemperature::factors`], everything else as `base`
    /// has it.
    /// Writes fields in place (no allocation); `self.leaks` must be `base.leaks`
    /// in length. Returns the factors.
    pub fn set_oil_temperature(&mut self, base: &ActuatorParams, temp_c: f64) -> OilFactors {
        let f = self.set_oil_temperature_keeping_bulk_modulus(base, temp_c);
        self.bulk_modulus_pa = base.bulk_modulus_pa * f.bulk_modulus;
        f
    }

    /// As [`Self::set_oil_temperature`], but the bulk modulus stays as it is:
    /// only the terms that follow the oil's viscosity (the seals' viscous
    /// friction, the valve's null leakage and the linear leaks) and the seals'
    /// dry friction move. A filter whose
    /// oil-stiffness state θ carries the bulk modulus uses this with the
    /// temperature it infers from θ. Allocates nothing. Returns the factors.
    pub fn set_oil_temperature_keeping_bulk_modulus(
        &mut self,
        base: &ActuatorParams,
        temp_c: f64,
    ) -> OilFactors {
        let f = base.oil_temperature.factors(temp_c);
        self.friction.viscous_n_s_per_m = base.friction.viscous_n_s_per_m * f.viscous_friction;
        self.friction.static_n = base.friction.static_n * f.dry_friction;
        self.friction.slip_n = base.friction.slip_n * f.dry_friction;
        if let (Some(r), Some(b)) = (self.friction.retract.as_mut(), base.friction.retract) {
            r.viscous_n_s_per_m = b.viscous_n_s_per_m * f.viscous_friction;
            r.static_n = b.static_n * f.dry_friction;
            r.slip_n = b.slip_n * f.dry_friction;
        }
        self.valve_null_leakage_m3_s_pa = base.valve_null_leakage_m3_s_pa * f.laminar_flow;
        for (l, b) in self.leaks.iter_mut().zip(&base.leaks) {
            if b.law == LeakLaw::Linear {
                l.coefficient = b.coefficient * f.laminar_flow;
            }
        }
        f
    }

    /// This rig made to differ from its model the way real ones do (the one
    /// definition the demonstration, tests and benchmarks share): friction 15 %
    /// higher extending and 10 % lower retracting, the bulk modulus times
    /// `bulk_modulus_factor` (air: below 1), and a spool null bias of
    /// `spool_bias_fraction` of a 3 V spool stroke (8.4e-5 m), m.
    pub fn off_nominal(&self, bulk_modulus_factor: f64, spool_bias_fraction: f64) -> ActuatorParams {
        let mut rig = self.clone();
        let mut ext = rig.friction.extend();
        let mut ret = ext;
        ext.static_n *= 1.15;
        ext.slip_n *= 1.15;
        ret.static_n *= 0.9;
        ret.slip_n *= 0.9;
        rig.friction.set_extend(ext);
        rig.friction.retract = Some(ret);
        rig.bulk_modulus_pa *= bulk_modulus_factor;
        rig.spool_null_bias_m = spool_bias_fraction * 8.4e-5;
        rig
    }

    /// A second rig, unlike the thesis rig: a vertical single-rod lift. Bore 50 mm,
    /// rod 32 mm (A1 1.963e-3 m², A2 1.159e-3 m²), stroke 0.4 m, 200 kg lifted
    /// by extension, 21 MPa, a valve whose port B is matched to the area ratio
    /// (w_B = w·A2/A1), 0.9 m hoses of 12.7 mm (1.1e-4 m³ each side), oil of
    /// 1.2 GPa, friction 1.5 kN static and 0.9 kN Coulomb.
    pub fn vertical_lift() -> Self {
        let bore = std::f64::consts::FRAC_PI_4 * 0.05 * 0.05;
        let annulus = bore - std::f64::consts::FRAC_PI_4 * 0.032 * 0.032;
        let w = 3.0e-2;
        ActuatorParams {
            piston_area_m2: bore,
            rod_side_area_m2: Some(annulus),
            mounting_angle_rad: std::f64::consts::FRAC_PI_2,
            mass_kg: 200.0,
            x_min_m: 0.0,
            x_max_m: 0.4,
            dead_volume_1_m3: 1.1e-4,
            dead_volume_2_m3: 1.1e-4,
            bulk_modulus_pa: 1.2e9,
            oil_density_kg_m3: 870.0,
            area_gradient_m2_per_m: w,
            area_gradient_b_m2_per_m: Some(w * annulus / bore),
            spool_gain_m_per_v: 3.0e-5,
            spool_natural_freq_rad_s: 700.0,
            supply_pressure_pa: 21.0e6,
            friction: Friction {
                static_n: 1.5e3,
                slip_n: 0.9e3,
                stribeck_velocity_m_s: 0.02,
                viscous_n_s_per_m: 700.0,
                ..Friction::default()
            },
            ..ActuatorParams::default()
        }
    }

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

    /// The range a measured chamber pressure may take, Pa (gauge), both ends
    /// inclusive: [−[`PRESSURE_NEGATIVE_MARGIN`]·p_s, [`PRESSURE_MAX_PER_SUPPLY`]·p_s]
    /// ([−0.276, 20.7] MPa by default). CSV rows, UDP frames and the estimator's
    /// samples outside it are unusable. Pressures below 0 within the margin
    /// (sensor noise near tank pressure) are used as measured; the filters'
    /// predictions stay clamped at their own floor ([`crate::process::ProcessModel::p_min_pa`]).
    pub fn measured_pressure_range_pa(&self) -> (f64, f64) {
        (
            -PRESSURE_NEGATIVE_MARGIN * self.supply_pressure_pa,
            PRESSURE_MAX_PER_SUPPLY * self.supply_pressure_pa,
        )
    }

    /// The piston areas (A1, A2) chambers 1 and 2 push on, m² (equal for a double-rod cylinder).
    #[inline]
    pub fn areas_m2(&self) -> (f64, f64) {
        (
            self.piston_area_m2,
            self.rod_side_area_m2.unwrap_or(self.piston_area_m2),
        )
    }

    /// The force of the chamber pressures on the piston, A1·p1 − A2·p2, N (for a
    /// double-rod cylinder computed as A·(p1 − p2), so its results stay bit for bit).
    #[inline]
    pub fn pressure_force_n(&self, p1_pa: f64, p2_pa: f64) -> f64 {
        match self.rod_side_area_m2 {
            None => self.piston_area_m2 * (p1_pa - p2_pa),
            Some(a2) => self.piston_area_m2 * p1_pa - a2 * p2_pa,
        }
    }

    /// The area gradients (w_A, w_B) of the port-A and port-B lands, m²/m.
    #[inline]
    pub fn area_gradients_m2_per_m(&self) -> (f64, f64) {
        (
            self.area_gradient_m2_per_m,
            self.area_gradient_b_m2_per_m
                .unwrap_or(self.area_gradient_m2_per_m),
        )
    }

    /// The weight of the moving mass along the direction of extension, N
    /// (positive opposes extension): m·g·sin(mounting angle), with standard gravity.
    #[inline]
    pub fn gravity_force_n(&self) -> f64 {
        if self.mounting_angle_rad == 0.0 {
            return 0.0;
        }
        self.mass_kg * STANDARD_GRAVITY_M_S2 * self.mounting_angle_rad.sin()
    }

    /// Chamber volumes (V1, V2) at rod position `x_m`, m³, never below 1 % of the dead volume.
    #[inline]
    pub fn chamber_volumes_m3(&self, x_m: f64) -> (f64, f64) {
        let (a1, a2) = self.areas_m2();
        let v1 = self.dead_volume_1_m3 + a1 * (x_m - self.x_min_m);
        let v2 = self.dead_volume_2_m3 + a2 * (self.x_max_m - x_m);
        (
            v1.max(0.01 * self.dead_volume_1_m3),
            v2.max(0.01 * self.dead_volume_2_m3),
        )
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
    fn measured_pressures_may_read_2_percent_of_supply_below_zero() {
        let p = ActuatorParams::default();
        assert_eq!(p.measured_pressure_range_pa(), (-0.02 * 13.8e6, 1.5 * 13.8e6));
        let p = ActuatorParams {
            supply_pressure_pa: 21.0e6,
            ..ActuatorParams::default()
        };
        assert_eq!(p.measured_pressure_range_pa(), (-420.0e3, 31.5e6));
    }

    #[test]
    fn the_declared_stiffness_range_is_the_filters_clamp() {
        let f = ActuatorParams::SCHEMA
            .find(&["oil_temperature", "reference_stiffness"])
            .expect("declared");
        let Range::Number { lo, hi, .. } = f.range else {
            panic!("{:?}", f.range);
        };
        assert_eq!((lo, hi), crate::process::BULK_SCALE_RANGE);
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
