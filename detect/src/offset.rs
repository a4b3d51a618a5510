//! A pressure transducer that reads off, told from a leak.
//!
//! An offset b on p1 or p2 moves the leak sizes by b·δ_c(t), where δ_c is the
//! filter's own response to an offset on that channel
//! ([`filter::Estimate::offset_response_lpm_per_mpa`]). δ_c swings with the
//! valve's flow: the offset moves the orifice's drop, so it shows while oil
//! flows and fades at rest. A leak moves one size steadily. Both hypotheses are
//! fitted to the rises of the sizes by least squares:
//!
//! - offset on channel c: rise(t) ≈ b·δ_c(t), one b per channel;
//! - the same offset seen through the baseline: rise(t) ≈ b·(δ_c − δ̄_c)(t);
//! - leak of kind k: rise_k(t) ≈ q, the other sizes ≈ 0.
//!
//! The rises are measured from a baseline that follows the sizes slowly (the
//! detector's `baseline_tau_s`). It takes up the steady part of a standing
//! offset's b·δ_c as it takes up any slow drift: δ̄_c is δ_c followed at the
//! baseline's rate, and δ_c − δ̄_c is the part that swings with the flow. A
//! drifting offset stays ahead of the baseline, so its rises keep some of the
//! steady part: both forms are fitted, and the swing counts where it fits
//! clearly better ([`SWING_FIT_RATIO`]).
//!
//! Where the rises run against the internal leak's direction (a chamber
//! gaining what the other loses: no leak does that), that part of them is the
//! model's own and is left out of every fit, and out of the offsets'
//! responses too ([`without_reverse_internal`]).
//!
//! A rise an offset explains clearly better than every leak is not leak evidence. An
//! offset that explains the rises over [`OFFSET_WINDOW_S`] and is large enough
//! to matter is raised as `sensor-offset` on its channel, with b in MPa.

use crate::{EventKind, LeakEvent, Phase};

/// Time constant of the window the offsets are named over, s.
pub const OFFSET_WINDOW_S: f64 = 10.0;
/// An episode of high rises ends once they have all stayed below
/// [`EPISODE_LEVEL`] of their thresholds for this long, s (longer than a duty
/// cycle's rest: an offset's rises come back with the next move).
pub const EPISODE_QUIET_S: f64 = 3.0;
/// Share of each threshold a rise must pass to start an episode (1).
pub const EPISODE_LEVEL: f64 = 0.5;
/// An offset explains the rises better than a leak when its fit leaves less
/// than this share of what the best leak's fit leaves unexplained (1): then
/// they are no leak evidence, and it may be named. (Where the offset's response
/// barely swings, as under a steady sine, both fit alike and neither wins.)
pub const OFFSET_FIT_RATIO: f64 = 0.5;
/// An offset's swing about its baseline is fitted in its place when it leaves
/// less than this share of what the offset's response as the filter gives it
/// leaves (1). A leak's steady rise, or a healthy rig's hoses, fit both forms
/// alike; a standing offset's rises, once the baseline has taken up their
/// steady part, fit the swing far better.
pub const SWING_FIT_RATIO: f64 = 0.5;
/// To be named, the offset's fit leaves at most this share of the rises'
/// energy unexplained (1).
pub const OFFSET_MAX_UNEXPLAINED: f64 = 0.5;
/// To be named, the offset's part of the rises reaches this share of the
/// smallest threshold, RMS over the window (1).
pub const OFFSET_NAMED_SHARE: f64 = 0.3;
/// Least offset named, as a share of the transducer's range (1): below it
/// the offset is within a transducer's accuracy, and a healthy rig's hoses
/// (the drop between a manifold transducer and its chamber, which moves with
/// the oil's viscosity) make as much.
pub const OFFSET_LEAST_SHARE_OF_RANGE: f64 = 0.01;
/// Over the window, an offset whose part of the rises reaches this share of
/// the smallest threshold (RMS) and fits better than any leak makes its
/// rises no leak evidence (1).
pub const OFFSET_MATERIAL_SHARE: f64 = 0.15;
/// The conditions to name an offset hold this long first, s.
pub const OFFSET_CONFIRM_S: f64 = 2.0;
/// A named offset clears once its part of the rises has stayed below half
/// the naming level this long, s.
pub const OFFSET_CLEAR_S: f64 = 10.0;
/// Least weight an episode's fit needs before it can veto, s of samples.
const EPISODE_MIN_S: f64 = 0.2;
/// Least magnitude of both internal-leak pressure factors (1) for the reverse
/// internal part to be told ([`without_reverse_internal`]): with the chambers
/// near each other the internal leak's direction is not pinned down.
const REVERSE_INTERNAL_LEAST_FACTOR: f64 = 0.05;

