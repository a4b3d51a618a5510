//! The oil's temperature inferred from its stiffness, for a rig without a
//! thermometer (docs/plant.md, "Oil temperature").
//!
//! The 12-state filter's θ is the oil's stiffness as a multiple of the model's
//! bulk modulus. Commissioning saw θ_ref at the oil law's reference
//! temperature, so θ/θ_ref = 1 + k_β·(T − T_ref) tells the temperature.
//! The terms that follow the viscosity (the valve's null leakage, the linear
//! leaks, the seals' viscous friction) are then set from that temperature.
//! θ itself keeps carrying the bulk modulus.
//!
//! θ also answers an error in the model's laminar flows: a null leakage set
//! too large for the oil pulls θ down as a warmer oil does (commissioning
//! measures that pull, s per unit of the laminar factor L). With the model
//! at temperature T_a, θ ≈ θ_ref·(1 + k_β·(T − T_ref)) + s·(L(T_a) − L(T)).
//! The temperature is read from that relation, not from the stiffness term
//! alone: read from the stiffness alone, a model set warmer leaks more, θ
//! falls further and the reading runs to the range's end (a press whose
//! valve leaks at the catalogue's maximum did, from the filter's start-up).
//! Where the pull cancels most of the stiffness' own change with
//! temperature ([`READABLE_SHARE`]), θ does not tell the temperature: the
//! model stays at the reference and the temperature is as uncertain as the
//! operating range.

use model::params::OilTemperature;
use model::ActuatorParams;

use crate::{Estimate, Estimator, FLAGS_UNSETTLED, FLAG_CONVERGING, FLAG_OIL_PAST_RANGE, OIL_TEMP_STEP_K};

/// Time constant of the low-pass on θ that the temperature is read from, s:
/// the oil warms over minutes, θ jitters over a duty cycle's strokes.
pub const OIL_STIFFNESS_TAU_S: f64 = 10.0;

/// The inferred temperature moves the model in steps of this much, K: the
/// viscosity changes 2-4 % over it.
pub const OIL_ESTIMATE_STEP_K: f64 = 0.5;

/// Farthest the inferred temperature may lie from the reference, K: beyond
/// it θ says more than the oil's temperature (air, a softened hose).
pub const OIL_ESTIMATE_SPAN_K: f64 = 40.0;

/// The temperature read from θ stays within the operating range
/// (`operating_min_c`..`operating_max_c` of the oil law) widened by this much,
/// K: the oil does not leave its operating range, so a θ that says it did says
/// something else (a pressure transducer reading off, air). Beyond it, the
/// model's viscous terms are held at the range's edge, and the temperature's σ
/// grows by how far past it θ reads ([`OilFromStiffness::past_range_k`]).
pub const OIL_RANGE_MARGIN_K: f64 = 5.0;

/// Relative uncertainty of the bulk modulus' temperature slope k_β (1): the
/// temperature read from θ is uncertain by this share of its distance from
/// the reference.
pub const BULK_SLOPE_UNCERTAINTY: f64 = 0.2;

/// The laminar flows' factor at oil temperature `temp_c` (°C) against the
/// reference of `oil`, and its standard deviation (1, 1): the law's
/// uncertainty ([`OilTemperature::law_uncertainty`] of the change) and the
/// temperature's (`sigma_t_k`, K, through the law's slope).
pub fn laminar_factor_with_sigma(oil: &OilTemperature, temp_c: f64, sigma_t_k: f64) -> (f64, f64) {
    let f = oil.factors(temp_c).laminar_flow;
    let slope_per_k = 0.5 * (oil.factors(temp_c + 1.0).laminar_flow - oil.factors(temp_c - 1.0).laminar_flow);
    let sigma = oil.law_uncertainty() * (f - 1.0).abs() + slope_per_k.abs() * sigma_t_k.max(0.0);
    (f, sigma)
}

/// The laminar factor's σ at oil temperature `temp_c` (°C) known to
/// `sigma_t_k` (K) for the model `params` at its reference temperature (1),
/// and that σ times its null leakage a path at p_s/2, L/min.
pub fn null_leakage_band(params: &ActuatorParams, temp_c: f64, sigma_t_k: f64) -> (f64, f64) {
    let (_, sigma) = laminar_factor_with_sigma(&params.oil_temperature, temp_c, sigma_t_k);
    let q_null_m3_s =
        params.valve_null_leakage_m3_s_pa * 0.5 * (params.supply_pressure_pa - params.return_pressure_pa);
    (sigma, model::units::m3_s_to_lpm(sigma * q_null_m3_s))
}

