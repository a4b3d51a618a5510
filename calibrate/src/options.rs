//! The options of the workflow ([`CalibrateOptions`]) and their defaults.

use serde::{Deserialize, Serialize};

use crate::Method;

/// Options of the workflow; every field has a default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CalibrateOptions {
    /// How model and measurement are compared: `equation-error` (default;
    /// short windows started from the measured state, not defeated by
    /// stick-slip) or `shooting` (windows simulated freely; smooth rigs only).
    pub method: Method,
    /// Length of one comparison window, s.
    pub window_s: f64,
    /// Fraction of the windows used for fitting; the rest validate.
    pub fit_fraction: f64,
    /// Split in blocks of this many windows: in each, the first
    /// `fit_fraction` fit and the rest validate, so both parts see every
    /// regime of the record. 0: the first `fit_fraction` of the record fits,
    /// the tail validates.
    pub split_block_windows: usize,
    /// RK4 sub-steps per sample period in the shooting simulations.
    pub substeps_per_sample: u32,
    /// Compare every n-th sample of a window.
    pub compare_stride: usize,
    /// Position error that counts as much as `scale_p_pa` of pressure error, m.
    pub scale_x_m: f64,
    /// Pressure error scale, Pa.
    pub scale_p_pa: f64,
    /// Force error scale of the equation-error comparison, N.
    pub scale_f_n: f64,
    /// Spool position error scale of the equation-error comparison, m.
    pub scale_sp_m: f64,
    /// Use at most this much of the record (from its start), s; 0: the whole record.
    pub max_seconds: f64,
    /// Least record length accepted, s.
    pub min_seconds: f64,
    /// Compare at most about this many windows (whole blocks spread evenly
    /// over the record; 0: all). 6000 windows of 50 ms = 5 min of data.
    pub max_windows: usize,
    /// Effect names to consider (empty: the whole library).
    pub candidates: Vec<String>,
    /// At most this many effects are added.
    pub max_effects: usize,
    /// Least relative reduction of the validation gap for an effect to be accepted.
    pub min_gap_reduction: f64,
    /// Least RMS change of the normalised residuals per resolution step of
    /// each parameter for the effect to count as identifiable.
    pub min_sensitivity: f64,
    /// Least absolute reduction of the normalised validation gap for an
    /// effect to be accepted (0.03 ≈ 3 kPa of pressure or 30 µm of position
    /// RMS at the default scales): what is left near the sensor-noise floor is
    /// not claimed.
    pub min_gap_reduction_normalised: f64,
    /// Least change of some parameter from the current model, in resolution
    /// steps ([`Effect::resolution`](crate::Effect::resolution), about 10 % of a typical value), for an
    /// effect to be claimed: smaller ones are below what the method resolves
    /// and are usually other small mismatches (e.g. mass) in disguise.
    pub min_size_steps: f64,
    /// Levenberg–Marquardt iterations of a full fit.
    pub max_iterations: usize,
    /// Candidates kept for a full fit after the screening iteration.
    pub screen_keep: usize,
    /// Keep the re-anchored traces in the result for plots.
    pub keep_traces: bool,
    /// Half-width of the local quadratic fit of positions that estimates the
    /// velocity at each window start, samples.
    pub velocity_half_width: usize,
    /// Standard deviation of the position sensor's noise beyond its
    /// quantisation, m (`[sensors] position_noise_m`; 0: an encoder that only
    /// counts). The force balance reads a velocity within three σ of the
    /// velocity's noise as at rest ([`crate::shoot::velocity_noise_m_s`]).
    pub position_noise_m: f64,
    /// For an effect with two forms (`bulk-modulus`): least paired t statistic,
    /// over every window of the record, of the per-window mean squared
    /// residual of the other form minus the chosen one, for the chosen form
    /// to be claimed (see [`FoundEffect::caveat`](crate::FoundEffect::caveat)).
    pub min_form_t: f64,
    /// ... or least ratio of the other form's RMS residual over every window
    /// to the chosen one's.
    pub min_form_gap_ratio: f64,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            method: Method::EquationError,
            window_s: 0.05,
            fit_fraction: 0.7,
            split_block_windows: 10,
            substeps_per_sample: 4,
            compare_stride: 5,
            scale_x_m: 1.0e-3,
            scale_p_pa: 1.0e5,
            scale_f_n: 100.0,
            scale_sp_m: 1.0e-6,
            max_seconds: 0.0,
            max_windows: 6000,
            min_seconds: 3.0,
            candidates: Vec::new(),
            max_effects: 3,
            min_gap_reduction: 0.2,
            min_sensitivity: 0.01,
            min_size_steps: 0.5,
            min_gap_reduction_normalised: 0.03,
            max_iterations: 10,
            screen_keep: 3,
            keep_traces: true,
            velocity_half_width: 1,
            position_noise_m: 0.0,
            min_form_t: 3.0,
            min_form_gap_ratio: 2.0,
        }
    }
}

impl CalibrateOptions {
    /// The multiple-shooting comparison with its own defaults (0.25 s
    /// windows, velocity from ±3 samples): for a smooth rig, where freely
    /// simulated windows stay close to the measurement.
    pub fn shooting() -> Self {
        CalibrateOptions {
            method: Method::Shooting,
            window_s: 0.25,
            velocity_half_width: 3,
            min_size_steps: 1.0,
            ..CalibrateOptions::default()
        }
    }
}
