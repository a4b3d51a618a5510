//! A transducer that reads off, told from a leak.
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
//! - an offset that drifts: rise(t) ≈ (b + ḃ·τ)·δ_c(t), τ the sample's age,
//!   |ḃ| at most [`MOST_DRIFT_MPA_PER_S`], judged against a leak that grows:
//!   rise_k(t) ≈ q + q̇·τ;
//! - span error g on channel c, an offset g·p_c that moves with the pressure
//!   read: rise(t) ≈ g·σ_c(t), σ_c the filter's own response to it
//!   ([`filter::Estimate::span_response_lpm`]), and the same through the
//!   baseline (counted where it fits clearly better than the offset,
//!   [`SPAN_FIT_RATIO`]);
//! - offset b on x: rise(t) ≈ b·ξ(t), ξ the filter's own response to it
//!   ([`filter::Estimate::position_offset_response_lpm_per_mm`]): the model
//!   reads the chambers' volumes at the wrong place, one too large and one
//!   too small; and the same through the baseline;
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
//! offset or span error that explains the rises over [`OFFSET_WINDOW_S`] and is
//! large enough to matter is raised as `sensor-offset` on its channel, with b
//! in kPa (mm on x) or g in %.

mod event;
mod fit;
mod floors;
mod healthy;
mod hold;
mod limits;
mod rival;

pub use event::offset_event;
pub use floors::{least_pressure_offset_pa, sound_transducer_misreading};
use healthy::HealthyPart;
pub use healthy::{HealthyMisreading, HEALTHY_MISREADING_LEAST_SHARE};
use hold::VetoHold;
pub use hold::{OFFSET_HOLD_RATIO, OFFSET_HOLD_RISE, OFFSET_HOLD_TAU_S};
pub use limits::*;
pub use rival::{
    EPISODE_LEAK_RATIO, EPISODE_RIVAL_NOW_SHARE, EPISODE_RIVAL_RATIO, EPISODE_RIVAL_WEIGHT_S,
    MISREADING_WIDENING,
};

use fit::{
    channel_of, is_drift, is_position, is_span, leak_directions, swing_of, without_reverse_internal,
    BestOffset, Fit, AS_GIVEN, HYPOTHESES,
};

/// An offset below the least named ([`OFFSET_LEAST_SHARE_OF_RANGE`], or
/// [`DRIFT_LEAST_SHARE_OF_RANGE`] drifting) but past this share of it (1) is
/// named where its fit leaves less than
/// [`OFFSET_CLEAN_UNEXPLAINED`] of the rises' energy for
/// [`OFFSET_CLEAN_CONFIRM_S`]: a healthy rig's hoses do not fit an offset
/// that cleanly for that long.
pub const OFFSET_CLEAN_FLOOR_SHARE: f64 = 0.5;
/// Share of the rises' energy (1) a clean offset's fit leaves at most
/// ([`OFFSET_CLEAN_FLOOR_SHARE`]).
pub const OFFSET_CLEAN_UNEXPLAINED: f64 = 0.05;
/// How long a clean offset's conditions hold before it is named, s of
/// samples read ([`OFFSET_CLEAN_FLOOR_SHARE`]).
pub const OFFSET_CLEAN_CONFIRM_S: f64 = 10.0;
/// Over the window, an offset whose part of the rises reaches this share of
/// the smallest threshold (RMS) and fits better than any leak makes its
/// rises no leak evidence (1).
pub const OFFSET_MATERIAL_SHARE: f64 = 0.15;
/// The conditions to name an offset hold this long first, s of samples
/// read (a gap, or estimates the detector may not read, do not count).
pub const OFFSET_CONFIRM_S: f64 = 2.0;
/// A named offset clears once its part of the rises has stayed below half
/// the naming level this long, s of samples read.
pub const OFFSET_CLEAR_S: f64 = 10.0;
/// Least weight an episode's fit needs before it can veto, s of samples.
const EPISODE_MIN_S: f64 = 0.2;
/// Least magnitude of both internal-leak pressure factors (1) for the reverse
/// internal part to be told ([`without_reverse_internal`]): with the chambers
/// near each other the internal leak's direction is not pinned down.
pub(crate) const REVERSE_INTERNAL_LEAST_FACTOR: f64 = 0.05;

