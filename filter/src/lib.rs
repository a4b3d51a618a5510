// Over 600 lines: the `Estimator` (its step, resets, re-anchoring after gaps and the oil's
// temperature) is one state machine with the `Estimate` it fills; its gap handling could move
// to a module of its own.
//! The EKF core of the estimator stage: a square-root EKF tracking the
//! actuator at 1 kHz against the healthy model of `model::process`
//! (docs/model.md#process-model), with the residuals and moving averages the
//! detectors read (docs/model.md#residuals-and-the-mae-pattern).
//!
//! The stage is pure and allocation-free per sample: one [`Estimator::on_sample`]
//! call per sensor sample returns one [`Estimate`]. The same type runs in the
//! `estimator` process (over iceoryx2) and in `leakwatch replay` (in-process).
//!
//! This crate is pure (no bus, command line or config files); the `estimator`
//! crate is the process around it and re-exports everything here.

pub mod bias;
pub mod ekf;
pub mod mae;
pub mod oil;
pub mod outlier;
pub mod stage;
pub mod tuning;

use model::process::{ProcessModel, FIRST_RANDOM_WALK, I_BULK, I_FE, I_QE1, I_QI, N_MEAS};
use model::{ActuatorParams, Sample};
use nalgebra::{SMatrix, SVector};

pub use bias::BiasResponse;
pub use ekf::{Ekf, EkfError, Innovation};
pub use mae::MovingMae;
pub use oil::OilFromStiffness;
pub use stage::{EstimatorStage, StageEstimate};
pub use tuning::{Init, Tuning};

/// Number of states an [`Estimate`] carries in [`Estimate::state`] (the 11-state
/// leak model with spool bias; the 12th state of the 12-state layout, the oil's
/// stiffness, has its own fields).
pub const MAX_STATES: usize = 11;
/// Largest number of states any layout has (the leak model with spool bias and oil stiffness).
pub const MAX_LAYOUT_STATES: usize = 12;
/// The fewest states of a leak filter's layout (the leak sizes from state 7 on).
const LEAK_LAYOUT_STATES: u32 = 10;

// The flag bits are the wire's (`frames::estimate_flags`), so flags are copied, not
// recoded; `estimator::wire` checks at compile time that the two agree (this crate
// is pure and does not depend on the wire types).
/// Flag bit: the filter was reset at this sample (see [`Estimate::flags`]).
pub const FLAG_RESET: u32 = 1 << 0;
/// Flag bit: the sample could not be used (no measurement update).
pub const FLAG_SKIPPED: u32 = 1 << 1;
/// Flag bit: the prediction had to be clamped to the physical range.
pub const FLAG_CLAMPED: u32 = 1 << 2;
/// Flag bit: the filter is still inside its initial convergence time.
pub const FLAG_CONVERGING: u32 = 1 << 4;
/// Flag bit: samples were missing just before this one (bridged or re-anchored).
pub const FLAG_AFTER_GAP: u32 = 1 << 5;
/// Flag bit: the estimated rod position is within [`END_STOP_MARGIN_M`] of an end of
/// its stroke (for the record: the leak filter's model has the stops, stepped in
/// [`model::process::STOP_SUBSTEPS`] sub-steps while the rod is in one, and the
/// detector takes evidence there as anywhere else).
pub const FLAG_END_STOP: u32 = 1 << 6;
/// Flag bit: the gap before this sample was longer than the filter bridges
/// ([`Tuning::max_bridged_gap_samples`]): its fast states restarted from this sample
/// (set with [`FLAG_AFTER_GAP`]; a bridged gap carries [`FLAG_AFTER_GAP`] alone).
pub const FLAG_REANCHORED: u32 = 1 << 7;
/// Every flag bit an [`Estimate`] can carry (the wire's end-of-stream bit is not one).
pub const FLAGS_ALL: u32 = FLAG_RESET
    | FLAG_SKIPPED
    | FLAG_CLAMPED
    | FLAG_CONVERGING
    | FLAG_AFTER_GAP
    | FLAG_END_STOP
    | FLAG_REANCHORED;
