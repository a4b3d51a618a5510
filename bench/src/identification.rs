//! Scores an identification ([`identify::Identification`]) against the true
//! parameters of a rig instance, where a data set has them (plant_dev's
//! `truth_rig.json` and `commission_cold.truth.json`).
//!
//! The truth is read for scoring only. Its oil laws (bulk modulus and
//! viscosity against temperature) are the generator's, written in
//! `truth_rig.json`; the flow gain is compared as Cd·w·k_sp/√ρ, so a model with
//! other Cd, k_sp or ρ is scored in its own terms.

use identify::{Found, Identification, Mechanics};
use model::ActuatorParams;
use serde::Serialize;
use serde_json::Value;

/// One identified parameter against its truth.
#[derive(Debug, Clone, Serialize)]
pub struct ScoredParam {
    /// What it is, with its unit.
    pub name: String,
    /// The model's value before identification, in the unit of `name`.
    pub datasheet: f64,
    /// The identified value and its σ, in the unit of `name` (`None`: not identified).
    pub identified: Option<(f64, f64)>,
    /// Why it was not identified.
    pub why_not: Option<String>,
    /// The true value, in the unit of `name` (`None`: the data set has none).
    pub truth: Option<f64>,
    /// (identified − truth)/truth, %.
    pub error_pct: Option<f64>,
}

/// The identification of one recording, scored.
#[derive(Debug, Clone, Serialize)]
pub struct IdentificationScore {
    /// The parameters.
    pub params: Vec<ScoredParam>,
    /// RMS flow-balance error before and after, and the sensors' floor, L/min.
    pub gap_lpm: [f64; 3],
    /// Windows used, and how many moved.
    pub windows: [usize; 2],
}

/// A number at `path` (keys) in a JSON value.
fn num(v: &Value, path: &[&str]) -> Option<f64> {
    path.iter().try_fold(v, |v, k| v.get(k))?.as_f64()
}

fn row(name: &str, scale: f64, datasheet: f64, found: &Found, truth: Option<f64>) -> ScoredParam {
    let (identified, why_not) = match found {
        Found::Identified(e) => (Some((e.value * scale, e.sigma * scale)), None),
        Found::NotIdentifiable(why) => (None, Some(why.clone())),
    };
    let truth = truth.map(|t| t * scale);
    let error_pct = match (identified, truth) {
        (Some((v, _)), Some(t)) if t != 0.0 => Some(100.0 * (v - t) / t),
        _ => None,
    };
    ScoredParam {
        name: name.to_string(),
        datasheet: datasheet * scale,
        identified,
        why_not,
        truth,
        error_pct,
    }
}

