//! How the oil's properties follow its temperature (docs/plant.md, "Oil
//! temperature"): the bulk modulus falls linearly, the viscosity follows
//! Walther's law (ASTM D341) through the oil's two catalogue viscosities, and
//! with the viscosity the seals' viscous friction (∝ √ν, a lubricating film)
//! and every laminar flow (∝ 1/ν: the valve's null leakage, a linear leak);
//! the seals' dry (static and Coulomb) friction falls linearly as the seals'
//! elastomer softens.

use schema::num;
use serde::{Deserialize, Serialize};

/// Kelvin at 0 °C.
const ZERO_C_K: f64 = 273.15;
/// Walther's offset, mm²/s (ASTM D341).
const WALTHER_OFFSET_MM2_S: f64 = 0.7;
/// The lowest bulk-modulus factor the linear law gives (1): 100 K above the
/// reference a mineral oil still has half its stiffness.
const MIN_BULK_FACTOR: f64 = 0.5;
/// The lowest dry-friction factor the linear law gives (1): a seal keeps
/// most of its grip however warm the oil.
const MIN_DRY_FRICTION_FACTOR: f64 = 0.5;

/// An oil of viscosity index 100 of ISO grade VG 46: its kinematic
/// viscosities at 40 and 100 °C, mm²/s (ISO 3448).
const VI_100_VG_46_MM2_S: (f64, f64) = (46.0, 6.8);

/// How the viscosity at 100 °C of oils of viscosity index 100 goes with
/// their grade (the viscosity at 40 °C), as a power (1): VG 22, 32, 46, 68
/// and 100 have 4.3, 5.4, 6.8, 8.6 and 11.1 mm²/s at 100 °C, within 2 % of it.
const VI_100_GRADE_EXPONENT: f64 = 0.63;

/// The kinematic viscosity at 100 °C of an oil of viscosity index 100 whose
/// viscosity at 40 °C is `viscosity_40c_mm2_s`, mm²/s: what the law takes
/// where the oil's data sheet gives none (6.8 for an HLP 46).
pub fn viscosity_100c_of_grade(viscosity_40c_mm2_s: f64) -> f64 {
    let (nu40, nu100) = VI_100_VG_46_MM2_S;
    nu100 * (viscosity_40c_mm2_s / nu40).powf(VI_100_GRADE_EXPONENT)
}

/// Relative uncertainty of the laminar flows' change with temperature where
/// the oil's ν at 100 °C is not given, or the commissioning's null leakage's
/// σ is not known (1): Walther's law through the catalogue's default slope,
/// against oils whose viscosity index lies 60 above or below the one it
/// assumes, a reference temperature read off a tank's thermometer, and the
/// commissioning's null leakage off the rig's.
pub const CATALOGUE_LAW_UNCERTAINTY: f64 = 0.4;

/// The law's own share of the laminar flows' uncertainty where the oil's
/// data sheet gives its ν at 40 and 100 °C (1): a batch's viscosity index
/// within ±15 of the sheet's (its ν at 100 °C within
/// [`STATED_VISCOSITY_100C_TOLERANCE`]) moves the change from 20 to 60 °C by
/// up to 0.13 of itself. The commissioning's null leakage's σ adds to it
/// ([`OilTemperature::law_uncertainty`]).
pub const STATED_LAW_UNCERTAINTY: f64 = 0.15;

/// How far a batch's ν at 100 °C lies from its data sheet's, ± fraction (1):
/// a viscosity index within ±15 of the sheet's.
pub const STATED_VISCOSITY_100C_TOLERANCE: f64 = 0.07;

