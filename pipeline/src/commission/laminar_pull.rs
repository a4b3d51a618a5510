//! How far the leak filter's oil stiffness θ moves per unit of error in the
//! model's laminar flows (the valve's null leakage, the linear leaks): the
//! recording replayed once more with those flows half again as large
//! ([`PROBE`]). Without `temp_c` the filter reads the oil's temperature from
//! θ with this pull taken out ([`filter::oil`]).

use std::path::Path;

use config::Config;
use model::LeakLaw;

/// The laminar flows' factor of the second pass is 1 + this (1): about
/// what 12 K of warming does to them near 40 °C.
pub const PROBE: f64 = 0.5;

/// θ's mean (1) over the settled estimates of `input` under `cfg` (its
/// model at the reference temperature: nothing read from θ); `None`
/// without a θ state.
fn mean_theta(input: &Path, cfg: &Config) -> Result<Option<f64>, String> {
    let mut at_reference = cfg.clone();
    at_reference.model.oil_temperature.reference_stiffness = None;
    let (mut sum, mut n) = (0.0, 0u64);
    super::replay_estimates(input, &at_reference, cfg.leak_filter.clone(), |e| {
        if e.bulk_scale.is_finite() && e.flags & filter::FLAGS_UNSETTLED == 0 {
            sum += e.bulk_scale;
            n += 1;
        }
    })?;
    Ok((n > 0).then(|| sum / n as f64))
}

/// The pull s on θ per unit of the laminar flows' factor (1), measured on
/// `input` against θ's mean `theta` (1) under `cfg`: (θ̄ with the flows
/// times 1 + [`PROBE`] − `theta`) / [`PROBE`]. `None` where the model has
/// no laminar flow or no θ.
pub fn laminar_pull(input: &Path, cfg: &Config, theta: f64) -> Result<Option<f64>, String> {
    let m = &cfg.model;
    let linear_leaks = m
        .leaks
        .iter()
        .any(|l| l.law == LeakLaw::Linear && l.coefficient > 0.0);
    if !(m.valve_null_leakage_m3_s_pa > 0.0 || linear_leaks) {
        return Ok(None);
    }
    let mut probed = cfg.clone();
    probed.model.valve_null_leakage_m3_s_pa *= 1.0 + PROBE;
    for l in probed.model.leaks.iter_mut().filter(|l| l.law == LeakLaw::Linear) {
        l.coefficient *= 1.0 + PROBE;
    }
    Ok(mean_theta(input, &probed)?.map(|t| (t - theta) / PROBE))
}
