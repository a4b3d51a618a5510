//! One step of the estimator's filter (predict with the process model, then
//! update on the measured channels), its start and its re-anchoring, for
//! every layout's number of states.

use model::process::{ProcessModel, FIRST_RANDOM_WALK, I_BULK, I_FE, I_QE1, I_QI};
use nalgebra::{SMatrix, SVector};

use crate::ekf::{self, Ekf, EkfError};
use crate::{
    outlier, BiasResponse, Estimate, Init, Tuning, FIRST_SLOW_STATE, MAX_STATES, SCALE, STILL_SAMPLES,
    THETA_LEARNS_ABOVE_SIGMA_V,
};

/// A filter of `N` states (factor width `W`) at its start: from the measured
/// [x m, p1 Pa, p2 Pa] where the tuning starts from the measurement, else from
/// the tuning's initial pressure.
pub(crate) fn make_filter<const N: usize, const W: usize>(
    tuning: &Tuning,
    model: &ProcessModel,
    measured: Option<[f64; 3]>,
) -> Ekf<N, 3, W> {
    let mut x0 = SVector::<f64, N>::zeros();
    let p0 = tuning.p0_diag::<N>();
    let q = tuning.q_diag::<N>();
    let r = tuning.r_diag();
    let scale = SVector::<f64, N>::from_fn(|i, _| SCALE[i]);
    match (tuning.init, measured) {
        (Init::Measured, Some([x, p1, p2])) => {
            x0[1] = p1;
            x0[2] = p2;
            x0[3] = x;
            if N >= 7 {
                x0[I_FE] = model.params.pressure_force_n(p1, p2) - model.params.gravity_force_n();
            }
        }
        _ => {
            let p = tuning.init_pressure_pa;
            x0[1] = p;
            x0[2] = p;
        }
    }
    // the oil's stiffness starts at the model's, whatever the start
    if N == 12 {
        x0[I_BULK] = 1.0;
    }
    let mut e = Ekf::new(x0, &p0, &q, r, scale);
    e.set_random_walks_from(FIRST_RANDOM_WALK);
    e
}

/// Re-anchors `e` on the measured [x m, p1 Pa, p2 Pa] after a gap, keeping
/// the slow states' estimates and their covariance.
pub(crate) fn reanchor_filter<const N: usize, const W: usize>(
    e: &mut Ekf<N, 3, W>,
    tuning: &Tuning,
    model: &ProcessModel,
    measured: [f64; 3],
) {
    let fresh = make_filter::<N, W>(tuning, model, Some(measured));
    e.reanchor(*fresh.state(), &tuning.p0_diag::<N>(), FIRST_SLOW_STATE.min(N));
}

/// A time update alone with valve command `u` (V); false if the filter refused it.
pub(crate) fn predict_only<const N: usize, const W: usize>(
    e: &mut Ekf<N, 3, W>,
    model: &ProcessModel,
    u: f64,
) -> bool {
    let (x, f, _) = model.step(e.state(), u);
    e.predict(x, &f).is_ok()
}

/// What a filter step carries from one sample to the next besides the filter.
pub(crate) struct StepMemory<'a> {
    /// Samples the rod has rested, for θ's hold.
    pub(crate) still_samples: &'a mut u32,
    /// How the estimate answers a pressure offset.
    pub(crate) offset_response: &'a mut BiasResponse,
    /// The outlier watch.
    pub(crate) outliers: &'a mut outlier::OutlierGate,
}