/// Distance from either end of the stroke within which an estimate carries
/// [`FLAG_END_STOP`], m (an encoder count or two, plus the bounce of a stop).
pub const END_STOP_MARGIN_M: f64 = 2e-3;

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
    /// The measurement y = [x m, p1 Pa, p2 Pa] as received (NaN where absent).
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
}

impl Estimate {
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
        }
    }
}

/// The leak filter has converged once `convergence_time_s` has passed and
/// the standard deviation of each leak size is below this share of its
/// initial one (1). A heavy or stiff rig takes seconds (plant_dev/differential:
/// 2-7 s); the thesis rig is there within its first second.
pub const CONVERGED_LEAK_SIGMA: f64 = 0.05;

/// The oil-stiffness scale θ (12 states) does not learn from the rod's
/// velocity while the rod rests: its velocity estimate within this many of its
/// standard deviations of zero (1) for [`STILL_SAMPLES`] samples in a row. At rest on plant_dev/double, θ
/// otherwise fell from 1 to 0.2 within 0.3 s and the first move raised a
/// false leak.
pub const THETA_LEARNS_ABOVE_SIGMA_V: f64 = 3.0;

/// Samples in a row the rod must rest before θ stops learning from v (50 ms at 1 kHz): a
/// velocity passing through zero in a reversal is not a rest (holding θ at
/// every reversal of a 5 Hz chirp raised a false leak in the 30-hour suite).
pub const STILL_SAMPLES: u32 = 50;

/// Counters of what the stage did, for summaries.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EstimatorCounters {
    /// Samples seen.
    pub samples: u64,
    /// Samples without a measurement update (unusable input).
    pub skipped: u64,
    /// Samples with at least one channel left out (NaN or out of range).
    pub channels_dropped: u64,
    /// Samples missing from the input (gaps): predicted across, or re-anchored after.
    pub bridged: u64,
    /// Filter resets (divergence, a non-finite step, or a gap too long to bridge).
    pub resets: u64,
    /// Predictions that had to be clamped to the physical range.
    pub clamped: u64,
    /// Channel readings left out of the update as outliers ([`outlier`]).
    pub outliers: u64,
}

/// One of the three layouts; sizes differ, but the stage holds exactly one, inline.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
enum Filter {
    S6(Ekf<6, 3, 8>),
    S7(Ekf<7, 3, 8>),
    S10(Ekf<10, 3, 12>),
    S11(Ekf<11, 3, 12>),
    S12(Ekf<12, 3, 12>),
}

/// The estimator stage.
#[derive(Debug, Clone)]
pub struct Estimator {
    tuning: Tuning,
    model: ProcessModel,
    filter: Filter,
    /// A copy of `filter` that [`Estimator::warm_up`] steps and throws away.
    warm: Filter,
    mae: [MovingMae; 2],
    last_u_v: f64,
    started: bool,
    t0_s: f64,
    /// The leak sizes' standard deviations have fallen below [`CONVERGED_LEAK_SIGMA`] of their start (latched until a restart).
    leaks_converged: bool,
    /// Samples in a row the rod's velocity estimate has been within noise of zero.
    still_samples: u32,
    /// How the estimate answers a pressure transducer's offset.
    offset_response: BiasResponse,
    /// Readings far off the prediction, left out of the update.
    outliers: outlier::OutlierGate,
    diverged_samples: u32,
    /// A gap too long to bridge by prediction was seen: re-anchor on the next full sample.
    reanchor_pending: bool,
    /// The range a measured pressure must be in to be used, Pa
    /// ([`ActuatorParams::measured_pressure_range_pa`], as for CSV rows).
    measured_p_range_pa: (f64, f64),
    counters: EstimatorCounters,
    /// The model at its oil law's reference temperature.
    params_at_reference: ActuatorParams,
    /// The oil temperature the model was last set to, °C (NaN: none yet).
    oil_temp_c: f64,
    /// The oil's temperature read from θ, while no sample carried `temp_c`
    /// (12 states with a bulk modulus identified at the reference temperature).
    oil_from_stiffness: Option<OilFromStiffness>,
    /// σ of the laminar flows' factor at the model's temperature (1), and that
    /// times the model's null leakage per path at p_s/2 (L/min).
    laminar_sigma: (f64, f64),
}

