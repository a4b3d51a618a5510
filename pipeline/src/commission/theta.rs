//! The leak filter's oil stiffness θ on the commissioning recording: its
//! mean ([`ThetaMean`]), and how far it moves per unit of error in the
//! model's laminar flows (the valve's null leakage, the linear leaks): the
//! recording replayed once more with those flows half again as large
//! ([`PROBE`]). Without `temp_c` the filter reads the oil's temperature from
//! θ with this pull taken out ([`filter::oil`]); `commission` says whether
//! θ tells the temperature ([`oil_reading_line`]).

use std::path::Path;

use config::Config;
use filter::oil::OIL_STIFFNESS_TAU_S;
use model::LeakLaw;

/// `cfg` with the model as the recording's oil has it: nothing read from θ
/// (no reference stiffness), so the leak filter's θ is the recording's own.
pub(super) fn nothing_read_from_theta(cfg: &Config) -> Config {
    let mut at_reference = cfg.clone();
    at_reference.model.oil_temperature.reference_stiffness = None;
    at_reference
}

/// The leak filter's mean θ over the settled estimates of a replay (1), and
/// the spread of its means over blocks of [`OIL_STIFFNESS_TAU_S`].
#[derive(Debug, Default)]
pub(super) struct ThetaMean {
    sum: f64,
    n: u64,
    /// The block being summed.
    block: Option<Block>,
    /// The full blocks' means: count, sum, sum of squares.
    blocks: (u64, f64, f64),
}

/// θ summed over one block of [`OIL_STIFFNESS_TAU_S`].
#[derive(Debug, Clone, Copy)]
struct Block {
    /// The block's index: its start over [`OIL_STIFFNESS_TAU_S`].
    index: i64,
    /// θ's sum (1) and the samples summed.
    sum: f64,
    n: u64,
    /// The first and last settled sample's time, s.
    first_s: f64,
    last_s: f64,
}

impl ThetaMean {
    /// Takes θ of estimate `e` where it is finite and the filter settled.
    pub(super) fn push(&mut self, e: &filter::Estimate) {
        if !(e.bulk_scale.is_finite() && e.flags & filter::FLAGS_UNSETTLED == 0) {
            return;
        }
        self.sum += e.bulk_scale;
        self.n += 1;
        let index = (e.t_s / OIL_STIFFNESS_TAU_S).floor() as i64;
        match &mut self.block {
            Some(b) if b.index == index => {
                b.sum += e.bulk_scale;
                b.n += 1;
                b.last_s = e.t_s;
            }
            _ => {
                self.close_block();
                self.block = Some(Block {
                    index,
                    sum: e.bulk_scale,
                    n: 1,
                    first_s: e.t_s,
                    last_s: e.t_s,
                });
            }
        }
    }

    /// Counts the block being summed where it covers half of
    /// [`OIL_STIFFNESS_TAU_S`] or more.
    fn close_block(&mut self) {
        if let Some(b) = self.block.take() {
            if b.last_s - b.first_s >= 0.5 * OIL_STIFFNESS_TAU_S {
                let m = b.sum / b.n as f64;
                self.blocks.0 += 1;
                self.blocks.1 += m;
                self.blocks.2 += m * m;
            }
        }
    }

    /// The mean (1); `None` without a settled θ.
    pub(super) fn mean(&self) -> Option<f64> {
        (self.n > 0).then(|| self.sum / self.n as f64)
    }

    /// The standard deviation of θ's means over blocks of
    /// [`OIL_STIFFNESS_TAU_S`], as a share of its mean (1): what the
    /// temperature read from θ cannot tell from the temperature. `None`
    /// with fewer than [`LEAST_BLOCKS`] blocks.
    pub(super) fn block_spread_share(&self) -> Option<f64> {
        let mut all = ThetaMean {
            block: self.block,
            blocks: self.blocks,
            ..ThetaMean::default()
        };
        all.close_block();
        let (k, sum, sum2) = all.blocks;
        if k < LEAST_BLOCKS {
            return None;
        }
        let mean = sum / k as f64;
        let var = (sum2 - sum * mean) / (k - 1) as f64;
        (mean > 0.0).then(|| var.max(0.0).sqrt() / mean)
    }
}

/// Fewest blocks of [`OIL_STIFFNESS_TAU_S`] θ's spread is read from: a
/// 2-minute commissioning recording gives about 10.
pub const LEAST_BLOCKS: u64 = 4;

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
    let spread = match oil.reference_stiffness_sigma_share {
        Some(share) => format!(
            "; θ's {:.0}-s means spread by {:.2} % on this recording: the temperature read from it is uncertain by {:.1} K (σ)",
            filter::oil::OIL_STIFFNESS_TAU_S,
            100.0 * share,
            o.spread_k()
        ),
        None => String::new(),
    };
    Some(if o.readable() {
        format!("oil temperature without temp_c: read from θ; {pull}, taken out of the reading{spread}")
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
