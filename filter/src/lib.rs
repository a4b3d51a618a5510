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
mod estimate;
mod flags;
pub mod mae;
pub mod oil;
pub mod outlier;
pub mod stage;
mod step;
pub mod track;
pub mod tuning;

use model::process::{ProcessModel, I_BULK, I_QE1, I_QI};
use model::{ActuatorParams, Sample};
use nalgebra::SVector;

pub use bias::BiasResponse;
pub use ekf::{Ekf, EkfError, Innovation};
pub use estimate::Estimate;
pub use flags::{
    END_STOP_MARGIN_M, FLAGS_ALL, FLAGS_UNSETTLED, FLAG_AFTER_GAP, FLAG_CLAMPED, FLAG_CONVERGING,
    FLAG_END_STOP, FLAG_OIL_PAST_RANGE, FLAG_REANCHORED, FLAG_RESET, FLAG_SKIPPED,
};
pub use mae::MovingMae;
pub use oil::{oil_stiffness_line, OilFromStiffness};
pub use stage::{EstimatorStage, StageEstimate};
pub use track::{TrackWatch, Tracking, DIVERGED_SAMPLES};
pub use tuning::{Init, Tuning};

use step::{make_filter, predict_only, reanchor_filter, step_filter, StepInput, StepMemory};

/// Number of states an [`Estimate`] carries in [`Estimate::state`] (the 11-state
/// leak model with spool bias; the 12th state of the 12-state layout, the oil's
/// stiffness, has its own fields).
pub const MAX_STATES: usize = 11;
/// Largest number of states any layout has (the leak model with spool bias and oil stiffness).
pub const MAX_LAYOUT_STATES: usize = 12;
/// The fewest states of a leak filter's layout (the leak sizes from state 7 on).
const LEAK_LAYOUT_STATES: u32 = 10;

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
    /// The last sample's pressure readings [p1, p2], Pa: a reading that
    /// repeats it is not a lagging one (its lag is not counted).
    last_pressures_pa: [f64; 2],
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
    /// Whether the filter follows the readings ([`track`]).
    track: TrackWatch,
    /// A gap too long to bridge, or a lost track ([`track`]): re-anchor on the next full sample.
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