/// The model follows the samples' oil temperature (`temp_c`) in steps of this
/// much, K: finer than any effect of it the filter can see, coarse enough that
/// a thermometer's last digit does not rescale the model every sample.
pub const OIL_TEMP_STEP_K: f64 = 0.05;

/// First state index kept across a re-anchoring (the leak sizes and the spool bias).
const FIRST_SLOW_STATE: usize = 7;

/// Typical magnitudes used to scale the filter's internal algebra.
const SCALE: [f64; MAX_LAYOUT_STATES] = [1e-5, 1e6, 1e6, 1e-3, 1e-2, 1e-2, 1e2, 1e-6, 1e-6, 1e-6, 1e-6, 1.0];

/// Samples of persistent divergence before a reset (see [`Tuning::divergence_reset_m`]).
pub const DIVERGED_SAMPLES: u32 = 200;

impl Estimator {
    /// A stage for model parameters `params` and filter settings `tuning`.
    pub fn new(params: ActuatorParams, tuning: Tuning) -> Result<Self, String> {
        tuning.validate()?;
        params.validate().map_err(|e| e.to_string())?;
        let measured_p_range_pa = params.measured_pressure_range_pa();
        let mut params = params;
        if tuning.states < 10 {
            // The thesis' layouts keep the thesis' model: no supply sag (its
            // published start, 1e4 m² on the rod position, throws the state
            // where the sagged orifice law's finite differences overflow).
            params.supply_sag_pa_per_m3_s = 0.0;
        }
        let params_at_reference = params.clone();
        let oil_from_stiffness = match params.oil_temperature.reference_stiffness {
            Some(theta_ref) if tuning.states == 12 => {
                OilFromStiffness::new(&params.oil_temperature, theta_ref)
            }
            _ => None,
        };
        let mut model = ProcessModel::new(params, tuning.sample_period_s);
        model.substeps = tuning.substeps;
        let filter = match tuning.states {
            6 => Filter::S6(make_filter::<6, 8>(&tuning, &model, None)),
            7 => Filter::S7(make_filter::<7, 8>(&tuning, &model, None)),
            10 => Filter::S10(make_filter::<10, 12>(&tuning, &model, None)),
            11 => Filter::S11(make_filter::<11, 12>(&tuning, &model, None)),
            _ => Filter::S12(make_filter::<12, 12>(&tuning, &model, None)),
        };
        let w = tuning.mae_window_samples;
        Ok(Estimator {
            tuning,
            model,
            warm: filter.clone(),
            filter,
            mae: [MovingMae::new(w), MovingMae::new(w)],
            last_u_v: 0.0,
            started: false,
            t0_s: 0.0,
            leaks_converged: false,
            still_samples: 0,
            offset_response: BiasResponse::default(),
            outliers: outlier::OutlierGate::default(),
            diverged_samples: 0,
            reanchor_pending: false,
            measured_p_range_pa,
            counters: EstimatorCounters::default(),
            params_at_reference,
            oil_temp_c: f64::NAN,
            oil_from_stiffness,
            laminar_sigma: (0.0, 0.0),
        }
        .with_laminar_sigma_at_start())
    }

