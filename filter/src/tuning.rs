//! Filter settings: the thesis' tuning (the default) and one derived from the
//! sensors, in the TOML config under `[estimator]`.

use nalgebra::SVector;
use schema::{int, num, Range};
use serde::{Deserialize, Serialize};

/// How the filter's initial state is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Init {
    /// The thesis' x0: everything zero but both pressures at `init_pressure_pa`.
    Thesis,
    /// Position and pressures from the first usable sample, F_e from the pressure difference.
    Measured,
}

schema::config_struct! {
    /// Everything the estimator needs besides the physical parameters.
    ///
    /// Q is the process noise added per sample (variance per step), R the
    /// measurement noise variance and P0 the initial covariance, each in the
    /// square of its state's SI unit. The ranges: variances in SI squared units,
    /// capped at the square of a physically absurd value of their state (1 cm of
    /// spool, 1 GPa, 10 m, 100 m/s, 10 MN, 0.01 m³/s); P0 up to the thesis' 1e4
    /// in every state; P0 > 0 (a zero initial variance makes the square-root
    /// factor singular). The defaults are the thesis' tuning ([`Tuning::thesis`]).
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct Tuning {
        /// Number of states: 6 (friction and load from the parameters), 7 (plus the
        /// effective load F_e), 10 (plus the three leak sizes q_e1, q_e2, q_i), 11
        /// (plus the spool null bias b) or 12 (plus the oil's stiffness θ, a multiple
        /// of the model's bulk modulus).
        pub states: u32 = 7 => ["", Range::OneOf(&[6, 7, 10, 11, 12])],
        /// Sample period T, s.
        pub sample_period_s: f64 = 1e-3 => ["s", num!("a number", 1e-5, 1.0)],
        /// Euler sub-steps per sample (1 = the thesis): forward Euler for 6 and 7 states,
        /// symplectic for the layouts with leaks (docs/model.md#discretisation).
        pub substeps: u32 = 1 => ["Euler steps per sample", int!(1, 100)],
        /// Initial state.
        pub init: Init = Init::Thesis,
        /// Initial chamber pressures for `init = "thesis"`, Pa.
        pub init_pressure_pa: f64 = 6.8e6 => ["Pa", num!("a number", 0.0, 1000000000.0)],
        /// Q of the spool position, m².
        pub q_x_sp_m2: f64 = 1e-10 => ["m²", num!("a number", 0.0, 0.0001)],
        /// Q of each chamber pressure, Pa².
        pub q_p_pa2: f64 = 1e4 => ["Pa²", num!("a number", 0.0, 1e18)],
        /// Q of the rod position, m².
        pub q_x_m2: f64 = 1e-6 => ["m²", num!("a number", 0.0, 100.0)],
        /// Q of the rod velocity, m²/s².
        pub q_v_m2_s2: f64 = 1e-4 => ["m²/s²", num!("a number", 0.0, 10000.0)],
        /// Q of the spool velocity, m²/s².
        pub q_v_sp_m2_s2: f64 = 1e-20 => ["m²/s²", num!("a number", 0.0, 10000.0)],
        /// Q of the effective load F_e (its random walk), N².
        pub q_f_e_n2: f64 = 1e2 => ["N²", num!("a number", 0.0, 100000000000000.0)],
        /// Q of each leak size q_e1, q_e2, q_i (their random walk), m⁶/s².
        pub q_leak_m6_s2: f64 = 1e-16 => ["m⁶/s²", num!("a number", 0.0, 0.0001)],
        /// Q of the spool null bias (its random walk), m².
        pub q_bias_m2: f64 = 1e-20 => ["m²", num!("a number", 0.0, 0.0001)],
        /// Q of the oil-stiffness scale θ (its random walk), 1 (dimensionless, squared).
        pub q_bulk_scale: f64 = 0.0 => ["(dimensionless)²", num!("a number", 0.0, 1.0)],
        /// R of the rod position, m².
        pub r_x_m2: f64 = 1e-4 => ["m²", num!("a number", 1e-30, 100.0)],
        /// R of each chamber pressure, Pa².
        pub r_p_pa2: f64 = 1e6 => ["Pa²", num!("a number", 1e-30, 1e18)],
        /// The DAQ's sample-time jitter, s (RMS; 0: none): a reading taken
        /// δ off its stamp is off by its rate times δ, so each channel's R
        /// grows by (rate · jitter)² at the predicted rates. `commission`
        /// sets it from the recording (docs/identification.md).
        pub sample_jitter_s: f64 = 0.0 => ["s", num!("a time", 0.0, 0.001)],
        /// The pressure transducers' first-order lags (p1, p2), s (0: none):
        /// a transducer lagging by τ reads p − τ·ṗ. The filter's NIS counts
        /// (τ·ṗ)², at the predicted rates, in each pressure's variance (not
        /// for a reading that repeats the last one); its gains and its
        /// outlier test do not. `commission` sets them from the recording
        /// (docs/identification.md).
        pub pressure_lag_s: [f64; 2] = [0.0; 2] => ["s", num!("lags", 0.0, 0.01)],
        /// The pressure transducers' delay taken off the leak sizes, s (0:
        /// none): a transducer delayed by d reads p − d·ṗ, which moves the
        /// leak sizes by d times the filter's own response to it
        /// ([`Estimate::delay_response_lpm_per_ms`](crate::Estimate::delay_response_lpm_per_ms)).
        /// `commission` fits it to the leak sizes' swings on its recording
        /// (docs/estimator.md).
        pub lag_correction_s: f64 = 0.0 => ["s", num!("a time", 0.0, 0.01)],
        /// P0 of the spool position, m².
        pub p0_x_sp_m2: f64 = 1e4 => ["m²", num!("a number", 1e-30, 10000.0)],
        /// P0 of each chamber pressure, Pa².
        pub p0_p_pa2: f64 = 1e4 => ["Pa²", num!("a number", 1e-30, 1e18)],
        /// P0 of the rod position, m².
        pub p0_x_m2: f64 = 1e4 => ["m²", num!("a number", 1e-30, 10000.0)],
        /// P0 of the rod velocity, m²/s².
        pub p0_v_m2_s2: f64 = 1e4 => ["m²/s²", num!("a number", 1e-30, 10000.0)],
        /// P0 of the spool velocity, m²/s².
        pub p0_v_sp_m2_s2: f64 = 1e4 => ["m²/s²", num!("a number", 1e-30, 10000.0)],
        /// P0 of F_e, N².
        pub p0_f_e_n2: f64 = 1e4 => ["N²", num!("a number", 1e-30, 100000000000000.0)],
        /// P0 of each leak size, m⁶/s².
        pub p0_leak_m6_s2: f64 = 1e4 => ["m⁶/s²", num!("a number", 1e-30, 10000.0)],
        /// P0 of the spool null bias, m².
        pub p0_bias_m2: f64 = 1e4 => ["m²", num!("a number", 1e-30, 10000.0)],
        /// P0 of the oil-stiffness scale θ (which starts at 1), 1 (dimensionless, squared).
        pub p0_bulk_scale: f64 = 1e-2 => ["(dimensionless)²", num!("a number", 1e-30, 1.0)],
        /// Window of the moving average of |residual| (the thesis' MAE), samples.
        pub mae_window_samples: usize = 4000 => ["samples", int!(1, 3600000, "(an hour at 1 kHz)")],
        /// Longest run of missing samples bridged by prediction; after a longer gap the
        /// fast states restart from the next sample and the leak sizes and spool bias are kept.
        /// A DAQ's dropouts of up to 10 ms are bridged: a re-anchor blinds the detector
        /// for `recovery_s`, and a poor prediction across the gap trips the NIS gate anyway.
        pub max_bridged_gap_samples: u32 = 10 => ["samples", int!(0, 3600000, "(an hour at 1 kHz)")],
        /// A position innovation beyond this, m (or beyond 20 of its standard deviations,
        /// if larger), held for 200 samples, resets the filter; 0 = never (the thesis'
        /// filter, whose R_x trusts the encoder to 1 cm only, drifts by centimetres).
        pub divergence_reset_m: f64 = 0.0 => ["m", num!("a number", 0.0, 100.0)],
        /// Time after a (re)start during which estimates are flagged as converging, s.
        pub convergence_time_s: f64 = 2.0 => ["s", num!("a number", 0.0, 1000000.0)],
    }
}

