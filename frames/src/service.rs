//! The topics of a rig, rig ids and the iceoryx2 service names built from them.

use core::fmt;

/// The five topics of a rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Topic {
    /// [`SensorFrame`](crate::SensorFrame)s from the acquisition process, 1 kHz.
    Frames,
    /// [`EstimateFrame`](crate::EstimateFrame)s from the estimator, 1 kHz.
    Estimates,
    /// [`LeakEventFrame`](crate::LeakEventFrame)s from the classifier, sparse.
    Events,
    /// [`HealthFrame`](crate::HealthFrame)s from the classifier, 10 Hz.
    Health,
    /// [`StatsFrame`](crate::StatsFrame)s from every process, 1 Hz each.
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