/// The transducers whose offsets are fitted, in the order of the response's rows.
pub const OFFSET_CHANNEL_NAMES: [&str; 2] = ["p1", "p2"];

/// The offset hypotheses fitted: per channel, its response as the filter
/// gives it (h = c) and that response's swing about its baseline (h = 2 + c).
const HYPOTHESES: usize = 4;

/// The channel of offset hypothesis `h`.
const fn channel_of(h: usize) -> usize {
    h % 2
}

/// Exponentially weighted sums of both fits over the chamber flows' rises
/// (w1, w2) (weights in s).
#[derive(Debug, Clone, Copy, Default)]
struct Fit {
    /// Σw, s.
    w: f64,
    /// Σw·|rise|², (L/min)²·s.
    energy: f64,
    /// Σw·δ_h·rise per offset hypothesis ([`HYPOTHESES`]), (L/min)²/MPa·s.
    response_rise: [f64; HYPOTHESES],
    /// Σw·|δ_h|² per offset hypothesis, (L/min/MPa)²·s.
    response_energy: [f64; HYPOTHESES],
    /// Σw·rise, L/min·s.
    rise: [f64; 2],
}

impl Fit {
    /// Adds a sample of weight `dt_s` after decaying the past by `keep` (1).
    fn add(&mut self, keep: f64, dt_s: f64, rise: [f64; 2], response: &[[f64; 2]; HYPOTHESES]) {
        self.w = keep * self.w + dt_s;
        self.energy = keep * self.energy + dt_s * (rise[0] * rise[0] + rise[1] * rise[1]);
        for c in 0..HYPOTHESES {
            let d = &response[c];
            let dr = d[0] * rise[0] + d[1] * rise[1];
            let dd = d[0] * d[0] + d[1] * d[1];
            self.response_rise[c] = keep * self.response_rise[c] + dt_s * dr;
            self.response_energy[c] = keep * self.response_energy[c] + dt_s * dd;
        }
        for k in 0..2 {
            self.rise[k] = keep * self.rise[k] + dt_s * rise[k];
        }
    }

    /// The offset of hypothesis `c` that fits best, MPa (0 without a response).
    fn offset_mpa(&self, c: usize) -> f64 {
        if self.response_energy[c] > 0.0 {
            self.response_rise[c] / self.response_energy[c]
        } else {
            0.0
        }
    }

    /// The energy the offset of hypothesis `c` explains, (L/min)²·s.
    fn explained_by_offset(&self, c: usize) -> f64 {
        self.offset_mpa(c) * self.response_rise[c]
    }

    /// The energy the best steady leak leaves unexplained, (L/min)²·s: a leak
    /// of kind k moves (w1, w2) along `directions[k]` (unit vectors).
    fn unexplained_by_leak(&self, directions: &[[f64; 2]; 3]) -> f64 {
        let best = directions
            .iter()
            .map(|u| (u[0] * self.rise[0] + u[1] * self.rise[1]).powi(2) / self.w.max(1e-12))
            .fold(0.0, f64::max);
        self.energy - best
    }

    /// The offset hypothesis that explains most, and what its fit leaves,
    /// (L/min)²·s. A channel's swing about its baseline counts only where it
    /// leaves less than [`SWING_FIT_RATIO`] of what its response as given
    /// leaves: the baseline has taken up the offset's steady part.
    /// Without `swing`, the responses as given alone.
    fn best_offset(&self, swing: bool) -> (usize, f64) {
        let left: [f64; HYPOTHESES] = std::array::from_fn(|h| self.energy - self.explained_by_offset(h));
        (0..HYPOTHESES)
            .filter(|&h| h < 2 || (swing && left[h] < SWING_FIT_RATIO * left[h - 2]))
            .map(|h| (h, left[h]))
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
    }

    /// Whether an offset's fit, leaving `left` ((L/min)²·s, of
    /// [`Fit::best_offset`]), leaves less than `ratio` times what the best
    /// leak's leaves unexplained.
    fn offset_fits_better(&self, left: f64, directions: &[[f64; 2]; 3], ratio: f64) -> bool {
        self.energy > 0.0 && left < ratio * self.unexplained_by_leak(directions)
    }

