//! The window veto's hold: a drifting offset's veto, once it has stood, is
//! not let go while the offset still fits nearly as well as before.
//!
//! The share is what the best offset's fit leaves over what the best leak's
//! leaves (1): under [`OFFSET_FIT_RATIO`] the offset
//! vetoes. A drifting offset's share creeps up over minutes as the filter's
//! slow states take part of it up, and flickers about the entry ratio on the
//! way: each rise above it let the leak evidence through. So a veto that has
//! stood for [`OFFSET_HOLD_TAU_S`] holds while the share stays under
//! [`OFFSET_HOLD_RATIO`] and runs less than [`OFFSET_HOLD_RISE`] above its
//! own mean over [`OFFSET_HOLD_TAU_S`]: a share climbing faster than
//! [`OFFSET_HOLD_RISE`] per [`OFFSET_HOLD_TAU_S`] (a leak's onset lifts it
//! within a second) is not held; a drift's slower creep is held until it
//! passes [`OFFSET_HOLD_RATIO`]. A veto entered by a share falling as fast
//! (a leak's onset whose rises happen to fit an offset) is not held.

use super::OFFSET_FIT_RATIO;

/// The share (1) the veto holds to, once held.
pub const OFFSET_HOLD_RATIO: f64 = 0.7;
/// The hold ends once the share is this much (1) above its mean over the
/// last [`OFFSET_HOLD_TAU_S`]: a rise faster than a drift's.
pub const OFFSET_HOLD_RISE: f64 = 0.1;
/// Time constant of the share's mean, and how long the veto must have stood
/// before it is held, s.
pub const OFFSET_HOLD_TAU_S: f64 = 5.0;
/// Largest share counted (1): a share past it says only "a leak fits far
/// better", and would lift the mean for long after.
const SHARE_CAP: f64 = 2.0;

/// Whether the window's offset vetoes, with the share's mean it is held by.
#[derive(Debug, Clone, Copy)]
pub(super) struct VetoHold {
    /// Whether the veto stands, as of the last sample.
    vetoes: bool,
    /// The time watched when the veto began, s.
    since_s: f64,
    /// Whether the share fell into the veto no faster than a drift moves it.
    entered_slowly: bool,
    /// The share averaged over [`OFFSET_HOLD_TAU_S`] (1); NaN until read.
    share_mean: f64,
    /// A sample period (s) and the mean's decay over it (1).
    keep: (f64, f64),
}

impl Default for VetoHold {
    fn default() -> Self {
        Self {
            vetoes: false,
            since_s: 0.0,
            entered_slowly: false,
            share_mean: f64::NAN,
            keep: (0.0, 1.0),
        }
    }
}

impl VetoHold {
    /// Whether the veto stands, as of the last [`VetoHold::update`].
    pub(super) fn vetoes(&self) -> bool {
        self.vetoes
    }