    /// One throw-away step on a copy of the filter (the estimate is unchanged): run
    /// just before a frame is due, after the wait's sleep in low-latency mode, it
    /// brings the filter's matrices, the model and the step's code back into the
    /// caches, so the frame's own step does not pay for them. Allocates nothing.
    pub fn warm_up(&mut self) {
        fn step<const N: usize, const W: usize>(
            w: &mut Ekf<N, 3, W>,
            f: &Ekf<N, 3, W>,
            model: &ProcessModel,
            u: f64,
            out: &mut Estimate,
        ) {
            w.clone_from(f);
            let y = ProcessModel::measure(w.state());
            // (the result is thrown away with the copy)
            let input = StepInput {
                u,
                y,
                use_channel: [true; 3],
                usable: true,
                gate_outliers: false,
            };
            let memory = StepMemory {
                still_samples: &mut 0,
                offset_response: &mut BiasResponse::default(),
                outliers: &mut outlier::OutlierGate::default(),
            };
            let _ = step_filter(w, model, &input, out, memory);
        }
        if !self.started {
            return;
        }
        let mut out = Estimate::empty(self.t0_s, self.tuning.states);
        let (model, u) = (&self.model, self.last_u_v);
        match (&mut self.warm, &self.filter) {
            (Filter::S6(w), Filter::S6(f)) => step(w, f, model, u, &mut out),
            (Filter::S7(w), Filter::S7(f)) => step(w, f, model, u, &mut out),
            (Filter::S10(w), Filter::S10(f)) => step(w, f, model, u, &mut out),
            (Filter::S11(w), Filter::S11(f)) => step(w, f, model, u, &mut out),
            (Filter::S12(w), Filter::S12(f)) => step(w, f, model, u, &mut out),
            (w, f) => w.clone_from(f),
        }
    }

    /// The filter settings.
    pub fn tuning(&self) -> &Tuning {
        &self.tuning
    }

    /// The process model.
    pub fn model(&self) -> &ProcessModel {
        &self.model
    }

    /// What the stage has done so far.
    pub fn counters(&self) -> EstimatorCounters {
        self.counters
    }

    /// The covariance of the current estimate, row-major n×n in SI units, into `out`
    /// (which must hold n² values); returns n.
    pub fn covariance_into(&self, out: &mut [f64]) -> usize {
        fn copy<const N: usize, const W: usize>(e: &Ekf<N, 3, W>, out: &mut [f64]) -> usize {
            let p = e.covariance();
            for i in 0..N {
                for j in 0..N {
                    if let Some(o) = out.get_mut(i * N + j) {
                        *o = p[(i, j)];
                    }
                }
            }
            N
        }
        match &self.filter {
            Filter::S6(e) => copy(e, out),
            Filter::S7(e) => copy(e, out),
            Filter::S10(e) => copy(e, out),
            Filter::S11(e) => copy(e, out),
            Filter::S12(e) => copy(e, out),
        }
    }

    /// The oil's stiffness θ as a multiple of the model's bulk modulus, and its
    /// standard deviation (1, 1), now; `None` for a layout without that state or
    /// before the filter has started.
    pub fn bulk_scale(&self) -> Option<(f64, f64)> {
        match &self.filter {
            Filter::S12(e) if self.started => Some((e.state()[I_BULK], e.sigma()[I_BULK])),
            _ => None,
        }
    }

    /// Smallest eigenvalue of the scaled covariance (a health figure: it must stay > 0).
    pub fn min_scaled_eigenvalue(&self) -> f64 {
        match &self.filter {
            Filter::S6(e) => e.scaled_covariance().symmetric_eigenvalues().min(),
            Filter::S7(e) => e.scaled_covariance().symmetric_eigenvalues().min(),
            Filter::S10(e) => e.scaled_covariance().symmetric_eigenvalues().min(),
            Filter::S11(e) => e.scaled_covariance().symmetric_eigenvalues().min(),
            Filter::S12(e) => e.scaled_covariance().symmetric_eigenvalues().min(),
        }
    }