schema::config_struct! {
    /// The oil's temperature law, relative to the temperature the model's
    /// parameters hold at. It is used only when the samples carry the oil's
    /// temperature (`temp_c`); without it nothing changes.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct OilTemperature {
        /// Oil temperature at which the model's bulk modulus, viscous friction and
        /// laminar flows hold, °C: the commissioning recording's mean when it has
        /// a `temp_c` column.
        pub reference_c: f64 = 40.0 => ["°C", num!("an oil temperature", -40, 150)],
        /// Kinematic viscosity at 40 °C, mm²/s (the ISO VG grade: 46 for HLP 46).
        pub viscosity_40c_mm2_s: f64 = 46.0 => ["mm²/s", num!("a kinematic viscosity", 1, 10000)],
        /// Kinematic viscosity at 100 °C, mm²/s, as the oil's data sheet gives
        /// it. Absent: an oil's of viscosity index 100 of its grade (6.8 for
        /// an HLP 46, [`viscosity_100c_of_grade`]), and the law's change with
        /// temperature is then known less well ([`OilTemperature::law_uncertainty`]).
        #[serde(skip_serializing_if = "Option::is_none")]
        pub viscosity_100c_mm2_s: Option<f64> = None => ["mm²/s", num!("a kinematic viscosity", 0.5, 10000)],
        /// Relative change of the bulk modulus per kelvin, 1/K (mineral oil about −0.0045).
        pub bulk_modulus_per_k: f64 = -0.0045 => ["(1/K)", num!("a relative change per kelvin", -0.02, 0)],
        /// Relative change of the seals' static and Coulomb friction per kelvin,
        /// 1/K (elastomer seals on mineral oil about −0.004: 10 % less from 30
        /// to 55 °C).
        pub dry_friction_per_k: f64 = -0.004 => ["(1/K)", num!("a relative change per kelvin", -0.02, 0.02)],
        /// The lowest oil temperature the rig runs at, °C (its operating range):
        /// `commission` states the smallest detectable leaks over the range, and a
        /// replay says how long the oil was outside it.
        pub operating_min_c: f64 = 20.0 => ["°C", num!("an oil temperature", -40, 150)],
        /// The highest oil temperature the rig runs at, °C.
        pub operating_max_c: f64 = 60.0 => ["°C", num!("an oil temperature", -40, 150)],
        /// The leak filter's oil stiffness θ on the commissioning recording, at
        /// `reference_c` (1; `commission` sets it). Without `temp_c` the 12-state
        /// filter then reads the oil's temperature from θ relative to it and sets
        /// the viscous terms from it; absent: those terms stay as given.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub reference_stiffness: Option<f64> = None => [
            "times the model's bulk modulus",
            num!("a stiffness", 0.2, 2)
        ],
        /// θ's spread about `reference_stiffness` at one temperature, as a
        /// share of it (1): the σ of its means over
        /// `filter::oil::OIL_STIFFNESS_TAU_S` on the commissioning recording
        /// (`commission` sets it). What else moves θ (the duty cycle, the
        /// rod's stroke) reads as temperature: the temperature read from θ is
        /// uncertain by this over |`bulk_modulus_per_k`|. Absent: none.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub reference_stiffness_sigma_share: Option<f64> = None => [
            "(1)",
            num!("a share of the stiffness", 0, 1)
        ],
        /// The σ of the model's null leakage as a share of it (1): how far the
        /// pressure transducers' tolerances move what commissioning identified
        /// (`commission` sets it). Away from `reference_c` that error grows
        /// with the laminar flows. Absent: not known.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub null_leakage_sigma_share: Option<f64> = None => [
            "(1)",
            num!("a share of the null leakage", 0, 1000)
        ],
        /// How far θ moves per unit of error in the model's laminar flows
        /// (the valve's null leakage, the linear leaks), 1 per unit of their
        /// factor (`commission` measures it on its recording). A valve that
        /// leaks much at null pulls θ as a change of the oil's temperature
        /// does: the temperature is read from θ with that pull taken out.
        /// Absent: none.
        #[serde(skip_serializing_if = "Option::is_none")]
        pub stiffness_per_laminar_factor: Option<f64> = None => [
            "(1)",
            num!("a change of stiffness per unit of laminar factor", -2, 2)
        ],
    }
}