/// The transducers whose misreadings are fitted: the channels of [`StandingOffset`].
pub const OFFSET_CHANNEL_NAMES: [&str; 3] = ["p1", "p2", "x"];

/// The filter's responses to a misreading of p1 (row 0), p2 (row 1) and x:
/// how it would have moved the leak sizes q_e1, q_e2, q_i by now.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MisreadingResponse {
    /// To a constant offset on p1 and p2, L/min per MPa.
    pub offset_lpm_per_mpa: [[f64; 3]; 2],
    /// To a span error on p1 and p2 (the reading (1 + g)·p), L/min per unit g.
    pub span_lpm: [[f64; 3]; 2],
    /// To a constant offset on x, L/min per mm.
    pub position_lpm_per_mm: [f64; 3],
}

/// A named offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StandingOffset {
    /// Channel index into [`OFFSET_CHANNEL_NAMES`].
    pub channel: usize,
    /// The offset fitted when it was named, MPa (measured minus true); for
    /// a span error, the offset it made on the reading then; NaN on x.
    pub offset_mpa: f64,
    /// The offset on x fitted when it was named, mm (measured minus true);
    /// NaN on p1 and p2.
    pub offset_mm: f64,
    /// The span error fitted when it was named, 1 (the channel reads
    /// (1 + g)·p); NaN where an offset fits better.
    pub span_error: f64,
    /// The rate at which the offset on p1 or p2 grew when it was named, MPa/s
    /// (measured minus true, per s); 0 where a standing offset fits better,
    /// NaN for a span error and on x.
    pub drift_mpa_per_s: f64,
    /// Since when it has read off, s: a drift's fitted line back to zero,
    /// else when the channel's part of the rises was last low; no earlier
    /// than the first sample the watch read.
    pub since_s: f64,
    /// How many times as much of the rises the best misreading of the other
    /// pressure channel leaves unexplained, when it was named (1): near 1,
    /// the two channels' misreadings fit alike (on a double-rod press, both
    /// reading high); infinite where this one's fit leaves nothing. NaN on x.
    pub other_channel_left_ratio: f64,
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
    /// The window's best misreading and what its fit leaves
    /// ([`Fit::best_offset`] in all forms), as of the last sample read.
    window_best: BestOffset,
    /// Since the rises last passed [`EPISODE_LEVEL`] of a threshold: vetoes leak evidence.
    episode: Option<Fit>,
    /// The episode's best misreading, p1's and p2's offsets' responses as
    /// given alone ([`Fit::best_offset`]), as of the last sample read; None
    /// before the episode is [`EPISODE_MIN_S`] long.
    episode_best: Option<BestOffset>,
    /// When the episode's rises were last high, s.
    episode_high_s: f64,
    /// The channel meeting the naming conditions, and the time watched when
    /// it began to, s (of `watched_s`: a stretch the watch was not fed, a gap
    /// or a reset, does not count towards confirming it).
    candidate: Option<(usize, f64)>,
    /// Per channel: when its offset's part of the rises was last below a tenth of the threshold, s.
    low_since_s: [f64; 3],
    /// The time of the first sample read, s; NaN before it.
    started_s: f64,
    /// The time watched when a named offset's part went low, s (of `watched_s`).
    fading_since_s: Option<f64>,
    standing: Option<StandingOffset>,
    /// The leak kinds' directions in (w1, w2) ([`leak_directions`]).
    directions: [[f64; 2]; 3],
    /// Least standing offset named, MPa ([`OFFSET_LEAST_SHARE_OF_RANGE`] of the range).
    least_offset_mpa: f64,
    /// What a sound transducer may read off at the pressures read: a standing
    /// offset's least named where it is smaller.
    sound: floors::SoundTransducer,
    /// Whether an offset on x is fitted: not where commissioning found its
    /// response lost in the model's error ([`crate::Commissioning::position_watched`]).
    position_watched: bool,
    /// Least drifting offset named, MPa ([`DRIFT_LEAST_SHARE_OF_RANGE`] of the range).
    least_drift_mpa: f64,
    /// Time the window has been filled over, s (nothing is named before [`OFFSET_WINDOW_S`]).
    watched_s: f64,
    /// The smallest of the last thresholds read, L/min.
    smallest_threshold_lpm: f64,
    /// A sample period (s) and the window's decay over it (1).
    keep_for: (f64, f64),
    /// Per hypothesis given as is (not a swing): the baseline of its response
    /// in (w1, w2) (L/min per MPa, or per unit span error), followed as the
    /// detector's baseline follows the sizes.
    response_baseline: [[f64; 2]; HYPOTHESES],
    /// The pressures read at the last sample, MPa (0 where not read).
    reading_mpa: [f64; 2],
    /// The share (1) by which the detector's baseline moved toward the sizes at
    /// this sample ([`OffsetWatch::follow_baseline`]).
    baseline_step: f64,
    /// Whether a leak of a named kind stands ([`OffsetWatch::leak_named`]).
    leak_named: bool,
    /// Whether the window's offset vetoes leak evidence, held while it drifts.
    window_veto: VetoHold,
    /// The last sample's rises in (w1, w2), L/min, and the episode's best
    /// misreading's response then (per unit of its coefficient), as fitted
    /// (the reverse internal part left out).
    last_rise: [f64; 2],
    episode_best_response: [f64; 2],
    /// The healthy rises' own misreading, taken off them or learned from them.
    healthy: HealthyPart,
}

