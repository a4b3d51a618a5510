//! The thesis' moving average of |e| (MAE), O(1) per sample.

/// Moving average over the last `window` values, O(1) per push.
///
/// The running sum is recomputed exactly once per window to keep rounding
/// from accumulating over long runs (amortised O(1)).
#[derive(Debug, Clone)]
pub struct MovingMae {
    buf: Vec<f64>,
    next: usize,
    filled: usize,
    sum: f64,
}

impl MovingMae {
    /// An empty average over `window` (≥ 1) samples.
    pub fn new(window: usize) -> Self {
        MovingMae {
            buf: vec![0.0; window.max(1)],
            next: 0,
            filled: 0,
            sum: 0.0,
        }
    }

    /// The window length, samples.
    pub fn window(&self) -> usize {
        self.buf.len()
    }

    /// Forgets every value.
    pub fn clear(&mut self) {
        self.next = 0;
        self.filled = 0;
        self.sum = 0.0;
    }

    /// Adds a value and returns the mean over the window (or over what has
    /// been seen, while the window fills).
    #[inline]
    pub fn push(&mut self, v: f64) -> f64 {
        let old = self.buf[self.next];
        self.buf[self.next] = v;
        self.next += 1;
        if self.filled == self.buf.len() {
            self.sum += v - old;
        } else {
            self.sum += v;
            self.filled += 1;
        }
        if self.next == self.buf.len() {
            self.next = 0;
            self.sum = self.buf[..self.filled].iter().sum();
        }
        self.mean()
    }

    /// The current mean (NaN before the first value).
    #[inline]
    pub fn mean(&self) -> f64 {
        if self.filled == 0 {
            f64::NAN
        } else {
            self.sum / self.filled as f64
        }
    }

    /// Whether a whole window has been seen.
    pub fn is_full(&self) -> bool {
        self.filled == self.buf.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_direct_average() {
        let mut m = MovingMae::new(7);
        assert!(m.mean().is_nan());
        let xs: Vec<f64> = (0..100).map(|i| ((i * 37) % 11) as f64 * 1.5e4).collect();
        for (i, &x) in xs.iter().enumerate() {
            let got = m.push(x);
            let lo = (i + 1).saturating_sub(7);
            let want = xs[lo..=i].iter().sum::<f64>() / (i + 1 - lo) as f64;
            assert!((got - want).abs() < 1e-9, "{i}: {got} vs {want}");
        }
        assert!(m.is_full());
        m.clear();
        assert!(m.mean().is_nan());
    }
}