/// What one sample gives a filter step.
pub(crate) struct StepInput {
    /// The sample's time, s.
    pub(crate) t_s: f64,
    /// Valve command, V.
    pub(crate) u: f64,
    /// Measurement [x m, p1 Pa, p2 Pa] (0 where a channel is not used).
    pub(crate) y: SVector<f64, 3>,
    /// Which channels update the filter.
    pub(crate) use_channel: [bool; 3],
    /// Whether the sample updates the filter at all.
    pub(crate) usable: bool,
    /// Whether a lone outlier is left out ([`outlier`]): in the leak filter
    /// only (the thesis filter stays as published), and not while it
    /// converges from its start, when large innovations are its own.
    pub(crate) gate_outliers: bool,
    /// The DAQ's sample-time jitter the measurement noise counts, s (RMS; 0:
    /// none, R as tuned).
    pub(crate) jitter_s: f64,
    /// The pressure transducers' lags (p1, p2) the NIS counts, s
    /// ([`Tuning::pressure_lag_s`]; 0: none, as for a repeated reading).
    pub(crate) pressure_lag_s: [f64; 2],
    /// The transducers' delay whose imprint is taken off the published leak
    /// sizes, s ([`Tuning::lag_correction_s`]; 0: none).
    pub(crate) lag_correction_s: f64,
}

impl StepInput {
    /// A reading `y` under command `u` (V) at t = 0, every channel updating,
    /// no outlier gate, no jitter or lag counted.
    pub(crate) fn plain(u: f64, y: SVector<f64, 3>) -> Self {
        Self {
            t_s: 0.0,
            u,
            y,
            use_channel: [true; 3],
            usable: true,
            gate_outliers: false,
            jitter_s: 0.0,
            pressure_lag_s: [0.0; 2],
            lag_correction_s: 0.0,
        }
    }
}

/// One predict + update; fills `out`; returns whether the prediction was clamped.
///
/// On an x86-64 processor with AVX2 and FMA the whole step (the model's too)
/// runs compiled for them: the model's arithmetic gives the same bits either
/// way (Rust fuses no multiply-add it is not asked to), the filter's fuses
/// its own ([`Ekf::predict`]).
pub(crate) fn step_filter<const N: usize, const W: usize>(
    e: &mut Ekf<N, 3, W>,
    model: &ProcessModel,
    input: &StepInput,
    out: &mut Estimate,
    memory: StepMemory,
) -> Result<bool, EkfError> {
    #[cfg(target_arch = "x86_64")]
    if ekf::fused_vector_unit() {
        // SAFETY: the processor has AVX2 and FMA (checked just above), the
        // only requirement of a `target_feature` function.
        return unsafe { step_filter_fma(e, model, input, out, memory) };
    }
    step_filter_body::<N, W, ekf::Separate>(e, model, input, out, memory)
}

/// [`step_filter_body`] compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(crate) fn step_filter_fma<const N: usize, const W: usize>(
    e: &mut Ekf<N, 3, W>,
    model: &ProcessModel,
    input: &StepInput,
    out: &mut Estimate,
    memory: StepMemory,
) -> Result<bool, EkfError> {
    step_filter_body::<N, W, ekf::Fused>(e, model, input, out, memory)
}