/// What the oil's temperature does to the model, as multiples of the values at
/// the reference temperature (1 each).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OilFactors {
    /// Bulk modulus.
    pub bulk_modulus: f64,
    /// Kinematic viscosity.
    pub viscosity: f64,
    /// Viscous friction of the seals: √ of the viscosity's factor.
    pub viscous_friction: f64,
    /// Laminar flows (null leakage, linear leaks): 1 / the viscosity's factor.
    pub laminar_flow: f64,
    /// The seals' static and Coulomb friction.
    pub dry_friction: f64,
}

impl OilFactors {
    /// No change (the reference temperature).
    pub const NONE: OilFactors = OilFactors {
        bulk_modulus: 1.0,
        viscosity: 1.0,
        viscous_friction: 1.0,
        laminar_flow: 1.0,
        dry_friction: 1.0,
    };
}

impl OilTemperature {
    /// Walther's W = log10(log10(ν + 0.7)) of a viscosity `nu_mm2_s`.
    fn walther(nu_mm2_s: f64) -> f64 {
        (nu_mm2_s + WALTHER_OFFSET_MM2_S).log10().log10()
    }

    /// The kinematic viscosity at 100 °C the law takes, mm²/s: the one
    /// given, else its grade's at viscosity index 100 ([`viscosity_100c_of_grade`]).
    pub fn viscosity_100c_or_default_mm2_s(&self) -> f64 {
        self.viscosity_100c_mm2_s
            .unwrap_or_else(|| viscosity_100c_of_grade(self.viscosity_40c_mm2_s))
    }

    /// Relative uncertainty of the model's laminar flows' change with
    /// temperature (1): where ν at 100 °C is given and the commissioning's
    /// null leakage's σ known, [`STATED_LAW_UNCERTAINTY`] plus that σ's
    /// share; else [`CATALOGUE_LAW_UNCERTAINTY`].
    pub fn law_uncertainty(&self) -> f64 {
        match (self.viscosity_100c_mm2_s, self.null_leakage_sigma_share) {
            (Some(_), Some(share)) if share.is_finite() => STATED_LAW_UNCERTAINTY + share.max(0.0),
            _ => CATALOGUE_LAW_UNCERTAINTY,
        }
    }

    /// The kinematic viscosity at `temp_c` (°C), mm²/s: Walther's law
    /// log10 log10(ν + 0.7) = A − B·log10(T/K) through the 40 °C and 100 °C values.
    pub fn viscosity_mm2_s(&self, temp_c: f64) -> f64 {
        let (t40, t100) = ((40.0 + ZERO_C_K).log10(), (100.0 + ZERO_C_K).log10());
        let (w40, w100) = (
            Self::walther(self.viscosity_40c_mm2_s),
            Self::walther(self.viscosity_100c_or_default_mm2_s()),
        );
        let b = (w40 - w100) / (t100 - t40);
        let w = w40 - b * ((temp_c + ZERO_C_K).log10() - t40);
        10f64.powf(10f64.powf(w)) - WALTHER_OFFSET_MM2_S
    }