    /// RMS of the rises that the offset of hypothesis `c` explains, L/min.
    fn explained_rms_lpm(&self, c: usize) -> f64 {
        (self.explained_by_offset(c).max(0.0) / self.w.max(1e-12)).sqrt()
    }

    /// RMS of the rises that an offset of channel `c` explains in either form, L/min.
    fn channel_explained_rms_lpm(&self, c: usize) -> f64 {
        self.explained_rms_lpm(c).max(self.explained_rms_lpm(c + 2))
    }
}

/// The unit directions in (w1, w2) of ext1, ext2 and int for the internal
/// leak's pressure factors `factors` ([`crate::signatures_with`]).
fn leak_directions(factors: [f64; 2]) -> [[f64; 2]; 3] {
    let [r1, r2] = factors;
    let n = (r1 * r1 + r2 * r2).sqrt().max(1e-12);
    [[1.0, 0.0], [0.0, 1.0], [r1 / n, -r2 / n]]
}

/// The rise `rise` in (w1, w2) (L/min) with its part against an internal
/// leak taken out, and the offset hypotheses' responses `hypotheses` with
/// theirs, where the rise has such a part; else all as they are. An internal
/// leak of the pressure factors `factors` moves (w1, w2) along u = (r1, −r2);
/// the rise is split along u and along the external leak whose ray bounds
/// what leaks can make on that side (ext2 while r1 ≥ 0, else ext1). A
/// negative part along u is a chamber gaining what the other loses, the wrong
/// way for any leak: it is what is taken out, of the rise and of every
/// response alike.
///
/// The model makes that pattern itself: the fast moves of a handling cycle,
/// and the rests under load after them, with no fault at all. No leak makes
/// it, and an offset alone does not explain it: left in, it weighs on both
/// fits alike, and a drift's smaller part of the rises is lost in it.
fn without_reverse_internal(
    rise: [f64; 2],
    factors: [f64; 2],
    hypotheses: &mut [[f64; 2]; HYPOTHESES],
) -> [f64; 2] {
    let [r1, r2] = factors;
    // the part along u of v split along u and the bounding external leak
    let along = |v: [f64; 2]| {
        if r1 >= 0.0 {
            v[0] / r1
        } else {
            -v[1] / r2
        }
    };
    let least = REVERSE_INTERNAL_LEAST_FACTOR;
    if !(r1.abs() >= least && r2.abs() >= least && along(rise) < 0.0) {
        return rise;
    }
    let take_out = |v: [f64; 2]| {
        let c = along(v);
        [v[0] - c * r1, v[1] + c * r2]
    };
    for h in hypotheses.iter_mut() {
        *h = take_out(*h);
    }
    take_out(rise)
}

/// A named offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandingOffset {
    /// Channel index into [`OFFSET_CHANNEL_NAMES`].
    pub channel: usize,
    /// The offset fitted when it was named, MPa (measured minus true).
    pub offset_mpa: f64,
    /// Since when its part of the rises has been growing, s.
    pub since_s: f64,
    /// Event id of its `sensor-offset` event.
    pub event_id: u64,
}

/// What [`OffsetWatch::on_rise`] decided about the named offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OffsetChange {
    /// An offset was named on a channel.
    Raised(StandingOffset),
    /// The named offset went away.
    Cleared(StandingOffset),
}

/// Watches the leak sizes' rises for a pressure transducer that reads off.
#[derive(Debug, Clone)]
pub struct OffsetWatch {
    /// Over [`OFFSET_WINDOW_S`]: names an offset.
    window: Fit,
    /// Since the rises last passed [`EPISODE_LEVEL`] of a threshold: vetoes leak evidence.
    episode: Option<Fit>,
    /// When the episode's rises were last high, s.
    episode_high_s: f64,
    /// The channel meeting the naming conditions, and since when, s.
    candidate: Option<(usize, f64)>,
    /// Per channel: when its offset's part of the rises was last below a tenth of the threshold, s.
    low_since_s: [f64; 2],
    /// Since when a named offset's part has been low, s.
    fading_since_s: Option<f64>,
    standing: Option<StandingOffset>,
    /// The leak kinds' directions in (w1, w2) ([`leak_directions`]).
    directions: [[f64; 2]; 3],
    /// Least offset named, MPa ([`OFFSET_LEAST_SHARE_OF_RANGE`] of the range).
    least_offset_mpa: f64,
    /// Time the window has been filled over, s (nothing is named before [`OFFSET_WINDOW_S`]).
    watched_s: f64,
    /// The smallest of the last thresholds read, L/min.
    smallest_threshold_lpm: f64,
    /// A sample period (s) and the window's decay over it (1).
    keep_for: (f64, f64),
    /// Per channel: the baseline of its response δ̄_c in (w1, w2), L/min per MPa,
    /// followed as the detector's baseline follows the sizes.
    response_baseline: [[f64; 2]; 2],
    /// The share (1) by which the detector's baseline moved toward the sizes at
    /// this sample ([`OffsetWatch::follow_baseline`]).
    baseline_step: f64,
}

