//! The classifier's side of the wire: [`LeakEvent`] ⇄ [`LeakEventFrame`] and the
//! codes of [`EventKind`] and [`Phase`], the one place where they are converted.
//!
//! The conversions are traits ([`EventWire`], [`WireCode`]): the event types live
//! in the pure `detect` crate and the frame in `frames`, so neither may hold a
//! `From` between them here.

use detect::{EventKind, LeakEvent, Phase};
use frames::{event_kind, event_phase, LeakEventFrame};

/// A value carried as an integer code on the wire.
pub trait WireCode: Sized {
    /// The wire code.
    fn code(self) -> u32;
    /// The value of a wire code; the error names an unknown code.
    fn from_code(code: u32) -> Result<Self, String>;
}

/// [`LeakEvent`] ⇄ [`LeakEventFrame`].
pub trait EventWire: Sized {
    /// The frame of this event, triggered by the estimate with sequence number
    /// `seq` acquired at `acq_mono_ns` and decided at `done_mono_ns`
    /// (`CLOCK_MONOTONIC`, ns). Texts longer than their field are cut.
    fn to_frame(&self, seq: u64, acq_mono_ns: u64, done_mono_ns: u64) -> LeakEventFrame;
    /// The event a frame reports; the error names an unknown kind or phase code.
    fn from_frame(f: &LeakEventFrame) -> Result<Self, String>;
}

/// The wire codes of kinds (`frames::event_kind`).
impl WireCode for EventKind {
    fn code(self) -> u32 {
        match self {
            EventKind::Ext1 => event_kind::EXT1,
            EventKind::Ext2 => event_kind::EXT2,
            EventKind::Int => event_kind::INTERNAL,
            EventKind::Leak => event_kind::LEAK_PENDING,
            EventKind::EstimatorReset => event_kind::ESTIMATOR_RESET,
            EventKind::SensorStuck => event_kind::SENSOR_STUCK,
            EventKind::SensorSaturated => event_kind::SENSOR_SATURATED,
            EventKind::SensorDead => event_kind::SENSOR_DEAD,
            EventKind::NotArmed => event_kind::NOT_ARMED,
            EventKind::SensorOffset => event_kind::SENSOR_OFFSET,
            EventKind::SensorSpikes => event_kind::SENSOR_SPIKES,
        }
    }

    fn from_code(code: u32) -> Result<Self, String> {
        Ok(match code {
            event_kind::EXT1 => EventKind::Ext1,
            event_kind::EXT2 => EventKind::Ext2,
            event_kind::INTERNAL => EventKind::Int,
            event_kind::LEAK_PENDING => EventKind::Leak,
            event_kind::ESTIMATOR_RESET => EventKind::EstimatorReset,
            event_kind::SENSOR_STUCK => EventKind::SensorStuck,
            event_kind::SENSOR_SATURATED => EventKind::SensorSaturated,
            event_kind::SENSOR_DEAD => EventKind::SensorDead,
            event_kind::NOT_ARMED => EventKind::NotArmed,
            event_kind::SENSOR_OFFSET => EventKind::SensorOffset,
            event_kind::SENSOR_SPIKES => EventKind::SensorSpikes,
            other => return Err(format!("unknown event kind code {other}")),
        })
    }
}

/// The wire codes of phases (`frames::event_phase`).
impl WireCode for Phase {
    fn code(self) -> u32 {
        match self {
            Phase::Raised => event_phase::RAISED,
            Phase::Updated => event_phase::UPDATED,
            Phase::Cleared => event_phase::CLEARED,
        }
    }

    fn from_code(code: u32) -> Result<Self, String> {
        Ok(match code {
            event_phase::RAISED => Phase::Raised,
            event_phase::UPDATED => Phase::Updated,
            event_phase::CLEARED => Phase::Cleared,
            other => return Err(format!("unknown event phase code {other}")),
        })
    }
}

