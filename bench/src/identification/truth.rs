//! A rig instance's true parameters at its commissioning recording's oil
//! temperature, from either kind of data set: plant_dev's (`truth_rig.json`
//! and `commission_cold.truth.json`, in the independent generator's terms and
//! oil laws) or the in-repo simulator's (`bench instances`: `instance.toml`,
//! the drawn rig at its oil law's reference temperature, and
//! `commission_cold.truth.json`, the recording's oil).

use model::ActuatorParams;
use serde_json::Value;

/// The true parameters of a rig at its commissioning recording's oil
/// temperature, SI; `None` where the data set does not give one.
/// The flow gains are area gradients in the scored model's Cd, spool gain
/// and density (compared as Cd·w·k_sp/√ρ).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Truth {
    /// Port A's area gradient, m²/m (in the scored model's terms).
    pub area_gradient_a_m2_per_m: Option<f64>,
    /// Port B's area gradient, m²/m (in the scored model's terms).
    pub area_gradient_b_m2_per_m: Option<f64>,
    /// The oil's bulk modulus at the recording's temperature, Pa.
    pub bulk_modulus_pa: Option<f64>,
    /// The valve's null leakage at the recording's temperature, m³/(s·Pa).
    pub null_leakage_m3_s_pa: Option<f64>,
    /// The supply's sag with the flow (without a line drop), Pa/(m³/s).
    pub supply_sag_pa_per_m3_s: Option<f64>,
    /// The spool's natural frequency, rad/s.
    pub spool_natural_freq_rad_s: Option<f64>,
    /// Each pressure transducer's lag (its time constant), s.
    pub pressure_lag_s: [Option<f64>; 2],
    /// The DAQ's sample-time jitter (RMS), s.
    pub sample_jitter_s: Option<f64>,
    /// The moving mass, kg.
    pub mass_kg: Option<f64>,
    /// The Coulomb friction at the recording's temperature, N.
    pub coulomb_n: Option<f64>,
    /// The static friction (at the recording's temperature where the data set's law moves it), N.
    pub static_n: Option<f64>,
    /// The Stribeck velocity, m/s.
    pub stribeck_velocity_m_s: Option<f64>,
    /// The viscous friction at the recording's temperature (without a line drop), N·s/m.
    pub viscous_n_s_per_m: Option<f64>,
}

/// A number at `path` (keys) in a JSON value.
fn num(v: &Value, path: &[&str]) -> Option<f64> {
    path.iter().try_fold(v, |v, k| v.get(k))?.as_f64()
}

/// Cd·k_sp/√ρ from a discharge coefficient `cd` (1), a spool gain
/// `spool_gain_m_per_v` (m/V) and an oil density `density_kg_m3` (kg/m³): the
/// factor (SI) that turns a port's area gradient into its flow gain.
fn gain_factor(cd: f64, spool_gain_m_per_v: f64, density_kg_m3: f64) -> f64 {
    cd * spool_gain_m_per_v / density_kg_m3.sqrt()
}

