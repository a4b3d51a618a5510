//! Scores an identification ([`identify::Identification`]) against the true
//! parameters of a rig instance ([`Truth`]), where a data set has them
//! (plant_dev's `truth_rig.json` and `commission_cold.truth.json`, or an
//! in-repo instance's `instance.toml`).
//!
//! The truth is read for scoring only. Its oil laws (bulk modulus and
//! viscosity against temperature) are the data set's own; the flow gain is
//! compared as Cd·w·k_sp/√ρ, so a model with other Cd, k_sp or ρ is scored in
//! its own terms.

use identify::{Found, Identification, Mechanics};
use model::ActuatorParams;
use serde::Serialize;

mod truth;
pub use truth::Truth;

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

/// Scores `id` and `mechanics` (found against the model `model`) with the
/// rig's truth `truth`. `lag_bound_s` is the longest transducer lag the
/// datasheet's response time allows, s (its "datasheet" value).
pub fn score(
    model: &ActuatorParams,
    lag_bound_s: Option<f64>,
    id: &Identification,
    mechanics: Option<&Mechanics>,
    truth: &Truth,
) -> IdentificationScore {
    let (wa, wb) = model.area_gradients_m2_per_m();
    let mut params = vec![row(
        "port A area gradient (mm²/mm, in the model's Cd, k_sp, ρ)",
        1e3,
        wa,
        &id.valve_gain_a.scaled(wa),
        truth.area_gradient_a_m2_per_m,
    )];
    if model.rod_side_area_m2.is_some() || model.area_gradient_b_m2_per_m.is_some() {
        params.push(row(
            "port B area gradient (mm²/mm, in the model's Cd, k_sp, ρ)",
            1e3,
            wb,
            &id.valve_gain_b.scaled(wb),
            truth.area_gradient_b_m2_per_m,
        ));
    }
    params.push(row(
        "effective bulk modulus (MPa, at the recording's temperature)",
        1e-6,
        model.bulk_modulus_pa,
        &id.bulk_modulus_pa,
        truth.bulk_modulus_pa,
    ));
    params.push(row(
        "valve null leakage C_L (1e-13 m³/(s·Pa))",
        1e13,
        model.valve_null_leakage_m3_s_pa,
        &id.null_leakage_m3_s_pa,
        truth.null_leakage_m3_s_pa,
    ));
    params.push(row(
        "supply sag (MPa per m³/s; truth without the line drop)",
        1e-6,
        model.supply_sag_pa_per_m3_s,
        &id.supply_sag_pa_per_m3_s,
        truth.supply_sag_pa_per_m3_s,
    ));
    params.push(row(
        "spool -90° frequency (Hz)",
        1.0 / (2.0 * std::f64::consts::PI),
        model.spool_natural_freq_rad_s,
        &id.spool_natural_freq_rad_s,
        truth.spool_natural_freq_rad_s,
    ));
    for (k, channel) in ["p1", "p2"].into_iter().enumerate() {
        params.push(row(
            &format!("{channel} transducer lag (ms, apparent; datasheet: the most its response time allows)"),
            1e3,
            lag_bound_s.unwrap_or(0.0),
            &id.pressure_lag_s[k],
            truth.pressure_lag_s[k],
        ));
    }
    params.push(row(
        "DAQ sample jitter (µs RMS; the model has none)",
        1e6,
        0.0,
        &id.sample_jitter_s,
        truth.sample_jitter_s,
    ));
    if let Some(m) = mechanics {
        let f = model.friction.extend();
        params.push(row(
            "moving mass (kg)",
            1.0,
            model.mass_kg,
            &m.mass_kg,
            truth.mass_kg,
        ));
        params.push(row(
            "Coulomb friction (N, at the recording's temperature)",
            1.0,
            f.slip_n,
            &m.coulomb_n,
            truth.coulomb_n,
        ));
        params.push(row(
            "static friction (N)",
            1.0,
            f.static_n,
            &m.static_n,
            truth.static_n,
        ));
        params.push(row(
            "Stribeck velocity (mm/s)",
            1e3,
            f.stribeck_velocity_m_s,
            &m.stribeck_velocity_m_s,
            truth.stribeck_velocity_m_s,
        ));
        params.push(row(
            "viscous friction (N·s/m; identified: apparent, with the line drop)",
            1.0,
            f.viscous_n_s_per_m,
            &m.viscous_n_s_per_m,
            truth.viscous_n_s_per_m,
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
