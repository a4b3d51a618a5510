//! The leak filter's watch on its own tracking.
//!
//! Two ways a filter stops following the rig, and what the stage does:
//!
//! - **Lost track.** The NIS passes [`LOST_TRACK_NIS`] on
//!   [`LOST_TRACK_SAMPLES`] samples in a row. The fast states no longer
//!   follow the readings: a step that swings further with every update (the
//!   rod leaving an end stop against a chamber at its dead volume). Left
//!   alone, the swing passes into the leak sizes. The filter re-anchors its
//!   fast states on the next full sample and keeps its slow ones, as after a
//!   gap (`FLAG_REANCHORED`). Watched in the leak filter's layouts started
//!   from the measurement (`Init::Measured`, whose re-anchoring takes the
//!   fast states from the readings), from `convergence_time_s` after a start
//!   on (before it, large innovations are its own, as for the outlier gate).
//! - **Diverged.** The position innovation stays beyond
//!   max(`divergence_reset_m`, 20 σ) for [`DIVERGED_SAMPLES`] samples. The
//!   filter restarts from the next usable sample (`FLAG_RESET`).

/// A NIS beyond this (1), on [`LOST_TRACK_SAMPLES`] samples in a row, means
/// the filter has lost track: about 26 σ on each of the three channels. The
/// detector's default NIS gate is the same value.
pub const LOST_TRACK_NIS: f64 = 2000.0;
/// Samples in a row beyond [`LOST_TRACK_NIS`] that re-anchor the filter. A
/// lone reading that far off is an outlier or a leak's onset, not a lost track.
pub const LOST_TRACK_SAMPLES: u32 = 2;
/// Samples of persistent divergence before a reset (see `Tuning::divergence_reset_m`).
pub const DIVERGED_SAMPLES: u32 = 200;

/// What the watch says after a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tracking {
    /// The filter follows the readings.
    Follows,
    /// Lost track: re-anchor the fast states on the next full sample.
    Lost,
    /// Diverged: restart from the next usable sample.
    Diverged,
}

/// The counts behind [`Tracking`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TrackWatch {
    /// Samples in a row beyond [`LOST_TRACK_NIS`].
    lost_samples: u32,
    /// Samples in a row with the position innovation beyond its limit.
    diverged_samples: u32,
}

impl TrackWatch {
    /// Forgets the samples so far (after a restart or a re-anchoring).
    pub fn clear(&mut self) {
        *self = TrackWatch::default();
    }

    /// The verdict after a sample: its NIS `nis` (1; NaN without an update),
    /// whether lost track is watched (`watch_lost`: the leak filter's
    /// layouts started from the measurement, once past their convergence
    /// time), the position innovation `nu_x_m` (m; NaN if x was not
    /// used), its σ `sigma_x_m` (m) and `divergence_reset_m` (m; 0: never).
    pub fn after_sample(
        &mut self,
        nis: f64,
        watch_lost: bool,
        nu_x_m: f64,
        sigma_x_m: f64,
        divergence_reset_m: f64,
    ) -> Tracking {
        let limit_m = divergence_reset_m.max(20.0 * sigma_x_m);
        let off = divergence_reset_m > 0.0 && nu_x_m.abs() > limit_m;
        if count_run(&mut self.diverged_samples, off, DIVERGED_SAMPLES) {
            self.clear();
            return Tracking::Diverged;
        }
        if count_run(
            &mut self.lost_samples,
            watch_lost && nis > LOST_TRACK_NIS,
            LOST_TRACK_SAMPLES,
        ) {
            self.clear();
            return Tracking::Lost;
        }
        Tracking::Follows
    }
}

/// Counts `run` up while `beyond`, back to 0 otherwise; whether it has reached `limit`.
fn count_run(run: &mut u32, beyond: bool, limit: u32) -> bool {
    *run = if beyond { *run + 1 } else { 0 };
    *run >= limit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_samples_past_the_nis_limit_lose_track_one_does_not() {
        let mut w = TrackWatch::default();
        let quiet = |w: &mut TrackWatch, nis| w.after_sample(nis, true, 0.0, 1e-6, 0.02);
        assert_eq!(quiet(&mut w, 5000.0), Tracking::Follows);
        assert_eq!(quiet(&mut w, 3.0), Tracking::Follows);
        assert_eq!(quiet(&mut w, 5000.0), Tracking::Follows);
        assert_eq!(quiet(&mut w, 2500.0), Tracking::Lost);
        // counted again from there
        assert_eq!(quiet(&mut w, 2500.0), Tracking::Follows);
        // NaN (no update) does not count
        assert_eq!(quiet(&mut w, f64::NAN), Tracking::Follows);
        assert_eq!(quiet(&mut w, 2500.0), Tracking::Follows);
        // the thesis filter is not watched
        let mut t = TrackWatch::default();
        for _ in 0..10 {
            assert_eq!(t.after_sample(1e6, false, 0.0, 1e-6, 0.0), Tracking::Follows);
        }
    }

    #[test]
    fn a_position_off_for_200_samples_diverges() {
        let mut w = TrackWatch::default();
        for k in 1..DIVERGED_SAMPLES {
            assert_eq!(
                w.after_sample(1.0, true, 0.03, 1e-6, 0.02),
                Tracking::Follows,
                "sample {k}"
            );
        }
        assert_eq!(w.after_sample(1.0, true, 0.03, 1e-6, 0.02), Tracking::Diverged);
        // within 20 σ it follows
        let mut w = TrackWatch::default();
        for _ in 0..2 * DIVERGED_SAMPLES {
            assert_eq!(w.after_sample(1.0, true, 0.03, 2e-3, 0.02), Tracking::Follows);
        }
        // 0 never resets
        for _ in 0..2 * DIVERGED_SAMPLES {
            assert_eq!(w.after_sample(1.0, true, 5.0, 1e-6, 0.0), Tracking::Follows);
        }
    }
}
