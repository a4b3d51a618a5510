//! How a run's leak events are read by the detection benchmarks: a leak alarm may
//! be raised with its kind pending (`leak`) and raised again, under the same event
//! id, with its kind; a false alarm is one event id, however many times it is raised.

use detect::{LeakEvent, Phase};

/// What a run's leak alarms say about a leak with onset `t_on_s` (s).
#[derive(Debug, Clone, Copy, Default)]
pub struct Alarms<'a> {
    /// Distinct leak events raised before the onset (all of them in a healthy run).
    pub false_alarms: u32,
    /// The first alarm at or after the onset, kind pending or named: the detection.
    pub first: Option<&'a LeakEvent>,
    /// The first alarm at or after the onset that names a kind: the kind a user acts on.
    pub first_named: Option<&'a LeakEvent>,
    /// The last word on the leak after the first alarm (named if any kind was named).
    pub last: Option<&'a LeakEvent>,
}

/// Reads `events` (one detector's, in time order) against an onset at `t_on_s`
/// (NaN or `None` for a healthy run).
pub fn read<'a>(events: &[&'a LeakEvent], t_on_s: Option<f64>) -> Alarms<'a> {
    let raised = |e: &&&LeakEvent| e.phase == Phase::Raised && e.kind.is_leak_alarm();
    let before = |e: &&&LeakEvent| t_on_s.is_none_or(|t| e.t_detect_s < t);
    let mut ids: Vec<u64> = events
        .iter()
        .filter(raised)
        .filter(before)
        .map(|e| e.event_id)
        .collect();
    ids.sort_unstable();
    ids.dedup();
    let Some(t_on) = t_on_s else {
        return Alarms {
            false_alarms: ids.len() as u32,
            ..Alarms::default()
        };
    };
    let after: Vec<&LeakEvent> = events
        .iter()
        .filter(raised)
        .filter(|e| e.t_detect_s >= t_on)
        .copied()
        .collect();
    let first = after.first().copied();
    let first_named = after.iter().find(|e| e.kind.is_leak()).copied();
    let last = first.and_then(|f| {
        let live = |e: &&&LeakEvent| e.t_detect_s >= f.t_detect_s && e.phase != Phase::Cleared;
        events
            .iter()
            .rev()
            .filter(live)
            .find(|e| e.kind.is_leak())
            .or_else(|| events.iter().rev().find(live))
            .copied()
    });
    Alarms {
        false_alarms: ids.len() as u32,
        first,
        first_named,
        last,
    }
}