impl OffsetWatch {
    /// A watch for pressure transducers of range `full_scale_pa` (Pa).
    pub fn new(full_scale_pa: f64) -> Self {
        OffsetWatch {
            least_offset_mpa: least_pressure_offset_pa(full_scale_pa, false) * 1e-6,
            position_watched: true,
            least_drift_mpa: least_pressure_offset_pa(full_scale_pa, true) * 1e-6,
            ..OffsetWatch::default()
        }
    }
}

impl OffsetWatch {
    /// The watch without offsets on x: commissioning found their response
    /// lost in the model's error, so a fit of one reads that error.
    pub fn without_position(mut self) -> Self {
        self.position_watched = false;
        self
    }
}

impl Default for OffsetWatch {
    fn default() -> Self {
        OffsetWatch {
            window: Fit::default(),
            window_best: BestOffset {
                h: 0,
                left: 0.0,
                leak_left: 0.0,
            },
            episode: None,
            episode_best: None,
            episode_high_s: f64::NEG_INFINITY,
            candidate: None,
            low_since_s: [f64::NEG_INFINITY; 3],
            started_s: f64::NAN,
            fading_since_s: None,
            standing: None,
            directions: leak_directions(crate::NOMINAL_INTERNAL_FACTORS),
            least_offset_mpa: 0.0,
            sound: floors::SoundTransducer::default(),
            position_watched: true,
            least_drift_mpa: 0.0,
            watched_s: 0.0,
            smallest_threshold_lpm: f64::INFINITY,
            keep_for: (0.0, 1.0),
            response_baseline: [[0.0; 2]; HYPOTHESES],
            reading_mpa: [0.0; 2],
            baseline_step: 0.0,
            leak_named: false,
            window_veto: VetoHold::default(),
            last_rise: [0.0; 2],
            episode_best_response: [0.0; 2],
            healthy: HealthyPart::default(),
        }
    }
}

