//! The wire types of leakwatch: every value that crosses a process boundary
//! over iceoryx2 shared memory, and the names of the services that carry them.
//!
//! Every frame is `#[repr(C)]`, fixed size, 8-byte aligned, with no implicit
//! padding (padding is an explicit `_pad` field, always 0), and carries a
//! versioned iceoryx2 type name `leakwatch.<Name>.v1`. iceoryx2 checks only the
//! type name, size and alignment when two processes open a service, so any
//! change of layout must bump the version in the type name. The byte layout of
//! every type (for the Python bindings' `ctypes.Structure`) is tabled in
//! `frames/README.md` and checked by the tests of this crate.
//!
//! Units: SI throughout (s, m, m/s, Pa, N, V, m³/s), except where a field name
//! says otherwise (`_lpm` = L/min, `_ns` = nanoseconds). Times named
//! `*_mono_ns` are `CLOCK_MONOTONIC` nanoseconds of the host; `t_s` is the
//! sample time of the source. A float that is `NaN` means "absent".
//!
//! [`udp`] is the other wire format: the little-endian datagrams in which a
//! DAQ board or PLC sends rig samples to the acquisition stage.

use core::fmt;

use iceoryx2::prelude::*;

pub mod udp;

/// Bits of [`SensorFrame::flags`].
pub mod sensor_flags {
    /// The first frame after a gap in the source (samples were missing before it).
    pub const AFTER_GAP: u32 = 1 << 0;
    /// The last frame of the stream: the source is exhausted.
    pub const END_OF_STREAM: u32 = 1 << 1;
}

/// Bits of [`EstimateFrame::flags`].
pub mod estimate_flags {
    /// The filter was reset at this sample.
    pub const RESET: u32 = 1 << 0;
    /// The input sample was unusable and skipped (prediction only).
    pub const SKIPPED: u32 = 1 << 1;
    /// The prediction was clamped to physical bounds.
    pub const CLAMPED: u32 = 1 << 2;
    /// The input frame was the last of its stream (mirrors
    /// [`super::sensor_flags::END_OF_STREAM`]).
    pub const END_OF_STREAM: u32 = 1 << 3;
    /// The filter is inside its convergence time after a (re)start.
    pub const CONVERGING: u32 = 1 << 4;
    /// Samples were missing just before this one (the filter bridged or re-anchored).
    pub const AFTER_GAP: u32 = 1 << 5;
}

/// Values of [`LeakEventFrame::kind`].
pub mod event_kind {
    /// External leak at chamber 1.
    pub const EXT1: u32 = 1;
    /// External leak at chamber 2.
    pub const EXT2: u32 = 2;
    /// Internal leak (chamber 1 to chamber 2 across the piston).
    pub const INTERNAL: u32 = 3;
    /// A leak whose kind is not decided yet (the same event id is raised again with
    /// its kind once decided).
    pub const LEAK_PENDING: u32 = 4;
    /// The estimator reset.
    pub const ESTIMATOR_RESET: u32 = 10;
    /// A sensor is stuck (constant output).
    pub const SENSOR_STUCK: u32 = 11;
    /// A sensor is saturated (at its range limit).
    pub const SENSOR_SATURATED: u32 = 12;
    /// A sensor is dead (no usable output).
    pub const SENSOR_DEAD: u32 = 13;
    /// The warm-up was too short to learn thresholds: detection is not armed.
    pub const NOT_ARMED: u32 = 14;
}

/// Values of [`LeakEventFrame::phase`].
pub mod event_phase {
    /// The event was raised.
    pub const RAISED: u32 = 0;
    /// The event's estimate (size, confidence) was updated.
    pub const UPDATED: u32 = 1;
    /// The event was cleared.
    pub const CLEARED: u32 = 2;
}

/// Values of [`HealthFrame::status`].
pub mod health_status {
    /// The estimator or classifier is still warming up.
    pub const WARMING_UP: u32 = 0;
    /// No leak and no fault.
    pub const HEALTHY: u32 = 1;
    /// At least one leak event is active.
    pub const LEAK: u32 = 2;
    /// A sensor fault is active.
    pub const SENSOR_FAULT: u32 = 3;
}

/// Values of [`StatsFrame::stage`].
pub mod stage {
    /// The acquisition process.
    pub const ACQUISITION: u32 = 0;
    /// The estimator process.
    pub const ESTIMATOR: u32 = 1;
    /// The classifier process.
    pub const CLASSIFIER: u32 = 2;
    /// The recorder process.
    pub const RECORDER: u32 = 3;
}

