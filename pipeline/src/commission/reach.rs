//! How large a misreading of each transducer the detector names on the
//! commissioning recording's duty cycle, and whether it watches x at all.
//!
//! The detector names an offset on a channel once the leak sizes' change it
//! explains reaches [`OFFSET_NAMED_SHARE`] of the smallest threshold (RMS over
//! [`OFFSET_WINDOW_S`]) and the offset passes the least named
//! ([`detect::offset`]). The leak filter gives its own response to a
//! misreading of each channel on every sample, so the recording says how large
//! an offset must be before its part of the rises reaches that level. The
//! rises are measured from a baseline that takes up a standing offset's
//! steady part, so the part that counts is the response's swing about it.

use detect::offset::{
    least_pressure_offset_pa, sound_transducer_misreading, OFFSET_LEAST_SHARE_OF_RANGE, OFFSET_NAMED_SHARE,
    OFFSET_WINDOW_S, POSITION_LEAST_OFFSET_MM, POSITION_MOST_OFFSET_MM,
};

/// The leak filter's responses to a misreading over a recording, every
/// [`ResponseTrace::EVERY`]-th settled estimate.
#[derive(Debug, Clone, Default)]
pub struct ResponseTrace {
    /// Sample times, s.
    t_s: Vec<f64>,
    /// Per kept estimate, the responses to 1 MPa on p1 and on p2 and to 1 mm
    /// on x: each the change of q_e1, q_e2, q_i, L/min.
    responses: Vec<[[f64; 3]; 3]>,
    /// Estimates seen.
    seen: u64,
    /// Σ of the p1 and p2 readings of the kept estimates, Pa.
    reading_sums_pa: [f64; 2],
}

impl ResponseTrace {
    /// One estimate in this many is kept (100 Hz at 1 kHz).
    pub const EVERY: u64 = 10;

    /// Takes estimate `e` (kept every [`Self::EVERY`]-th, while the filter is settled).
    pub fn push(&mut self, e: &filter::Estimate) {
        self.seen += 1;
        if !(self.seen - 1).is_multiple_of(Self::EVERY) || e.flags & filter::FLAGS_UNSETTLED != 0 {
            return;
        }
        let r = [
            e.offset_response_lpm_per_mpa[0],
            e.offset_response_lpm_per_mpa[1],
            e.position_offset_response_lpm_per_mm,
        ];
        let reading = [e.measured[1], e.measured[2]];
        if r.iter().flatten().chain(&reading).all(|v| v.is_finite()) && e.t_s.is_finite() {
            self.t_s.push(e.t_s);
            self.responses.push(r);
            for (sum, p) in self.reading_sums_pa.iter_mut().zip(reading) {
                *sum += p.abs();
            }
        }
    }

    /// The mean p1 and p2 readings of the kept estimates, Pa (NaN: none kept).
    pub fn mean_reading_pa(&self) -> [f64; 2] {
        let n = self.t_s.len() as f64;
        self.reading_sums_pa
            .map(|sum| if n > 0.0 { sum / n } else { f64::NAN })
    }

