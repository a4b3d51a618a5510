//! [`StatsFrame`]: one process's counters and latency figures, 1 Hz.

use iceoryx2::prelude::*;

use crate::{Frame, Topic};

/// One process's counters and latency figures (1 Hz per process).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.StatsFrame.v1")]
pub struct StatsFrame {
    /// `CLOCK_MONOTONIC` when published, ns.
    pub mono_ns: u64,
    /// Process id.
    pub pid: u32,
    /// One of [`stage`](crate::stage).
    pub stage: u32,
    /// Frames received since the process started.
    pub frames_in: u64,
    /// Frames published since the process started.
    pub frames_out: u64,
    /// Frames missing from the input sequence since the process started.
    pub seq_gaps: u64,
    /// Deadlines missed since the process started (acquisition: publish
    /// instants later than the schedule by more than one period).
    pub deadline_misses: u64,
    /// Processing time per frame over the interval since the previous stats
    /// frame, median, ns (all percentiles below are of that interval; the
    /// counters above are since the process started).
    pub proc_ns_p50: u64,
    /// Processing time per frame, 99th percentile, ns.
    pub proc_ns_p99: u64,
    /// Processing time per frame, maximum, ns.
    pub proc_ns_max: u64,
    /// Latency since `acq_mono_ns` (acquisition: schedule jitter), median, ns.
    pub lat_ns_p50: u64,
    /// Latency, 99th percentile, ns.
    pub lat_ns_p99: u64,
    /// Latency, maximum, ns.
    pub lat_ns_max: u64,
    /// CPU time over wall time since the previous stats frame (1.0 = one core).
    pub cpu_fraction: f64,
    /// Resident set size, bytes.
    pub rss_bytes: u64,
}

impl Frame for StatsFrame {
    const TOPIC: Topic = Topic::Stats;
    fn seq(&self) -> Option<u64> {
        None
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        None
    }
}

/// All-zero counters, NaN CPU fraction.
impl Default for StatsFrame {
    fn default() -> Self {
        StatsFrame {
            mono_ns: 0,
            pid: 0,
            stage: 0,
            frames_in: 0,
            frames_out: 0,
            seq_gaps: 0,
            deadline_misses: 0,
            proc_ns_p50: 0,
            proc_ns_p99: 0,
            proc_ns_max: 0,
            lat_ns_p50: 0,
            lat_ns_p99: 0,
            lat_ns_max: 0,
            cpu_fraction: f64::NAN,
            rss_bytes: 0,
        }
    }
}
