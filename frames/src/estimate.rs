//! [`EstimateFrame`]: the estimator's output for one sensor frame, and the
//! sizes of its state arrays.

use iceoryx2::prelude::*;

use crate::{estimate_flags, impl_sequenced_frame, Topic};

/// Number of states in [`EstimateFrame::state`]: x_sp m, p1 Pa, p2 Pa, x m,
/// v m/s, v_sp m/s, F_e N, w1 m³/s, w2 m³/s.
pub const MAX_STATES: usize = 11;

/// Number of states of the thesis filter carried in [`EstimateFrame::th_state`].
pub const THESIS_STATES: usize = 7;

/// The estimator's output for one sensor frame (1 kHz).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.EstimateFrame.v6")]
pub struct EstimateFrame {
    /// Sequence number of the sensor frame this estimate is for.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when the sensor frame was published, ns (copied).
    pub acq_mono_ns: u64,
    /// `CLOCK_MONOTONIC` when the estimator received the sensor frame, ns.
    pub est_recv_mono_ns: u64,
    /// `CLOCK_MONOTONIC` when the estimate was complete, ns.
    pub est_done_mono_ns: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// Number of states in use (the first `n_states` of [`Self::state`]).
    pub n_states: u32,
    /// Bit set of [`estimate_flags`].
    pub flags: u32,
    /// The leak filter's a-posteriori state, order: x_sp m, p1 Pa, p2 Pa, x m,
    /// v m/s, v_sp m/s, F_e N, q_e1 m³/s, q_e2 m³/s, q_i m³/s (leak sizes at the
    /// nominal drop), spool null bias m; unused entries NaN.
    pub state: [f64; MAX_STATES],
    /// One standard deviation of each state, same order and units as [`Self::state`].
    pub state_sigma: [f64; MAX_STATES],
    /// Leak filter: a-posteriori residual y − Hx⁺: x m, p1 Pa, p2 Pa.
    pub residual: [f64; 3],
    /// Leak filter: innovation y − Hx⁻: x m, p1 Pa, p2 Pa.
    pub innovation: [f64; 3],
    /// Leak filter: standard deviation of each innovation: m, Pa, Pa.
    pub innovation_sigma: [f64; 3],
    /// The measurement the filter used: x m, p1 Pa, p2 Pa, the model's
    /// transducer misreading taken off (NaN where absent).
    pub measured: [f64; 3],
    /// The valve command as received, V.
    pub u_v: f64,
    /// Leak filter: normalised innovation squared.
    pub nis: f64,
    /// Leak filter: mean absolute residual of p1 and p2 over the MAE window, Pa.
    pub mae_pa: [f64; 2],
    /// Thesis filter: bit set of [`estimate_flags`].
    pub th_flags: u32,
    /// Explicit padding (zero).
    pub _pad: u32,
    /// Thesis filter: a-posteriori state x_sp m, p1 Pa, p2 Pa, x m, v m/s, v_sp m/s, F_e N.
    pub th_state: [f64; THESIS_STATES],
    /// Thesis filter: a-posteriori residual: x m, p1 Pa, p2 Pa.
    pub th_residual: [f64; 3],
    /// Thesis filter: innovation: x m, p1 Pa, p2 Pa.
    pub th_innovation: [f64; 3],
    /// Thesis filter: MAE of the p1 and p2 residuals (the thesis' figure), Pa.
    pub th_mae_pa: [f64; 2],
    /// Thesis filter: normalised innovation squared.
    pub th_nis: f64,
    /// Leak filter: the oil's stiffness θ, a multiple of the model's bulk
    /// modulus (1); NaN when the filter does not estimate it.
    pub bulk_scale: f64,
    /// One standard deviation of [`Self::bulk_scale`] (1).
    pub bulk_scale_sigma: f64,
    /// The oil's temperature the leak filter works with, °C: measured, or
    /// read from θ; NaN when it has none.
    pub oil_temp_c: f64,
    /// One standard deviation of [`Self::oil_temp_c`], K.
    pub oil_temp_sigma_k: f64,
    /// One standard deviation of the laminar flows' factor at that
    /// temperature (1): how uncertain the null leakage and linear leaks are.
    pub laminar_factor_sigma: f64,
    /// The model's null leakage as a leak size, L/min at p_s/2: the band the
    /// detector widens its thresholds by, scaled by [`Self::laminar_factor_sigma`].
    pub null_leakage_band_lpm: f64,
    /// The leak sizes' response to a constant offset on p1, L/min per MPa:
    /// ext1, ext2, int.
    pub offset_response_p1_lpm_per_mpa: [f64; 3],
    /// The leak sizes' response to a constant offset on p2, L/min per MPa:
    /// ext1, ext2, int.
    pub offset_response_p2_lpm_per_mpa: [f64; 3],
    /// The leak sizes' response to a span error of 1 on p1 (a reading of
    /// (1 + g)·p for g = 1), L/min: ext1, ext2, int (g times as much for g).
    pub span_response_p1_lpm: [f64; 3],
    /// The leak sizes' response to a span error of 1 on p2, L/min: ext1, ext2, int.
    pub span_response_p2_lpm: [f64; 3],
    /// The leak sizes' response to a constant offset on x, L/min per mm:
    /// ext1, ext2, int.
    pub offset_response_x_lpm_per_mm: [f64; 3],
    /// The leak sizes' response to a delay of 1 ms on p1, L/min per ms:
    /// ext1, ext2, int.
    pub delay_response_p1_lpm_per_ms: [f64; 3],
    /// The leak sizes' response to a delay of 1 ms on p2, L/min per ms:
    /// ext1, ext2, int.
    pub delay_response_p2_lpm_per_ms: [f64; 3],
}

impl_sequenced_frame!(EstimateFrame, Topic::Estimates, estimate_flags::END_OF_STREAM);

/// All-zero integers, NaN floats ("absent").
impl Default for EstimateFrame {
    fn default() -> Self {
        EstimateFrame {
            seq: 0,
            acq_mono_ns: 0,
            est_recv_mono_ns: 0,
            est_done_mono_ns: 0,
            t_s: f64::NAN,
            n_states: 0,
            flags: 0,
            state: [f64::NAN; MAX_STATES],
            state_sigma: [f64::NAN; MAX_STATES],
            residual: [f64::NAN; 3],
            innovation: [f64::NAN; 3],
            innovation_sigma: [f64::NAN; 3],
            measured: [f64::NAN; 3],
            u_v: f64::NAN,
            nis: f64::NAN,
            mae_pa: [f64::NAN; 2],
            th_flags: 0,
            _pad: 0,
            th_state: [f64::NAN; THESIS_STATES],
            th_residual: [f64::NAN; 3],
            th_innovation: [f64::NAN; 3],
            th_mae_pa: [f64::NAN; 2],
            th_nis: f64::NAN,
            bulk_scale: f64::NAN,
            bulk_scale_sigma: f64::NAN,
            oil_temp_c: f64::NAN,
            oil_temp_sigma_k: f64::NAN,
            laminar_factor_sigma: f64::NAN,
            null_leakage_band_lpm: f64::NAN,
            offset_response_p1_lpm_per_mpa: [f64::NAN; 3],
            offset_response_p2_lpm_per_mpa: [f64::NAN; 3],
            span_response_p1_lpm: [f64::NAN; 3],
            span_response_p2_lpm: [f64::NAN; 3],
            offset_response_x_lpm_per_mm: [f64::NAN; 3],
            delay_response_p1_lpm_per_ms: [f64::NAN; 3],
            delay_response_p2_lpm_per_ms: [f64::NAN; 3],
        }
    }
}
