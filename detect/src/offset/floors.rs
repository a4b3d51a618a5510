//! The least misreadings named, and what a small one must show first: a
//! standing offset from [`OFFSET_LEAST_SHARE_OF_RANGE`](super::OFFSET_LEAST_SHARE_OF_RANGE),
//! one that drifts fast from [`DRIFT_LEAST_SHARE_OF_RANGE`](super::DRIFT_LEAST_SHARE_OF_RANGE),
//! and an offset on p1 or p2 told from the other pressure channel
//! ([`CHANNEL_FIT_RATIO`]).

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

impl OffsetWatch {
    /// The least misreading named of hypothesis `h`: [`SPAN_LEAST_ERROR`]
    /// for a span error, [`POSITION_LEAST_OFFSET_MM`] on x, the least
    /// drifting or standing pressure offset (MPa) for an offset.
    pub(super) fn least(&self, h: usize) -> f64 {
        if is_span(h) {
            SPAN_LEAST_ERROR
        } else if is_position(h) {
            POSITION_LEAST_OFFSET_MM
        } else if is_drift(h) && self.drifts_clearly(h) {
            self.least_drift_mpa
        } else {
            self.least_offset_mpa
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
    /// the least standing offset named (MPa), a sound transducer reads
    /// within it; a span error or an offset on x from
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
