//! Scheduled sensor faults of the simulated rig (docs/model.md#sensor-faults)
//! and their command-line spec `CHANNEL:KIND[=VALUE][,KEY=VALUE]@ONSET`, e.g.
//! `p1:drift=200kPa/min,max=500kPa@30s`, `p2:span=+2%@20s`, `p1:stuck@40s`,
//! `x:drift=1mm/min@10s`, `p2:spikes=2MPa,rate=0.5/s@0s`.
//!
//! A fault changes what a transducer reads, never the rig: the simulator forms
//! each reading from the true value (and the installation's effects), lets the
//! channel's faults distort it ([`Distortion`]) around the noise, quantises it,
//! and freezes it while the channel is stuck ([`SensorFaultRun::read`]).

use crate::params::InvalidParam;
use crate::rng::Rng;

/// A measured channel of the rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// Chamber-1 pressure, Pa.
    P1,
    /// Chamber-2 pressure, Pa.
    P2,
    /// Rod position, m.
    X,
}

impl Channel {
    /// Every channel, in the order of [`Channel::index`].
    pub const ALL: [Channel; 3] = [Channel::P1, Channel::P2, Channel::X];

    /// The channel's name in a spec: `p1`, `p2` or `x`.
    pub fn name(self) -> &'static str {
        match self {
            Channel::P1 => "p1",
            Channel::P2 => "p2",
            Channel::X => "x",
        }
    }

    /// The channel named `name` (`p1`, `p2`, `x`).
    pub fn from_name(name: &str) -> Option<Channel> {
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }

    /// 0, 1, 2 for p1, p2, x.
    pub fn index(self) -> usize {
        match self {
            Channel::P1 => 0,
            Channel::P2 => 1,
            Channel::X => 2,
        }
    }

    /// Whether the channel reads a pressure (Pa) rather than a position (m).
    pub fn is_pressure(self) -> bool {
        self != Channel::X
    }

    /// The channel's SI unit: `Pa` or `m`.
    pub fn si_unit(self) -> &'static str {
        if self.is_pressure() {
            "Pa"
        } else {
            "m"
        }
    }
}

/// What goes wrong with a transducer. Values are in the channel's SI unit
/// (Pa for p1 and p2, m for x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SensorFaultKind {
    /// A zero offset growing at `rate_si_per_s` from the onset until its size reaches
    /// `max_abs_si`: offset(t) = sign(r)·min(|r|·(t − t_on), max).
    Drift {
        /// Rate of the offset, Pa/s or m/s (either sign).
        rate_si_per_s: f64,
        /// Largest |offset|, Pa or m (infinite: no limit).
        max_abs_si: f64,
    },
    /// The reading times (1 + g·min(1, (t − t_on)/ramp)) from the onset, applied
    /// to the value before the noise: the error grows over `ramp_s` (0: at once).
    Span {
        /// g, relative (0.02: reads 2 % high).
        gain_error: f64,
        /// Time the error takes to grow to g, s (0: at once).
        ramp_s: f64,
    },
    /// The reading frozen at its value at the onset, noise and all.
    Stuck,
    /// Isolated outliers of ±`amplitude_si` (sign at random), each sample one
    /// with probability `rate_hz`·T (T the sample period), from a seeded generator.
    Spikes {
        /// Size of an outlier, Pa or m.
        amplitude_si: f64,
        /// Mean number of outliers per second, 1/s.
        rate_hz: f64,
    },
}

/// A sensor fault on one channel from a scheduled time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFault {
    /// The faulty channel.
    pub channel: Channel,
    /// What goes wrong.
    pub kind: SensorFaultKind,
    /// Time the fault starts, s.
    pub onset_s: f64,
}

/// Most outliers per second a spikes fault may ask for, 1/s (they stay isolated).
pub const MAX_SPIKE_RATE_HZ: f64 = 100.0;

/// A channel's distortion at one sample, applied by the sensor models
/// ([`crate::sensors::SensorParams::pressure_channel_distorted`],
/// [`crate::sensors::SensorParams::encoder_distorted`]):
/// reading = ADC(v·gain + offset + noise + spike), v the healthy transducer's
/// value before the noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distortion {
    /// Factor on the value before the noise, relative (1: none).
    pub gain: f64,
    /// Offset added before the noise, Pa or m.
    pub offset_si: f64,
    /// Outlier added after the noise, Pa or m (0: none).
    pub spike_si: f64,
}

