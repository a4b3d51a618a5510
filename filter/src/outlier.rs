//! Single readings far off the filter's prediction, kept out of its update.
//!
//! A transducer's outlier (a loose connector, interference) lands tens to
//! hundreds of innovation σ off on one channel while the others agree with
//! the prediction. Taken into the update, it kicks every state the channel is
//! correlated with: the oil's stiffness θ (and the temperature read from it)
//! and the leak sizes. A channel is left out of one sample's update when its
//! innovation passes [`OUTLIER_SIGMAS`] while every other used channel's
//! stays within [`OTHERS_WITHIN_SIGMAS`], and it was not left out on the
//! sample before. A reading that stays off (a step, a stuck or drifting
//! transducer, the model's own error at a reversal) updates the filter from
//! its second sample on.

/// A channel's innovation beyond this many of its σ, alone, is an outlier (1).
pub const OUTLIER_SIGMAS: f64 = 50.0;
/// The other used channels' innovations stay within this many σ (1).
pub const OTHERS_WITHIN_SIGMAS: f64 = 5.0;

/// The outlier watch over the three measured channels (x, p1, p2).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OutlierGate {
    /// Each channel was left out of the previous sample's update.
    left_out_last: [bool; 3],
    /// Channel readings left out so far.
    left_out: u64,
}

impl OutlierGate {
    /// Forgets the previous sample (after a restart or a re-anchoring).
    pub fn clear(&mut self) {
        self.left_out_last = [false; 3];
    }

    /// Channel readings left out of the update so far.
    pub fn left_out(&self) -> u64 {
        self.left_out
    }

    /// The channels that update the filter: `use_channel` less an outlier,
    /// judged from the innovations `nu` (m, Pa, Pa) and their prior σ
    /// `sigma` (same units).
    pub fn gate(&mut self, nu: &[f64; 3], sigma: &[f64; 3], use_channel: [bool; 3]) -> [bool; 3] {
        let z: [f64; 3] = std::array::from_fn(|k| {
            if use_channel[k] && sigma[k] > 0.0 {
                (nu[k] / sigma[k]).abs()
            } else {
                0.0
            }
        });
        let mut out = use_channel;
        let mut left_out_now = [false; 3];
        for k in 0..3 {
            let others_agree = (0..3).all(|j| j == k || z[j] <= OTHERS_WITHIN_SIGMAS);
            if z[k] > OUTLIER_SIGMAS && others_agree && !self.left_out_last[k] {
                out[k] = false;
                left_out_now[k] = true;
                self.left_out += 1;
            }
        }
        self.left_out_last = left_out_now;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lone_jump_is_left_out_once_and_a_lasting_one_is_taken() {
        let mut g = OutlierGate::default();
        let sigma = [1e-6, 1e4, 1e4];
        // a 2 MPa spike on p2 while x and p1 agree: left out
        assert_eq!(g.gate(&[0.0, 2e4, 2e6], &sigma, [true; 3]), [true, true, false]);
        // the same reading again: a lasting change, taken
        assert_eq!(g.gate(&[0.0, 2e4, 2e6], &sigma, [true; 3]), [true; 3]);
        // the model off on both pressures (a reversal): nothing left out
        assert_eq!(g.gate(&[0.0, 8e5, 9e5], &sigma, [true; 3]), [true; 3]);
        // just within the gate: taken
        assert_eq!(g.gate(&[0.0, 0.0, 4.9e5], &sigma, [true; 3]), [true; 3]);
        assert_eq!(g.left_out(), 1);
        // an unused channel stays unused and does not count as disagreeing
        assert_eq!(
            g.gate(&[5e-3, 0.0, 0.0], &sigma, [true, false, true]),
            [false, false, true]
        );
        assert_eq!(g.left_out(), 2);
    }
}