/// One rig sample as published by the acquisition process (1 kHz).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.SensorFrame.v1")]
pub struct SensorFrame {
    /// Sequence number, 0 for the first frame of a stream, +1 per frame.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when the frame was published, ns.
    pub acq_mono_ns: u64,
    /// Sample time of the source, s.
    pub t_s: f64,
    /// Valve command applied from this sample to the next, V.
    pub u_v: f64,
    /// Measured rod position, m.
    pub x_m: f64,
    /// Measured chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Measured chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Measured spool position, m (NaN = channel absent).
    pub x_sp_m: f64,
    /// Measured external load force, N (NaN = channel absent).
    pub f_load_n: f64,
    /// Position reference of the controller, m (NaN = open loop or absent).
    pub ref_m: f64,
    /// Leak flow (flow meter or simulator truth), L/min (NaN = channel absent).
    pub q_leak_lpm: f64,
    /// Bit set of [`sensor_flags`].
    pub flags: u32,
    /// Explicit padding, always 0.
    pub _pad: u32,
}

/// Number of states in [`EstimateFrame::state`]: x_sp m, p1 Pa, p2 Pa, x m,
/// v m/s, v_sp m/s, F_e N, w1 m³/s, w2 m³/s.
pub const MAX_STATES: usize = 11;

/// Number of states of the thesis filter carried in [`EstimateFrame::th_state`].
pub const THESIS_STATES: usize = 7;

/// The estimator's output for one sensor frame (1 kHz).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.EstimateFrame.v2")]
pub struct EstimateFrame {
    /// Sequence number of the sensor frame this estimate is for.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when the sensor frame was published, ns (copied).
    pub acq_mono_ns: u64,
    /// `CLOCK_MONOTONIC` when the estimator received the sensor frame, ns.
    pub est_recv_mono_ns: u64,
    /// `CLOCK_MONOTONIC` when the estimate was complete, ns.
    pub est_done_mono_ns: u64,
    /// Sample time, s.
    pub t_s: f64,
    /// Number of states in use (the first `n_states` of [`Self::state`]).
    pub n_states: u32,
    /// Bit set of [`estimate_flags`].
    pub flags: u32,
    /// The leak filter's a-posteriori state, order: x_sp m, p1 Pa, p2 Pa, x m,
    /// v m/s, v_sp m/s, F_e N, q_e1 m³/s, q_e2 m³/s, q_i m³/s (leak sizes at the
    /// nominal drop), spool null bias m; unused entries NaN.
    pub state: [f64; MAX_STATES],
    /// One standard deviation of each state, same order and units as [`Self::state`].
    pub state_sigma: [f64; MAX_STATES],
    /// Leak filter: a-posteriori residual y − Hx⁺: x m, p1 Pa, p2 Pa.
    pub residual: [f64; 3],
    /// Leak filter: innovation y − Hx⁻: x m, p1 Pa, p2 Pa.
    pub innovation: [f64; 3],
    /// Leak filter: standard deviation of each innovation: m, Pa, Pa.
    pub innovation_sigma: [f64; 3],
    /// The measurement as received: x m, p1 Pa, p2 Pa (NaN where absent).
    pub measured: [f64; 3],
    /// The valve command as received, V.
    pub u_v: f64,
    /// Leak filter: normalised innovation squared.
    pub nis: f64,
    /// Leak filter: mean absolute residual of p1 and p2 over the MAE window, Pa.
    pub mae_pa: [f64; 2],
    /// Thesis filter: bit set of [`estimate_flags`].
    pub th_flags: u32,
    /// Explicit padding (zero).
    pub _pad: u32,
    /// Thesis filter: a-posteriori state x_sp m, p1 Pa, p2 Pa, x m, v m/s, v_sp m/s, F_e N.
    pub th_state: [f64; THESIS_STATES],
    /// Thesis filter: a-posteriori residual: x m, p1 Pa, p2 Pa.
    pub th_residual: [f64; 3],
    /// Thesis filter: innovation: x m, p1 Pa, p2 Pa.
    pub th_innovation: [f64; 3],
    /// Thesis filter: MAE of the p1 and p2 residuals (the thesis' figure), Pa.
    pub th_mae_pa: [f64; 2],
    /// Thesis filter: normalised innovation squared.
    pub th_nis: f64,
}

/// Length of [`LeakEventFrame::detector`], bytes.
pub const DETECTOR_NAME_LEN: usize = 16;
/// Length of [`LeakEventFrame::channel`], bytes.
pub const CHANNEL_NAME_LEN: usize = 8;
/// Length of [`LeakEventFrame::detail`], bytes (UTF-8, cut at a character boundary).
pub const DETAIL_LEN: usize = 192;