    /// Tells the stage that `missing` samples were lost before the next one.
    /// Gaps up to [`Tuning::max_bridged_gap_samples`] are bridged by prediction;
    /// after a longer one the fast states (spool, pressures, rod, load) restart
    /// from the next complete sample while the leak sizes and the spool bias keep
    /// their estimate and covariance (an open-loop prediction over tens of
    /// milliseconds of a stick-slipping rod is meaningless, and its update would
    /// throw the mismatch into the leak states).
    pub fn on_gap(&mut self, missing: u64) {
        if !self.started || missing == 0 {
            return;
        }
        self.counters.bridged += missing;
        if missing > self.tuning.max_bridged_gap_samples as u64 {
            self.reanchor_pending = true;
            return;
        }
        let u = self.last_u_v;
        for _ in 0..missing {
            let ok = match &mut self.filter {
                Filter::S6(e) => predict_only(e, &self.model, u),
                Filter::S7(e) => predict_only(e, &self.model, u),
                Filter::S10(e) => predict_only(e, &self.model, u),
                Filter::S11(e) => predict_only(e, &self.model, u),
                Filter::S12(e) => predict_only(e, &self.model, u),
            };
            if !ok {
                self.started = false;
                self.counters.resets += 1;
                return;
            }
        }
    }

    /// Tells the filter that its input stream restarted before the next sample
    /// (its time went back, or the source flagged a gap its time does not
    /// show: a sender's reboot; see [`stage`]). Nothing is bridged: the fast
    /// states restart from the next complete sample as after a gap longer than
    /// [`Tuning::max_bridged_gap_samples`] ([`Estimator::on_gap`]; the estimate is
    /// flagged [`FLAG_REANCHORED`]), the leak sizes, the spool bias and the
    /// oil's stiffness keep their estimate. `time_shift_s` (the new sample's time
    /// minus the time the next sample was due at, s) moves the filter's start
    /// time with the stream, so its convergence time does not start again.
    pub fn on_restart(&mut self, time_shift_s: f64) {
        if !self.started {
            return;
        }
        self.reanchor_pending = true;
        if time_shift_s.is_finite() {
            self.t0_s += time_shift_s;
        }
    }

    /// The oil temperature the model is at, °C: the latest sample's `temp_c`
    /// (to [`OIL_TEMP_STEP_K`]); NaN while no sample carried one (the model
    /// then holds at its parameters as given).
    pub fn oil_temp_c(&self) -> f64 {
        self.oil_temp_c
    }

    /// Processes one sensor sample (one sample period after the previous one).
    pub fn on_sample(&mut self, s: &Sample) -> Estimate {
        let measured_temp = s.temp_c.is_finite();
        if measured_temp {
            // a thermometer: the model follows it, not θ
            self.oil_from_stiffness = None;
            self.follow_oil_temperature(s.temp_c);
        }
        let mut e = self.on_sample_inner(s);
        e.measured = [s.x_m, s.p1_pa, s.p2_pa];
        e.u_v = s.u_v;
        if measured_temp {
            e.oil_temp_sigma_k = 0.0;
            if self.started && s.t_s - self.t0_s < oil::OIL_STIFFNESS_TAU_S {
                e.flags |= FLAG_CONVERGING;
            }
        } else if self.oil_from_stiffness.is_some() {
            self.follow_oil_stiffness(&mut e);
        }
        e.oil_temp_c = self.oil_temp_c;
        (e.laminar_factor_sigma, e.null_leakage_band_lpm) = self.laminar_sigma;
        e
    }

