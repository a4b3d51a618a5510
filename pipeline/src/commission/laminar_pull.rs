//! How far the leak filter's oil stiffness θ moves per unit of error in the
//! model's laminar flows (the valve's null leakage, the linear leaks): the
//! recording replayed once more with those flows half again as large
//! ([`PROBE`]). Without `temp_c` the filter reads the oil's temperature from
//! θ with this pull taken out ([`filter::oil`]); `commission` says whether
//! θ tells the temperature ([`oil_reading_line`]).

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

/// What commissioning says of reading the oil's temperature from θ under the
/// oil law `oil` (its reference stiffness and the laminar flows' pull on
/// θ set); `None` where θ is not read.
pub(super) fn oil_reading_line(oil: &model::params::OilTemperature) -> Option<String> {
    let o = filter::oil::OilFromStiffness::new(oil, oil.reference_stiffness?)?;
    let pull = format!(
        "the leak filter's θ moves {:+.4} per unit of the laminar flows' factor (the valve's null leakage)",
        o.pull()
    );
    Some(if o.readable() {
        format!("oil temperature without temp_c: read from θ; {pull}, taken out of the reading")
    } else {
        format!(
            "oil temperature without temp_c: not readable from θ on this rig: {pull}, which cancels more than {:.0} % of the stiffness' own change with temperature; the model stays at {:.1} °C and the thresholds widen for the whole operating range ({:.0}-{:.0} °C); a thermometer's temp_c lets it watch closer",
            100.0 * (1.0 - filter::oil::READABLE_SHARE),
            oil.reference_c,
            oil.operating_min_c,
            oil.operating_max_c
        )
    })
}