impl OffsetWatch {
    /// A watch for pressure transducers of range `full_scale_pa` (Pa).
    pub fn new(full_scale_pa: f64) -> Self {
        OffsetWatch {
            least_offset_mpa: OFFSET_LEAST_SHARE_OF_RANGE * full_scale_pa * 1e-6,
            ..OffsetWatch::default()
        }
    }
}

impl Default for OffsetWatch {
    fn default() -> Self {
        OffsetWatch {
            window: Fit::default(),
            episode: None,
            episode_high_s: f64::NEG_INFINITY,
            candidate: None,
            low_since_s: [f64::NEG_INFINITY; 2],
            fading_since_s: None,
            standing: None,
            directions: leak_directions(crate::NOMINAL_INTERNAL_FACTORS),
            least_offset_mpa: 0.0,
            watched_s: 0.0,
            smallest_threshold_lpm: f64::INFINITY,
            keep_for: (0.0, 1.0),
            response_baseline: [[0.0; 2]; 2],
            baseline_step: 0.0,
        }
    }
}

impl OffsetWatch {
    /// Forgets everything (the filter restarted).
    pub fn restart(&mut self) {
        *self = OffsetWatch {
            standing: self.standing,
            least_offset_mpa: self.least_offset_mpa,
            ..OffsetWatch::default()
        };
    }

    /// The detector's baseline moved by `share` (1) of the way toward the
    /// sizes at this sample: the responses' baselines follow by as much in
    /// the next [`OffsetWatch::on_rise`].
    pub fn follow_baseline(&mut self, share: f64) {
        self.baseline_step = share;
    }

    /// The named offset, if one stands.
    pub fn standing(&self) -> Option<StandingOffset> {
        self.standing
    }

    /// Names `offset` as standing, as a fit would (for the detector's tests).
    #[cfg(test)]
    pub(crate) fn stand(&mut self, offset: StandingOffset) {
        self.standing = Some(offset);
    }

    /// Whether the rises of the present episode fit an offset better than any
    /// leak, or those of the window do with the offset's part of them past
    /// [`OFFSET_MATERIAL_SHARE`] of the smallest threshold: they are no leak evidence.
    /// The episode's fit takes the responses as given alone: over its first
    /// seconds a leak's step fits some swing as well as it fits the leak.
    pub fn vetoes(&self) -> bool {
        let episode = self.episode.as_ref().is_some_and(|f| {
            f.w >= EPISODE_MIN_S
                && f.offset_fits_better(f.best_offset(false).1, &self.directions, OFFSET_FIT_RATIO)
        });
        episode || self.window_offset_fits(OFFSET_FIT_RATIO)
    }

    /// Whether, over the window, the best offset's part of the rises is past
    /// [`OFFSET_MATERIAL_SHARE`] of the smallest threshold and its fit leaves
    /// less than `ratio` times what the best leak's leaves.
    fn window_offset_fits(&self, ratio: f64) -> bool {
        let (c, left) = self.window.best_offset(true);
        self.watched_s >= OFFSET_WINDOW_S
            && self.window.explained_rms_lpm(c) > OFFSET_MATERIAL_SHARE * self.smallest_threshold_lpm
            && self.window.offset_fits_better(left, &self.directions, ratio)
    }

    /// Whether an offset on a transducer could explain the window's rises:
    /// its fit leaves at most 1/[`OFFSET_FIT_RATIO`] times what the best
    /// leak's leaves unexplained, and its part of them is past
    /// [`OFFSET_MATERIAL_SHARE`] of the smallest threshold. Then a leak is not
    /// told from it on a kind's clear rises alone (at rest an offset on p_c
    /// and an external leak from chamber c leave the same rises).
    pub fn could_explain(&self) -> bool {
        self.window_offset_fits(1.0 / OFFSET_FIT_RATIO)
    }