/// The temperature's σ once θ has settled, K, at `temp_c` (°C) for the oil
/// law `oil`: k_β's share of the distance from the reference and θ's spread
/// at one temperature ([`stiffness_spread_k`]; θ's own σ is small beside them).
pub fn settled_sigma_k(oil: &OilTemperature, temp_c: f64) -> f64 {
    (BULK_SLOPE_UNCERTAINTY * (temp_c - oil.reference_c).abs()).hypot(stiffness_spread_k(oil))
}

/// The temperature's σ from θ's spread at one temperature, K:
/// `reference_stiffness_sigma_share` over |k_β| (0 where not stated, or
/// where the bulk modulus does not follow the temperature).
pub fn stiffness_spread_k(oil: &OilTemperature) -> f64 {
    let share = oil
        .reference_stiffness_sigma_share
        .filter(|s| s.is_finite())
        .unwrap_or(0.0);
    if oil.bulk_modulus_per_k.abs() < MIN_BULK_PER_K {
        return 0.0;
    }
    share / oil.bulk_modulus_per_k.abs()
}

/// The smallest |k_β| a temperature is inferred with, 1/K (below it θ says
/// nothing about the temperature).
const MIN_BULK_PER_K: f64 = 1e-4;

/// The share of the stiffness' own change with temperature (θ_ref·k_β per
/// K) that must remain, from the reference to where the reading stops, once
/// the laminar flows' pull on θ is taken out, for θ to tell the temperature (1): at half,
/// an error of θ reads as at most twice the temperature error it would on
/// a rig without null leakage.
pub const READABLE_SHARE: f64 = 0.5;

/// Points of the table θ is read against over the range ([`OilFromStiffness`]).
const TABLE_POINTS: usize = 257;

/// The temperature read from θ, and when it last moved the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OilFromStiffness {
    /// θ low-passed over [`OIL_STIFFNESS_TAU_S`] (1).
    theta_mean: f64,
    /// θ at the reference temperature (1).
    theta_ref: f64,
    /// The temperature the model was last set to, °C.
    applied_c: f64,
    /// Time θ has been observed, s (the low-pass is a running mean until
    /// [`OIL_STIFFNESS_TAU_S`] has passed, so a run that starts warm is read
    /// as warm within seconds).
    observed_s: f64,
    reference_c: f64,
    bulk_per_k: f64,
    /// The coldest and warmest temperature θ is read as, °C: the operating
    /// range widened by [`OIL_RANGE_MARGIN_K`], and the reference within it.
    lowest_c: f64,
    highest_c: f64,
    /// The pull s on θ per unit of the laminar factor's error (1; 0: none).
    pull: f64,
    /// Whether θ tells the temperature at the reference ([`READABLE_SHARE`]).
    readable: bool,
    /// The table's points (first, last) between which θ tells the
    /// temperature, the reference among them: the reading stays within.
    readable_points: (usize, usize),
    /// With a pull: θ_ref·(1 + k_β·(T − T_ref)) − s·L(T) at [`TABLE_POINTS`]
    /// temperatures evenly from `lowest_c` to `highest_c` (1).
    stiffness_less_pull: [f64; TABLE_POINTS],
    /// The oil law L(T) is taken from.
    oil: OilTemperature,
    /// L at the temperature the model is at (1).
    laminar_applied: f64,
    /// How far past `lowest_c`..`highest_c` θ read the oil when the model
    /// last moved, K ([`Self::past_range_k`]).
    past_applied_k: f64,
}

impl OilFromStiffness {
    /// An inference for the oil law `oil` from a θ of `theta_ref` (1) at its
    /// reference temperature, or `None` when its bulk modulus does not follow
    /// the temperature or `theta_ref` is not a stiffness.
    pub fn new(oil: &OilTemperature, theta_ref: f64) -> Option<Self> {
        if oil.bulk_modulus_per_k.abs() < MIN_BULK_PER_K || !(theta_ref.is_finite() && theta_ref > 0.0) {
            return None;
        }
        let pull = oil
            .stiffness_per_laminar_factor
            .filter(|s| s.is_finite())
            .unwrap_or(0.0);
        let mut o = OilFromStiffness {
            theta_mean: theta_ref,
            theta_ref,
            applied_c: oil.reference_c,
            observed_s: 0.0,
            reference_c: oil.reference_c,
            bulk_per_k: oil.bulk_modulus_per_k,
            lowest_c: (oil.operating_min_c - OIL_RANGE_MARGIN_K).min(oil.reference_c),
            highest_c: (oil.operating_max_c + OIL_RANGE_MARGIN_K).max(oil.reference_c),
            pull,
            readable: true,
            readable_points: (0, TABLE_POINTS - 1),
            stiffness_less_pull: [0.0; TABLE_POINTS],
            oil: *oil,
            laminar_applied: 1.0,
            past_applied_k: 0.0,
        };
        if pull != 0.0 {
            o.tabulate();
        }
        Some(o)
    }