    fn on_sample_inner(&mut self, s: &Sample) -> Estimate {
        self.counters.samples += 1;
        let mut flags = 0;
        let just_started = !self.started;
        // Measured pressures slightly below 0 (noise near tank pressure) are used as
        // they are; the predictions stay clamped at the model's own floor (p_min_pa).
        let limits = self.measured_p_range_pa;
        let p_ok = |p: f64| p.is_finite() && p >= limits.0 && p <= limits.1;
        let use_channel = [s.x_m.is_finite(), p_ok(s.p1_pa), p_ok(s.p2_pa)];
        let usable = s.u_v.is_finite() && use_channel.iter().any(|u| *u);
        if !use_channel.iter().all(|u| *u) {
            self.counters.channels_dropped += 1;
        }
        if !self.started {
            if !(usable && use_channel.iter().all(|u| *u)) {
                self.counters.skipped += 1;
                let mut e = Estimate::empty(s.t_s, self.tuning.states);
                e.flags = FLAG_SKIPPED;
                return e;
            }
            let measured = [s.x_m, s.p1_pa, s.p2_pa];
            let tuning = &self.tuning;
            match &mut self.filter {
                Filter::S6(e) => *e = make_filter::<6, 8>(tuning, &self.model, Some(measured)),
                Filter::S7(e) => *e = make_filter::<7, 8>(tuning, &self.model, Some(measured)),
                Filter::S10(e) => *e = make_filter::<10, 12>(tuning, &self.model, Some(measured)),
                Filter::S11(e) => *e = make_filter::<11, 12>(tuning, &self.model, Some(measured)),
                Filter::S12(e) => *e = make_filter::<12, 12>(tuning, &self.model, Some(measured)),
            }
            if self.counters.samples > 1 {
                flags |= FLAG_RESET;
            }
            self.started = true;
            self.offset_response.clear();
            self.outliers.clear();
            self.t0_s = s.t_s;
            self.leaks_converged = false;
            self.diverged_samples = 0;
            self.mae[0].clear();
            self.mae[1].clear();
            self.reanchor_pending = false;
        } else if self.reanchor_pending && use_channel.iter().all(|u| *u) {
            let measured = [s.x_m, s.p1_pa, s.p2_pa];
            let tuning = &self.tuning;
            match &mut self.filter {
                Filter::S6(e) => reanchor_filter::<6, 8>(e, tuning, &self.model, measured),
                Filter::S7(e) => reanchor_filter::<7, 8>(e, tuning, &self.model, measured),
                Filter::S10(e) => reanchor_filter::<10, 12>(e, tuning, &self.model, measured),
                Filter::S11(e) => reanchor_filter::<11, 12>(e, tuning, &self.model, measured),
                Filter::S12(e) => reanchor_filter::<12, 12>(e, tuning, &self.model, measured),
            }
            self.reanchor_pending = false;
            self.offset_response.clear();
            self.outliers.clear();
            self.diverged_samples = 0;
            flags |= FLAG_REANCHORED;
        }
        // The command of a sample is held until the next one (a zero-order hold): the
        // interval that ends at this sample was driven by the previous sample's command.
        let u_now = if s.u_v.is_finite() { s.u_v } else { self.last_u_v };
        let u = if just_started { u_now } else { self.last_u_v };
        self.last_u_v = u_now;
        let y = SVector::<f64, 3>::new(
            if use_channel[0] { s.x_m } else { 0.0 },
            if use_channel[1] { s.p1_pa } else { 0.0 },
            if use_channel[2] { s.p2_pa } else { 0.0 },
        );
        let mut out = Estimate::empty(s.t_s, self.tuning.states);
        let input = StepInput {
            u,
            y,
            use_channel,
            usable,
            gate_outliers: self.tuning.states >= LEAK_LAYOUT_STATES
                && s.t_s - self.t0_s >= self.tuning.convergence_time_s,
        };
        let memory = StepMemory {
            still_samples: &mut self.still_samples,
            offset_response: &mut self.offset_response,
            outliers: &mut self.outliers,
        };
        let step = match &mut self.filter {
            Filter::S6(e) => step_filter(e, &self.model, &input, &mut out, memory),
            Filter::S7(e) => step_filter(e, &self.model, &input, &mut out, memory),
            Filter::S10(e) => step_filter(e, &self.model, &input, &mut out, memory),
            Filter::S11(e) => step_filter(e, &self.model, &input, &mut out, memory),
            Filter::S12(e) => step_filter(e, &self.model, &input, &mut out, memory),
        };
        match step {
            Ok(clamped) => {
                if clamped {
                    flags |= FLAG_CLAMPED;
                    self.counters.clamped += 1;
                }
            }
            Err(_) => {
                // A non-finite step: restart from the next usable sample.
                self.started = false;
                self.counters.resets += 1;
                out.flags = flags | FLAG_RESET | FLAG_SKIPPED;
                return out;
            }
        }
        self.counters.outliers = self.outliers.left_out();
        if !usable {
            flags |= FLAG_SKIPPED;
            self.counters.skipped += 1;
        }
        for k in 0..2 {
            let r = out.residual[k + 1];
            out.mae_pa[k] = if r.is_finite() {
                self.mae[k].push(r.abs())
            } else {
                self.mae[k].mean()
            };
        }
        let diverged_limit = self.tuning.divergence_reset_m.max(20.0 * out.innovation_sigma[0]);
        if self.tuning.divergence_reset_m > 0.0 && use_channel[0] && out.innovation[0].abs() > diverged_limit
        {
            self.diverged_samples += 1;
            if self.diverged_samples >= DIVERGED_SAMPLES {
                self.started = false;
                self.counters.resets += 1;
            }
        } else {
            self.diverged_samples = 0;
        }
        if s.t_s - self.t0_s < self.tuning.convergence_time_s {
            flags |= FLAG_CONVERGING;
        } else if !self.leaks_converged {
            // The layouts with leak sizes (10 states and more) converge when the
            // three sizes are known to [`CONVERGED_LEAK_SIGMA`] of their start
            // (held sizes, without a random walk, have nothing to converge).
            let limit = CONVERGED_LEAK_SIGMA * self.tuning.p0_leak_m6_s2.sqrt();
            let leaks = I_QE1..(I_QI + 1).min(self.tuning.states as usize);
            let worst = leaks.map(|i| out.sigma[i]).fold(0.0, f64::max);
            if worst > limit && self.tuning.q_leak_m6_s2 > 0.0 {
                flags |= FLAG_CONVERGING;
            } else {
                self.leaks_converged = true;
            }
        }
        let (x_min_m, x_max_m) = (self.model.params.x_min_m, self.model.params.x_max_m);
        let x_m = out.state[3];
        if x_m < x_min_m + END_STOP_MARGIN_M || x_m > x_max_m - END_STOP_MARGIN_M {
            flags |= FLAG_END_STOP;
        }
        out.flags |= flags;
        out
    }
}