/// The body of [`step_filter`], its multiply-adds computed by `A` (the filter's
/// own bodies are called directly: the processor was checked once, above).
#[inline(always)]
pub(crate) fn step_filter_body<const N: usize, const W: usize, A: ekf::MulAdd>(
    e: &mut Ekf<N, 3, W>,
    model: &ProcessModel,
    input: &StepInput,
    out: &mut Estimate,
    memory: StepMemory,
) -> Result<bool, EkfError> {
    let StepInput {
        t_s,
        u,
        ref y,
        use_channel,
        usable,
        gate_outliers,
        jitter_s,
        pressure_lag_s,
        lag_correction_s,
    } = *input;
    let StepMemory {
        still_samples,
        offset_response,
        outliers,
    } = memory;
    let (mut x_pred, mut f) = (SVector::<f64, N>::zeros(), SMatrix::<f64, N, N>::zeros());
    let guard = model.step_into(e.state(), u, &mut x_pred, &mut f);
    if N == 12 {
        if e.state()[4].abs() < THETA_LEARNS_ABOVE_SIGMA_V * e.sigma_of(4) {
            *still_samples = still_samples.saturating_add(1);
        } else {
            *still_samples = 0;
        }
    }
    if N == 12 && *still_samples >= STILL_SAMPLES {
        // θ scales the pressure change the net flow Q − A·v makes. While the
        // rod rests, v̂ is noise, and that noise would pass for a change and
        // pull θ toward 0 (an errors-in-variables bias): the A·v part leaves
        // θ's column. The valve's and the leaks' flows stay (a chamber
        // compressed against a stop still tells θ).
        let (from_v1, from_v2) = model.bulk_column_from_velocity(e.state());
        f[(1, I_BULK)] -= from_v1;
        f[(2, I_BULK)] -= from_v2;
    }
    // the measured states' rates over this step, from the prediction
    let rates = {
        let prior = e.state();
        ProcessModel::MEASURED_STATES.map(|i| (x_pred[i] - prior[i]) / model.dt_s)
    };
    if jitter_s > 0.0 {
        // each reading is off by its rate times the jitter
        e.set_measurement_rates(rates, jitter_s);
    }
    // A lagging transducer reads p − τ·ṗ: off by up to τ·ṗ, the part the
    // estimate has not followed. The NIS counts it as noise, (τ·ṗ)² at the
    // predicted rate on each pressure's variance. The gains and the outlier
    // test do not: a spike in a fast move stays a spike.
    let lag_var = [
        0.0,
        (pressure_lag_s[0] * rates[1]).powi(2),
        (pressure_lag_s[1] * rates[2]).powi(2),
    ];
    e.predict_lean::<A>(x_pred, &f)?;
    offset_response.predict(&f);
    let y_pred = model.read(e.state());
    if usable {
        let lag_nis = if pressure_lag_s == [0.0; 2] {
            None
        } else {
            Some(e.selected_nis(&(y - y_pred), ProcessModel::MEASURED_STATES, lag_var, use_channel)?)
        };
        // The channels that update: less a lone outlier once the filter has converged.
        let mut updating = use_channel;
        let inn =
            e.update_selected_choosing::<A>(y, &y_pred, ProcessModel::MEASURED_STATES, |nu, sigma| {
                if gate_outliers {
                    updating = outliers.gate(
                        t_s,
                        &[nu[0], nu[1], nu[2]],
                        &[sigma[0], sigma[1], sigma[2]],
                        use_channel,
                    );
                }
                updating
            })?;
        offset_response.update(e, ProcessModel::MEASURED_STATES, updating, y, rates);
        let mut x = *e.state();
        if model.keep_physical(&mut x).any() {
            e.set_state(x);
        }
        let y_post = model.read(e.state());
        for k in 0..3 {
            out.innovation[k] = if use_channel[k] { inn.nu[k] } else { f64::NAN };
            out.innovation_sigma[k] = inn.sigma[k];
            out.residual[k] = if use_channel[k] {
                y[k] - y_post[k]
            } else {
                f64::NAN
            };
        }
        // A reading left out still counts in the NIS: the detector holds its
        // evidence after such a burst as after any other.
        let left_out: f64 = (0..3)
            .filter(|&k| use_channel[k] && !updating[k])
            .map(|k| (inn.nu[k] / inn.sigma[k]).powi(2))
            .sum();
        out.nis = lag_nis.unwrap_or(inn.nis + left_out);
    }
    let x = e.state();
    let sig = e.sigma();
    for i in 0..N.min(MAX_STATES) {
        out.state[i] = x[i];
        out.sigma[i] = sig[i];
    }
    out.offset_response_lpm_per_mpa = offset_response.leak_sizes_lpm_per_mpa();
    out.span_response_lpm = offset_response.leak_sizes_lpm_per_span();
    out.position_offset_response_lpm_per_mm = offset_response.leak_sizes_lpm_per_mm();
    out.delay_response_lpm_per_ms = offset_response.leak_sizes_lpm_per_ms_delay();
    if lag_correction_s > 0.0 && N > I_QI {
        // the leak sizes published are those of transducers without the delay
        for (k, imprint) in offset_response.lag_imprint(lag_correction_s).iter().enumerate() {
            out.state[I_QE1 + k] -= imprint;
        }
    }
    if N == 12 {
        out.bulk_scale = x[I_BULK];
        out.bulk_scale_sigma = sig[I_BULK];
    }
    Ok(guard.any())
}

#[cfg(test)]
mod tests;