    /// The median over the recording of each response's swing about its
    /// baseline, RMS over the detector's window, in the rises' plane (w1, w2)
    /// of the internal leak's pressure factors `factors`: p1 and p2 in L/min
    /// per MPa, x in L/min per mm. The baseline follows the response at the
    /// detector's `baseline_tau_s` (s), as the rises' baseline takes up a
    /// standing offset's steady part. 0 where the recording is shorter than
    /// a window.
    pub fn typical_rms(&self, factors: [f64; 2], baseline_tau_s: f64) -> [f64; 3] {
        let plane = |r: &[[f64; 3]; 3]| -> [[f64; 2]; 3] {
            std::array::from_fn(|c| {
                let [w1, w2, _] = detect::signatures_with(r[c], factors);
                [w1, w2]
            })
        };
        // (the baseline starts at the recording's mean, where it stands once settled)
        let n = self.responses.len().max(1) as f64;
        let mut base = [[0.0; 2]; 3];
        for w in self.responses.iter().map(plane) {
            for c in 0..3 {
                for k in 0..2 {
                    base[c][k] += w[c][k] / n;
                }
            }
        }
        let (mut mean_square, mut weight) = ([0.0; 3], 0.0);
        let mut windows: [Vec<f64>; 3] = Default::default();
        let start_s = self.t_s.first().copied().unwrap_or(0.0);
        for (i, (t, r)) in self.t_s.iter().zip(&self.responses).enumerate() {
            let dt = if i == 0 {
                0.0
            } else {
                (t - self.t_s[i - 1]).max(0.0)
            };
            let keep = (-dt / OFFSET_WINDOW_S).exp();
            let follow = 1.0 - (-dt / baseline_tau_s.max(1e-3)).exp();
            weight = keep * weight + (1.0 - keep);
            let w = plane(r);
            for c in 0..3 {
                let mut swing_square = 0.0;
                for k in 0..2 {
                    base[c][k] += follow * (w[c][k] - base[c][k]);
                    swing_square += (w[c][k] - base[c][k]).powi(2);
                }
                mean_square[c] = keep * mean_square[c] + (1.0 - keep) * swing_square;
                if t - start_s >= OFFSET_WINDOW_S {
                    windows[c].push((mean_square[c] / weight).sqrt());
                }
            }
        }
        windows.map(|mut w| median(&mut w))
    }
}

/// The median of `v` (0 when empty).
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The smallest misreading of each transducer the detector names on a duty
/// cycle like the recording's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorReach {
    /// The offset on p1 and on p2 whose part of the rises reaches the naming
    /// level, kPa (infinite where the recording's flow shows none).
    pub pressure_shown_kpa: [f64; 2],
    /// The least standing offset on a pressure transducer named, kPa
    /// ([`OFFSET_LEAST_SHARE_OF_RANGE`] of its range).
    pub pressure_least_kpa: f64,
    /// What a sound p1 and p2 may read off at the recording's mean reading,
    /// kPa: the datasheet's zero offset plus its span error times the reading
    /// (infinite where the datasheet gives neither). A standing offset is
    /// named from it where it is under `pressure_least_kpa`.
    pub pressure_sound_kpa: [f64; 2],
    /// The least drifting offset on a pressure transducer named, kPa
    /// ([`detect::offset::DRIFT_LEAST_SHARE_OF_RANGE`] of its range).
    pub pressure_least_drifting_kpa: f64,
    /// The offset on x whose part of the rises reaches the naming level, mm
    /// (infinite where the recording shows none).
    pub position_shown_mm: f64,
    /// The typical swing of the leak sizes about their baseline for 1 mm on x, L/min (RMS over the window).
    pub position_response_lpm_per_mm: f64,
    /// The naming level: the leak sizes' change an offset must explain, L/min (RMS).
    pub naming_level_lpm: f64,
}

impl SensorReach {
    /// The reach for the typical responses `typical_rms` ([`ResponseTrace::typical_rms`]),
    /// the detector's thresholds `thresholds_lpm` (L/min at p_s/2) and the
    /// pressure transducers' range `full_scale_pa` (Pa).
    pub fn new(typical_rms: [f64; 3], thresholds_lpm: [f64; 3], full_scale_pa: f64) -> SensorReach {
        let level = OFFSET_NAMED_SHARE * thresholds_lpm.iter().copied().fold(f64::INFINITY, f64::min);
        let shown = |rms: f64| if rms > 0.0 { level / rms } else { f64::INFINITY };
        SensorReach {
            pressure_shown_kpa: [shown(typical_rms[0]) * 1e3, shown(typical_rms[1]) * 1e3],
            pressure_least_kpa: least_pressure_offset_pa(full_scale_pa, false) * 1e-3,
            pressure_sound_kpa: [f64::INFINITY; 2],
            pressure_least_drifting_kpa: least_pressure_offset_pa(full_scale_pa, true) * 1e-3,
            position_shown_mm: shown(typical_rms[2]),
            position_response_lpm_per_mm: typical_rms[2],
            naming_level_lpm: level,
        }
    }