fn make_filter<const N: usize, const W: usize>(
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

fn reanchor_filter<const N: usize, const W: usize>(
    e: &mut Ekf<N, 3, W>,
    tuning: &Tuning,
    model: &ProcessModel,
    measured: [f64; 3],
) {
    let fresh = make_filter::<N, W>(tuning, model, Some(measured));
    e.reanchor(*fresh.state(), &tuning.p0_diag::<N>(), FIRST_SLOW_STATE.min(N));
}

fn predict_only<const N: usize, const W: usize>(e: &mut Ekf<N, 3, W>, model: &ProcessModel, u: f64) -> bool {
    let (x, f, _) = model.step(e.state(), u);
    e.predict(x, &f).is_ok()
}

/// What a filter step carries from one sample to the next besides the filter.
struct StepMemory<'a> {
    /// Samples the rod has rested, for θ's hold.
    still_samples: &'a mut u32,
    /// How the estimate answers a pressure offset.
    offset_response: &'a mut BiasResponse,
    /// The outlier watch.
    outliers: &'a mut outlier::OutlierGate,
}

/// What one sample gives a filter step.
struct StepInput {
    /// Valve command, V.
    u: f64,
    /// Measurement [x m, p1 Pa, p2 Pa] (0 where a channel is not used).
    y: SVector<f64, 3>,
    /// Which channels update the filter.
    use_channel: [bool; 3],
    /// Whether the sample updates the filter at all.
    usable: bool,
    /// Whether a lone outlier is left out ([`outlier`]): in the leak filter
    /// only (the thesis filter stays as published), and not while it
    /// converges from its start, when large innovations are its own.
    gate_outliers: bool,
}