    /// The temperature of table point `i`, °C.
    fn table_c(&self, i: usize) -> f64 {
        self.lowest_c + (self.highest_c - self.lowest_c) * i as f64 / (TABLE_POINTS - 1) as f64
    }

    /// Fills the table θ is read against under a pull and finds where θ
    /// tells the temperature: θ_ref·(1 + k_β·(T − T_ref)) − s·L(T) must
    /// change with T in the stiffness' own direction, by at least
    /// [`READABLE_SHARE`] of θ_ref·k_β a kelvin, between every two points
    /// from the reference's out (the warm end goes first: L steepens there).
    fn tabulate(&mut self) {
        let own = self.theta_ref * self.bulk_per_k;
        for i in 0..TABLE_POINTS {
            let t = self.table_c(i);
            self.stiffness_less_pull[i] = self.theta_ref * (1.0 + self.bulk_per_k * (t - self.reference_c))
                - self.pull * self.oil.factors(t).laminar_flow;
        }
        let step_k = (self.highest_c - self.lowest_c) / (TABLE_POINTS - 1) as f64;
        let h = &self.stiffness_less_pull;
        let tells = |i: usize| step_k > 0.0 && (h[i + 1] - h[i]) / step_k / own >= READABLE_SHARE;
        // the segment the reference lies in
        let at = (((self.reference_c - self.lowest_c) / step_k.max(f64::MIN_POSITIVE)).floor() as usize)
            .min(TABLE_POINTS - 2);
        self.readable = tells(at);
        let (mut first, mut last) = (at, at + 1);
        while first > 0 && tells(first - 1) {
            first -= 1;
        }
        while last < TABLE_POINTS - 1 && tells(last) {
            last += 1;
        }
        self.readable_points = (first, last);
        self.laminar_applied = self.oil.factors(self.applied_c).laminar_flow;
    }

    /// The oil temperatures between which θ tells the temperature, °C (the
    /// range θ is read in where there is no pull; equal ends where it tells none).
    pub fn readable_range_c(&self) -> (f64, f64) {
        if !self.readable {
            return (self.reference_c, self.reference_c);
        }
        (
            self.table_c(self.readable_points.0),
            self.table_c(self.readable_points.1),
        )
    }

    /// Whether θ tells the oil's temperature at the reference on this rig ([`READABLE_SHARE`]).
    pub fn readable(&self) -> bool {
        self.readable
    }

    /// The pull s on θ per unit of the laminar factor's error it was built with (1).
    pub fn pull(&self) -> f64 {
        self.pull
    }

    /// The temperature θ's low-pass says now, °C (within
    /// [`OIL_ESTIMATE_SPAN_K`] of the reference and [`OIL_RANGE_MARGIN_K`] of
    /// the operating range).
    pub fn temperature_c(&self) -> f64 {
        if !self.readable {
            return self.reference_c;
        }
        let t = if self.pull == 0.0 {
            let dt = ((self.theta_mean / self.theta_ref - 1.0) / self.bulk_per_k)
                .clamp(-OIL_ESTIMATE_SPAN_K, OIL_ESTIMATE_SPAN_K);
            self.reference_c + dt
        } else {
            self.read_against_table().clamp(
                self.reference_c - OIL_ESTIMATE_SPAN_K,
                self.reference_c + OIL_ESTIMATE_SPAN_K,
            )
        };
        t.clamp(self.lowest_c, self.highest_c)
    }

    /// The temperature (°C) where θ_ref·(1 + k_β·ΔT) − s·L(T) meets
    /// θ̄ − s·L(T_a) in the table (monotone where readable: the table's ends
    /// beyond it), linearly between its points.
    fn read_against_table(&self) -> f64 {
        let target = self.theta_mean - self.pull * self.laminar_applied;
        let (first, last) = self.readable_points;
        let h = &self.stiffness_less_pull[first..=last];
        // (monotone there: h falls with T where k_β < 0, rises where k_β > 0)
        let falling = self.bulk_per_k < 0.0;
        let below = |v: f64| if falling { v > target } else { v < target };
        // the first point past the target
        let i = h.partition_point(|&v| below(v));
        if i == 0 {
            return self.table_c(first);
        }
        if i >= h.len() {
            return self.table_c(last);
        }
        let (a, b) = (h[i - 1], h[i]);
        let w = if b != a { (target - a) / (b - a) } else { 0.0 };
        self.table_c(first + i - 1) + w * (self.table_c(first + i) - self.table_c(first + i - 1))
    }