/// A leak or fault event from the classifier (raised, updated, cleared).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.LeakEventFrame.v2")]
pub struct LeakEventFrame {
    /// Sequence number of the estimate that triggered the event.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when that sample was acquired, ns.
    pub acq_mono_ns: u64,
    /// `CLOCK_MONOTONIC` when the classifier decided, ns.
    pub cls_done_mono_ns: u64,
    /// Identifier of the event, the same for its raised, updated and cleared frames.
    pub event_id: u64,
    /// One of [`event_kind`].
    pub kind: u32,
    /// One of [`event_phase`].
    pub phase: u32,
    /// Sample time of the decision, s.
    pub t_detect_s: f64,
    /// Estimated onset time, s (NaN = unknown).
    pub t_onset_s: f64,
    /// Estimated leak flow, L/min (NaN for non-leak events).
    pub size_lpm: f64,
    /// One standard deviation of [`Self::size_lpm`], L/min.
    pub size_lpm_sigma: f64,
    /// Confidence of the decision, 0..1.
    pub confidence: f64,
    /// Name of the detector, ASCII, NUL-padded (see [`detector_name`]).
    pub detector: [u8; DETECTOR_NAME_LEN],
    /// The same leak at the nominal pressure drop p_s/2, L/min (NaN if not sized).
    pub size_nominal_lpm: f64,
    /// Leak coefficient of the square-root law q = k·√Δp, m³/(s·√Pa) (NaN if not sized).
    pub coefficient_m3_s_sqrt_pa: f64,
    /// Decision statistic, in healthy spreads (NaN where not applicable).
    pub statistic: f64,
    /// Threshold of the statistic, in healthy spreads (NaN where not applicable).
    pub threshold: f64,
    /// Sensor events: the channel (`x`, `p1`, `p2`), ASCII, NUL-padded; empty otherwise.
    pub channel: [u8; CHANNEL_NAME_LEN],
    /// Human-readable detail, UTF-8, NUL-padded, cut to [`DETAIL_LEN`] bytes (see [`text`]).
    pub detail: [u8; DETAIL_LEN],
}

/// The classifier's summary of the actuator (10 Hz).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.HealthFrame.v1")]
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
}

/// One process's counters and latency figures (1 Hz per process).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.StatsFrame.v1")]
pub struct StatsFrame {
    /// `CLOCK_MONOTONIC` when published, ns.
    pub mono_ns: u64,
    /// Process id.
    pub pid: u32,
    /// One of [`stage`].
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

/// A frame type with its topic: what the `bus` and `recorder` crates need to
/// know about every wire type.
pub trait Frame: fmt::Debug + Copy + Send + ZeroCopySend + Default + 'static {
    /// The topic that carries this type.
    const TOPIC: Topic;
    /// The sequence number, if the type carries one.
    fn seq(&self) -> Option<u64>;
    /// The acquisition time (`CLOCK_MONOTONIC`, ns), if the type carries one.
    fn acq_mono_ns(&self) -> Option<u64>;
    /// True if this is the last frame of its stream (types without the flag: false).
    fn is_end_of_stream(&self) -> bool {
        false
    }
    /// Marks this frame as the last of its stream (types without the flag: no-op).
    fn mark_end_of_stream(&mut self) {}
}

impl Frame for SensorFrame {
    const TOPIC: Topic = Topic::Frames;
    fn seq(&self) -> Option<u64> {
        Some(self.seq)
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        Some(self.acq_mono_ns)
    }
    fn is_end_of_stream(&self) -> bool {
        self.flags & sensor_flags::END_OF_STREAM != 0
    }
    fn mark_end_of_stream(&mut self) {
        self.flags |= sensor_flags::END_OF_STREAM;
    }
}

impl Frame for EstimateFrame {
    const TOPIC: Topic = Topic::Estimates;
    fn seq(&self) -> Option<u64> {
        Some(self.seq)
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        Some(self.acq_mono_ns)
    }
    fn is_end_of_stream(&self) -> bool {
        self.flags & estimate_flags::END_OF_STREAM != 0
    }
    fn mark_end_of_stream(&mut self) {
        self.flags |= estimate_flags::END_OF_STREAM;
    }
}

