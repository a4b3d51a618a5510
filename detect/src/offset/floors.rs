//! The least misreadings named, and what a small one must show first: a
//! standing offset from [`OFFSET_LEAST_SHARE_OF_RANGE`](super::OFFSET_LEAST_SHARE_OF_RANGE),
//! one that drifts fast from [`DRIFT_LEAST_SHARE_OF_RANGE`](super::DRIFT_LEAST_SHARE_OF_RANGE),
//! and an offset on p1 or p2 told from the other pressure channel
//! ([`CHANNEL_FIT_RATIO`]). Where the datasheet gives the transducers' zero
//! and span tolerances, a standing offset is named from the smaller of its
//! share of the range and what a sound transducer may read off at the
//! pressures read ([`SoundTransducer`]).

use super::fit::{channel_of, is_drift, is_position, is_span};
use super::{
    OffsetWatch, CHANNEL_FIT_RATIO, DRIFT_LEAST_MOVE_SHARE, DRIFT_LEAST_SHARE_OF_RANGE,
    OFFSET_CLEAN_CONFIRM_S, OFFSET_CLEAN_FLOOR_SHARE, OFFSET_CLEAN_UNEXPLAINED, OFFSET_CONFIRM_S,
    OFFSET_LEAST_SHARE_OF_RANGE, OFFSET_WINDOW_S, POSITION_LEAST_OFFSET_MM, SPAN_LEAST_ERROR,
};

/// The least pressure offset named on a transducer of range `full_scale_pa`
/// (Pa), in Pa: [`DRIFT_LEAST_SHARE_OF_RANGE`] of it for an offset that
/// drifts fast (`drifting`), else [`OFFSET_LEAST_SHARE_OF_RANGE`].
pub fn least_pressure_offset_pa(full_scale_pa: f64, drifting: bool) -> f64 {
    let share = if drifting {
        DRIFT_LEAST_SHARE_OF_RANGE
    } else {
        OFFSET_LEAST_SHARE_OF_RANGE
    };
    share * full_scale_pa
}

/// What a sound pressure transducer may read off at `reading`: its
/// datasheet's largest zero offset `zero_offset_max` plus its largest span
/// error `span_error_max` (a fraction) times |reading|, in the unit of
/// `zero_offset_max` and `reading`; infinite where the datasheet gives
/// neither (both 0).
pub fn sound_transducer_misreading(zero_offset_max: f64, span_error_max: f64, reading: f64) -> f64 {
    if zero_offset_max > 0.0 || span_error_max > 0.0 {
        zero_offset_max + span_error_max * reading.abs()
    } else {
        f64::INFINITY
    }
}

/// What a sound pressure transducer may read off at the pressures it has
/// read: the datasheet's largest zero offset plus its largest span error
/// times each channel's mean reading over the window ([`OFFSET_WINDOW_S`]).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SoundTransducer {
    /// The datasheet's largest zero offset, MPa (0, with no span error: not given).
    zero_offset_max_mpa: f64,
    /// The datasheet's largest span error, as a fraction of the reading (1).
    span_error_max: f64,
    /// Per channel (p1, p2): Σ weight·|reading| over the window, MPa·s.
    reading_sums_mpa_s: [f64; 2],
    /// Σ weight over the window, s.
    weight_s: f64,
}

impl SoundTransducer {
    /// Whether the datasheet gives a tolerance.
    fn given(&self) -> bool {
        sound_transducer_misreading(self.zero_offset_max_mpa, self.span_error_max, 0.0).is_finite()
    }

    /// Takes the readings `reading_mpa` (MPa; 0 where not read) held for
    /// `dt_s` (s), the window's older sums kept at `keep` (1).
    pub(super) fn add(&mut self, keep: f64, dt_s: f64, reading_mpa: [f64; 2]) {
        if !self.given() {
            return;
        }
        for (sum, p) in self.reading_sums_mpa_s.iter_mut().zip(reading_mpa) {
            *sum = keep * *sum + dt_s * p.abs();
        }
        self.weight_s = keep * self.weight_s + dt_s;
    }

    /// The largest misreading of a sound transducer on channel `c` (0 p1, 1
    /// p2) at its mean reading over the window, MPa; infinite where the
    /// datasheet gives no tolerance or nothing has been read.
    pub(super) fn largest_misreading_mpa(&self, c: usize) -> f64 {
        if self.weight_s <= 0.0 {
            return f64::INFINITY;
        }
        let mean_mpa = self.reading_sums_mpa_s[c] / self.weight_s;
        sound_transducer_misreading(self.zero_offset_max_mpa, self.span_error_max, mean_mpa)
    }

    /// The same tolerance, its readings forgotten (the filter restarted).
    pub(super) fn forgotten(&self) -> Self {
        SoundTransducer {
            zero_offset_max_mpa: self.zero_offset_max_mpa,
            span_error_max: self.span_error_max,
            ..SoundTransducer::default()
        }
    }
}

