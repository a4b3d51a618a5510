//! The EKF's process models (docs/model.md#process-model): the healthy actuator integrated
//! with forward Euler at the sample period, with analytic Jacobians on every
//! branch (valve sign, stick band, spring contact).
//!
//! Three layouts share one right-hand side, selected by the state count `N`:
//!
//! | N | states (SI) |
//! |---|---|
//! | 6 | x_sp m, p1 Pa, p2 Pa, x m, v m/s, v_sp m/s (friction and spring from the parameters) |
//! | 7 | the 6 plus F_e N, the whole effective load (friction + environment) as a random walk |
//! | 10 | the 7 plus q_e1, q_e2, q_i m³/s: the three leak sizes (random walks) |
//! | 11 | the 10 plus b m: the spool's null bias (a random walk) |
//! | 12 | the 11 plus θ (1): the oil's stiffness as a multiple of the model's effective bulk modulus (a random walk; entrained air and a soft hose make a rig's oil 0-30 % softer than the data sheet's, and that error otherwise shows as leaks) |
//!
//! The 10-state "leak" layout is leakwatch's own: a leak is a flow the healthy
//! model lacks, so the filter estimates the three leaks directly, each as its
//! size at the nominal pressure drop Δp_n = p_s/2 under the square-root law:
//! q = q_n · sgn(Δp)·√(|Δp| / Δp_n), with Δp = p1 − p_r, p2 − p_r and p1 − p2.
//!
//! The 10-, 11- and 12-state layouts have the end stops as the rig has them
//! (a stiff spring-damper beyond each end, [`STOP_SUBSTEPS`] Euler sub-steps
//! while the rod is in one); the thesis' 6- and 7-state layouts have none, as
//! published. A sample step uses the command it is given over the whole
//! interval: the filters pass the command of the sample the interval starts at.
//!
//! Measurements are y = [x, p1, p2] (m, Pa, Pa).

use nalgebra::{SMatrix, SVector};

use crate::dynamics::LeakSet;
use crate::params::ActuatorParams;

mod discrete;
use discrete::SpoolStep;
pub use discrete::{spool_mean, spool_transition, STOP_SUBSTEPS};
mod rhs;
#[cfg(test)]
mod tests;

/// Index of the effective load F_e (N) in the 7- and 9-state layouts.
pub const I_FE: usize = 6;
/// The first of the random-walk states (F_e, the leaks, b, θ): the step's
/// dynamics move no state from this index on (only [`ProcessModel::keep_physical`]
/// may clamp θ into its range), so their rows of the step Jacobian are the
/// identity's (a filter may take them as such).
pub const FIRST_RANDOM_WALK: usize = I_FE;
/// Index of q_e1, the chamber-1 external leak at nominal drop (m³/s), in the 10-state layout.
pub const I_QE1: usize = 7;
/// Index of q_e2, the chamber-2 external leak at nominal drop (m³/s), in the 10-state layout.
pub const I_QE2: usize = 8;
/// Index of q_i, the internal leak at nominal drop (m³/s), in the 10-state layout.
pub const I_QI: usize = 9;
/// Index of the spool null bias b (m) in the 11- and 12-state layouts.
pub const I_BIAS: usize = 10;
/// Index of θ, the oil stiffness as a multiple of the model's effective bulk modulus (1), in the 12-state layout.
pub const I_BULK: usize = 11;
/// Range θ is kept in by [`ProcessModel::keep_physical`] (1): from a fifth of the model's stiffness to twice it.
pub const BULK_SCALE_RANGE: (f64, f64) = (0.2, 2.0);
/// Number of measurements: rod position (m) and the two chamber pressures (Pa).
pub const N_MEAS: usize = 3;

/// Smallest |Δp| used for the slope of a square-root flow law, Pa: below it the
/// slope 1/(2√|Δp|) is held at its value here, so the Jacobian stays finite
/// when a land's pressure drop crosses zero.
pub const MIN_SLOPE_DROP_PA: f64 = 1.0e3;

/// What the prediction had to do to keep the state physical.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Guard {
    /// A pressure was pulled back into [min, max] of [`PressureRange`].
    pub pressure_clamped: bool,
    /// The rod position was pulled back into the stroke (± the end-stop margin).
    pub position_clamped: bool,
    /// The oil-stiffness scale θ was pulled back into [`BULK_SCALE_RANGE`].
    pub bulk_clamped: bool,
}

impl Guard {
    /// Whether anything was clamped.
    pub fn any(&self) -> bool {
        self.pressure_clamped || self.position_clamped || self.bulk_clamped
    }
}

/// The discrete process model x(k+1) = x(k) + T·f(x(k), u(k)) of the healthy actuator.
#[derive(Debug, Clone)]
pub struct ProcessModel {
    /// Physical parameters of the model (not of the rig).
    pub params: ActuatorParams,
    /// Sample period T, s.
    pub dt_s: f64,
    /// Euler sub-steps per sample (1 = the thesis' plain forward Euler); set
    /// with [`Self::set_substeps`], which keeps the spool's steps for them.
    pub substeps: u32,
    /// Leaks that are part of the model itself (from `params.leaks`).
    pub leaks: LeakSet,
    /// Lowest pressure a prediction may hold, Pa (vacuum, gauge).
    pub p_min_pa: f64,
    /// Highest pressure a prediction may hold, Pa.
    pub p_max_pa: f64,
    /// Constants of the right-hand side derived from `params` (used while
    /// `params` are those they were derived from; [`ProcessModel::set_params`]
    /// derives them again).
    derived: rhs::Derived,
    /// The spool's exact step over a free step's and over an end stop's
    /// sub-step, for `params`, `dt_s` and `substeps` as they were derived (a
    /// model whose spool, period or sub-steps changed since computes it
    /// afresh in every step).
    spool_steps: [SpoolStep; 2],
}