impl Frame for LeakEventFrame {
    const TOPIC: Topic = Topic::Events;
    /// Events are sparse and their `seq` is the triggering estimate's: no sequence to check.
    fn seq(&self) -> Option<u64> {
        None
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        Some(self.acq_mono_ns)
    }
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

impl Frame for StatsFrame {
    const TOPIC: Topic = Topic::Stats;
    fn seq(&self) -> Option<u64> {
        None
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        None
    }
}

/// All-zero integers, NaN floats ("absent"), empty detector name.
impl Default for SensorFrame {
    fn default() -> Self {
        SensorFrame {
            seq: 0,
            acq_mono_ns: 0,
            t_s: f64::NAN,
            u_v: f64::NAN,
            x_m: f64::NAN,
            p1_pa: f64::NAN,
            p2_pa: f64::NAN,
            x_sp_m: f64::NAN,
            f_load_n: f64::NAN,
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
            flags: 0,
            _pad: 0,
        }
    }
}

/// All-zero integers, NaN floats ("absent").
impl Default for EstimateFrame {
    fn default() -> Self {
        EstimateFrame {
            seq: 0,
            acq_mono_ns: 0,
            est_recv_mono_ns: 0,
            est_done_mono_ns: 0,
            t_s: f64::NAN,
            n_states: 0,
            flags: 0,
            state: [f64::NAN; MAX_STATES],
            state_sigma: [f64::NAN; MAX_STATES],
            residual: [f64::NAN; 3],
            innovation: [f64::NAN; 3],
            innovation_sigma: [f64::NAN; 3],
            measured: [f64::NAN; 3],
            u_v: f64::NAN,
            nis: f64::NAN,
            mae_pa: [f64::NAN; 2],
            th_flags: 0,
            _pad: 0,
            th_state: [f64::NAN; THESIS_STATES],
            th_residual: [f64::NAN; 3],
            th_innovation: [f64::NAN; 3],
            th_mae_pa: [f64::NAN; 2],
            th_nis: f64::NAN,
        }
    }
}

/// All-zero integers, NaN floats ("absent"), empty detector name.
impl Default for LeakEventFrame {
    fn default() -> Self {
        LeakEventFrame {
            seq: 0,
            acq_mono_ns: 0,
            cls_done_mono_ns: 0,
            event_id: 0,
            kind: 0,
            phase: 0,
            t_detect_s: f64::NAN,
            t_onset_s: f64::NAN,
            size_lpm: f64::NAN,
            size_lpm_sigma: f64::NAN,
            confidence: f64::NAN,
            detector: [0; DETECTOR_NAME_LEN],
            size_nominal_lpm: f64::NAN,
            coefficient_m3_s_sqrt_pa: f64::NAN,
            statistic: f64::NAN,
            threshold: f64::NAN,
            channel: [0; CHANNEL_NAME_LEN],
            detail: [0; DETAIL_LEN],
        }
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
        }
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

/// The detector name as a NUL-padded ASCII field: non-ASCII bytes become `?`
/// and a name longer than [`DETECTOR_NAME_LEN`] bytes is cut.
pub fn detector_bytes(name: &str) -> [u8; DETECTOR_NAME_LEN] {
    let mut out = [0u8; DETECTOR_NAME_LEN];
    for (o, b) in out.iter_mut().zip(name.bytes()) {
        *o = if b.is_ascii() && b != 0 { b } else { b'?' };
    }
    out
}

/// The detector name of a NUL-padded field: the bytes before the first NUL
/// (non-UTF-8 content gives `"?"`).
pub fn detector_name(field: &[u8; DETECTOR_NAME_LEN]) -> &str {
    text(field)
}

/// A UTF-8 text as a NUL-padded field of `N` bytes: cut at the last character
/// boundary that fits, NUL characters left out.
pub fn text_bytes<const N: usize>(text: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut n = 0;
    for c in text.chars().filter(|c| *c != '\0') {
        let len = c.len_utf8();
        if n + len > N {
            break;
        }
        c.encode_utf8(&mut out[n..n + len]);
        n += len;
    }
    out
}

/// The text of a NUL-padded field: the bytes before the first NUL (non-UTF-8
/// content gives `"?"`).
pub fn text<const N: usize>(field: &[u8; N]) -> &str {
    let end = field.iter().position(|&b| b == 0).unwrap_or(N);
    core::str::from_utf8(&field[..end]).unwrap_or("?")
}

/// The sample a sensor frame carries (sequence, clock and flags stay on the wire).
impl From<&SensorFrame> for model::Sample {
    fn from(f: &SensorFrame) -> Self {
        model::Sample {
            t_s: f.t_s,
            u_v: f.u_v,
            x_m: f.x_m,
            p1_pa: f.p1_pa,
            p2_pa: f.p2_pa,
            x_sp_m: f.x_sp_m,
            f_load_n: f.f_load_n,
            ref_m: f.ref_m,
            q_leak_lpm: f.q_leak_lpm,
        }
    }
}

/// A sensor frame carrying `s`, with sequence 0, clock 0 and no flags (the
/// publisher sets those).
impl From<&model::Sample> for SensorFrame {
    fn from(s: &model::Sample) -> Self {
        SensorFrame {
            seq: 0,
            acq_mono_ns: 0,
            t_s: s.t_s,
            u_v: s.u_v,
            x_m: s.x_m,
            p1_pa: s.p1_pa,
            p2_pa: s.p2_pa,
            x_sp_m: s.x_sp_m,
            f_load_n: s.f_load_n,
            ref_m: s.ref_m,
            q_leak_lpm: s.q_leak_lpm,
            flags: 0,
            _pad: 0,
        }
    }
}

/// The five topics of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Topic {
    /// [`SensorFrame`]s from the acquisition process, 1 kHz.
    Frames,
    /// [`EstimateFrame`]s from the estimator, 1 kHz.
    Estimates,
    /// [`LeakEventFrame`]s from the classifier, sparse.
    Events,
    /// [`HealthFrame`]s from the classifier, 10 Hz.
    Health,
    /// [`StatsFrame`]s from every process, 1 Hz each.
    Stats,
}

impl Topic {
    /// Every topic, in pipeline order.
    pub const ALL: [Topic; 5] = [
        Topic::Frames,
        Topic::Estimates,
        Topic::Events,
        Topic::Health,
        Topic::Stats,
    ];