    /// The reach with what a sound transducer may read off at the recording's
    /// mean readings `mean_reading_pa` (Pa), for a datasheet's largest zero
    /// offset `zero_offset_max_pa` (Pa) and span error `span_error_max` (a
    /// fraction of the reading; both 0: not given).
    pub fn with_sound_transducer(
        mut self,
        mean_reading_pa: [f64; 2],
        zero_offset_max_pa: f64,
        span_error_max: f64,
    ) -> SensorReach {
        self.pressure_sound_kpa = mean_reading_pa.map(|p| {
            let bound = sound_transducer_misreading(zero_offset_max_pa, span_error_max, p) * 1e-3;
            // (NaN where no reading was kept)
            if bound.is_nan() {
                f64::INFINITY
            } else {
                bound
            }
        });
        self
    }

    /// The least standing offset named on p1 and on p2, kPa: the range's
    /// share, or what a sound transducer may read off where that is smaller.
    pub fn pressure_least_standing_kpa(&self) -> [f64; 2] {
        self.pressure_sound_kpa.map(|s| s.min(self.pressure_least_kpa))
    }

    /// The smallest offset named on p1 and on p2, kPa (infinite: none is).
    pub fn pressure_named_kpa(&self) -> [f64; 2] {
        let least = self.pressure_least_standing_kpa();
        [0, 1].map(|c| self.pressure_shown_kpa[c].max(least[c]))
    }

    /// The smallest offset named on x, mm; `None` where x is not watched: an
    /// offset would show only past the largest the detector fits
    /// ([`POSITION_MOST_OFFSET_MM`]).
    pub fn position_named_mm(&self) -> Option<f64> {
        if self.position_shown_mm <= POSITION_MOST_OFFSET_MM {
            Some(self.position_shown_mm.max(POSITION_LEAST_OFFSET_MM))
        } else {
            None
        }
    }

    /// The least offset named on p1 and on p2 (kPa) and on x (mm); inf: not
    /// watched ([`detect::Commissioning::least_offsets_named`]).
    pub fn least_named(&self) -> [f64; 3] {
        let [p1, p2] = self.pressure_named_kpa();
        [p1, p2, self.position_named_mm().unwrap_or(f64::INFINITY)]
    }

