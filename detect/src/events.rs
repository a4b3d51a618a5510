//! The events the classifier raises: their kinds, phases and fields (events.json).

use serde::{Deserialize, Serialize};

/// What an event is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventKind {
    /// External leak, chamber 1 to tank.
    Ext1,
    /// External leak, chamber 2 to tank.
    Ext2,
    /// Internal (cross-piston) leak.
    Int,
    /// A leak whose kind is not decided yet (raised as soon as the leak is clear; the
    /// same event id is raised again with its kind once the kind has stayed the same
    /// for `kind_confirm_s`).
    Leak,
    /// The estimator had to restart its filter.
    EstimatorReset,
    /// A sensor's value did not change for too long.
    SensorStuck,
    /// A sensor sat at the end of its range.
    SensorSaturated,
    /// A sensor delivered no usable value for too long.
    SensorDead,
    /// The warm-up was too short (or too disturbed) to learn thresholds: detection is not armed.
    NotArmed,
    /// A pressure transducer reads off (an offset or a span error): the leak
    /// sizes move as the filter's response to an offset on that channel predicts.
    SensorOffset,
    /// A transducer gives outliers: single readings that jump away and straight back.
    SensorSpikes,
}

impl EventKind {
    /// The leak kinds, in state order (q_e1, q_e2, q_i).
    pub const LEAKS: [EventKind; 3] = [EventKind::Ext1, EventKind::Ext2, EventKind::Int];

    /// The name used in events.json: `ext1`, `ext2`, `int`, `estimator-reset`, ...
    pub fn name(self) -> &'static str {
        match self {
            EventKind::Ext1 => "ext1",
            EventKind::Ext2 => "ext2",
            EventKind::Int => "int",
            EventKind::Leak => "leak",
            EventKind::EstimatorReset => "estimator-reset",
            EventKind::SensorStuck => "sensor-stuck",
            EventKind::SensorSaturated => "sensor-saturated",
            EventKind::SensorDead => "sensor-dead",
            EventKind::NotArmed => "not-armed",
            EventKind::SensorOffset => "sensor-offset",
            EventKind::SensorSpikes => "sensor-spikes",
        }
    }

    /// Whether this is a named leak kind (ext1, ext2, int).
    pub fn is_leak(self) -> bool {
        matches!(self, EventKind::Ext1 | EventKind::Ext2 | EventKind::Int)
    }

    /// Whether this is a sensor event: a transducer stuck, saturated, dead, off or giving outliers.
    pub fn is_sensor(self) -> bool {
        matches!(
            self,
            EventKind::SensorStuck
                | EventKind::SensorSaturated
                | EventKind::SensorDead
                | EventKind::SensorOffset
                | EventKind::SensorSpikes
        )
    }

    /// Whether this is a leak alarm: a named leak kind or a leak whose kind is pending.
    pub fn is_leak_alarm(self) -> bool {
        self.is_leak() || self == EventKind::Leak
    }
}

/// The life of an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// First report.
    Raised,
    /// A better size estimate for an event already raised.
    Updated,
    /// The condition went away.
    Cleared,
}

/// One event, as written to events.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LeakEvent {
    /// What it is about.
    pub kind: EventKind,
    /// Raised, updated or cleared.
    pub phase: Phase,
    /// Which detector (`leak-size`, `thesis-mae`, `sensors`).
    pub detector: String,
    /// Identifier shared by all phases of one event.
    pub event_id: u64,
    /// Time of this decision, s (sample time).
    pub t_detect_s: f64,
    /// Estimated onset time, s (NaN if unknown).
    pub t_onset_s: f64,
    /// Leak flow at the measured pressures, L/min (NaN if not sized): the
    /// estimated coefficient times the mean of √Δp over the last
    /// `size_window_s` (Δp = p1, p2 or |p1 − p2| for ext1, ext2, int).
    pub size_lpm: f64,
    /// One standard deviation of `size_lpm`, L/min.
    pub size_lpm_sigma: f64,
    /// The same leak at the nominal pressure drop p_s/2, L/min (NaN if not sized).
    #[serde(default = "nan")]
    pub size_nominal_lpm: f64,
    /// Leak coefficient of the square-root law q = k·√Δp, m³/(s·√Pa) (NaN if not sized).
    #[serde(default = "nan")]
    pub coefficient_m3_s_sqrt_pa: f64,
    /// Decision statistic: the rise in healthy spreads (NaN where not applicable).
    #[serde(default = "nan")]
    pub statistic: f64,
    /// Threshold of the statistic, in healthy spreads (NaN where not applicable).
    #[serde(default = "nan")]
    pub threshold: f64,
    /// Confidence in [0, 1] that the kind is right and the leak is real.
    pub confidence: f64,
    /// For sensor events: which channel (`x`, `p1`, `p2`); empty otherwise.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub channel: String,
    /// Human-readable detail.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub detail: String,
}

/// NaN, the serde default of a missing number.
pub(crate) fn nan() -> f64 {
    f64::NAN
}

impl LeakEvent {
    /// An event of `detector` with no size or statistic (NaN), confidence 1, no channel or detail.
    pub fn plain(
        kind: EventKind,
        phase: Phase,
        detector: &str,
        event_id: u64,
        t_detect_s: f64,
        t_onset_s: f64,
    ) -> Self {
        LeakEvent {
            kind,
            phase,
            detector: detector.into(),
            event_id,
            t_detect_s,
            t_onset_s,
            size_lpm: f64::NAN,
            size_lpm_sigma: f64::NAN,
            size_nominal_lpm: f64::NAN,
            coefficient_m3_s_sqrt_pa: f64::NAN,
            statistic: f64::NAN,
            threshold: f64::NAN,
            confidence: 1.0,
            channel: String::new(),
            detail: String::new(),
        }
    }
}