    /// The topic's path segment in service names (`frames`, `estimates`, ...).
    pub const fn as_str(self) -> &'static str {
        match self {
            Topic::Frames => "frames",
            Topic::Estimates => "estimates",
            Topic::Events => "events",
            Topic::Health => "health",
            Topic::Stats => "stats",
        }
    }
}

impl fmt::Display for Topic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Longest rig id, characters.
pub const RIG_ID_MAX_LEN: usize = 32;

/// A validated rig id: 1 to 32 characters of `[A-Za-z0-9_-]`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RigId(String);

/// A rig id that is not 1 to 32 characters of `[A-Za-z0-9_-]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RigIdError {
    /// The refused id.
    pub id: String,
    /// What is wrong with it.
    pub reason: String,
}

impl fmt::Display for RigIdError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "invalid rig id {:?}: {} (a rig id is 1 to {RIG_ID_MAX_LEN} characters of A-Z a-z 0-9 _ -)",
            self.id, self.reason
        )
    }
}

impl std::error::Error for RigIdError {}

impl RigId {
    /// Validates `id`.
    pub fn new(id: &str) -> Result<RigId, RigIdError> {
        let err = |reason: String| RigIdError {
            id: id.to_string(),
            reason,
        };
        if id.is_empty() {
            return Err(err("it is empty".into()));
        }
        if id.chars().count() > RIG_ID_MAX_LEN {
            return Err(err(format!("it has {} characters", id.chars().count())));
        }
        if let Some(c) = id
            .chars()
            .find(|c| !(c.is_ascii_alphanumeric() || *c == '_' || *c == '-'))
        {
            return Err(err(format!("it contains {c:?}")));
        }
        Ok(RigId(id.to_string()))
    }

    /// The id as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for RigId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl core::str::FromStr for RigId {
    type Err = RigIdError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        RigId::new(s)
    }
}

/// The publish-subscribe service of `topic` on `rig`: `leakwatch/<rig>/<topic>`.
pub fn service_name(rig: &RigId, topic: Topic) -> String {
    format!("leakwatch/{rig}/{topic}")
}

/// The event service that wakes subscribers of `topic` on `rig`:
/// `leakwatch/<rig>/<topic>/wake`. Publishers notify it after every send.
pub fn wake_service_name(rig: &RigId, topic: Topic) -> String {
    format!("leakwatch/{rig}/{topic}/wake")
}

// Compile-time layout checks (the offsets are checked in tests/layout.rs).
const _: () = assert!(core::mem::size_of::<SensorFrame>() == 96);
const _: () = assert!(core::mem::size_of::<EstimateFrame>() == 488);
const _: () = assert!(core::mem::size_of::<LeakEventFrame>() == 328);
const _: () = assert!(core::mem::size_of::<HealthFrame>() == 80);
const _: () = assert!(core::mem::size_of::<StatsFrame>() == 112);