impl OffsetWatch {
    /// The watch for transducers whose datasheet gives their largest zero
    /// offset `zero_offset_max_pa` (Pa) and span error `span_error_max` (a
    /// fraction of the reading; both 0: not given). A standing offset on p1 or
    /// p2 is then named from the smaller of its share of the range and what a
    /// sound transducer may read off at the pressures read: a span error where
    /// the pressure barely moves fits as an offset, and a small one is named
    /// where the chamber's pressure is low.
    pub fn with_transducer_tolerance(mut self, zero_offset_max_pa: f64, span_error_max: f64) -> Self {
        let valid = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
        self.sound = SoundTransducer {
            zero_offset_max_mpa: valid(zero_offset_max_pa) * 1e-6,
            span_error_max: valid(span_error_max),
            ..SoundTransducer::default()
        };
        self
    }

    /// The least misreading named of hypothesis `h`: [`SPAN_LEAST_ERROR`]
    /// for a span error, [`POSITION_LEAST_OFFSET_MM`] on x, the least
    /// drifting or standing pressure offset (MPa) for an offset (a standing
    /// one's at most what a sound transducer may read off, [`SoundTransducer`]).
    pub(super) fn least(&self, h: usize) -> f64 {
        if is_span(h) {
            SPAN_LEAST_ERROR
        } else if is_position(h) {
            POSITION_LEAST_OFFSET_MM
        } else if is_drift(h) && self.drifts_clearly(h) {
            self.least_drift_mpa
        } else {
            self.least_offset_mpa
                .min(self.sound.largest_misreading_mpa(channel_of(h)))
        }
    }

    /// Whether the drifting offset of hypothesis `h` moves by at least
    /// [`DRIFT_LEAST_MOVE_SHARE`] of itself over the window
    /// ([`OFFSET_WINDOW_S`]). Else it is named as a standing offset would be.
    fn drifts_clearly(&self, h: usize) -> bool {
        let moved = self.window.drift_rate_mpa_per_s(h).abs() * OFFSET_WINDOW_S;
        moved >= DRIFT_LEAST_MOVE_SHARE * self.window.coefficient(h).abs()
    }

    /// The least misreading of hypothesis `h` that rivals a leak: on p1 or p2
    /// [`OFFSET_LEAST_SHARE_OF_RANGE`] of the range (MPa), a sound transducer
    /// reads within it (not what it may read at the pressures read: a leak's
    /// rises fit a small offset often); a span error or an offset on x from
    /// [`OFFSET_CLEAN_FLOOR_SHARE`] of the least named.
    pub(super) fn tolerance(&self, h: usize) -> f64 {
        if is_span(h) || is_position(h) {
            OFFSET_CLEAN_FLOOR_SHARE * self.least(h)
        } else {
            self.least_offset_mpa
        }
    }

    /// Whether the misreading of hypothesis `h`, whose fit leaves `left`
    /// ((L/min)²·s), is told from the other pressure channel's: it fits
    /// clearly better: the other channel's best leaves more than
    /// [`OFFSET_CLEAN_UNEXPLAINED`] of the rises' energy and this one less
    /// than [`CHANNEL_FIT_RATIO`] of that. A span error and an offset on x
    /// are told by their own tests.
    pub(super) fn channel_told(&self, h: usize, left: f64) -> bool {
        if is_span(h) || is_position(h) {
            return true;
        }
        let other = self.window.other_pressure_channel_left(channel_of(h));
        other > OFFSET_CLEAN_UNEXPLAINED * self.window.energy && left < CHANNEL_FIT_RATIO * other
    }

    /// How long the naming conditions must hold for the misreading of
    /// hypothesis `h`, whose fit leaves `left` ((L/min)²·s), to be named, s:
    /// [`OFFSET_CONFIRM_S`] past its least ([`Self::least`]),
    /// [`OFFSET_CLEAN_CONFIRM_S`] past [`OFFSET_CLEAN_FLOOR_SHARE`] of it where
    /// the fit of a drifting pressure offset or an offset on x is clean; None
    /// where it is too small to name. A standing pressure offset under its
    /// least is not named however cleanly it fits: a sound transducer's
    /// misreading is one (its zero and span tolerance at the working point,
    /// which commissioning may not resolve), and a duty cycle unlike the
    /// commissioning's shows it.
    pub(super) fn confirm_s(&self, h: usize, left: f64) -> Option<f64> {
        // (the least read once: a drift's takes its fitted rate)
        let (b, least) = (self.window.coefficient(h).abs(), self.least(h));
        if b > least {
            Some(OFFSET_CONFIRM_S)
        } else if (is_drift(h) || is_position(h))
            && left < OFFSET_CLEAN_UNEXPLAINED * self.window.energy
            && b > OFFSET_CLEAN_FLOOR_SHARE * least
        {
            Some(OFFSET_CLEAN_CONFIRM_S)
        } else {
            None
        }
    }
}
