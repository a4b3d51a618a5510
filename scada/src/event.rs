//! The OPC UA event of each leak and sensor event: `LeakwatchEventType`, a
//! subtype of `BaseEventType` with the event's kind, phase, size and times as
//! fields, so a client's event filter selects them by name.

use opcua::nodes::BaseEventType;
use opcua::types::{ByteString, DateTime, LocalizedText, NodeId, UAString};
use opcua::Event;

use frames::{code_name, event_kind, event_phase, LeakEventFrame};

use crate::state::{is_leak, is_sensor_fault};

/// The namespace of leakwatch's nodes.
pub const NAMESPACE: &str = "urn:leakwatch";

/// The identifier of `LeakwatchEventType` in [`NAMESPACE`].
pub const EVENT_TYPE: &str = "LeakwatchEventType";

/// A leak or sensor event as an OPC UA event (fields by their browse names:
/// `Kind`, `Phase`, `EventNumber`, `SizeLpm`, `SizeSigmaLpm`, `OnsetTimeS`,
/// `DetectTimeS`, `Confidence`, `Channel`, `Detector`).
#[derive(Debug, Event)]
#[opcua(identifier = "s=LeakwatchEventType", namespace = "urn:leakwatch")]
pub struct LeakwatchEvent {
    base: BaseEventType,
    own_namespace_index: u16,
    /// `ext1`, `ext2`, `int`, `leak`, `sensor-stuck`, ... (events.json's names).
    kind: UAString,
    /// `raised`, `updated` or `cleared`.
    phase: UAString,
    /// The event's id (as in events.json), the same for its three phases.
    event_number: u64,
    /// Leak flow at the measured pressures, L/min.
    size_lpm: f64,
    /// One standard deviation of `size_lpm`, L/min.
    size_sigma_lpm: f64,
    /// Estimated onset, sample time, s.
    onset_time_s: f64,
    /// Decision time, sample time, s.
    detect_time_s: f64,
    /// Confidence, 0 to 1.
    confidence: f64,
    /// A sensor event's channel (`x`, `p1`, `p2`), else empty.
    channel: UAString,
    /// The detector that decided.
    detector: UAString,
}

/// The custom fields of [`LeakwatchEvent`]: browse name, its data type, meaning.
pub const EVENT_FIELDS: [(&str, EventFieldType, &str); 10] = [
    (
        "Kind",
        EventFieldType::Str,
        "ext1, ext2, int, leak (kind pending), sensor-stuck, ... as in events.json",
    ),
    ("Phase", EventFieldType::Str, "raised, updated or cleared"),
    (
        "EventNumber",
        EventFieldType::U64,
        "the event's id in events.json, the same for its three phases",
    ),
    (
        "SizeLpm",
        EventFieldType::Double,
        "leak flow at the measured pressures, L/min",
    ),
    (
        "SizeSigmaLpm",
        EventFieldType::Double,
        "one standard deviation of SizeLpm, L/min",
    ),
    (
        "OnsetTimeS",
        EventFieldType::Double,
        "estimated onset, sample time, s",
    ),
    (
        "DetectTimeS",
        EventFieldType::Double,
        "decision time, sample time, s",
    ),
    ("Confidence", EventFieldType::Double, "confidence, 0 to 1"),
    (
        "Channel",
        EventFieldType::Str,
        "a sensor event's channel (x, p1, p2), else empty",
    ),
    ("Detector", EventFieldType::Str, "the detector that decided"),
];

/// The data type of an event field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventFieldType {
    /// String.
    Str,
    /// UInt64.
    U64,
    /// Double.
    Double,
}

/// The event's Severity (1 to 1000): a raised leak 800, its update 600,
/// a raised sensor fault 700, any other raise 500, an update 400, a clear 300.
pub fn severity(kind: u32, phase: u32) -> u16 {
    match (phase, is_leak(kind), is_sensor_fault(kind)) {
        (event_phase::CLEARED, ..) => 300,
        (event_phase::RAISED, true, _) => 800,
        (_, true, _) => 600,
        (event_phase::RAISED, _, true) => 700,
        (event_phase::RAISED, ..) => 500,
        _ => 400,
    }
}