impl OffsetWatch {
    /// Forgets everything (the filter restarted).
    pub fn restart(&mut self) {
        *self = OffsetWatch {
            standing: self.standing,
            least_offset_mpa: self.least_offset_mpa,
            sound: self.sound.forgotten(),
            least_drift_mpa: self.least_drift_mpa,
            position_watched: self.position_watched,
            healthy: std::mem::take(&mut self.healthy),
            ..OffsetWatch::default()
        };
    }

    /// The detector's baseline moved by `share` (1) of the way toward the
    /// sizes at this sample: the responses' baselines follow by as much in
    /// the next [`OffsetWatch::on_rise`].
    pub fn follow_baseline(&mut self, share: f64) {
        self.baseline_step = share;
    }

    /// Whether a leak of a named kind stands, as of the next
    /// [`OffsetWatch::on_rise`]: then an offset is named only where it could
    /// have grown at a transducer's drift ([`MOST_DRIFT_MPA_PER_S`] on p1 or
    /// p2, [`MOST_POSITION_DRIFT_MM_PER_S`] on x) since its part of the rises
    /// began to grow. One that appeared in seconds, with the leak's onset, is
    /// the leak.
    pub fn leak_named(&mut self, named: bool) {
        self.leak_named = named;
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
    /// The episode's fit takes p1's and p2's offsets' responses as given alone:
    /// over its first seconds a leak's step fits some swing, or a span error's
    /// response under a cycle that moves the pressure, as well as it fits the
    /// leak; an offset on x grows too slowly to make an episode's step.
    /// The window's veto is held while the offset drifts ([`OFFSET_HOLD_RATIO`]).
    pub fn vetoes(&self) -> bool {
        self.episode_fits(OFFSET_FIT_RATIO) || self.window_veto.vetoes()
    }

    /// Whether the episode, once [`EPISODE_MIN_S`] long, fits its best
    /// misreading ([`Self::episode_best`]) at `ratio` of what the best leak leaves.
    fn episode_fits(&self, ratio: f64) -> bool {
        match (&self.episode, &self.episode_best) {
            (Some(f), Some(best)) => f.offset_fits_better(best, ratio),
            _ => false,
        }
    }

    /// Whether, over the window, the best offset's part of the rises is past
    /// [`OFFSET_MATERIAL_SHARE`] of the smallest threshold and its fit leaves
    /// less than `ratio` times what the best leak's leaves.
    fn window_offset_fits(&self, ratio: f64) -> bool {
        // (the comparison first: it is two numbers, the material part a fit)
        self.window.offset_fits_better(&self.window_best, ratio) && self.window_offset_material()
    }

    /// Whether, over the window, the best offset's part of the rises is past
    /// [`OFFSET_MATERIAL_SHARE`] of the smallest threshold.
    fn window_offset_material(&self) -> bool {
        self.watched_s >= OFFSET_WINDOW_S
            && self.window.explained_rms_lpm(self.window_best.h)
                > OFFSET_MATERIAL_SHARE * self.smallest_threshold_lpm
    }

    /// Whether a leak of a named kind stands ([`OffsetWatch::leak_named`]) and
    /// the misreading of hypothesis `h` grew faster than a drift
    /// ([`Self::grew_faster_than_a_drift`]).
    fn grew_past_a_drift(&self, h: usize, t_s: f64) -> bool {
        self.leak_named && self.grew_faster_than_a_drift(h, t_s)
    }

    /// Whether the pressure offset of hypothesis `h` grew faster than a drift
    /// ([`Self::grew_faster_than_a_drift`]). False on x: a misreading of x
    /// holds a leak back through the window's fit alone.
    fn faster_than_a_drift(&self, h: usize, t_s: f64) -> bool {
        !is_position(h) && self.grew_faster_than_a_drift(h, t_s)
    }

    /// Whether the misreading of hypothesis `h` fitted over the window is
    /// larger than its channel's fastest drift could have made it since its
    /// part of the rises began to grow, at `t_s` (s): the pressure offset
    /// against [`MOST_DRIFT_MPA_PER_S`], the offset on x against
    /// [`MOST_POSITION_DRIFT_MM_PER_S`].
    fn grew_faster_than_a_drift(&self, h: usize, t_s: f64) -> bool {
        let grew_s = t_s - self.low_since_s[channel_of(h)];
        if is_position(h) {
            self.window.coefficient(h).abs() > MOST_POSITION_DRIFT_MM_PER_S * grew_s
        } else {
            self.pressure_offset_mpa(h).abs() > MOST_DRIFT_MPA_PER_S * grew_s
        }
    }

    /// Since when the misreading of hypothesis `h` has read off, at `t_s` (s):
    /// a drift's fitted line back to zero where its rate is under
    /// [`MOST_DRIFT_MPA_PER_S`] (its first part is too small to show), else
    /// when its channel's part of the rises was last low; no earlier than the
    /// first sample read.
    fn since_s(&self, h: usize, t_s: f64) -> f64 {
        let rate = self.window.drift_rate_mpa_per_s(h);
        let b = self.window.coefficient(h);
        let since = if is_drift(h) && rate.abs() < MOST_DRIFT_MPA_PER_S && b * rate > 0.0 {
            t_s - b / rate
        } else {
            self.low_since_s[channel_of(h)]
        };
        since.max(self.started_s)
    }

    /// The offset on p1 or p2 the misreading of hypothesis `h` fitted over the
    /// window makes, MPa: a span error's at the pressure read. NaN on x.
    fn pressure_offset_mpa(&self, h: usize) -> f64 {
        let b = self.window.coefficient(h);
        if is_position(h) {
            f64::NAN
        } else if is_span(h) {
            b * self.reading_mpa[channel_of(h)]
        } else {
            b
        }
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
    /// with the filter's responses `response` to an offset (q_e1, q_e2, q_i
    /// per MPa on p1 and on p2) and to a span error (L/min per unit error on
    /// p1 and on p2) and the pressures read `reading_mpa` (p1, p2, MPa; a span
    /// error's offset), `dt_s` after the last, with the thresholds
    /// `thresholds_lpm`; `next_id` gives an event id. Returns a change of the
    /// named offset.
    #[allow(clippy::too_many_arguments)]
    pub fn on_rise(
        &mut self,
        t_s: f64,
        dt_s: f64,
        rise: [f64; 3],
        response: &MisreadingResponse,
        reading_mpa: [f64; 2],
        factors: [f64; 2],
        thresholds_lpm: [f64; 3],
        next_id: &mut u64,
    ) -> Option<OffsetChange> {
        let share = std::mem::take(&mut self.baseline_step);
        if !(rise
            .iter()
            .chain(response.offset_lpm_per_mpa.iter().flatten())
            .chain(response.span_lpm.iter().flatten())
            .chain(&response.position_lpm_per_mm)
            .all(|v| v.is_finite())
            && dt_s > 0.0)
        {
            return None;
        }
        self.directions = leak_directions(factors);
        if self.started_s.is_nan() {
            self.started_s = t_s;
        }
        // (a span error's offset at naming: g times the pressure read, 0 where not read)
        self.reading_mpa = reading_mpa.map(|p| if p.is_finite() { p } else { 0.0 });
        let mut hypotheses = [[0.0; 2]; HYPOTHESES];
        // (each response as given at h, its swing about its baseline at swing_of(h))
        let responses = [
            response.offset_lpm_per_mpa[0],
            response.offset_lpm_per_mpa[1],
            response.span_lpm[0],
            response.span_lpm[1],
            response.position_lpm_per_mm,
        ];
        for (h, r) in AS_GIVEN.into_iter().zip(responses) {
            let w = crate::signatures_with(r, factors);
            for k in 0..2 {
                let base = &mut self.response_baseline[h][k];
                *base += share * (w[k] - *base);
                hypotheses[h][k] = w[k];
                hypotheses[swing_of(h)][k] = w[k] - *base;
            }
        }
        let mut rise3 = rise;
        self.healthy.take_off(&mut rise3, &hypotheses);
        let rise = without_reverse_internal([rise3[0], rise3[1]], factors, &mut hypotheses);
        self.last_rise = rise;
        let response = &hypotheses;
        // (the samples come at one period: the decay is computed once per period)
        if dt_s != self.keep_for.0 {
            self.keep_for = (dt_s, (-dt_s / OFFSET_WINDOW_S).exp());
        }
        let keep = self.keep_for.1;
        self.watched_s += dt_s;
        self.window.add(keep, dt_s, rise, response);
        self.sound.add(keep, dt_s, self.reading_mpa);
        self.healthy.learn(dt_s, rise, response);
        self.window_best = self
            .window
            .best_offset(true, self.position_watched, &self.directions);
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
        // (fitted once a sample: the veto and the rival to a new leak both read it)
        self.episode_best = self
            .episode
            .as_ref()
            .filter(|f| f.w >= EPISODE_MIN_S)
            .map(|f| f.best_offset(false, false, &self.directions));
        if let Some(best) = &self.episode_best {
            // (a drifting offset's response now is its channel's as given)
            let h = best.h;
            self.episode_best_response = response[if is_drift(h) { channel_of(h) } else { h }];
        }
        let smallest = thresholds_lpm.iter().cloned().fold(f64::INFINITY, f64::min);
        self.smallest_threshold_lpm = smallest;
        let left = (self.window_best.left, self.window_best.leak_left);
        let material = self.window_offset_material() && self.window.energy > 0.0;
        self.window_veto.update(left, material, self.watched_s, dt_s);
        let level = OFFSET_NAMED_SHARE * smallest;
        let explained_rms = self.window.channels_explained_rms_lpm();
        for (c, rms) in explained_rms.iter().enumerate() {
            if *rms < 0.1 * smallest {
                self.low_since_s[c] = t_s;
            }
        }
        if let Some(s) = self.standing {
            if explained_rms[s.channel] < 0.5 * level {
                let since = *self.fading_since_s.get_or_insert(self.watched_s);
                if self.watched_s - since >= OFFSET_CLEAR_S {
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
        let BestOffset { h, left, .. } = self.window_best;
        let named = self.watched_s >= OFFSET_WINDOW_S
            && self
                .window
                .offset_fits_better(&self.window_best, OFFSET_FIT_RATIO)
            && left < OFFSET_MAX_UNEXPLAINED * self.window.energy
            && self.window.explained_rms_lpm(h) > level
            && self.channel_told(h, left);
        let confirm_s = if named { self.confirm_s(h, left) } else { None };
        let c = channel_of(h);
        match (confirm_s, self.candidate) {
            (None, _) => self.candidate = None,
            (Some(_), _) if self.grew_past_a_drift(h, t_s) => self.candidate = None,
            (Some(confirm_s), Some((j, watched_at_s))) if j == c => {
                if self.watched_s - watched_at_s >= confirm_s {
                    let coefficient = self.window.coefficient(h);
                    let s = StandingOffset {
                        channel: c,
                        offset_mpa: self.pressure_offset_mpa(h),
                        offset_mm: if is_position(h) { coefficient } else { f64::NAN },
                        span_error: if is_span(h) { coefficient } else { f64::NAN },
                        drift_mpa_per_s: if is_span(h) || is_position(h) {
                            f64::NAN
                        } else {
                            self.window.drift_rate_mpa_per_s(h)
                        },
                        since_s: self.since_s(h, t_s),
                        other_channel_left_ratio: if is_position(h) {
                            f64::NAN
                        } else if left > 0.0 {
                            self.window.other_pressure_channel_left(c) / left
                        } else {
                            f64::INFINITY
                        },
                        event_id: *next_id,
                    };
                    *next_id += 1;
                    self.standing = Some(s);
                    return Some(OffsetChange::Raised(s));
                }
            }
            (Some(_), _) => self.candidate = Some((c, self.watched_s)),
        }
        None
    }
}

#[cfg(test)]
mod tests;