    /// The factors at oil temperature `temp_c` (°C) against [`Self::reference_c`].
    pub fn factors(&self, temp_c: f64) -> OilFactors {
        let viscosity = self.viscosity_mm2_s(temp_c) / self.viscosity_mm2_s(self.reference_c);
        OilFactors {
            bulk_modulus: (1.0 + self.bulk_modulus_per_k * (temp_c - self.reference_c)).max(MIN_BULK_FACTOR),
            viscosity,
            viscous_friction: viscosity.sqrt(),
            laminar_flow: 1.0 / viscosity,
            dry_friction: (1.0 + self.dry_friction_per_k * (temp_c - self.reference_c))
                .max(MIN_DRY_FRICTION_FACTOR),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walther_passes_through_both_catalogue_points_and_halves_the_viscosity_over_about_17_k() {
        let oil = OilTemperature::default();
        assert!((oil.viscosity_mm2_s(40.0) - 46.0).abs() < 1e-9);
        assert!((oil.viscosity_mm2_s(100.0) - 6.8).abs() < 1e-9);
        // an HLP 46 of VI 100 at 60 °C is about 20 mm²/s (ISO 3448 tables: 19-21)
        let nu60 = oil.viscosity_mm2_s(60.0);
        assert!((19.0..21.5).contains(&nu60), "{nu60}");
        // monotone
        assert!(oil.viscosity_mm2_s(30.0) > 46.0 && oil.viscosity_mm2_s(55.0) < 46.0);
    }

    #[test]
    fn an_oil_without_its_viscosity_at_100_c_takes_its_grades_at_viscosity_index_100() {
        // ISO 3448 grades of VI 100 at 100 °C, mm²/s
        for (nu40, nu100) in [(22.0, 4.3), (32.0, 5.4), (46.0, 6.8), (68.0, 8.6), (100.0, 11.1)] {
            let got = viscosity_100c_of_grade(nu40);
            assert!((got / nu100 - 1.0).abs() < 0.02, "VG {nu40}: {got}");
        }
        assert_eq!(viscosity_100c_of_grade(46.0), 6.8);
        let vg32 = OilTemperature {
            viscosity_40c_mm2_s: 32.0,
            ..OilTemperature::default()
        };
        assert!((vg32.viscosity_mm2_s(100.0) - viscosity_100c_of_grade(32.0)).abs() < 1e-9);
    }

    #[test]
    fn the_laws_uncertainty_narrows_only_where_the_oil_and_the_null_leakage_are_known() {
        let catalogue = OilTemperature::default();
        assert_eq!(catalogue.law_uncertainty(), CATALOGUE_LAW_UNCERTAINTY);
        // ν at 100 °C given, the commissioning's null leakage not yet known
        let stated = OilTemperature {
            viscosity_100c_mm2_s: Some(6.8),
            ..catalogue
        };
        assert_eq!(stated.law_uncertainty(), CATALOGUE_LAW_UNCERTAINTY);
        // known to 6 %: the law's 0.15 and the null leakage's 0.06
        let known = OilTemperature {
            null_leakage_sigma_share: Some(0.06),
            ..stated
        };
        assert!((known.law_uncertainty() - 0.21).abs() < 1e-12);
        // known to 34 %: wider than the catalogue's
        let poorly = OilTemperature {
            null_leakage_sigma_share: Some(0.34),
            ..stated
        };
        assert!((poorly.law_uncertainty() - 0.49).abs() < 1e-12);
        // a known null leakage without the oil's ν at 100 °C: the catalogue's
        let unstated = OilTemperature {
            null_leakage_sigma_share: Some(0.06),
            ..catalogue
        };
        assert_eq!(unstated.law_uncertainty(), CATALOGUE_LAW_UNCERTAINTY);
        // the default ν at 100 °C is the HLP 46's either way
        assert_eq!(catalogue.viscosity_mm2_s(75.0), stated.viscosity_mm2_s(75.0));
    }

    #[test]
    fn the_factors_are_one_at_the_reference_and_follow_the_laws_away_from_it() {
        let oil = OilTemperature {
            reference_c: 30.0,
            ..OilTemperature::default()
        };
        let f = oil.factors(30.0);
        for v in [
            f.bulk_modulus,
            f.viscosity,
            f.viscous_friction,
            f.laminar_flow,
            f.dry_friction,
        ] {
            assert!((v - 1.0).abs() < 1e-12);
        }
        let f = oil.factors(55.0);
        assert!((f.bulk_modulus - (1.0 - 0.0045 * 25.0)).abs() < 1e-12);
        let ratio = oil.viscosity_mm2_s(55.0) / oil.viscosity_mm2_s(30.0);
        assert!((f.viscosity - ratio).abs() < 1e-12);
        assert!((f.viscous_friction - ratio.sqrt()).abs() < 1e-12);
        assert!((f.laminar_flow * ratio - 1.0).abs() < 1e-12);
        assert!((f.dry_friction - (1.0 - 0.004 * 25.0)).abs() < 1e-12);
        assert_eq!(oil.factors(1000.0).bulk_modulus, MIN_BULK_FACTOR);
        assert_eq!(oil.factors(1000.0).dry_friction, MIN_DRY_FRICTION_FACTOR);
    }
}
