//! The simulated rig (docs/model.md#the-simulator): the continuous model integrated with RK4
//! sub-steps, sampled at 1 kHz through the sensor models, driven by a
//! scenario, with a leak fault schedule and sensor faults. It is deliberately not the estimator's
//! forward-Euler model.

use schema::{int, num};
use serde::{Deserialize, Serialize};

use crate::dynamics::{derivative, rk4_step, state_at_rest, Forces, LeakSet, State, I_P1, I_P2, I_X};
use crate::fault::FaultSchedule;
use crate::leakage::LeakFlows;
use crate::params::{ActuatorParams, InvalidParam};
use crate::rng::Rng;
use crate::sample::Sample;
use crate::scenario::Scenario;
use crate::sensor_fault::{Channel, SensorFaultRun, SensorFaultSchedule};
use crate::sensors::SensorParams;
use crate::units::m3_s_to_lpm;

schema::config_struct! {
    /// Integration settings of the simulator, and its pump.
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct SimSettings {
        /// Sample period of the DAQ, s.
        pub sample_period_s: f64 = 1.0e-3 => ["s", num!("a sample period", 1e-5, 1)],
        /// RK4 sub-steps per sample period (40 gives 25 µs steps).
        pub substeps_per_sample: u32 = 40 => ["sub-steps per sample", int!(1, 10000)],
        /// The simulated pump's ripple: amplitude as a fraction of the supply
        /// pressure (0.004: ±0.4 %; 0: none). The filters' model has no ripple.
        pub supply_ripple_fraction: f64 = 0.0 => ["", num!("a fraction of the supply pressure", 0, 0.5)],
        /// The ripple's frequency, Hz.
        pub supply_ripple_hz: f64 = 250.0 => ["Hz", num!("a frequency", 0, 1e5)],
        /// The oil's temperature over the run (None: constant, at the rig's
        /// `oil_temperature.reference_c`).
        pub oil: Option<OilWarmUp> = None,
    }
}

schema::config_struct! {
    /// The simulated oil's temperature over a run, T(t) = T_end + (T_start −
    /// T_end)·e^(−t/τ): a warm-up (or a cool-down); the rig's bulk modulus,
    /// viscous friction and laminar flows follow it
    /// ([`ActuatorParams::set_oil_temperature`]).
    #[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct OilWarmUp {
        /// Temperature at t = 0, °C.
        pub start_c: f64 => ["°C", num!("an oil temperature", -40, 150)],
        /// Temperature the oil tends to, °C.
        pub end_c: f64 => ["°C", num!("an oil temperature", -40, 150)],
        /// Time constant τ, s.
        pub time_constant_s: f64 => ["s", num!("a time constant", 1e-3, 1e7)],
        /// Whether the samples carry it (`temp_c`, to [`TEMP_RESOLUTION_C`]); false: the rig has no thermometer.
        #[serde(default)]
        pub measured: bool,
    }
}

/// Resolution of the simulated oil thermometer, °C.
pub const TEMP_RESOLUTION_C: f64 = 0.1;

impl OilWarmUp {
    /// The temperature at time `t_s` (s), °C.
    pub fn at(&self, t_s: f64) -> f64 {
        self.end_c + (self.start_c - self.end_c) * (-t_s / self.time_constant_s).exp()
    }
}

impl SimSettings {
    /// Checks the settings against their declared ranges, naming the first bad
    /// one (`sim.<field>`) with its range and unit.
    pub fn validate(&self) -> Result<(), InvalidParam> {
        Ok(self.check_ranges("sim")?)
    }
}

/// What the simulator knows that the sensors don't, at one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Sample time, s.
    pub t_s: f64,
    /// True state `[x_sp, p1, p2, x, v, v_sp]`.
    pub state: State,
    /// Forces and flows at that instant.
    pub forces: Forces,
    /// Leak flows along the three paths, m³/s.
    pub leaks: LeakFlows,
}

