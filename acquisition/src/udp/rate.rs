//! The sender's sample period, measured over blocks of sequence steps.

use super::{RATE_EARLY_STEPS, RATE_EARLY_TOLERANCE, RATE_TOLERANCE, RATE_WINDOW};

/// The sender's sample period, measured over blocks of steps (module docs).
pub(super) struct RateMeter {
    /// `Δt / Δseq` of the block's steps, s.
    steps: [f64; RATE_WINDOW],
    /// Steps in the block.
    n: usize,
    /// Whether the block is the first of the stream (looked at early).
    first_block: bool,
    /// The median of the last block looked at, s.
    pub(super) measured_s: Option<f64>,
}

impl RateMeter {
    pub(super) fn new() -> RateMeter {
        RateMeter {
            steps: [0.0; RATE_WINDOW],
            n: 0,
            first_block: true,
            measured_s: None,
        }
    }

    /// A new stream: its first block is looked at early again.
    pub(super) fn restart(&mut self) {
        self.n = 0;
        self.first_block = true;
    }

    /// Adds a step of `period_s`; returns the block's median period, s, and
    /// the tolerance to judge it with when the block is due to be looked at.
    pub(super) fn push(&mut self, period_s: f64) -> Option<(f64, f64)> {
        if !(period_s.is_finite() && period_s > 0.0) || self.n >= RATE_WINDOW {
            return None;
        }
        self.steps[self.n] = period_s;
        self.n += 1;
        let tolerance = if self.n == RATE_WINDOW {
            RATE_TOLERANCE
        } else if self.first_block && self.n == RATE_EARLY_STEPS {
            RATE_EARLY_TOLERANCE
        } else {
            return None;
        };
        let mut sorted = self.steps;
        let block = &mut sorted[..self.n];
        let mid = self.n / 2;
        block.select_nth_unstable_by(mid, f64::total_cmp);
        let mut median = block[mid];
        if self.n.is_multiple_of(2) {
            // the mean of the two middle steps: the largest of the lower half
            let below = block[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
            median = 0.5 * (median + below);
        }
        if self.n == RATE_WINDOW {
            self.n = 0;
            self.first_block = false;
        }
        self.measured_s = Some(median);
        Some((median, tolerance))
    }
}
