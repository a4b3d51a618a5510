//! The leak filter's oil stiffness θ on the commissioning recording: its
//! mean ([`ThetaMean`]), and how far it moves per unit of error in the
//! model's laminar flows (the valve's null leakage, the linear leaks): the
//! recording replayed once more with those flows half again as large
//! ([`PROBE`]). Without `temp_c` the filter reads the oil's temperature from
//! θ with this pull taken out ([`filter::oil`]); `commission` says whether
//! θ tells the temperature ([`oil_reading_line`]).

use std::path::Path;

use config::Config;
use model::LeakLaw;

/// `cfg` with the model as the recording's oil has it: nothing read from θ
/// (no reference stiffness), so the leak filter's θ is the recording's own.
pub(super) fn nothing_read_from_theta(cfg: &Config) -> Config {
    let mut at_reference = cfg.clone();
    at_reference.model.oil_temperature.reference_stiffness = None;
    at_reference
}

/// The leak filter's mean θ over the settled estimates of a replay (1).
#[derive(Debug, Default)]
pub(super) struct ThetaMean {
    sum: f64,
    n: u64,
}

impl ThetaMean {
    /// Takes θ of estimate `e` where it is finite and the filter settled.
    pub(super) fn push(&mut self, e: &filter::Estimate) {
        if e.bulk_scale.is_finite() && e.flags & filter::FLAGS_UNSETTLED == 0 {
            self.sum += e.bulk_scale;
            self.n += 1;
        }
    }

    /// The mean (1); `None` without a settled θ.
    pub(super) fn mean(&self) -> Option<f64> {
        (self.n > 0).then(|| self.sum / self.n as f64)
    }
}

/// The laminar flows' factor of the second pass is 1 + this (1): about
/// what 12 K of warming does to them near 40 °C.
pub const PROBE: f64 = 0.5;

/// θ's mean (1) over the settled estimates of `input` under `cfg` (its
/// model at the reference temperature: nothing read from θ); `None`
/// without a θ state.
fn mean_theta(input: &Path, cfg: &Config) -> Result<Option<f64>, String> {
    let mut theta = ThetaMean::default();
    super::replay_estimates(
        input,
        &nothing_read_from_theta(cfg),
        cfg.leak_filter.clone(),
        |e| theta.push(e),
    )?;
    Ok(theta.mean())
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
