//! The `sensor-offset` event of a named misreading, in words.

use super::{OffsetChange, OFFSET_CHANNEL_NAMES, OFFSET_WINDOW_S};
use crate::{EventKind, LeakEvent, Phase};

/// The `sensor-offset` event of `change` at time `t_s` (s), from `detector`.
pub fn offset_event(change: OffsetChange, t_s: f64, detector: &str) -> LeakEvent {
    let (phase, s) = match change {
        OffsetChange::Raised(s) => (Phase::Raised, s),
        OffsetChange::Cleared(s) => (Phase::Cleared, s),
    };
    let mut ev = LeakEvent::plain(
        EventKind::SensorOffset,
        phase,
        detector,
        s.event_id,
        t_s,
        s.since_s,
    );
    let name = OFFSET_CHANNEL_NAMES[s.channel];
    ev.channel = name.into();
    ev.detail = match phase {
        Phase::Cleared => format!("{name} reads true again: leak decisions resume"),
        _ => {
            let high_low = |v: f64| if v >= 0.0 { "high" } else { "low" };
            let reading = if s.offset_mm.is_finite() {
                format!("{:.1} mm {} (an offset", s.offset_mm.abs(), high_low(s.offset_mm))
            } else if s.span_error.is_finite() {
                format!(
                    "{:.1} % {} (a span error: {:.0} kPa at this pressure",
                    s.span_error.abs() * 100.0,
                    high_low(s.span_error),
                    s.offset_mpa.abs() * 1e3
                )
            } else if s.drift_mpa_per_s != 0.0 {
                format!(
                    "{:.0} kPa {} (an offset drifting by {:.0} kPa a minute",
                    s.offset_mpa.abs() * 1e3,
                    high_low(s.offset_mpa),
                    s.drift_mpa_per_s.abs() * 6e4
                )
            } else {
                format!(
                    "{:.0} kPa {} (an offset",
                    s.offset_mpa.abs() * 1e3,
                    high_low(s.offset_mpa)
                )
            };
            let since = if s.since_s.is_finite() {
                format!(" since {:.1} s", s.since_s)
            } else {
                String::new()
            };
            // (the pressure transducer the fit ranks second: where the named one
            // reads true, the one to check)
            let other = match s.channel {
                0 | 1 if s.other_channel_left_ratio.is_finite() => format!(
                    ". A misreading of {o} leaves {r:.1} times as much of the rises unexplained: if {name} \
                     reads true, check {o}",
                    o = OFFSET_CHANNEL_NAMES[1 - s.channel],
                    r = s.other_channel_left_ratio
                ),
                _ => String::new(),
            };
            format!(
                "{name} reads {reading}, fitted over {OFFSET_WINDOW_S:.0} s){since}: the leak sizes move with \
                 the valve's flow as a misreading of {name} makes them, not as a leak does; no leak decision \
                 while it stands{other}"
            )
        }
    };
    ev
}
