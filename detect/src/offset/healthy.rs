//! The healthy rises' own misreading: a rig's model error can swing with the
//! flow as a transducer's misreading does. Commissioning fits it on its
//! healthy recording; the watch takes it off the rises before it fits, so a
//! fault is fitted from where the healthy rig stood, not from zero.

use super::fit::{channel_of, is_span, Fit, HYPOTHESES};
use super::OffsetWatch;

/// The hypotheses a healthy misreading is taken in: the swings of p1's and
/// p2's offsets (2, 3) and span errors (6, 7). The rises are measured from a
/// baseline that takes up a misreading's steady part: only its swing is left.
pub(crate) const HEALTHY_HYPOTHESES: [usize; 4] = [2, 3, 6, 7];

/// Least share of the healthy rises' energy (1) the best misreading must
/// explain over the whole recording to be taken as the healthy one.
pub const HEALTHY_MISREADING_LEAST_SHARE: f64 = 1.0 / 3.0;

/// The misreading the healthy rises fit best over a whole recording, in its
/// swing form ([`HEALTHY_HYPOTHESES`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HealthyMisreading {
    /// Channel: 0 p1, 1 p2.
    pub channel: usize,
    /// The offset fitted, MPa (measured minus true); NaN where a span error fits better.
    pub offset_mpa: f64,
    /// The span error fitted, 1 (the channel reads (1 + g)·p); NaN where an offset fits better.
    pub span_error: f64,
    /// Share of the rises' energy it explains, 1.
    pub share: f64,
}

impl HealthyMisreading {
    /// The misreading `offset_kpa` (kPa on p1 and p2) or `span_error` (1 on
    /// p1 and p2) as `[classifier.commissioning]` keeps it: the first
    /// non-zero one, None where all are zero.
    pub fn from_kept(offset_kpa: [f64; 2], span_error: [f64; 2]) -> Option<HealthyMisreading> {
        let offset = (0..2).find(|&c| offset_kpa[c] != 0.0).map(|c| HealthyMisreading {
            channel: c,
            offset_mpa: offset_kpa[c] * 1e-3,
            span_error: f64::NAN,
            share: f64::NAN,
        });
        let span = (0..2).find(|&c| span_error[c] != 0.0).map(|c| HealthyMisreading {
            channel: c,
            offset_mpa: f64::NAN,
            span_error: span_error[c],
            share: f64::NAN,
        });
        offset.or(span)
    }

    /// The hypothesis it is fitted in.
    fn hypothesis(&self) -> usize {
        if self.span_error.is_nan() {
            2 + self.channel
        } else {
            6 + self.channel
        }
    }

    /// Its coefficient in its hypothesis: MPa for an offset, 1 for a span error.
    fn coefficient(&self) -> f64 {
        if self.span_error.is_nan() {
            self.offset_mpa
        } else {
            self.span_error
        }
    }
}

/// The healthy misreading's part in the watch: taken off the rises, or
/// learned from them.
#[derive(Debug, Clone, Default)]
pub(crate) struct HealthyPart {
    /// The misreading taken off the rises (hypothesis, coefficient).
    taken: Option<(usize, f64)>,
    /// The whole recording's fit, where it is being learned.
    learning: Option<Fit>,
}

impl HealthyPart {
    /// Takes `rise` (w1, w2, L/min) to what is left of it once the healthy
    /// misreading's part, in `hypotheses` (its responses this sample), is off.
    pub(crate) fn take_off(&self, rise: &mut [f64; 3], hypotheses: &[[f64; 2]; HYPOTHESES]) {
        if let Some((h, c)) = self.taken {
            for k in 0..2 {
                rise[k] -= c * hypotheses[h][k];
            }
        }
    }

    /// Adds a sample to the learning fit, where one is kept.
    pub(crate) fn learn(&mut self, dt_s: f64, rise: [f64; 2], hypotheses: &[[f64; 2]; HYPOTHESES]) {
        if let Some(f) = &mut self.learning {
            f.add(1.0, dt_s, rise, hypotheses);
        }
    }
}

impl OffsetWatch {
    /// The watch with `misreading` taken off the rises before it fits: the
    /// healthy rises' own ([`HealthyMisreading`], as commissioning found it).
    pub fn with_healthy_misreading(mut self, misreading: Option<HealthyMisreading>) -> Self {
        self.healthy.taken = misreading
            .filter(|m| m.coefficient().is_finite() && m.channel < 2)
            .map(|m| (m.hypothesis(), m.coefficient()));
        self
    }

    /// The watch fitting every rise it reads, over all of them, for
    /// [`OffsetWatch::healthy_misreading`].
    pub fn learning_healthy_misreading(mut self) -> Self {
        self.healthy.learning = Some(Fit::default());
        self
    }

    /// The misreading the rises read so far fit best in its swing form, where
    /// it explains at least [`HEALTHY_MISREADING_LEAST_SHARE`] of their energy
    /// (None otherwise, or without [`OffsetWatch::learning_healthy_misreading`]).
    pub fn healthy_misreading(&self) -> Option<HealthyMisreading> {
        let f = self.healthy.learning.as_ref().filter(|f| f.energy > 0.0)?;
        let (h, explained) = HEALTHY_HYPOTHESES
            .iter()
            .map(|&h| (h, f.explained_by_offset(h)))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        let share = explained / f.energy;
        let b = f.coefficient(h);
        (share >= HEALTHY_MISREADING_LEAST_SHARE && b.is_finite()).then(|| HealthyMisreading {
            channel: channel_of(h),
            offset_mpa: if is_span(h) { f64::NAN } else { b },
            span_error: if is_span(h) { b } else { f64::NAN },
            share,
        })
    }
}