/// Advances `state` by `dt_s` under constant command `u_v` with `substeps` RK4 steps.
#[inline]
pub fn advance(
    p: &ActuatorParams,
    state: &State,
    u_v: f64,
    leaks: &LeakSet,
    dt_s: f64,
    substeps: u32,
) -> State {
    let h = dt_s / substeps as f64;
    let mut s = *state;
    for _ in 0..substeps {
        s = rk4_step(&s, h, |y| derivative(p, y, u_v, leaks).0);
    }
    s
}

/// The simulated rig.
#[derive(Debug, Clone)]
pub struct Simulator {
    rig: ActuatorParams,
    sensors: SensorParams,
    settings: SimSettings,
    scenario: Scenario,
    faults: FaultSchedule,
    base_leaks: LeakSet,
    rng: Rng,
    state: State,
    k: u64,
    truth: Truth,
    /// The lagging transducers' readings before noise, Pa (set at the first sample).
    lagged: Option<[f64; 2]>,
    /// The pressures at the transducers at the last sample, Pa (the lag's input).
    lag_input: Option<[f64; 2]>,
    /// The rig at its oil law's reference temperature (with a warm-up only).
    rig_at_reference: Option<ActuatorParams>,
    /// The noise seed.
    seed: u64,
    /// The sensor faults at work (None: healthy transducers).
    sensor_faults: Option<SensorFaultRun>,
}

impl Simulator {
    /// [`Simulator::new`] with the default sensors and settings (the encoder,
    /// pressure channels and integrator of docs/model.md#the-simulator).
    pub fn with_default_sensors(
        rig: ActuatorParams,
        scenario: Scenario,
        faults: FaultSchedule,
        seed: u64,
    ) -> Result<Simulator, InvalidParam> {
        Simulator::new(
            rig,
            SensorParams::default(),
            SimSettings::default(),
            scenario,
            faults,
            seed,
        )
    }

    /// A rig with parameters `rig` (whose load is replaced by the scenario's
    /// spring), sensors, settings, scenario, faults and noise seed, at rest at
    /// the scenario's initial position with both chambers at the mean pressure.
    pub fn new(
        mut rig: ActuatorParams,
        sensors: SensorParams,
        settings: SimSettings,
        scenario: Scenario,
        faults: FaultSchedule,
        seed: u64,
    ) -> Result<Simulator, InvalidParam> {
        if scenario.spring.stiffness_n_per_m > 0.0 {
            rig.load = scenario.spring;
        }
        rig.validate()?;
        settings.validate()?;
        sensors.validate()?;
        let state = state_at_rest(scenario.initial_position_m, rig.nominal_chamber_pressure_pa());
        let base_leaks = LeakSet::from_params(&rig);
        let rig_at_reference = settings.oil.map(|_| rig.clone());
        Ok(Simulator {
            rig,
            sensors,
            settings,
            scenario,
            faults,
            base_leaks,
            rng: Rng::new(seed),
            state,
            k: 0,
            lagged: None,
            lag_input: None,
            rig_at_reference,
            seed,
            sensor_faults: None,
            truth: Truth {
                t_s: 0.0,
                state,
                forces: Forces::default(),
                leaks: LeakFlows::default(),
            },
        })
    }

    /// The simulator with sensor faults (docs/model.md#sensor-faults): they
    /// distort the readings, the controller of a closed-loop scenario included
    /// (it reads the measured position), and never the rig's physics; spikes are
    /// drawn from a generator of their own, seeded from the run's seed.
    pub fn with_sensor_faults(mut self, schedule: SensorFaultSchedule) -> Result<Simulator, InvalidParam> {
        schedule.validate()?;
        self.sensor_faults = (!schedule.faults.is_empty()).then(|| SensorFaultRun::new(schedule, self.seed));
        Ok(self)
    }

    /// The rig's parameters (may be changed between samples, e.g. to model
    /// drift; with a warm-up ([`SimSettings::oil`]) each sample sets the bulk
    /// modulus, viscous friction, null leakage and linear leaks from the
    /// parameters the simulator started with).
    pub fn rig_mut(&mut self) -> &mut ActuatorParams {
        &mut self.rig
    }

