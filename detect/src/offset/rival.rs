//! The misreading that rivals a leak: one that fits the rises at least as
//! well holds the leak back; one that fits them nearly as well is said in the
//! leak's event, so the operator is told which transducer to check.

use super::fit::{channel_of, is_position, is_span};
use super::{OffsetWatch, OFFSET_CHANNEL_NAMES};

/// How long an episode must have lasted before its misreading holds back a
/// new leak ([`OffsetWatch::rivals_new_leak`]): its weight, s (its length
/// discounted over [`super::OFFSET_WINDOW_S`]: 3 s of weight is 3.6 s).
pub const EPISODE_RIVAL_WEIGHT_S: f64 = 3.0;

/// The share (1) of what the best leak's fit leaves under which an
/// episode's misreading holds back a new leak: a new leak is raised only
/// where it fits the episode's rises better than the misreading does. The
/// misreading vetoes all leak evidence under [`super::OFFSET_FIT_RATIO`].
pub const EPISODE_RIVAL_RATIO: f64 = 1.0;

/// The share (1) of the last sample's rises that an episode's misreading, at
/// its fitted size, may leave unexplained and still hold back a new leak. A
/// leak that steps in while a misreading's episode lasts adds a rise the
/// misreading does not make now: it is raised, however well the episode fits.
pub const EPISODE_RIVAL_NOW_SHARE: f64 = 0.5;

/// Where a misreading could make the rises as well as a new leak
/// ([`OffsetWatch::could_make_new_rises`]), a new leak's rise must pass this
/// multiple of its threshold (1). A transducer drifting low moves the leak
/// sizes with the flow: its rises creep past a threshold for moments, long
/// before its fit is clean enough to name it.
pub const MISREADING_WIDENING: f64 = 1.5;

/// A present episode whose best misreading's fit leaves more than this
/// multiple of what its best leak's leaves (1) is a leak's own: its rises do
/// not need [`MISREADING_WIDENING`]. The window may still fit a misreading
/// there, from the healthy rises before the leak.
pub const EPISODE_LEAK_RATIO: f64 = 2.0;

impl OffsetWatch {
    /// Whether, at `t_s` (s), the window's best misreading fits the rises at
    /// least as well as the best leak does, with its part of them material,
    /// is past a sound transducer's tolerance (on p1 or p2
    /// [`super::OFFSET_LEAST_SHARE_OF_RANGE`] of the range), and could
    /// have grown at a transducer's drift since its part began to grow
    /// ([`super::MOST_DRIFT_MPA_PER_S`]): then the rises are no leak evidence.
    /// A leak is raised only where it fits better than every misreading a
    /// drifting transducer past its tolerance could make; one that appeared
    /// in seconds, with a leak's onset, is the leak.
    pub fn rivals_leak(&self, t_s: f64) -> bool {
        let h = self.window_best.h;
        self.window_offset_fits(1.0) && self.past_tolerance(h) && !self.faster_than_a_drift(h, t_s)
    }

    /// Whether a misreading could make the rises as well as a new leak: the
    /// window's could explain them ([`Self::could_explain`]), and the
    /// present episode's best misreading leaves at most
    /// [`EPISODE_LEAK_RATIO`] times what its best leak leaves (or no episode
    /// is long enough to tell: 0.2 s of weight). A new leak's rise must
    /// then pass [`MISREADING_WIDENING`] times its threshold.
    pub fn could_make_new_rises(&self) -> bool {
        self.could_explain() && !self.leaks_own_episode()
    }

    /// Whether the present episode fits a leak clearly better than any
    /// misreading: its best misreading leaves more than [`EPISODE_LEAK_RATIO`]
    /// times what its best leak leaves (false before it is 0.2 s of weight).
    pub fn leaks_own_episode(&self) -> bool {
        match (&self.episode, &self.episode_best) {
            (Some(f), Some(best)) => f.energy > 0.0 && best.left > EPISODE_LEAK_RATIO * best.leak_left,
            _ => false,
        }
    }

    /// Whether the present episode has lasted [`EPISODE_RIVAL_WEIGHT_S`], a
    /// misreading of p1 or p2 (its response as given, standing or drifting)
    /// fits its rises at least as well as the best leak
    /// ([`EPISODE_RIVAL_RATIO`]), and at its fitted size it explains the last sample's rises
    /// ([`EPISODE_RIVAL_NOW_SHARE`]): then no new leak is raised on them.
    /// A misreading that grows shows for seconds with the flow before its
    /// rises reach a threshold; a leak's onset starts an episode of its own
    /// and is raised within its first seconds, and one that steps in during
    /// a misreading's episode adds a rise the misreading does not make.
    pub fn rivals_new_leak(&self) -> bool {
        self.episode
            .as_ref()
            .is_some_and(|f| f.w >= EPISODE_RIVAL_WEIGHT_S)
            && self.episode_fits(EPISODE_RIVAL_RATIO)
            && self.episode_explains_now()
    }

    /// Whether the episode's best misreading, at its fitted size, explains the
    /// last sample's rises: what it leaves of them is under
    /// [`EPISODE_RIVAL_NOW_SHARE`] of their size.
    pub(super) fn episode_explains_now(&self) -> bool {
        let share = EPISODE_RIVAL_NOW_SHARE;
        let (Some(f), Some(best)) = (&self.episode, &self.episode_best) else {
            return false;
        };
        let h = best.h;
        let b = f.coefficient(h);
        let r = self.episode_best_response;
        let rise = self.last_rise;
        let left = (rise[0] - b * r[0]).powi(2) + (rise[1] - b * r[1]).powi(2);
        left < share * share * (rise[0].powi(2) + rise[1].powi(2))
    }

    /// Whether the misreading of hypothesis `h` fitted over the window is at
    /// least its tolerance ([`OffsetWatch::tolerance`]): a smaller one lies
    /// within a sound transducer's.
    fn past_tolerance(&self, h: usize) -> bool {
        self.window.coefficient(h).abs() >= self.tolerance(h)
    }

    /// The window's best misreading in words ("p2 reading 162 kPa low"),
    /// where it could explain the rises as well as a leak
    /// ([`OffsetWatch::could_explain`]) and is past a sound transducer's
    /// tolerance (as in [`OffsetWatch::rivals_leak`]): a smaller one lies
    /// within it, and a leak's rises often fit one.
    /// None otherwise.
    pub fn rival_misreading(&self) -> Option<String> {
        let h = self.window_best.h;
        if !self.could_explain() || !self.past_tolerance(h) {
            return None;
        }
        let b = self.window.coefficient(h);
        let name = OFFSET_CHANNEL_NAMES[channel_of(h)];
        let high_low = if b >= 0.0 { "high" } else { "low" };
        Some(if is_position(h) {
            format!("{name} reading {:.1} mm {high_low}", b.abs())
        } else if is_span(h) {
            format!(
                "{name} reading {:.1} % {high_low} (a span error)",
                b.abs() * 100.0
            )
        } else {
            format!("{name} reading {:.0} kPa {high_low}", b.abs() * 1e3)
        })
    }
}
