//! Why the leak-size detector took no evidence: its seconds without
//! evidence after arming, charged to their causes.

use serde::Serialize;

/// Why the detector took no evidence at a sample. Where several causes hold,
/// the sample is charged to the first in this order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlindCause {
    /// The filter restarted (a reset, a skipped sample), is converging again,
    /// or the baseline is being taken again after it.
    Restart,
    /// The filter re-anchored its fast states on the readings: a gap it could
    /// not bridge, or it had lost track.
    Reanchored,
    /// A reading was left out of the update (NaN or out of range).
    ChannelLeftOut,
    /// A suspect reading: an outlier, or a repeat that may be a stuck transducer.
    SuspectReading,
    /// The filter's NIS burst past the gate, or its average stayed high.
    Nis,
    /// The command reversed faster than the model follows.
    CommandRate,
    /// A transducer is named reading off: its offset is in the leak sizes.
    SensorNamed,
    /// An excursion to tank or supply pressure and its recovery.
    Excursion,
}

/// Number of [`BlindCause`]s.
const CAUSES: usize = 8;

/// The seconds without evidence after arming, by cause, s. Each blind sample
/// is charged to one cause ([`BlindCause`]'s order): they add up to the
/// detector's blind seconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct BlindSeconds {
    /// The filter restarted, converged again or the baseline was taken again, s.
    pub restart_s: f64,
    /// The filter re-anchored on the readings (a gap, or it had lost track), s.
    pub reanchored_s: f64,
    /// A reading was left out of the update, s.
    pub channel_left_out_s: f64,
    /// A suspect reading (an outlier, a repeat), s.
    pub suspect_reading_s: f64,
    /// The filter's NIS past the gate (a burst or a high average), s.
    pub nis_s: f64,
    /// The command reversed faster than the model follows, s.
    pub command_rate_s: f64,
    /// A transducer was named reading off, s.
    pub sensor_named_s: f64,
    /// Excursions to tank or supply pressure and their recoveries, s.
    pub excursion_s: f64,
}

impl std::ops::AddAssign for BlindSeconds {
    fn add_assign(&mut self, other: BlindSeconds) {
        self.restart_s += other.restart_s;
        self.reanchored_s += other.reanchored_s;
        self.channel_left_out_s += other.channel_left_out_s;
        self.suspect_reading_s += other.suspect_reading_s;
        self.nis_s += other.nis_s;
        self.command_rate_s += other.command_rate_s;
        self.sensor_named_s += other.sensor_named_s;
        self.excursion_s += other.excursion_s;
    }
}

impl BlindSeconds {
    /// All the seconds, s.
    pub fn total_s(&self) -> f64 {
        self.named().iter().map(|(_, s)| s).sum()
    }

    /// The causes with their seconds, in [`BlindCause`]'s order, named for
    /// a reader ("NIS bursts").
    pub fn named(&self) -> [(&'static str, f64); CAUSES] {
        [
            ("filter restarts", self.restart_s),
            ("re-anchorings", self.reanchored_s),
            ("readings left out", self.channel_left_out_s),
            ("suspect readings", self.suspect_reading_s),
            ("NIS bursts", self.nis_s),
            ("fast commands", self.command_rate_s),
            ("a transducer named", self.sensor_named_s),
            ("excursions", self.excursion_s),
        ]
    }

    /// The causes that took any time, in words ("excursions 2.1 s, NIS bursts
    /// 1.9 s"); empty if none did.
    pub fn describe(&self) -> String {
        self.named()
            .iter()
            .filter(|(_, s)| *s >= 0.05)
            .map(|(name, s)| format!("{name} {s:.1} s"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Until when each cause blinds the detector (s), and the seconds charged to each.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlindCauses {
    until_s: [f64; CAUSES],
    seconds: [f64; CAUSES],
}

impl Default for BlindCauses {
    fn default() -> Self {
        BlindCauses {
            until_s: [f64::NEG_INFINITY; CAUSES],
            seconds: [0.0; CAUSES],
        }
    }
}

impl BlindCauses {
    /// `cause` blinds the detector until `t_s` (s) at least.
    pub(crate) fn hold(&mut self, cause: BlindCause, t_s: f64) {
        let u = &mut self.until_s[cause as usize];
        *u = u.max(t_s);
    }

    /// Charges a blind sample at `t_s` (s), `dt_s` (s) long, to the first
    /// cause that holds: `converging` (the filter converging again) and
    /// `misreading` (a transducer named) hold now, the others until their
    /// time. One held by nothing is charged to a restart (the baseline taken again).
    pub(crate) fn charge(&mut self, t_s: f64, dt_s: f64, converging: bool, misreading: bool) {
        let cause = (0..CAUSES)
            .find(|&c| {
                t_s < self.until_s[c]
                    || (c == BlindCause::Restart as usize && converging)
                    || (c == BlindCause::SensorNamed as usize && misreading)
            })
            .unwrap_or(BlindCause::Restart as usize);
        self.seconds[cause] += dt_s;
    }

    /// The seconds charged so far, by cause.
    pub(crate) fn seconds(&self) -> BlindSeconds {
        let [restart_s, reanchored_s, channel_left_out_s, suspect_reading_s, nis_s, command_rate_s, sensor_named_s, excursion_s] =
            self.seconds;
        BlindSeconds {
            restart_s,
            reanchored_s,
            channel_left_out_s,
            suspect_reading_s,
            nis_s,
            command_rate_s,
            sensor_named_s,
            excursion_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_blind_sample_is_charged_to_the_first_cause_that_holds() {
        let mut b = BlindCauses::default();
        b.hold(BlindCause::Excursion, 1.0);
        b.hold(BlindCause::Nis, 0.5);
        // 0.0-0.5: NIS and excursion hold, NIS comes first; 0.5-1.0: the excursion
        for i in 0..10 {
            b.charge(f64::from(i) * 0.1, 0.1, false, false);
        }
        // a named transducer while nothing else holds, then converging over it
        b.charge(2.0, 0.25, false, true);
        b.charge(2.5, 0.5, true, true);
        let s = b.seconds();
        assert!((s.nis_s - 0.5).abs() < 1e-12, "{s:?}");
        assert!((s.excursion_s - 0.5).abs() < 1e-12, "{s:?}");
        assert_eq!(s.sensor_named_s, 0.25);
        assert_eq!(s.restart_s, 0.5);
        assert!((s.total_s() - 1.75).abs() < 1e-12);
        let mut twice = s;
        twice += s;
        assert!((twice.total_s() - 3.5).abs() < 1e-12);
        assert_eq!(twice.nis_s, 1.0);
        assert_eq!(
            s.describe(),
            "filter restarts 0.5 s, NIS bursts 0.5 s, a transducer named 0.2 s, excursions 0.5 s"
        );
        assert_eq!(BlindSeconds::default().describe(), "");
    }
}