impl Distortion {
    /// No distortion: the healthy reading, bit for bit.
    pub const NONE: Distortion = Distortion {
        gain: 1.0,
        offset_si: 0.0,
        spike_si: 0.0,
    };

    /// `value` (Pa or m, before the noise) with the gain and the offset.
    #[inline]
    pub fn before_noise(&self, value: f64) -> f64 {
        value * self.gain + self.offset_si
    }
}

impl SensorFault {
    /// Whether the fault acts at time `t_s` (s).
    #[inline]
    pub fn active_at(&self, t_s: f64) -> bool {
        t_s >= self.onset_s
    }

    /// A drift's offset at time `t_s` (s), Pa or m (0 for other kinds and before the onset).
    pub fn drift_offset_si(&self, t_s: f64) -> f64 {
        match self.kind {
            SensorFaultKind::Drift {
                rate_si_per_s,
                max_abs_si,
            } if self.active_at(t_s) => {
                let size = (rate_si_per_s.abs() * (t_s - self.onset_s)).min(max_abs_si);
                size.copysign(rate_si_per_s)
            }
            _ => 0.0,
        }
    }

    /// Checks the values, naming the first bad one (`sensor_fault.<channel>.<field>`).
    pub fn validate(&self) -> Result<(), InvalidParam> {
        let ch = self.channel.name();
        let bad = |field: &str, value: f64, expected: &str| InvalidParam {
            field: format!("sensor_fault.{ch}.{field}"),
            value,
            expected: expected.to_string(),
        };
        if !(self.onset_s.is_finite() && self.onset_s >= 0.0) {
            return Err(bad("onset_s", self.onset_s, "an onset of 0 s or later"));
        }
        let (scale, what) = if self.channel.is_pressure() {
            (1e8, "Pa")
        } else {
            (10.0, "m")
        };
        match self.kind {
            SensorFaultKind::Drift {
                rate_si_per_s,
                max_abs_si,
            } => {
                if !(rate_si_per_s.is_finite() && rate_si_per_s.abs() <= scale) {
                    return Err(bad("drift.rate_si_per_s", rate_si_per_s, rate_range(what)));
                }
                if max_abs_si.is_nan() || max_abs_si <= 0.0 {
                    return Err(bad("drift.max_abs_si", max_abs_si, "a positive largest offset"));
                }
            }
            SensorFaultKind::Span { gain_error, ramp_s } => {
                if !(gain_error.is_finite() && gain_error.abs() <= 0.5) {
                    return Err(bad(
                        "span.gain_error",
                        gain_error,
                        "a span error from -0.5 to 0.5",
                    ));
                }
                if !(ramp_s.is_finite() && ramp_s >= 0.0) {
                    return Err(bad("span.ramp_s", ramp_s, "a ramp of 0 s or more"));
                }
            }
            SensorFaultKind::Stuck => {}
            SensorFaultKind::Spikes {
                amplitude_si,
                rate_hz,
            } => {
                if !(amplitude_si.is_finite() && amplitude_si > 0.0 && amplitude_si <= scale) {
                    return Err(bad("spikes.amplitude_si", amplitude_si, amplitude_range(what)));
                }
                if !(rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= MAX_SPIKE_RATE_HZ) {
                    return Err(bad(
                        "spikes.rate_hz",
                        rate_hz,
                        "a rate above 0 and at most 100 per second",
                    ));
                }
            }
        }
        Ok(())
    }
}

fn rate_range(unit: &str) -> &'static str {
    if unit == "Pa" {
        "a drift rate of at most 1e8 Pa/s in size"
    } else {
        "a drift rate of at most 10 m/s in size"
    }
}

fn amplitude_range(unit: &str) -> &'static str {
    if unit == "Pa" {
        "an amplitude above 0 and at most 1e8 Pa"
    } else {
        "an amplitude above 0 and at most 10 m"
    }
}

/// The sensor faults of a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SensorFaultSchedule {
    /// The scheduled faults, in any order; several on one channel add up
    /// (offsets summed, spans multiplied, the earliest stuck freezes it).
    pub faults: Vec<SensorFault>,
}