/// The continuous right-hand side and its Jacobian at one state.
#[derive(Debug, Clone, Copy)]
pub struct Linearisation<const N: usize> {
    /// dx/dt.
    pub f: SVector<f64, N>,
    /// ∂f/∂x.
    pub a: SMatrix<f64, N, N>,
}

impl ProcessModel {
    /// The model for parameters `params` at sample period `dt_s` (s).
    pub fn new(params: ActuatorParams, dt_s: f64) -> Self {
        let leaks = LeakSet::from_params(&params);
        let p_max_pa = 1.5 * params.supply_pressure_pa;
        let derived = rhs::Derived::of(&params);
        let spool_steps = SpoolStep::for_steps(&params, dt_s, 1);
        ProcessModel {
            params,
            dt_s,
            substeps: 1,
            leaks,
            p_min_pa: -1.0e5,
            p_max_pa,
            derived,
            spool_steps,
        }
    }

    /// The spool's null bias at state `s`, m: the model's plus the bias
    /// state's in the layouts that estimate it (11 and 12 states).
    #[inline(always)]
    pub(crate) fn spool_bias_m<const N: usize>(&self, s: &SVector<f64, N>) -> f64 {
        self.params.spool_null_bias_m + if N >= 11 { s[I_BIAS] } else { 0.0 }
    }

    /// Where the spool comes to rest under the command `u_v` (V) held, m:
    /// its null bias at `s` plus k_sp·u.
    #[inline(always)]
    pub(crate) fn spool_rest_m<const N: usize>(&self, s: &SVector<f64, N>, u_v: f64) -> f64 {
        self.spool_bias_m(s) + self.params.spool_gain_m_per_v * u_v
    }

    /// Sets the Euler sub-steps per sample (`substeps`) and derives the
    /// spool's steps for them. Allocates nothing.
    pub fn set_substeps(&mut self, substeps: u32) {
        self.substeps = substeps;
        self.params_changed();
    }

    /// Derives what the model keeps from `params` again (its own leaks and the
    /// right-hand side's constants) after `params` were changed in place (as a
    /// change of oil temperature does). Allocates nothing.
    pub fn params_changed(&mut self) {
        self.leaks = LeakSet::from_params(&self.params);
        self.derived = rhs::Derived::of(&self.params);
        self.spool_steps = SpoolStep::for_steps(&self.params, self.dt_s, self.substeps);
    }

    /// The nominal pressure drop at which the 10-state layout's leak sizes are given, Pa (p_s/2).
    pub fn nominal_drop_pa(&self) -> f64 {
        0.5 * (self.params.supply_pressure_pa - self.params.return_pressure_pa)
    }

    /// The part the rod's velocity makes of θ's column in a sample step's
    /// Jacobian (12 states), ∂(p1, p2)(k+1)/∂θ through −A1·v and +A2·v, Pa
    /// per unit of θ: what a filter leaves out when v̂ is noise (a resting rod).
    pub fn bulk_column_from_velocity<const N: usize>(&self, s: &SVector<f64, N>) -> (f64, f64) {
        let p = &self.params;
        let (v1, v2) = p.chamber_volumes_m3(s[3]);
        let (a1, a2) = p.areas_m2();
        let b1 = crate::dynamics::effective_bulk_modulus_pa(p, s[1]);
        let b2 = crate::dynamics::effective_bulk_modulus_pa(p, s[2]);
        let h = self.dt_s;
        (-h * b1 / v1 * a1 * s[4], h * b2 / v2 * a2 * s[4])
    }

    /// The measurement y = [x, p1, p2] of a state, m, Pa, Pa.
    #[inline]
    pub fn measure<const N: usize>(s: &SVector<f64, N>) -> SVector<f64, N_MEAS> {
        SVector::<f64, N_MEAS>::new(s[3], s[1], s[2])
    }

    /// What the transducers read of a state, y = [x, p1, p2] (m, Pa, Pa): the
    /// chambers' pressures plus the line's laminar drop between them and the
    /// transducers, R·Q1 into chamber 1 and −R·Q2 out of chamber 2, with R the
    /// model's `line_resistance_pa_s_per_m3` (0: the transducers read the
    /// chambers, [`Self::measure`]). H stays the selector: R·∂Q/∂x is left out.
    #[inline]
    pub fn read<const N: usize>(&self, s: &SVector<f64, N>) -> SVector<f64, N_MEAS> {
        let mut y = Self::measure(s);
        let r = self.params.line_resistance_pa_s_per_m3;
        if r > 0.0 {
            let q = crate::dynamics::valve_flows(&self.params, s[0], s[1], s[2]);
            y[1] += r * q.q1_m3_s;
            y[2] -= r * q.q2_m3_s;
        }
        y
    }

    /// The states the measurement y = [x, p1, p2] reads, in its order (H is
    /// the selector of these states).
    pub const MEASURED_STATES: [usize; N_MEAS] = [3, 1, 2];

    /// The measurement matrix H (selects x, p1, p2).
    pub fn measurement_matrix<const N: usize>() -> SMatrix<f64, N_MEAS, N> {
        let mut h = SMatrix::<f64, N_MEAS, N>::zeros();
        h[(0, 3)] = 1.0;
        h[(1, 1)] = 1.0;
        h[(2, 2)] = 1.0;
        h
    }
}