    /// Reads one sample's rises `rise` (w1, w2, int; L/min at p_s/2, of
    /// [`crate::signatures_with`] with the internal leak's factors `factors`)
    /// with the filter's offset response `response` (q_e1, q_e2, q_i per MPa
    /// on p1 and on p2), `dt_s` after the last, with the thresholds
    /// `thresholds_lpm`; `next_id` gives an event id. Returns a change of the
    /// named offset.
    #[allow(clippy::too_many_arguments)]
    pub fn on_rise(
        &mut self,
        t_s: f64,
        dt_s: f64,
        rise: [f64; 3],
        response: &[[f64; 3]; 2],
        factors: [f64; 2],
        thresholds_lpm: [f64; 3],
        next_id: &mut u64,
    ) -> Option<OffsetChange> {
        let share = std::mem::take(&mut self.baseline_step);
        if !(rise
            .iter()
            .chain(response.iter().flatten())
            .all(|v| v.is_finite())
            && dt_s > 0.0)
        {
            return None;
        }
        self.directions = leak_directions(factors);
        let mut hypotheses = [[0.0; 2]; HYPOTHESES];
        for c in 0..2 {
            let w = crate::signatures_with(response[c], factors);
            for k in 0..2 {
                let base = &mut self.response_baseline[c][k];
                *base += share * (w[k] - *base);
                hypotheses[c][k] = w[k];
                hypotheses[2 + c][k] = w[k] - *base;
            }
        }
        let rise3 = rise;
        let rise = without_reverse_internal([rise3[0], rise3[1]], factors, &mut hypotheses);
        let response = &hypotheses;
        // (the samples come at one period: the decay is computed once per period)
        if dt_s != self.keep_for.0 {
            self.keep_for = (dt_s, (-dt_s / OFFSET_WINDOW_S).exp());
        }
        let keep = self.keep_for.1;
        self.watched_s += dt_s;
        self.window.add(keep, dt_s, rise, response);
        let high = (0..3).any(|k| rise3[k].abs() > EPISODE_LEVEL * thresholds_lpm[k]);
        if high {
            self.episode_high_s = t_s;
            self.episode.get_or_insert_with(Fit::default);
        } else if t_s - self.episode_high_s > EPISODE_QUIET_S {
            self.episode = None;
        }
        if let Some(f) = &mut self.episode {
            f.add(keep, dt_s, rise, response);
        }
        let smallest = thresholds_lpm.iter().cloned().fold(f64::INFINITY, f64::min);
        self.smallest_threshold_lpm = smallest;
        let level = OFFSET_NAMED_SHARE * smallest;
        for c in 0..2 {
            if self.window.channel_explained_rms_lpm(c) < 0.1 * smallest {
                self.low_since_s[c] = t_s;
            }
        }
        if let Some(s) = self.standing {
            if self.window.channel_explained_rms_lpm(s.channel) < 0.5 * level {
                let since = *self.fading_since_s.get_or_insert(t_s);
                if t_s - since >= OFFSET_CLEAR_S {
                    self.standing = None;
                    self.fading_since_s = None;
                    self.candidate = None;
                    return Some(OffsetChange::Cleared(s));
                }
            } else {
                self.fading_since_s = None;
            }
            return None;
        }
        let (h, left) = self.window.best_offset(true);
        let named = self.watched_s >= OFFSET_WINDOW_S
            && self
                .window
                .offset_fits_better(left, &self.directions, OFFSET_FIT_RATIO)
            && left < OFFSET_MAX_UNEXPLAINED * self.window.energy
            && self.window.explained_rms_lpm(h) > level
            && self.window.offset_mpa(h).abs() > self.least_offset_mpa;
        let c = channel_of(h);
        match (named, self.candidate) {
            (false, _) => self.candidate = None,
            (true, Some((j, t0))) if j == c => {
                if t_s - t0 >= OFFSET_CONFIRM_S {
                    let s = StandingOffset {
                        channel: c,
                        offset_mpa: self.window.offset_mpa(h),
                        since_s: self.low_since_s[c],
                        event_id: *next_id,
                    };
                    *next_id += 1;
                    self.standing = Some(s);
                    return Some(OffsetChange::Raised(s));
                }
            }
            (true, _) => self.candidate = Some((c, t_s)),
        }
        None
    }
}

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
        _ => format!(
            "{name} reads {:.0} kPa {} (an offset or a span error, fitted over {:.0} s): the leak sizes move \
             with the valve's flow as an offset on {name} makes them, not as a leak does; no leak decision \
             while it stands",
            s.offset_mpa.abs() * 1e3,
            if s.offset_mpa >= 0.0 { "high" } else { "low" },
            OFFSET_WINDOW_S
        ),
    };
    ev
}

#[cfg(test)]
mod tests;