/// Scores `id` and `mechanics` (found against the model `model`) with the truth of the rig
/// instance `rig` (`truth_rig.json`) and of the recording `recording`
/// (`commission_cold.truth.json`), either absent. `lag_bound_s` is the longest
/// transducer lag the datasheet's response time allows, s (its "datasheet" value).
pub fn score(
    model: &ActuatorParams,
    lag_bound_s: Option<f64>,
    id: &Identification,
    mechanics: Option<&Mechanics>,
    rig: Option<&Value>,
    recording: Option<&Value>,
) -> IdentificationScore {
    let p = rig.and_then(|r| r.get("params"));
    let temp_c = recording.and_then(|r| num(r, &["nuisances", "oil_temperature", "T_C"]));
    let t_ref = p.and_then(|p| num(p, &["T_ref"]));
    // Flow gain as Cd·w·k_sp/√ρ, expressed as the model's area gradient.
    let model_gain = model.discharge_coefficient * model.spool_gain_m_per_v / model.oil_density_kg_m3.sqrt();
    let true_gradient = |key: &str| -> Option<f64> {
        let p = p?;
        let w = num(p, &[key]).or_else(|| num(p, &["w"]))?;
        Some(num(p, &["Cd"])? * w * num(p, &["k_sp"])? / num(p, &["rho"])?.sqrt() / model_gain)
    };
    let (wa, wb) = model.area_gradients_m2_per_m();
    let beta_true = (|| {
        let p = p?;
        let dt = temp_c? - t_ref?;
        Some(num(p, &["beta"])? * (1.0 - num(p, &["beta_tc"])? * dt))
    })();
    let cl_true = (|| {
        let c40 = num(recording?, &["nuisances", "null_leakage", "C_L_40C_m3_s_Pa"])?;
        let dt = temp_c? - t_ref?;
        // laminar flow ∝ 1/ν, ν = ν_ref·exp(−nu_tc·(T − T_ref))
        Some(c40 * (num(p?, &["nu_tc"])? * dt).exp())
    })();
    let sag_true = p.and_then(|p| num(p, &["supply_sag"]));
    let mut params = vec![row(
        "port A area gradient (mm²/mm, in the model's Cd, k_sp, ρ)",
        1e3,
        wa,
        &id.valve_gain_a.scaled(wa),
        true_gradient("w"),
    )];
    if model.rod_side_area_m2.is_some() || model.area_gradient_b_m2_per_m.is_some() {
        params.push(row(
            "port B area gradient (mm²/mm, in the model's Cd, k_sp, ρ)",
            1e3,
            wb,
            &id.valve_gain_b.scaled(wb),
            true_gradient("w2"),
        ));
    }
    params.push(row(
        "effective bulk modulus (MPa, at the recording's temperature)",
        1e-6,
        model.bulk_modulus_pa,
        &id.bulk_modulus_pa,
        beta_true,
    ));
    params.push(row(
        "valve null leakage C_L (1e-13 m³/(s·Pa))",
        1e13,
        model.valve_null_leakage_m3_s_pa,
        &id.null_leakage_m3_s_pa,
        cl_true,
    ));
    params.push(row(
        "supply sag (MPa per m³/s; truth without the line drop)",
        1e-6,
        model.supply_sag_pa_per_m3_s,
        &id.supply_sag_pa_per_m3_s,
        sag_true,
    ));
    params.push(row(
        "spool -90° frequency (Hz)",
        1.0 / (2.0 * std::f64::consts::PI),
        model.spool_natural_freq_rad_s,
        &id.spool_natural_freq_rad_s,
        p.and_then(|p| num(p, &["omega_n"])),
    ));
    for (k, channel) in ["p1", "p2"].into_iter().enumerate() {
        let tau = recording.and_then(|r| {
            r.get("nuisances")?
                .get("pressure_sensors")?
                .get("tau_s")?
                .get(k)?
                .as_f64()
        });
        params.push(row(
            &format!("{channel} transducer lag (ms, apparent; datasheet: the most its response time allows)"),
            1e3,
            lag_bound_s.unwrap_or(0.0),
            &id.pressure_lag_s[k],
            tau,
        ));
    }
    params.push(row(
        "DAQ sample jitter (µs RMS; the model has none)",
        1e6,
        0.0,
        &id.sample_jitter_s,
        p.and_then(|p| num(p, &["jitter"])),
    ));
    if let Some(m) = mechanics {
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
        let f = model.friction.extend();
        params.push(row(
            "moving mass (kg)",
            1.0,
            model.mass_kg,
            &m.mass_kg,
            p.and_then(|p| num(p, &["m"])),
        ));
        params.push(row(
            "Coulomb friction (N, at the recording's temperature)",
            1.0,
            f.slip_n,
            &m.coulomb_n,
            p.and_then(|p| Some(num(p, &["f_sl"])? * factor("coulomb_factor")?)),
        ));
        params.push(row(
            "static friction (N)",
            1.0,
            f.static_n,
            &m.static_n,
            p.and_then(|p| num(p, &["f_st"])),
        ));
        params.push(row(
            "Stribeck velocity (mm/s)",
            1e3,
            f.stribeck_velocity_m_s,
            &m.stribeck_velocity_m_s,
            p.and_then(|p| num(p, &["alpha"])),
        ));
        params.push(row(
            "viscous friction (N·s/m; identified: apparent, with the line drop)",
            1.0,
            f.viscous_n_s_per_m,
            &m.viscous_n_s_per_m,
            p.and_then(|p| Some(num(p, &["d"])? * factor("viscous_factor")?)),
        ));
    }
    IdentificationScore {
        params,
        gap_lpm: [id.gap_before_lpm, id.gap_after_lpm, id.sensor_floor_lpm],
        windows: [id.windows, id.moving_windows],
    }
}

impl IdentificationScore {
    /// The score as a Markdown table and a line on the gap.
    pub fn markdown(&self) -> String {
        let f = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.4}"));
        let mut s = String::from(
            "| parameter | datasheet | identified ± σ | truth | error |\n|---|---|---|---|---|\n",
        );
        for p in &self.params {
            let id = match (&p.identified, &p.why_not) {
                (Some((v, sd)), _) => format!("{v:.4} ± {sd:.4}"),
                (None, Some(why)) => format!("not identified: {why}"),
                (None, None) => "–".to_string(),
            };
            let err = p.error_pct.map_or("–".to_string(), |e| format!("{e:+.1} %"));
            s.push_str(&format!(
                "| {} | {:.4} | {id} | {} | {err} |\n",
                p.name,
                p.datasheet,
                f(p.truth)
            ));
        }
        s.push_str(&format!(
            "\nFlow-balance gap {:.3} → {:.3} L/min RMS (sensor floor {:.3} L/min; {:.1}× the floor), over {} windows of 20 samples ({} moving). Not identified: the load beyond a constant, transducer offsets (at rest an offset difference is a load; a common offset is a supply error) and the line drop (it is in the apparent viscous friction).\n",
            self.gap_lpm[0],
            self.gap_lpm[1],
            self.gap_lpm[2],
            self.gap_lpm[1] / self.gap_lpm[2],
            self.windows[0],
            self.windows[1]
        ));
        s
    }
}
