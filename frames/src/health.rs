//! [`HealthFrame`]: the classifier's 10 Hz summary of the actuator.

use iceoryx2::prelude::*;

use crate::{health_status, Frame, Topic};

/// The classifier's summary of the actuator (10 Hz).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.HealthFrame.v2")]
pub struct HealthFrame {
    /// Sequence number of this health stream, +1 per frame.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when published, ns.
    pub mono_ns: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// One of [`health_status`].
    pub status: u32,
    /// Number of active events.
    pub active_events: u32,
    /// Estimated leak flows: external at chamber 1, external at chamber 2, internal, L/min.
    pub leak_flow_lpm: [f64; 3],
    /// One standard deviation of each of [`Self::leak_flow_lpm`], L/min.
    pub leak_flow_sigma_lpm: [f64; 3],
    /// The leak-size detector's threshold on each of [`Self::leak_flow_lpm`],
    /// L/min at the nominal drop p_s/2 (NaN before it armed).
    pub leak_threshold_lpm: [f64; 3],
}

impl Frame for HealthFrame {
    const TOPIC: Topic = Topic::Health;
    fn seq(&self) -> Option<u64> {
        Some(self.seq)
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        None
    }
}

/// All-zero integers, NaN floats ("absent").
impl Default for HealthFrame {
    fn default() -> Self {
        HealthFrame {
            seq: 0,
            mono_ns: 0,
            t_s: f64::NAN,
            status: health_status::WARMING_UP,
            active_events: 0,
            leak_flow_lpm: [f64::NAN; 3],
            leak_flow_sigma_lpm: [f64::NAN; 3],
            leak_threshold_lpm: [f64::NAN; 3],
        }
    }
}