impl Truth {
    /// The truth plant_dev gives: the instance `rig` (`truth_rig.json`) and
    /// the recording `recording` (`commission_cold.truth.json`), either
    /// absent, scored against `model`'s Cd, spool gain and density.
    pub fn from_plant(model: &ActuatorParams, rig: Option<&Value>, recording: Option<&Value>) -> Truth {
        let p = rig.and_then(|r| r.get("params"));
        let temp_c = recording.and_then(|r| num(r, &["nuisances", "oil_temperature", "T_C"]));
        let t_ref = p.and_then(|p| num(p, &["T_ref"]));
        let model_gain = gain_factor(
            model.discharge_coefficient,
            model.spool_gain_m_per_v,
            model.oil_density_kg_m3,
        );
        let gradient = |key: &str| -> Option<f64> {
            let p = p?;
            let w = num(p, &[key]).or_else(|| num(p, &["w"]))?;
            Some(gain_factor(num(p, &["Cd"])?, num(p, &["k_sp"])?, num(p, &["rho"])?) * w / model_gain)
        };
        let beta = (|| {
            let p = p?;
            let dt = temp_c? - t_ref?;
            Some(num(p, &["beta"])? * (1.0 - num(p, &["beta_tc"])? * dt))
        })();
        let null_leakage = (|| {
            let c40 = num(recording?, &["nuisances", "null_leakage", "C_L_40C_m3_s_Pa"])?;
            let dt = temp_c? - t_ref?;
            // laminar flow ∝ 1/ν, ν = ν_ref·exp(−nu_tc·(T − T_ref))
            Some(c40 * (num(p?, &["nu_tc"])? * dt).exp())
        })();
        // The generator's factors at the recording's temperature, where it wrote them.
        let factor = |key: &str| {
            let t = temp_c?;
            let derived = rig?.get("derived")?;
            ["oil_at_30C", "oil_at_55C"]
                .iter()
                .filter_map(|k| derived.get(*k))
                .find(|o| num(o, &["T_C"]) == Some(t))
                .and_then(|o| num(o, &[key]))
        };
        let lag = |k: usize| {
            recording?
                .get("nuisances")?
                .get("pressure_sensors")?
                .get("tau_s")?
                .get(k)?
                .as_f64()
        };
        let param = |key: &str| p.and_then(|p| num(p, &[key]));
        Truth {
            area_gradient_a_m2_per_m: gradient("w"),
            area_gradient_b_m2_per_m: gradient("w2"),
            bulk_modulus_pa: beta,
            null_leakage_m3_s_pa: null_leakage,
            supply_sag_pa_per_m3_s: param("supply_sag"),
            spool_natural_freq_rad_s: param("omega_n"),
            pressure_lag_s: [lag(0), lag(1)],
            sample_jitter_s: param("jitter"),
            mass_kg: param("m"),
            coulomb_n: param("f_sl").and_then(|f| Some(f * factor("coulomb_factor")?)),
            static_n: param("f_st"),
            stribeck_velocity_m_s: param("alpha"),
            viscous_n_s_per_m: param("d").and_then(|d| Some(d * factor("viscous_factor")?)),
        }
    }