impl schema::FieldType for Init {
    const KIND: schema::Kind = schema::Kind::Choice(&["thesis", "measured"]);
}

impl Tuning {
    /// The thesis' tuning (docs/model.md#tuning), the declared defaults:
    /// Q = diag(1e-10, 1e4, 1e4, 1e-6, 1e-4, 1e-20, 1e2),
    /// R = diag(1e-4, 1e6, 1e6), x0 with pressures at 6.8 MPa, P0 = 1e4·I, 7 states.
    pub fn thesis() -> Self {
        Tuning::default()
    }

    /// A tuning derived from the sensors and the model's known errors:
    /// R from the encoder quantum (3e-5 m) and the pressure channel (12-bit ADC
    /// over 20.7 MPa plus 5 kPa noise, about 5.2 kPa RMS); Q from the flow and
    /// force errors the healthy model makes; 12 states (leak model with spool bias and the oil's stiffness);
    /// initial state from the first sample.
    pub fn sensor_derived() -> Self {
        Tuning {
            states: 12,
            init: Init::Measured,
            q_x_sp_m2: 1e-14,
            q_p_pa2: 1e6,
            q_x_m2: 1e-12,
            q_v_m2_s2: 1e-6,
            q_v_sp_m2_s2: 1e-8,
            q_f_e_n2: 1e4,
            q_leak_m6_s2: 2e-18,
            r_x_m2: 1e-10,
            r_p_pa2: 2.7e7,
            p0_x_sp_m2: 1e-10,
            p0_p_pa2: 1e11,
            p0_x_m2: 1e-8,
            p0_v_m2_s2: 1e-2,
            p0_v_sp_m2_s2: 1e-4,
            p0_f_e_n2: 1e6,
            p0_leak_m6_s2: 1e-10,
            q_bias_m2: 1e-20,
            p0_bias_m2: 1e-11,
            // θ starts at the model's stiffness, ±20 % (a rig's oil is 0-30 % softer
            // than the data sheet's), and may wander by 0.055 %/√s at 1 kHz (temperature, air).
            q_bulk_scale: 3e-10,
            p0_bulk_scale: 0.04,
            divergence_reset_m: 0.02,
            // The leak sizes converge within 0.2 s of a start (a leak present at start included).
            convergence_time_s: 1.0,
            ..Tuning::thesis()
        }
    }