    /// The rig's parameters.
    pub fn rig(&self) -> &ActuatorParams {
        &self.rig
    }

    /// The oil's temperature at the last sample, °C (NaN without a warm-up, [`SimSettings::oil`]).
    pub fn oil_temp_c(&self) -> f64 {
        let t_s = self.k.saturating_sub(1) as f64 * self.settings.sample_period_s;
        self.settings.oil.map_or(f64::NAN, |oil| oil.at(t_s))
    }

    /// The scenario.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The sample period, s.
    pub fn sample_period_s(&self) -> f64 {
        self.settings.sample_period_s
    }

    /// The current true state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The truth at the last sample returned by [`Simulator::step`].
    pub fn truth(&self) -> &Truth {
        &self.truth
    }

    fn leaks_at(&self, t_s: f64) -> LeakSet {
        let mut l = self.base_leaks;
        self.faults.add_to(t_s, &mut l);
        l
    }

    /// Samples the rig at the current time, computes the command, and
    /// integrates to the next sample. Returns the sample (time, command applied
    /// over the coming period, measurements, reference and true leak flow).
    pub fn step(&mut self) -> Sample {
        let dt = self.settings.sample_period_s;
        let t = self.k as f64 * dt;
        let mut temp_c = f64::NAN;
        if let (Some(oil), Some(base)) = (self.settings.oil, self.rig_at_reference.as_ref()) {
            let temp = oil.at(t);
            self.rig.set_oil_temperature(base, temp);
            self.base_leaks = LeakSet::from_params(&self.rig);
            if oil.measured {
                temp_c = (temp * TEMP_RESOLUTION_C.recip()).round() / TEMP_RESOLUTION_C.recip();
            }
        }
        let leaks = self.leaks_at(t);
        let s = self.state;
        let [x_meas, p1_meas, p2_meas] = self.read_sensors(&s, t);
        let x_sp_meas = self.sensors.spool(s[0], &mut self.rng);
        let u = self.scenario.command_v(t, x_meas);
        let ripple = self.settings.supply_ripple_fraction;
        let supply = self.rig.supply_pressure_pa;
        let rippled = |t_s: f64| {
            let phase = 2.0 * std::f64::consts::PI * self.settings.supply_ripple_hz * t_s;
            supply * (1.0 + ripple * phase.sin())
        };
        if ripple > 0.0 {
            self.rig.supply_pressure_pa = rippled(t);
        }
        let (_, forces) = derivative(&self.rig, &s, u, &leaks);
        let load_meas = self.sensors.load_cell(forces.load_n, &mut self.rng);
        let lq = forces.leaks;
        self.truth = Truth {
            t_s: t,
            state: s,
            forces,
            leaks: lq,
        };
        let mut fault_flow = LeakSet::NONE;
        self.faults.add_to(t, &mut fault_flow);
        let fq = fault_flow.flows(s[1], s[2], self.rig.return_pressure_pa);
        let sample = Sample {
            t_s: t,
            u_v: u,
            x_m: x_meas,
            p1_pa: p1_meas,
            p2_pa: p2_meas,
            x_sp_m: x_sp_meas,
            f_load_n: load_meas,
            ref_m: self.scenario.reference_m(t),
            q_leak_lpm: m3_s_to_lpm(fq.ext1_m3_s + fq.ext2_m3_s + fq.int_m3_s),
            temp_c,
        };
        // integrate to the next sample; leak coefficients follow ramps per sub-step
        let n = self.settings.substeps_per_sample;
        let h = dt / n as f64;
        let mut y = s;
        for j in 0..n {
            let lj = if self.faults.faults.is_empty() {
                leaks
            } else {
                self.leaks_at(t + j as f64 * h)
            };
            if ripple > 0.0 {
                // the pump's ripple at the middle of the sub-step
                self.rig.supply_pressure_pa = rippled(t + (j as f64 + 0.5) * h);
            }
            y = rk4_step(&y, h, |z| derivative(&self.rig, z, u, &lj).0);
        }
        self.rig.supply_pressure_pa = supply;
        self.state = y;
        self.k += 1;
        sample
    }