    /// The truth of an in-repo instance: the drawn rig `rig` and its
    /// sensors `sensors` (its `instance.toml`, at the oil law's reference
    /// temperature), at the recording's
    /// oil temperature `temp_c` (°C; NaN: not constant, the
    /// temperature-dependent values absent), scored against `model`'s Cd,
    /// spool gain and density.
    pub fn from_instance(
        model: &ActuatorParams,
        rig: &ActuatorParams,
        sensors: &model::SensorParams,
        temp_c: f64,
    ) -> Truth {
        let known = temp_c.is_finite();
        let mut at = rig.clone();
        at.set_oil_temperature(
            rig,
            if known {
                temp_c
            } else {
                rig.oil_temperature.reference_c
            },
        );
        let at_temp = |v: f64| known.then_some(v);
        let scale = gain_factor(
            rig.discharge_coefficient,
            rig.spool_gain_m_per_v,
            rig.oil_density_kg_m3,
        ) / gain_factor(
            model.discharge_coefficient,
            model.spool_gain_m_per_v,
            model.oil_density_kg_m3,
        );
        let (wa, wb) = rig.area_gradients_m2_per_m();
        let friction = at.friction.extend();
        Truth {
            area_gradient_a_m2_per_m: Some(wa * scale),
            area_gradient_b_m2_per_m: Some(wb * scale),
            bulk_modulus_pa: at_temp(at.bulk_modulus_pa),
            null_leakage_m3_s_pa: at_temp(at.valve_null_leakage_m3_s_pa),
            supply_sag_pa_per_m3_s: Some(rig.supply_sag_pa_per_m3_s),
            spool_natural_freq_rad_s: Some(rig.spool_natural_freq_rad_s),
            pressure_lag_s: [Some(sensors.pressure_lag_s); 2],
            sample_jitter_s: Some(sensors.sample_jitter_s),
            mass_kg: Some(rig.mass_kg),
            coulomb_n: at_temp(friction.slip_n),
            static_n: at_temp(friction.static_n),
            stribeck_velocity_m_s: Some(friction.stribeck_velocity_m_s),
            viscous_n_s_per_m: at_temp(friction.viscous_n_s_per_m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rig whose oil law moves the bulk modulus, the friction and the null leakage.
    fn drawn_rig() -> ActuatorParams {
        let mut rig = ActuatorParams {
            valve_null_leakage_m3_s_pa: 2e-13,
            ..ActuatorParams::default()
        };
        rig.oil_temperature.bulk_modulus_per_k = -0.0045;
        rig.oil_temperature.dry_friction_per_k = -0.004;
        rig.oil_temperature.viscosity_100c_mm2_s = Some(6.8);
        rig
    }

    #[test]
    fn an_instance_at_its_laws_reference_temperature_is_its_drawn_rig() {
        let rig = drawn_rig();
        let sensors = model::SensorParams {
            pressure_lag_s: 4e-4,
            ..model::SensorParams::default()
        };
        let t = Truth::from_instance(&rig, &rig, &sensors, rig.oil_temperature.reference_c);
        let f = rig.friction.extend();
        assert_eq!(t.area_gradient_a_m2_per_m, Some(rig.area_gradient_m2_per_m));
        assert_eq!(t.bulk_modulus_pa, Some(rig.bulk_modulus_pa));
        assert_eq!(t.null_leakage_m3_s_pa, Some(rig.valve_null_leakage_m3_s_pa));
        assert_eq!(t.coulomb_n, Some(f.slip_n));
        assert_eq!(t.viscous_n_s_per_m, Some(f.viscous_n_s_per_m));
        assert_eq!(t.mass_kg, Some(rig.mass_kg));
        assert_eq!(t.pressure_lag_s, [Some(4e-4); 2]);
    }

    #[test]
    fn a_warmer_recording_reads_softer_oil_less_friction_and_more_null_leakage() {
        let rig = drawn_rig();
        let sensors = model::SensorParams::default();
        let warm = rig.oil_temperature.reference_c + 10.0;
        let t = Truth::from_instance(&rig, &rig, &sensors, warm);
        let f = rig.oil_temperature.factors(warm);
        let bulk = t.bulk_modulus_pa.unwrap_or(f64::NAN);
        assert!(
            (bulk / (rig.bulk_modulus_pa * 0.955) - 1.0).abs() < 1e-12,
            "{bulk}"
        );
        let coulomb = t.coulomb_n.unwrap_or(f64::NAN);
        assert!(
            (coulomb / (rig.friction.extend().slip_n * 0.96) - 1.0).abs() < 1e-12,
            "{coulomb}"
        );
        let null = t.null_leakage_m3_s_pa.unwrap_or(f64::NAN);
        assert!(
            f.laminar_flow > 1.0 && (null / (2e-13 * f.laminar_flow) - 1.0).abs() < 1e-12,
            "{null}"
        );
        // an oil that moved during the recording: no temperature's truth
        let moving = Truth::from_instance(&rig, &rig, &sensors, f64::NAN);
        assert_eq!(moving.bulk_modulus_pa, None);
        assert_eq!(moving.coulomb_n, None);
        assert_eq!(moving.mass_kg, Some(rig.mass_kg));
    }

    #[test]
    fn a_flow_gain_is_scored_in_the_models_own_cd() {
        let rig = drawn_rig();
        let mut model = rig.clone();
        model.discharge_coefficient = 0.8 * rig.discharge_coefficient;
        let t = Truth::from_instance(&model, &rig, &model::SensorParams::default(), f64::NAN);
        // the same flow through a valve of the model's Cd needs a wider port
        let w = t.area_gradient_a_m2_per_m.unwrap_or(f64::NAN);
        assert!(
            (w / (rig.area_gradient_m2_per_m / 0.8) - 1.0).abs() < 1e-12,
            "{w}"
        );
    }
}