impl SensorFaultSchedule {
    /// Parses each spec ([`SensorFault::parse`]); `none` is skipped.
    pub fn parse_all<S: AsRef<str>>(specs: &[S]) -> Result<SensorFaultSchedule, SensorFaultSpecError> {
        let faults = specs
            .iter()
            .map(AsRef::as_ref)
            .filter(|s| s.trim() != "none")
            .map(SensorFault::parse)
            .collect::<Result<_, _>>()?;
        Ok(SensorFaultSchedule { faults })
    }

    /// Checks every fault ([`SensorFault::validate`]).
    pub fn validate(&self) -> Result<(), InvalidParam> {
        self.faults.iter().try_for_each(SensorFault::validate)
    }

    /// Whether channel `ch` is stuck at time `t_s` (s).
    pub fn stuck_at(&self, ch: Channel, t_s: f64) -> bool {
        self.faults
            .iter()
            .any(|f| f.channel == ch && f.kind == SensorFaultKind::Stuck && f.active_at(t_s))
    }

    /// Channel `ch`'s distortion at time `t_s` (s), a sample period `dt_s` (s)
    /// long; spikes are drawn from `rng` (only while a spikes fault is active).
    pub fn distortion(&self, ch: Channel, t_s: f64, dt_s: f64, rng: &mut Rng) -> Distortion {
        let mut d = Distortion::NONE;
        for f in self.faults.iter().filter(|f| f.channel == ch && f.active_at(t_s)) {
            match f.kind {
                SensorFaultKind::Drift { .. } => d.offset_si += f.drift_offset_si(t_s),
                SensorFaultKind::Span { gain_error, ramp_s } => {
                    let grown = if ramp_s > 0.0 {
                        ((t_s - f.onset_s) / ramp_s).min(1.0)
                    } else {
                        1.0
                    };
                    d.gain *= 1.0 + gain_error * grown
                }
                SensorFaultKind::Stuck => {}
                SensorFaultKind::Spikes {
                    amplitude_si,
                    rate_hz,
                } => {
                    if rng.uniform() < rate_hz * dt_s {
                        let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                        d.spike_si += sign * amplitude_si;
                    }
                }
            }
        }
        d
    }
}

/// A schedule at work in a run: its spike generator and the stuck channels' readings.
#[derive(Debug, Clone)]
pub struct SensorFaultRun {
    schedule: SensorFaultSchedule,
    rng: Rng,
    frozen: [Option<f64>; 3],
}

impl SensorFaultRun {
    /// Runs `schedule` with spikes drawn from a generator seeded by `seed`
    /// (its own: the rig's noise is drawn as without the faults).
    pub fn new(schedule: SensorFaultSchedule, seed: u64) -> SensorFaultRun {
        SensorFaultRun {
            schedule,
            rng: Rng::new(seed ^ 0x5e75_0f4a_u64.rotate_left(32)),
            frozen: [None; 3],
        }
    }

    /// The schedule.
    pub fn schedule(&self) -> &SensorFaultSchedule {
        &self.schedule
    }

    /// Channel `ch`'s reading at time `t_s` (s) of a sample period `dt_s` (s):
    /// `form` makes it from the distortion (noise and ADC included, and it is
    /// always called, so the noise is drawn as on a healthy rig); while the
    /// channel is stuck the reading of its first stuck sample is returned instead.
    pub fn read(&mut self, ch: Channel, t_s: f64, dt_s: f64, form: impl FnOnce(Distortion) -> f64) -> f64 {
        let reading = form(self.schedule.distortion(ch, t_s, dt_s, &mut self.rng));
        if self.schedule.stuck_at(ch, t_s) {
            *self.frozen[ch.index()].get_or_insert(reading)
        } else {
            self.frozen[ch.index()] = None;
            reading
        }
    }
}

/// A sensor-fault spec that could not be parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorFaultSpecError {
    /// The spec as given.
    pub spec: String,
    /// What is wrong with it.
    pub message: String,
}

impl std::fmt::Display for SensorFaultSpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "bad sensor fault spec `{}`: {}", self.spec, self.message)
    }
}

impl std::error::Error for SensorFaultSpecError {}

mod spec;