    /// A preset by name: `thesis` or `sensor`.
    pub fn preset(name: &str) -> Option<Tuning> {
        match name {
            "thesis" => Some(Tuning::thesis()),
            "sensor" => Some(Tuning::sensor_derived()),
            _ => None,
        }
    }

    /// Checks every field against its declared range, naming the first bad
    /// one (`[estimator] q_p_pa2 = ...: must be ...`) with its range and unit.
    pub fn validate(&self) -> Result<(), String> {
        self.check_ranges("").map_err(|e| format!("[estimator] {e}"))
    }

    fn per_state(v: [f64; 9]) -> [f64; 12] {
        [
            v[0], v[1], v[1], v[2], v[3], v[4], v[5], v[6], v[6], v[6], v[7], v[8],
        ]
    }

    /// diag(Q) for an `N`-state layout, SI squared units.
    pub fn q_diag<const N: usize>(&self) -> SVector<f64, N> {
        let all = Self::per_state([
            self.q_x_sp_m2,
            self.q_p_pa2,
            self.q_x_m2,
            self.q_v_m2_s2,
            self.q_v_sp_m2_s2,
            self.q_f_e_n2,
            self.q_leak_m6_s2,
            self.q_bias_m2,
            self.q_bulk_scale,
        ]);
        SVector::<f64, N>::from_fn(|i, _| all[i])
    }

    /// diag(P0) for an `N`-state layout, SI squared units.
    pub fn p0_diag<const N: usize>(&self) -> SVector<f64, N> {
        let all = Self::per_state([
            self.p0_x_sp_m2,
            self.p0_p_pa2,
            self.p0_x_m2,
            self.p0_v_m2_s2,
            self.p0_v_sp_m2_s2,
            self.p0_f_e_n2,
            self.p0_leak_m6_s2,
            self.p0_bias_m2,
            self.p0_bulk_scale,
        ]);
        SVector::<f64, N>::from_fn(|i, _| all[i])
    }

    /// diag(R): rod position m², pressures Pa².
    pub fn r_diag(&self) -> SVector<f64, 3> {
        SVector::<f64, 3>::new(self.r_x_m2, self.r_p_pa2, self.r_p_pa2)
    }
}
