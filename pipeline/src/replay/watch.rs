//! How much of a replay the leak-size detector watched, in summary.json.

use detect::{BlindSeconds, LeakEvent};
use serde::Serialize;

/// How much of a run the leak-size detector watched: from arming to the end,
/// less the time it took no evidence (gaps it could not bridge, resets,
/// excursions, a filter that did not track).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Watch {
    /// Length of the run, s (first to last sample).
    pub run_s: f64,
    /// When the detector armed (its thresholds learned or loaded), s; null if never.
    pub armed_at_s: Option<f64>,
    /// Seconds it watched (armed and taking evidence), s.
    pub watched_s: f64,
    /// Seconds after arming without evidence, s.
    pub blind_s: f64,
    /// The same seconds by cause, s (they add up to `blind_s`).
    pub blind_by_cause: BlindSeconds,
    /// Why it never armed (the `not-armed` event's detail), if it did not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_armed: Option<String>,
}

impl Watch {
    /// What the detectors of `cls` watched of a replay from `first_t` to
    /// `last_t` (s), with its `events` (a warm-up that never ended is one).
    pub(super) fn of(cls: &detect::Classifier, events: &[LeakEvent], first_t: f64, last_t: f64) -> Watch {
        let armed_at_s = cls.leak_size.armed_at_s();
        let blind_s = cls.leak_size.blind_s();
        Watch {
            run_s: if first_t.is_finite() {
                (last_t - first_t).max(0.0)
            } else {
                0.0
            },
            armed_at_s,
            watched_s: armed_at_s.map_or(0.0, |a| (last_t - a - blind_s).max(0.0)),
            blind_s: if armed_at_s.is_some() { blind_s } else { 0.0 },
            blind_by_cause: if armed_at_s.is_some() {
                cls.leak_size.blind_by_cause()
            } else {
                BlindSeconds::default()
            },
            not_armed: events
                .iter()
                .find(|e| e.kind == detect::EventKind::NotArmed)
                .map(|e| e.detail.to_string()),
        }
    }
}