    /// How far past the range it is read in (`lowest_c`..`highest_c`) θ's
    /// low-pass says the oil is, K: θ read at the stiffness' own slope, without
    /// the laminar flows' pull (a few % of the stiffness' change there). The
    /// model is held at the range's edge, so its null leakage is uncertain by
    /// that much more ([`Self::sigma_k`]). 0 inside the range, or where θ
    /// does not tell the temperature.
    pub fn past_range_k(&self) -> f64 {
        if !self.readable {
            return 0.0;
        }
        let t = self.reference_c + (self.theta_mean / self.theta_ref - 1.0) / self.bulk_per_k;
        (t - self.highest_c).max(self.lowest_c - t).max(0.0)
    }

    /// How far past the range θ read the oil when the model last moved, K:
    /// what [`Self::sigma_k`] adds to θ's part (0 inside the range).
    pub fn past_applied_k(&self) -> f64 {
        self.past_applied_k
    }

    /// The temperature the model is at, °C.
    pub fn applied_c(&self) -> f64 {
        self.applied_c
    }

    /// Whether θ has been observed for [`OIL_STIFFNESS_TAU_S`].
    pub fn settled(&self) -> bool {
        self.observed_s >= OIL_STIFFNESS_TAU_S
    }

    /// One standard deviation of the temperature for θ's `theta_sigma` (1), K:
    /// θ's own, k_β's ([`BULK_SLOPE_UNCERTAINTY`] of the distance from the
    /// reference) and θ's spread at one temperature ([`stiffness_spread_k`]),
    /// in quadrature; half of [`OIL_ESTIMATE_SPAN_K`] more until
    /// [`Self::settled`].
    pub fn sigma_k(&self, theta_sigma: f64) -> f64 {
        if !self.readable {
            // the temperature may be anywhere in the range θ is read in
            return (self.reference_c - self.lowest_c).max(self.highest_c - self.reference_c);
        }
        // read at an end of the range θ tells it in (short of the range's
        // end): the oil may lie anywhere beyond it
        let (lo, hi) = self.readable_range_c();
        let beyond = if self.pull == 0.0 {
            0.0
        } else if self.applied_c <= lo + OIL_ESTIMATE_STEP_K {
            lo - self.lowest_c
        } else if self.applied_c >= hi - OIL_ESTIMATE_STEP_K {
            self.highest_c - hi
        } else {
            0.0
        };
        let from_theta =
            theta_sigma / (self.theta_ref * self.bulk_per_k.abs()) + beyond + self.past_applied_k;
        let from_slope = BULK_SLOPE_UNCERTAINTY * (self.applied_c - self.reference_c);
        let from_spread = self.spread_k();
        let unsettled = if self.settled() {
            0.0
        } else {
            0.5 * OIL_ESTIMATE_SPAN_K
        };
        from_theta.hypot(from_slope).hypot(from_spread) + unsettled
    }

    /// The temperature's σ from θ's spread at one temperature, K ([`stiffness_spread_k`]).
    pub fn spread_k(&self) -> f64 {
        stiffness_spread_k(&self.oil)
    }

    /// Takes θ (1) after a sample period `dt_s` (s); returns the temperature
    /// to set the model to (°C) when it moved by [`OIL_ESTIMATE_STEP_K`], when
    /// the reading past the range ([`Self::past_range_k`]) moved by as much,
    /// or when the estimate has just [`Self::settled`].
    pub fn observe(&mut self, theta: f64, dt_s: f64) -> Option<f64> {
        if !theta.is_finite() {
            return None;
        }
        let was_settled = self.settled();
        self.observed_s += dt_s;
        let weight = (dt_s / OIL_STIFFNESS_TAU_S.min(self.observed_s)).min(1.0);
        self.theta_mean += weight * (theta - self.theta_mean);
        let t = self.temperature_c();
        let past_k = self.past_range_k();
        if (t - self.applied_c).abs() < OIL_ESTIMATE_STEP_K
            && (past_k - self.past_applied_k).abs() < OIL_ESTIMATE_STEP_K
            && was_settled == self.settled()
        {
            return None;
        }
        self.applied_c = t;
        self.past_applied_k = past_k;
        if self.pull != 0.0 {
            // (once a move of the model, not a sample)
            self.laminar_applied = self.oil.factors(t).laminar_flow;
        }
        Some(t)
    }
}