    /// The readings [x (m), p1 (Pa), p2 (Pa)] of state `s` at time `t_s` (s):
    /// the transducers' values (with the installation's effects), distorted by
    /// the sensor faults, through the sensor models. The noise is drawn in the
    /// same order with and without faults.
    fn read_sensors(&mut self, s: &State, t_s: f64) -> [f64; 3] {
        let mut p = if self.sensors.has_installation_effects() {
            self.at_transducers(s)
        } else {
            [s[1], s[2]]
        };
        // the misreading the model knows of ([`ActuatorParams::pressure_misreading_pa`])
        for (p, z) in p.iter_mut().zip(self.rig.pressure_misreading_pa) {
            if z != 0.0 {
                *p += z;
            }
        }
        let mut s = *s;
        if self.sensors.sample_jitter_s > 0.0 && self.sensors.enabled {
            // read at t + δ: each value moved by its rate times δ (the
            // pressures' rates do not depend on the command)
            let delta = self.sensors.sample_jitter_s * self.rng.normal();
            let (rate, _) = derivative(&self.rig, &s, 0.0, &self.leaks_at(t_s));
            s[I_X] += rate[I_X] * delta;
            p[0] += rate[I_P1] * delta;
            p[1] += rate[I_P2] * delta;
        }
        let s = &s;
        let (sensors, rng) = (&self.sensors, &mut self.rng);
        let Some(run) = self.sensor_faults.as_mut() else {
            return [
                sensors.encoder(s[I_X], rng),
                sensors.pressure_channel(0, p[0], rng),
                sensors.pressure_channel(1, p[1], rng),
            ];
        };
        let dt = self.settings.sample_period_s;
        let x = run.read(Channel::X, t_s, dt, |d| sensors.encoder_distorted(s[I_X], d, rng));
        let p1 = run.read(Channel::P1, t_s, dt, |d| {
            sensors.pressure_channel_distorted(0, p[0], d, rng)
        });
        let p2 = run.read(Channel::P2, t_s, dt, |d| {
            sensors.pressure_channel_distorted(1, p[1], d, rng)
        });
        [x, p1, p2]
    }

    /// The pressures at the transducers, Pa: at the valve manifold the chambers'
    /// plus the line's drop (R·Q1 into chamber 1, −R·Q2 out of chamber 2), through
    /// the transducers' first-order lag τ·ẏ = p − y, solved exactly for a
    /// pressure linear between samples (from the first sample's pressures).
    fn at_transducers(&mut self, s: &State) -> [f64; 2] {
        let r = self.sensors.line_resistance_pa_s_per_m3;
        let mut p = [s[1], s[2]];
        if r > 0.0 {
            let q = crate::dynamics::valve_flows(&self.rig, s[0], s[1], s[2]);
            p[0] += r * q.q1_m3_s;
            p[1] -= r * q.q2_m3_s;
        }
        let tau = self.sensors.pressure_lag_s;
        if tau <= 0.0 {
            return p;
        }
        let period = self.settings.sample_period_s;
        let e = (-period / tau).exp();
        let before = *self.lag_input.get_or_insert(p);
        let lagged = self.lagged.get_or_insert(p);
        for ((l, now), was) in lagged.iter_mut().zip(p).zip(before) {
            let slope = (now - was) / period;
            *l = now - tau * slope + (*l - was + tau * slope) * e;
        }
        self.lag_input = Some(p);
        *lagged
    }

    /// Runs `seconds` of the scenario and returns every sample.
    pub fn run(&mut self, seconds: f64) -> Vec<Sample> {
        let n = (seconds / self.settings.sample_period_s).round() as usize;
        (0..n).map(|_| self.step()).collect()
    }
}