    /// Reads one sample of period `dt_s` (s), `watched_s` (s) into the watch:
    /// what the best offset's and the best leak's fits leave (any one unit),
    /// and whether the offset's part of the rises is `material`. The offset
    /// fits at a ratio where it is material and its fit leaves less than the
    /// ratio times the leak's. The veto stands where it fits at
    /// [`OFFSET_FIT_RATIO`], or where it was entered with the share falling
    /// slowly, has stood for [`OFFSET_HOLD_TAU_S`] and fits at
    /// [`OFFSET_HOLD_RATIO`] with its share rising slowly. Returns whether it
    /// stands.
    pub(super) fn update(
        &mut self,
        (offset_left, leak_left): (f64, f64),
        material: bool,
        watched_s: f64,
        dt_s: f64,
    ) -> bool {
        let fits = |ratio: f64| material && offset_left < ratio * leak_left;
        let share = if leak_left > 0.0 {
            (offset_left / leak_left).min(SHARE_CAP)
        } else {
            f64::NAN
        };
        // (a NaN share or mean makes the comparison false: no hold)
        let rising_slowly = share - self.share_mean < OFFSET_HOLD_RISE;
        let falling_fast = self.share_mean - share >= OFFSET_HOLD_RISE;
        if share.is_finite() {
            if self.share_mean.is_finite() {
                if dt_s != self.keep.0 {
                    self.keep = (dt_s, (-dt_s / OFFSET_HOLD_TAU_S).exp());
                }
                self.share_mean = share + self.keep.1 * (self.share_mean - share);
            } else {
                self.share_mean = share;
            }
        }
        let stood = self.vetoes && self.entered_slowly && watched_s - self.since_s >= OFFSET_HOLD_TAU_S;
        let vetoes = fits(OFFSET_FIT_RATIO) || (stood && rising_slowly && fits(OFFSET_HOLD_RATIO));
        if vetoes && !self.vetoes {
            self.since_s = watched_s;
            self.entered_slowly = !falling_fast;
        }
        self.vetoes = vetoes;
        vetoes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs the hold over `seconds` at 10 ms with the share `share(t)`, the
    /// offset fitting wherever the share is under the ratio asked; returns
    /// whether it vetoed at each sample.
    fn run(seconds: f64, share: impl Fn(f64) -> f64) -> Vec<bool> {
        let dt = 0.01;
        let mut hold = VetoHold::default();
        (0..(seconds / dt).round() as usize)
            .map(|n| {
                let t = (n + 1) as f64 * dt;
                let s = share(t);
                hold.update((s, 1.0), true, t, dt)
            })
            .collect()
    }

    /// Whether the hold vetoed at time `t_s` (s) of a [`run`].
    fn at(vetoes: &[bool], t_s: f64) -> bool {
        vetoes[(t_s / 0.01).round() as usize - 1]
    }

    #[test]
    fn a_share_creeping_past_the_entry_ratio_stays_vetoed_to_the_hold_ratio() {
        // 0.3 for 20 s, then up at 0.01 per s (a drift): 0.5 at 40 s, 0.7 at 60 s.
        let v = run(80.0, |t| 0.3 + 0.01 * (t - 20.0).max(0.0));
        assert!(
            at(&v, 10.0) && at(&v, 45.0) && at(&v, 59.0),
            "held from 0.5 up to 0.7"
        );
        assert!(!at(&v, 61.0) && !at(&v, 79.0), "let go past 0.7");
    }

    #[test]
    fn a_share_that_jumps_ends_the_veto_at_the_entry_ratio() {
        // 0.3, then 0.6 from 30 s on: under the hold ratio, but a jump.
        let v = run(40.0, |t| if t < 30.0 { 0.3 } else { 0.6 });
        assert!(at(&v, 29.99) && !at(&v, 30.0) && !at(&v, 39.0));
    }

    #[test]
    fn a_leaks_onset_lifting_the_share_within_a_second_ends_the_veto_at_the_entry_ratio() {
        // 0.3, then up 0.3 over 1 s from 30 s on, to 0.6: under the hold
        // ratio, but its lead over its mean passes 0.1 within 0.4 s.
        let v = run(40.0, |t| 0.3 + 0.3 * (t - 30.0).clamp(0.0, 1.0));
        assert!(at(&v, 29.99));
        let released = v.iter().position(|&x| !x).expect("the onset ends the veto") as f64 * 0.01;
        assert!(
            (30.6..30.7).contains(&released),
            "released at {released} s, where the share passes 0.5"
        );
        assert!(!at(&v, 39.0), "and stays released while the share stays up");
    }

    #[test]
    fn a_veto_entered_by_a_share_falling_within_a_second_is_not_held() {
        // 1.0, down to 0.3 over 0.5 s at 20 s (a leak's onset that fits an
        // offset), then up at 0.01 per s as a drift would: 0.5 at 40.5 s.
        let v = run(60.0, |t| {
            if t < 20.0 {
                1.0
            } else {
                (1.0 - 1.4 * (t - 20.0)).max(0.3 + 0.01 * (t - 20.5).max(0.0))
            }
        });
        assert!(!at(&v, 19.9) && at(&v, 21.0) && at(&v, 40.4));
        assert!(!at(&v, 40.6) && !at(&v, 59.0), "let go at the entry ratio");
    }

    #[test]
    fn a_veto_younger_than_the_hold_time_is_not_held() {
        // Under 0.5 for 3 s only, then at 0.6: no hold.
        let v = run(10.0, |t| if (2.0..5.0).contains(&t) { 0.4 } else { 0.6 });
        assert!(!at(&v, 1.0) && at(&v, 4.0), "vetoes while under the entry ratio");
        assert!(
            !at(&v, 5.5) && !at(&v, 9.0),
            "not held: it stood under {OFFSET_HOLD_TAU_S} s"
        );
    }

    #[test]
    fn without_a_leak_fit_to_compare_with_the_veto_is_not_held() {
        let mut hold = VetoHold::default();
        for n in 1..=1000 {
            assert!(hold.update((0.3, 1.0), true, n as f64 * 0.01, 0.01));
        }
        // The leak's fit leaves nothing (NaN share): only the entry ratio counts.
        assert!(!hold.update((0.3, 0.0), true, 10.01, 0.01));
    }
}
