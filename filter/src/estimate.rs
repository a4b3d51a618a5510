//! What the estimator reports for one sample.

use model::process::N_MEAS;

use crate::MAX_STATES;
#[allow(unused_imports)] // (named in the docs)
use crate::{bias, oil};

/// What the estimator reports for one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Sample time, s.
    pub t_s: f64,
    /// Number of entries of [`Self::state`] in use: the filter's states (6, 7, 10 or 11; the 12-state layout fills 11 and [`Self::bulk_scale`]).
    pub n_states: u32,
    /// Bit set of `FLAG_*`.
    pub flags: u32,
    /// A-posteriori state: x_sp m, p1 Pa, p2 Pa, x m, v m/s, v_sp m/s, F_e N, and the leak
    /// sizes at nominal drop q_e1, q_e2, q_i m³/s, and the spool null bias b m
    /// (entries past `n_states` are NaN).
    pub state: [f64; MAX_STATES],
    /// Standard deviation of each state, same units (NaN past `n_states`).
    pub sigma: [f64; MAX_STATES],
    /// 12-state layout: the oil's stiffness as a multiple of the model's effective
    /// bulk modulus θ (1); NaN for the other layouts.
    pub bulk_scale: f64,
    /// One standard deviation of [`Self::bulk_scale`] (1); NaN for the other layouts.
    pub bulk_scale_sigma: f64,
    /// The measurement y = [x m, p1 Pa, p2 Pa] the filter used: as received,
    /// less the model's transducer misreading (`pressure_misreading_pa`; NaN where absent).
    pub measured: [f64; N_MEAS],
    /// Valve command u, V (as received).
    pub u_v: f64,
    /// A-posteriori residual y − H x̂⁺: m, Pa, Pa (NaN where the channel was not used).
    pub residual: [f64; N_MEAS],
    /// Innovation y − H x̂⁻: m, Pa, Pa.
    pub innovation: [f64; N_MEAS],
    /// Standard deviation of each innovation, √diag(H P⁻ Hᵀ + R): m, Pa, Pa.
    pub innovation_sigma: [f64; N_MEAS],
    /// Moving average of |residual| of p1 and p2 over the MAE window, Pa.
    pub mae_pa: [f64; 2],
    /// Normalised innovation squared (χ² with 3 degrees of freedom when consistent).
    pub nis: f64,
    /// The oil temperature the model was at, °C: the sample's `temp_c`, else
    /// the one read from θ ([`oil`]); NaN: neither.
    pub oil_temp_c: f64,
    /// One standard deviation of [`Self::oil_temp_c`], K: 0 when measured, from θ's
    /// σ when read from θ, NaN when unknown.
    pub oil_temp_sigma_k: f64,
    /// One standard deviation of the laminar flows' factor since the reference
    /// temperature (1): how far the model's null leakage may have moved from
    /// what the commissioning saw ([`oil::laminar_factor_with_sigma`]); 0 at the reference.
    pub laminar_factor_sigma: f64,
    /// That σ times the model's null leakage per path at p_s/2, L/min.
    pub null_leakage_band_lpm: f64,
    /// How an offset of 1 MPa on p1 (row 0) and on p2 (row 1) would have moved
    /// the leak sizes q_e1, q_e2, q_i by now, L/min per MPa ([`bias`]); zero
    /// for the layouts without leak sizes.
    pub offset_response_lpm_per_mpa: [[f64; 3]; 2],
    /// How a span error of 1 on p1 (row 0) and on p2 (row 1), a reading of
    /// (1 + g)·p for g = 1, would have moved q_e1, q_e2, q_i by now, L/min
    /// (g times as much for a span error g; [`bias`]); zero for the layouts
    /// without leak sizes.
    pub span_response_lpm: [[f64; 3]; 2],
    /// How an offset of 1 mm on x would have moved q_e1, q_e2, q_i by now,
    /// L/min per mm ([`bias`]); zero for the layouts without leak sizes.
    pub position_offset_response_lpm_per_mm: [f64; 3],
    /// How a delay of 1 ms on p1 and on p2 would have moved q_e1, q_e2, q_i
    /// by now, L/min per ms ([`bias`]); zero for the layouts without leak
    /// sizes. The leak sizes in `state` have
    /// [`Tuning::lag_correction_s`](crate::Tuning::lag_correction_s) times its sum taken off.
    pub delay_response_lpm_per_ms: [[f64; 3]; 2],
}

impl Default for Estimate {
    /// An estimate of nothing: time 0, no states, no flags, every value NaN
    /// but the responses and the null-leakage band (0), as a buffer for
    /// [`crate::Estimator::on_sample_into`].
    fn default() -> Self {
        Estimate::empty(0.0, 0)
    }
}

impl Estimate {
    #[inline]
    pub(crate) fn empty(t_s: f64, n_states: u32) -> Self {
        Estimate {
            t_s,
            n_states: n_states.min(MAX_STATES as u32),
            flags: 0,
            measured: [f64::NAN; N_MEAS],
            u_v: f64::NAN,
            state: [f64::NAN; MAX_STATES],
            sigma: [f64::NAN; MAX_STATES],
            bulk_scale: f64::NAN,
            bulk_scale_sigma: f64::NAN,
            residual: [f64::NAN; N_MEAS],
            innovation: [f64::NAN; N_MEAS],
            innovation_sigma: [f64::NAN; N_MEAS],
            mae_pa: [f64::NAN; 2],
            nis: f64::NAN,
            oil_temp_c: f64::NAN,
            oil_temp_sigma_k: f64::NAN,
            laminar_factor_sigma: 0.0,
            null_leakage_band_lpm: 0.0,
            offset_response_lpm_per_mpa: [[0.0; 3]; 2],
            span_response_lpm: [[0.0; 3]; 2],
            position_offset_response_lpm_per_mm: [0.0; 3],
            delay_response_lpm_per_ms: [[0.0; 3]; 2],
        }
    }
}