/// How the stage's model follows the oil: a thermometer's `temp_c`, or the
/// temperature read from θ.
impl Estimator {
    /// Sets the model to oil temperature `temp_c` (°C) when it moved by
    /// [`OIL_TEMP_STEP_K`] or more ([`ActuatorParams::set_oil_temperature`]:
    /// bulk modulus, viscous friction, laminar flows). Allocates nothing.
    pub(crate) fn follow_oil_temperature(&mut self, temp_c: f64) {
        if (temp_c - self.oil_temp_c).abs() < OIL_TEMP_STEP_K {
            return;
        }
        self.model
            .params
            .set_oil_temperature(&self.params_at_reference, temp_c);
        self.model.params_changed();
        self.oil_temp_c = temp_c;
        self.set_laminar_sigma(temp_c, 0.0);
    }

    /// The stage as it starts: a temperature still to be read from θ is as
    /// uncertain as [`OilFromStiffness::sigma_k`] says before it settled.
    pub(crate) fn with_laminar_sigma_at_start(mut self) -> Self {
        if let Some(oil) = self.oil_from_stiffness {
            self.set_laminar_sigma(oil.applied_c(), oil.sigma_k(0.0));
        }
        self
    }

    /// The laminar flows' uncertainty at oil temperature `temp_c` (°C) known to
    /// `sigma_t_k` (K). Allocates nothing.
    pub(crate) fn set_laminar_sigma(&mut self, temp_c: f64, sigma_t_k: f64) {
        self.laminar_sigma = null_leakage_band(&self.params_at_reference, temp_c, sigma_t_k);
    }

    /// Reads the oil's temperature from θ of estimate `e` (once the filter has
    /// converged) and, when it moved by [`OIL_ESTIMATE_STEP_K`], sets every
    /// term of the model that follows it but the bulk modulus
    /// ([`ActuatorParams::set_oil_temperature_keeping_bulk_modulus`]).
    /// Allocates nothing.
    pub(crate) fn follow_oil_stiffness(&mut self, e: &mut Estimate) {
        let usable = self.started && e.flags & FLAGS_UNSETTLED == 0;
        let Some(oil) = self.oil_from_stiffness.as_mut() else {
            return;
        };
        let moved = if usable {
            oil.observe(e.bulk_scale, self.tuning.sample_period_s)
        } else {
            None
        };
        let (applied_c, sigma_t_k) = (oil.applied_c(), oil.sigma_k(e.bulk_scale_sigma));
        let settled = oil.settled();
        if oil.past_applied_k() > 0.0 {
            e.flags |= FLAG_OIL_PAST_RANGE;
        }
        if let Some(t) = moved {
            self.model
                .params
                .set_oil_temperature_keeping_bulk_modulus(&self.params_at_reference, t);
            self.model.params_changed();
            self.set_laminar_sigma(t, sigma_t_k);
        }
        self.oil_temp_c = applied_c;
        e.oil_temp_sigma_k = sigma_t_k;
        if !settled {
            // the oil's state is not known yet: the model's viscous terms may be far off
            e.flags |= FLAG_CONVERGING;
        }
    }
}

/// The line that reports the oil's stiffness the leak filter estimated: θ (a
/// multiple of the model's bulk modulus `model_bulk_modulus_pa`, Pa) ± `sigma`;
/// below 0.9 it says what a soft rig usually means, and that a pressure
/// transducer reading off pulls θ down too. `None` without an estimate.
pub fn oil_stiffness_line(theta: f64, sigma: f64, model_bulk_modulus_pa: f64) -> Option<String> {
    if !theta.is_finite() {
        return None;
    }
    let hint = if theta < 0.9 {
        ": softer than the model's, as with entrained air or long hoses (`leakwatch calibrate` on a \
         healthy recording names it and puts it into the model), or a pressure transducer that reads off \
         (the filter takes part of its misreading into the stiffness)"
    } else {
        ""
    };
    Some(format!(
        "oil stiffness: {theta:.3} ± {sigma:.3} of the model's bulk modulus ({:.0} of {:.0} MPa){hint}",
        theta * model_bulk_modulus_pa / 1e6,
        model_bulk_modulus_pa / 1e6
    ))
}

#[cfg(test)]
mod tests;