/// One predict + update; fills `out`; returns whether the prediction was clamped.
///
/// On an x86-64 processor with AVX2 and FMA the whole step (the model's too)
/// runs compiled for them: the model's arithmetic gives the same bits either
/// way (Rust fuses no multiply-add it is not asked to), the filter's fuses
/// its own ([`Ekf::predict`]).
fn step_filter<const N: usize, const W: usize>(
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
fn step_filter_fma<const N: usize, const W: usize>(
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
fn step_filter_body<const N: usize, const W: usize, A: ekf::MulAdd>(
    e: &mut Ekf<N, 3, W>,
    model: &ProcessModel,
    input: &StepInput,
    out: &mut Estimate,
    memory: StepMemory,
) -> Result<bool, EkfError> {
    let StepInput {
        u,
        ref y,
        use_channel,
        usable,
        gate_outliers,
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
    e.predict_lean::<A>(x_pred, &f)?;
    offset_response.predict(&f);
    let y_pred = ProcessModel::measure(e.state());
    if usable {
        // The channels that update: less a lone outlier once the filter has converged.
        let mut updating = use_channel;
        let inn =
            e.update_selected_choosing::<A>(y, &y_pred, ProcessModel::MEASURED_STATES, |nu, sigma| {
                if gate_outliers {
                    updating = outliers.gate(
                        &[nu[0], nu[1], nu[2]],
                        &[sigma[0], sigma[1], sigma[2]],
                        use_channel,
                    );
                }
                updating
            })?;
        offset_response.update(e, ProcessModel::MEASURED_STATES, updating);
        let mut x = *e.state();
        if model.keep_physical(&mut x).any() {
            e.set_state(x);
        }
        let y_post = ProcessModel::measure(e.state());
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
        out.nis = inn.nis + left_out;
    }
    let x = e.state();
    let sig = e.sigma();
    for i in 0..N.min(MAX_STATES) {
        out.state[i] = x[i];
        out.sigma[i] = sig[i];
    }
    out.offset_response_lpm_per_mpa = offset_response.leak_sizes_lpm_per_mpa();
    if N == 12 {
        out.bulk_scale = x[I_BULK];
        out.bulk_scale_sigma = sig[I_BULK];
    }
    Ok(guard.any())
}

/// The line that reports the oil's stiffness the leak filter estimated: θ (a
/// multiple of the model's bulk modulus `model_bulk_modulus_pa`, Pa) ± `sigma`;
/// below 0.9 it says what a soft rig usually means. `None` without an estimate.
pub fn oil_stiffness_line(theta: f64, sigma: f64, model_bulk_modulus_pa: f64) -> Option<String> {
    if !theta.is_finite() {
        return None;
    }
    let hint = if theta < 0.9 {
        ": softer than the model's, as with entrained air or long hoses (`leakwatch calibrate` on a \
         healthy recording names it and puts it into the model)"
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
mod oil_stiffness_tests {
    use super::oil_stiffness_line;

    #[test]
    fn the_oil_stiffness_line_names_theta_the_modulus_and_a_soft_rig() {
        assert_eq!(oil_stiffness_line(f64::NAN, f64::NAN, 6.89e8), None);
        assert_eq!(
            oil_stiffness_line(0.98, 0.004, 6.89e8).unwrap(),
            "oil stiffness: 0.980 ± 0.004 of the model's bulk modulus (675 of 689 MPa)"
        );
        let soft = oil_stiffness_line(0.74, 0.01, 6.89e8).unwrap();
        assert!(
            soft.starts_with(
                "oil stiffness: 0.740 ± 0.010 of the model's bulk modulus (510 of 689 MPa): softer"
            ),
            "{soft}"
        );
        assert!(soft.contains("leakwatch calibrate"), "{soft}");
    }
}