impl Estimator {
    /// A stage for model parameters `params` and filter settings `tuning`.
    pub fn new(params: ActuatorParams, tuning: Tuning) -> Result<Self, String> {
        tuning.validate()?;
        params.validate().map_err(|e| e.to_string())?;
        let measured_p_range_pa = params.measured_pressure_range_pa();
        let mut params = params;
        if tuning.states < 10 {
            // The thesis' layouts keep the thesis' model: no line drop, no supply sag (its
            // published start, 1e4 m² on the rod position, throws the state
            // where the sagged orifice law's finite differences overflow).
            params.supply_sag_pa_per_m3_s = 0.0;
            params.line_resistance_pa_s_per_m3 = 0.0;
        }
        let params_at_reference = params.clone();
        let oil_from_stiffness = match params.oil_temperature.reference_stiffness {
            Some(theta_ref) if tuning.states == 12 => {
                OilFromStiffness::new(&params.oil_temperature, theta_ref)
            }
            _ => None,
        };
        let mut model = ProcessModel::new(params, tuning.sample_period_s);
        model.set_substeps(tuning.substeps);
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
            last_pressures_pa: [f64::NAN; 2],
            started: false,
            t0_s: 0.0,
            leaks_converged: false,
            still_samples: 0,
            offset_response: BiasResponse::default(),
            outliers: outlier::OutlierGate::default(),
            track: TrackWatch::default(),
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
            let input = StepInput::plain(u, y);
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

    /// Processes one sensor sample (one sample period after the previous one),
    /// its pressures less the model's `pressure_misreading_pa`.
    pub fn on_sample(&mut self, s: &Sample) -> Estimate {
        let mut e = Estimate::empty(s.t_s, self.tuning.states);
        self.on_sample_into(s, &mut e);
        e
    }

    /// [`Self::on_sample`] into `e`, which it overwrites whole: the hot path's
    /// form (the estimate is written where the caller keeps it, not copied there).
    pub fn on_sample_into(&mut self, s: &Sample, e: &mut Estimate) {
        // the transducers' misreading the model knows comes off each reading
        let misreading_pa = self.params_at_reference.pressure_misreading_pa;
        let corrected;
        let s = if misreading_pa == [0.0; 2] {
            s
        } else {
            corrected = Sample {
                p1_pa: s.p1_pa - misreading_pa[0],
                p2_pa: s.p2_pa - misreading_pa[1],
                ..*s
            };
            &corrected
        };
        let measured_temp = s.temp_c.is_finite();
        if measured_temp {
            // a thermometer: the model follows it, not θ
            self.oil_from_stiffness = None;
            self.follow_oil_temperature(s.temp_c);
        }
        self.on_sample_inner(s, e);
        e.measured = [s.x_m, s.p1_pa, s.p2_pa];
        e.u_v = s.u_v;
        if measured_temp {
            e.oil_temp_sigma_k = 0.0;
            if self.started && s.t_s - self.t0_s < oil::OIL_STIFFNESS_TAU_S {
                e.flags |= FLAG_CONVERGING;
            }
        } else if self.oil_from_stiffness.is_some() {
            self.follow_oil_stiffness(e);
        }
        e.oil_temp_c = self.oil_temp_c;
        (e.laminar_factor_sigma, e.null_leakage_band_lpm) = self.laminar_sigma;
    }

    /// The filter's part of [`Self::on_sample_into`]: `out` starts empty.
    fn on_sample_inner(&mut self, s: &Sample, out: &mut Estimate) {
        *out = Estimate::empty(s.t_s, self.tuning.states);
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
                out.flags = FLAG_SKIPPED;
                return;
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
            self.track.clear();
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
            self.offset_response.reanchor();
            self.outliers.clear();
            self.track.clear();
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
        let lag_s = self.counted_lags(s);
        let input = StepInput {
            t_s: s.t_s,
            u,
            y,
            use_channel,
            usable,
            gate_outliers: self.tuning.states >= LEAK_LAYOUT_STATES
                && s.t_s - self.t0_s >= self.tuning.convergence_time_s,
            jitter_s: self.tuning.sample_jitter_s,
            pressure_lag_s: lag_s,
            lag_correction_s: self.tuning.lag_correction_s,
        };
        let memory = StepMemory {
            still_samples: &mut self.still_samples,
            offset_response: &mut self.offset_response,
            outliers: &mut self.outliers,
        };
        let step = match &mut self.filter {
            Filter::S6(e) => step_filter(e, &self.model, &input, out, memory),
            Filter::S7(e) => step_filter(e, &self.model, &input, out, memory),
            Filter::S10(e) => step_filter(e, &self.model, &input, out, memory),
            Filter::S11(e) => step_filter(e, &self.model, &input, out, memory),
            Filter::S12(e) => step_filter(e, &self.model, &input, out, memory),
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
                return;
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
        let watch_lost = input.gate_outliers && self.tuning.init == Init::Measured;
        let (nu_x, sigma_x) = (out.innovation[0], out.innovation_sigma[0]);
        match self
            .track
            .after_sample(out.nis, watch_lost, nu_x, sigma_x, self.tuning.divergence_reset_m)
        {
            Tracking::Follows => {}
            Tracking::Lost => self.reanchor_pending = true,
            Tracking::Diverged => {
                self.started = false;
                self.counters.resets += 1;
            }
        }
        if self.converging(s.t_s, out) {
            flags |= FLAG_CONVERGING;
        }
        let (x_min_m, x_max_m) = (self.model.params.x_min_m, self.model.params.x_max_m);
        let x_m = out.state[3];
        if x_m < x_min_m + END_STOP_MARGIN_M || x_m > x_max_m - END_STOP_MARGIN_M {
            flags |= FLAG_END_STOP;
        }
        out.flags |= flags;
    }

    /// The lags (p1, p2) the NIS counts for sample `s`, s: the tuning's, 0 for
    /// a repeated reading (a stuck one does not lag a moving pressure).
    fn counted_lags(&mut self, s: &Sample) -> [f64; 2] {
        let readings = [s.p1_pa, s.p2_pa];
        let lag_s = std::array::from_fn(|k| {
            if readings[k] == self.last_pressures_pa[k] {
                0.0
            } else {
                self.tuning.pressure_lag_s[k]
            }
        });
        self.last_pressures_pa = readings;
        lag_s
    }

    /// Whether the filter still converges at `t_s` (s), estimate `out`: within
    /// `convergence_time_s` of its start; with leak sizes, until all three are
    /// known to [`CONVERGED_LEAK_SIGMA`] of their start (held ones converge).
    fn converging(&mut self, t_s: f64, out: &Estimate) -> bool {
        if t_s - self.t0_s < self.tuning.convergence_time_s {
            return true;
        }
        if self.leaks_converged {
            return false;
        }
        let limit = CONVERGED_LEAK_SIGMA * self.tuning.p0_leak_m6_s2.sqrt();
        let leaks = I_QE1..(I_QI + 1).min(self.tuning.states as usize);
        let worst = leaks.map(|i| out.sigma[i]).fold(0.0, f64::max);
        if worst > limit && self.tuning.q_leak_m6_s2 > 0.0 {
            true
        } else {
            self.leaks_converged = true;
            false
        }
    }
}
