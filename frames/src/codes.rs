//! The codes carried in integer fields of the frames: flag bits, event kinds
//! and phases, health statuses and stage numbers.

/// Bits of [`SensorFrame::flags`](crate::SensorFrame::flags).
pub mod sensor_flags {
    /// The first frame after a gap in the source (samples were missing before it).
    pub const AFTER_GAP: u32 = 1 << 0;
    /// The last frame of the stream: the source is exhausted.
    pub const END_OF_STREAM: u32 = 1 << 1;
}

/// Bits of [`EstimateFrame::flags`](crate::EstimateFrame::flags).
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
    /// The estimated rod position is at an end of its stroke (the stop's contact is
    /// not tracked by the model).
    pub const END_STOP: u32 = 1 << 6;
    /// Samples were missing just before this one, more than the filter bridges: it
    /// restarted its fast states from this sample (set with [`AFTER_GAP`]).
    pub const REANCHORED: u32 = 1 << 7;
    /// The leak filter reads the oil's temperature past its operating range
    /// (from the oil's stiffness): its model is held at the range's edge.
    pub const OIL_PAST_RANGE: u32 = 1 << 8;
}

/// Values of [`LeakEventFrame::kind`](crate::LeakEventFrame::kind).
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
    /// A pressure transducer reads off: an offset or span error that the flow
    /// balance shows while the valve passes flow.
    pub const SENSOR_OFFSET: u32 = 15;
    /// A transducer gives outliers: single readings that jump away and back.
    pub const SENSOR_SPIKES: u32 = 16;

    /// Every kind with its name (the names of events.json).
    pub const NAMES: [(u32, &str); 11] = [
        (EXT1, "ext1"),
        (EXT2, "ext2"),
        (INTERNAL, "int"),
        (LEAK_PENDING, "leak"),
        (ESTIMATOR_RESET, "estimator-reset"),
        (SENSOR_STUCK, "sensor-stuck"),
        (SENSOR_SATURATED, "sensor-saturated"),
        (SENSOR_DEAD, "sensor-dead"),
        (NOT_ARMED, "not-armed"),
        (SENSOR_OFFSET, "sensor-offset"),
        (SENSOR_SPIKES, "sensor-spikes"),
    ];
}

/// Values of [`LeakEventFrame::phase`](crate::LeakEventFrame::phase).
pub mod event_phase {
    /// The event was raised.
    pub const RAISED: u32 = 0;
    /// The event's estimate (size, confidence) was updated.
    pub const UPDATED: u32 = 1;
    /// The event was cleared.
    pub const CLEARED: u32 = 2;

    /// Every phase with its name (the names of events.json).
    pub const NAMES: [(u32, &str); 3] = [(RAISED, "raised"), (UPDATED, "updated"), (CLEARED, "cleared")];
}

/// Values of [`HealthFrame::status`](crate::HealthFrame::status).
pub mod health_status {
    /// The estimator or classifier is still warming up.
    pub const WARMING_UP: u32 = 0;
    /// No leak and no fault.
    pub const HEALTHY: u32 = 1;
    /// At least one leak event is active.
    pub const LEAK: u32 = 2;
    /// A sensor fault is active.
    pub const SENSOR_FAULT: u32 = 3;

    /// Every status with its name.
    pub const NAMES: [(u32, &str); 4] = [
        (WARMING_UP, "warming-up"),
        (HEALTHY, "healthy"),
        (LEAK, "leak"),
        (SENSOR_FAULT, "sensor-fault"),
    ];
}

/// Values of [`StatsFrame::stage`](crate::StatsFrame::stage).
pub mod stage {
    /// The acquisition process.
    pub const ACQUISITION: u32 = 0;
    /// The estimator process.
    pub const ESTIMATOR: u32 = 1;
    /// The classifier process.
    pub const CLASSIFIER: u32 = 2;
    /// The recorder process.
    pub const RECORDER: u32 = 3;

    /// Every stage with its name.
    pub const NAMES: [(u32, &str); 4] = [
        (ACQUISITION, "acquisition"),
        (ESTIMATOR, "estimator"),
        (CLASSIFIER, "classifier"),
        (RECORDER, "recorder"),
    ];
}

/// The name of `code` in a table of codes and names (`event_kind::NAMES`, ...):
/// its name, or the code in decimal if the table has none (a code of a later
/// version); [`code_of`] reads either back.
pub fn code_name(names: &[(u32, &'static str)], code: u32) -> std::borrow::Cow<'static, str> {
    match names.iter().find(|(c, _)| *c == code) {
        Some((_, n)) => std::borrow::Cow::Borrowed(n),
        None => std::borrow::Cow::Owned(code.to_string()),
    }
}

/// The code of `name` in a table of codes and names: a name of the table, or a
/// code in decimal (as [`code_name`] writes a code the table does not name).
pub fn code_of(names: &[(u32, &'static str)], name: &str) -> Option<u32> {
    names
        .iter()
        .find(|(_, n)| *n == name)
        .map(|(c, _)| *c)
        .or_else(|| name.parse().ok())
}