impl EventWire for LeakEvent {
    fn to_frame(&self, seq: u64, acq_mono_ns: u64, done_mono_ns: u64) -> LeakEventFrame {
        LeakEventFrame {
            seq,
            acq_mono_ns,
            cls_done_mono_ns: done_mono_ns,
            event_id: self.event_id,
            kind: self.kind.code(),
            phase: self.phase.code(),
            t_detect_s: self.t_detect_s,
            t_onset_s: self.t_onset_s,
            size_lpm: self.size_lpm,
            size_lpm_sigma: self.size_lpm_sigma,
            confidence: self.confidence,
            detector: frames::detector_bytes(&self.detector),
            size_nominal_lpm: self.size_nominal_lpm,
            coefficient_m3_s_sqrt_pa: self.coefficient_m3_s_sqrt_pa,
            statistic: self.statistic,
            threshold: self.threshold,
            channel: frames::text_bytes(&self.channel),
            detail: frames::detail_bytes(&self.detail),
        }
    }

    fn from_frame(f: &LeakEventFrame) -> Result<Self, String> {
        let mut ev = LeakEvent::plain(
            EventKind::from_code(f.kind)?,
            Phase::from_code(f.phase)?,
            frames::detector_name(&f.detector),
            f.event_id,
            f.t_detect_s,
            f.t_onset_s,
        );
        ev.size_lpm = f.size_lpm;
        ev.size_lpm_sigma = f.size_lpm_sigma;
        ev.size_nominal_lpm = f.size_nominal_lpm;
        ev.coefficient_m3_s_sqrt_pa = f.coefficient_m3_s_sqrt_pa;
        ev.statistic = f.statistic;
        ev.threshold = f.threshold;
        ev.confidence = f.confidence;
        ev.channel = frames::text(&f.channel).to_string();
        ev.detail = frames::text(&f.detail).to_string();
        Ok(ev)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip_and_unknown_codes_are_named() {
        let kinds = [
            EventKind::Ext1,
            EventKind::Ext2,
            EventKind::Int,
            EventKind::Leak,
            EventKind::EstimatorReset,
            EventKind::SensorStuck,
            EventKind::SensorSaturated,
            EventKind::SensorDead,
            EventKind::NotArmed,
            EventKind::SensorOffset,
            EventKind::SensorSpikes,
        ];
        for k in kinds {
            assert_eq!(EventKind::from_code(k.code()), Ok(k));
        }
        for p in [Phase::Raised, Phase::Updated, Phase::Cleared] {
            assert_eq!(Phase::from_code(p.code()), Ok(p));
        }
        assert_eq!(EventKind::Int.code(), 3);
        assert_eq!(
            EventKind::from_code(99),
            Err("unknown event kind code 99".to_string())
        );
        assert_eq!(Phase::from_code(7), Err("unknown event phase code 7".to_string()));
    }

    #[test]
    fn events_round_trip_through_frames() {
        let mut ev = LeakEvent::plain(EventKind::Ext2, Phase::Raised, "leak-size", 7, 12.5, 11.75);
        ev.size_lpm = 0.231;
        ev.size_lpm_sigma = 0.012;
        ev.size_nominal_lpm = 0.25;
        ev.coefficient_m3_s_sqrt_pa = 1.59e-9;
        ev.statistic = 7.5;
        ev.threshold = 4.9;
        ev.confidence = 0.8;
        ev.detail =
            "rise 7.5 healthy spreads; 0.231 L/min at the measured pressures, k = 1.59e-9 m³/(s·√Pa)".into();
        let f = ev.to_frame(42, 1_000, 2_000);
        assert_eq!(
            (f.seq, f.acq_mono_ns, f.cls_done_mono_ns, f.kind),
            (42, 1_000, 2_000, 2)
        );
        assert_eq!(LeakEvent::from_frame(&f), Ok(ev.clone()));
        // a sensor event keeps its channel
        let mut s = LeakEvent::plain(EventKind::SensorStuck, Phase::Raised, "sensors", 8, 3.0, f64::NAN);
        s.channel = "p1".into();
        let back = LeakEvent::from_frame(&s.to_frame(0, 0, 0)).expect("known codes");
        assert_eq!(back.channel, "p1");
        assert!(back.t_onset_s.is_nan() && back.size_lpm.is_nan());
        // a detail longer than the field with no space is cut at a character
        // boundary and ends in an ellipsis
        ev.detail = "√".repeat(200);
        let back = LeakEvent::from_frame(&ev.to_frame(0, 0, 0)).expect("known codes");
        assert_eq!(
            back.detail,
            format!("{}…", "√".repeat((frames::DETAIL_LEN - 3) / 3))
        );
        assert_eq!(back.detail.len(), 3 * 127 + 3);
    }

    /// The longest detail the leak-size detector writes (the base text of
    /// `detect/src/leak_size.rs` behind the longest prefix of
    /// `detect/src/leak_size/step.rs`, "slowly growing", every number at the
    /// widest it takes on a rig) crosses the wire whole.
    #[test]
    fn the_longest_detail_crosses_the_wire_whole() {
        let base = format!(
            "rise {z:.1} healthy spreads (threshold {:.1}, for {} false alarms/h); {:.3} L/min at the measured \
             pressures (mean over {} s), {:.3} L/min at p_s/2, k = {:.3e} m³/(s·√Pa)",
            123.45,
            0.001,
            -123.456,
            0.125,
            -123.456,
            -6.94e-10,
            z = 99999.9,
        );
        let detail = format!(
            "slowly growing: the healthy baseline drifted {:.3} L/min (at p_s/2) since the warm-up; {base}",
            -123.456
        );
        assert_eq!(detail.len(), 280, "{detail}");
        let mut ev = LeakEvent::plain(EventKind::Ext1, Phase::Raised, "leak-size", 1, 1.0, 0.5);
        ev.detail = detail.clone();
        let back = LeakEvent::from_frame(&ev.to_frame(0, 0, 0)).expect("known codes");
        assert_eq!(back.detail, detail);
        // the 192-byte field of LeakEventFrame.v2 cut it inside the unit
        assert!(detail.len() > 192);
        // twice as long: cut before a word, ended by an ellipsis, never inside the unit
        ev.detail = format!("{detail} {detail}");
        let back = LeakEvent::from_frame(&ev.to_frame(0, 0, 0)).expect("known codes");
        assert!(back.detail.len() <= frames::DETAIL_LEN, "{}", back.detail.len());
        assert!(back.detail.ends_with('…'), "{}", back.detail);
        let kept = back.detail.trim_end_matches('…');
        assert!(ev.detail.starts_with(kept), "{kept}");
        // the next character of the original after the kept text is a space
        assert_eq!(
            ev.detail[kept.len()..].chars().next(),
            Some(' '),
            "{}",
            back.detail
        );
        assert!(kept.len() > frames::DETAIL_LEN - 64, "{}", kept.len());
    }

    /// The widest `sensor-offset` detail (a drifting offset of 10 MPa at the
    /// fastest drift fitted, since a day of running, the other channel's fit
    /// 999.9 times worse) crosses the wire whole.
    #[test]
    fn the_widest_offset_detail_crosses_the_wire_whole() {
        let s = detect::offset::StandingOffset {
            channel: 1,
            offset_mpa: -9.999,
            offset_mm: f64::NAN,
            span_error: f64::NAN,
            drift_mpa_per_s: -detect::offset::MOST_DRIFT_MPA_PER_S,
            since_s: 86_399.9,
            other_channel_left_ratio: 999.9,
            event_id: 1,
        };
        let ev = detect::offset::offset_event(detect::offset::OffsetChange::Raised(s), 1.0, "leak-size");
        assert!(ev.detail.contains("if p2 reads true, check p1"), "{}", ev.detail);
        assert_eq!(ev.detail.len(), 326, "{}", ev.detail);
        let back = LeakEvent::from_frame(&ev.to_frame(0, 0, 0)).expect("known codes");
        assert_eq!(back.detail, ev.detail);
    }
}