    /// The terminal's line.
    pub fn line(&self) -> String {
        let named = self.pressure_named_kpa();
        let pressure = |c: usize| {
            if named[c].is_finite() {
                format!("p{} from {:.0} kPa", c + 1, named[c])
            } else {
                format!(
                    "p{} not watched (no flow on this recording shows an offset)",
                    c + 1
                )
            }
        };
        let position = match self.position_named_mm() {
            Some(mm) => format!("x from {mm:.1} mm"),
            None => format!(
                "x not watched: 1 mm on x swings the leak sizes by {:.4} L/min about their baseline, so an offset shows only past {:.0} mm, \
                 beyond the {:.0} mm the detector fits (a drifting position sensor is not seen on this rig)",
                self.position_response_lpm_per_mm, self.position_shown_mm, POSITION_MOST_OFFSET_MM
            ),
        };
        let range = format!(
            "{:.0} kPa ({} % of the range)",
            self.pressure_least_kpa,
            OFFSET_LEAST_SHARE_OF_RANGE * 100.0
        );
        let least = if self.pressure_sound_kpa.iter().any(|s| s.is_finite()) {
            format!(
                "the smaller of {range} and what a sound transducer may read off at the recording's mean reading, {:.0}/{:.0} kPa",
                self.pressure_sound_kpa[0], self.pressure_sound_kpa[1]
            )
        } else {
            range
        };
        format!(
            "transducer offsets named on a duty cycle like this recording's: {}, {} (the least named is {least}; \
             {:.0} kPa for a drifting one; the leak sizes show {:.0}/{:.0} kPa); {position}",
            pressure(0),
            pressure(1),
            self.pressure_least_drifting_kpa,
            self.pressure_shown_kpa[0],
            self.pressure_shown_kpa[1],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plant rig's x: 0.0004 L/min per mm against a smallest threshold of
    /// 0.03 L/min shows only past 22.5 mm, beyond the 15 mm fitted: not
    /// watched. The thesis rig's 0.01 L/min per mm shows at 0.9 mm: named from
    /// the least, 1 mm. Pressures: the 0.5 % floor where the response is
    /// strong (1 % drifting), the response's own level where it is weak.
    #[test]
    fn the_reach_follows_the_responses_and_the_floors() {
        let plant = SensorReach::new([0.5, 0.05, 0.0004], [0.05, 0.03, 0.04], 25e6);
        assert!((plant.naming_level_lpm - 0.009).abs() < 1e-12);
        assert!((plant.position_shown_mm - 22.5).abs() < 1e-9);
        assert_eq!(plant.position_named_mm(), None);
        let named = plant.pressure_named_kpa();
        assert!((named[0] - 125.0).abs() < 1e-9 && (plant.pressure_shown_kpa[0] - 18.0).abs() < 1e-9);
        // p2's weaker response shows an offset only from 180 kPa, past the floor
        assert!((named[1] - 180.0).abs() < 1e-9);
        assert!((plant.pressure_least_drifting_kpa - 250.0).abs() < 1e-9);
        let weak = SensorReach::new([0.02, 0.0, 0.01], [0.05, 0.03, 0.04], 20.7e6);
        assert!((weak.pressure_named_kpa()[0] - 450.0).abs() < 1e-9);
        assert!(weak.pressure_named_kpa()[1].is_infinite());
        assert_eq!(weak.position_named_mm(), Some(1.0));
        let line = plant.line();
        assert!(
            line.contains("p1 from 125 kPa")
                && line.contains("250 kPa for a drifting one")
                && line.contains("x not watched"),
            "{line}"
        );
        assert!(weak.line().contains("p2 not watched") && weak.line().contains("x from 1.0 mm"));
        // a datasheet's 50 kPa and 0.5 %: at 8 MPa a sound transducer reads
        // up to 90 kPa off, at 20 MPa 150 kPa (past the range's share)
        let sound = plant.with_sound_transducer([8e6, 20e6], 50e3, 0.005);
        let named = sound.pressure_named_kpa();
        assert!(
            (named[0] - 90.0).abs() < 1e-9 && (named[1] - 180.0).abs() < 1e-9,
            "{named:?}"
        );
        assert!((sound.pressure_least_standing_kpa()[1] - 125.0).abs() < 1e-9);
        assert!(sound.line().contains("p1 from 90 kPa") && sound.line().contains("90/150 kPa"));
        assert_eq!(plant.with_sound_transducer([8e6, 20e6], 0.0, 0.0), plant);
    }

    /// A response that swings steadily (RMS 0.3 over every window) about
    /// zero gives its RMS; a steady response gives next to nothing (the
    /// baseline takes it up), and a steady part under the swing is left out;
    /// the first window's worth of samples is left out.
    #[test]
    fn the_typical_response_is_the_swing_about_its_baseline() {
        let trace = |steady: f64, swing: f64| {
            let mut trace = ResponseTrace::default();
            for i in 0..6000 {
                let t = i as f64 * 0.01;
                let s = steady + swing * std::f64::consts::SQRT_2 * (2.0 * std::f64::consts::PI * t).sin();
                trace.t_s.push(t);
                // ext1 only: (w1, w2) = (s, 0) for any factors
                trace.responses.push([[s, 0.0, 0.0], [0.0; 3], [0.0; 3]]);
            }
            trace.typical_rms([-0.7, -0.6], 15.0)
        };
        let rms = trace(0.0, 0.3);
        assert!((rms[0] - 0.3).abs() < 0.01, "{rms:?}");
        assert_eq!(rms[1], 0.0);
        assert!(trace(0.5, 0.0)[0] < 1e-9, "{:?}", trace(0.5, 0.0));
        let under = trace(0.5, 0.3);
        assert!((under[0] - 0.3).abs() < 0.01, "{under:?}");
        assert_eq!(ResponseTrace::default().typical_rms([1.0, 1.0], 15.0), [0.0; 3]);
    }
}