/// The event's Message: what happened, in a line.
pub fn message(rig: &str, e: &LeakEventFrame) -> String {
    let kind = code_name(&event_kind::NAMES, e.kind);
    let phase = code_name(&event_phase::NAMES, e.phase);
    let channel = frames::text(&e.channel);
    let mut m = format!("rig {rig}: {kind} {phase}");
    if !channel.is_empty() {
        m.push_str(&format!(" on {channel}"));
    }
    if is_leak(e.kind) && e.size_lpm.is_finite() {
        m.push_str(&format!(
            ", {:.3} L/min ± {:.3} at t = {:.3} s (onset {:.3} s), confidence {:.2}",
            e.size_lpm, e.size_lpm_sigma, e.t_detect_s, e.t_onset_s, e.confidence
        ));
    } else {
        m.push_str(&format!(" at t = {:.3} s", e.t_detect_s));
    }
    let detail = frames::text(&e.detail);
    if !detail.is_empty() {
        m.push_str(&format!(" ({detail})"));
    }
    m
}

impl LeakwatchEvent {
    /// The OPC UA event of `e` from rig `rig`'s object `source`, in namespace
    /// `ns`: its Time the acquisition time of the sample it was decided on
    /// (`time_ns`, Unix ns), its ReceiveTime now.
    pub fn of_frame(ns: u16, source: &NodeId, rig: &str, e: &LeakEventFrame, time_ns: u64) -> Self {
        let type_id = NodeId::new(ns, EVENT_TYPE);
        // a unique EventId: the event, its phase and its sequence number
        let mut id = Vec::with_capacity(20);
        id.extend_from_slice(&e.event_id.to_be_bytes());
        id.extend_from_slice(&e.phase.to_be_bytes());
        id.extend_from_slice(&e.seq.to_be_bytes());
        let time = unix_ns_to_datetime(time_ns);
        let mut base = BaseEventType::new(
            type_id,
            ByteString::from(id),
            LocalizedText::from(message(rig, e)),
            time,
        )
        .set_source_node(source.clone())
        .set_source_name(UAString::from(rig))
        .set_receive_time(DateTime::now());
        base.severity = severity(e.kind, e.phase);
        LeakwatchEvent {
            base,
            own_namespace_index: ns,
            kind: UAString::from(code_name(&event_kind::NAMES, e.kind).as_ref()),
            phase: UAString::from(code_name(&event_phase::NAMES, e.phase).as_ref()),
            event_number: e.event_id,
            size_lpm: e.size_lpm,
            size_sigma_lpm: e.size_lpm_sigma,
            onset_time_s: e.t_onset_s,
            detect_time_s: e.t_detect_s,
            confidence: e.confidence,
            channel: UAString::from(frames::text(&e.channel)),
            detector: frames::detector_name(&e.detector).into(),
        }
    }
}

/// 100 ns ticks from 1601-01-01 (OPC UA's epoch) to 1970-01-01 (Unix's).
const UNIX_EPOCH_TICKS: i64 = 11_644_473_600 * 10_000_000;

/// Unix time, ns → OPC UA `DateTime` (100 ns ticks since 1601).
pub fn unix_ns_to_datetime(ns: u64) -> DateTime {
    DateTime::from((ns / 100) as i64 + UNIX_EPOCH_TICKS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_raised_leak_is_severe_and_says_its_kind_and_size() {
        let e = LeakEventFrame {
            event_id: 3,
            kind: event_kind::INTERNAL,
            phase: event_phase::RAISED,
            t_detect_s: 20.5,
            t_onset_s: 20.0,
            size_lpm: 0.42,
            size_lpm_sigma: 0.03,
            confidence: 0.97,
            ..LeakEventFrame::default()
        };
        assert_eq!(severity(e.kind, e.phase), 800);
        assert_eq!(severity(event_kind::SENSOR_DEAD, event_phase::RAISED), 700);
        assert_eq!(severity(event_kind::INTERNAL, event_phase::CLEARED), 300);
        assert_eq!(
            message("r1", &e),
            "rig r1: int raised, 0.420 L/min ± 0.030 at t = 20.500 s (onset 20.000 s), confidence 0.97"
        );
        let ev = LeakwatchEvent::of_frame(2, &NodeId::new(2, "r1"), "r1", &e, 1_700_000_000_123_456_789);
        assert_eq!(ev.event_number, 3);
        assert_eq!(ev.base.severity, 800);
        assert_eq!(
            ev.base.time.as_chrono().timestamp_nanos_opt(),
            Some(1_700_000_000_123_456_700)
        );
        assert_eq!(unix_ns_to_datetime(0).as_chrono().timestamp(), 0);
    }
}
