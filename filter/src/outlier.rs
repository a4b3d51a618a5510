//! Single readings far off the filter's prediction, kept out of its update.
//!
//! A transducer's outlier (a loose connector, interference) lands tens to
//! hundreds of innovation σ off on one channel while the others agree with
//! the prediction. Taken into the update, it kicks every state the channel is
//! correlated with: the oil's stiffness θ (and the temperature read from it)
//! and the leak sizes. A channel is left out of one sample's update when its
//! innovation passes [`OUTLIER_SIGMAS`] while every other used channel's
//! stays within [`OTHERS_WITHIN_SIGMAS`] (or within a [`OUTLIER_DOMINANCE`]th
//! of the outlier's own, up to [`OTHERS_WITHIN_MOST_SIGMAS`]), and it was
//! not left out on the sample before. A reading that stays off (a step, a
//! stuck or drifting transducer, the model's own error at a reversal) updates
//! the filter from its second sample on.
//!
//! A channel that has given two such outliers within [`SUSPECT_WINDOW_S`] is
//! suspect: its lone readings are left out from [`SUSPECT_SIGMAS`] on. The
//! model's own lone errors reach 46 σ on the lift (the rod's position at a
//! reversal, a chamber's pressure as the valve opens), so the first gate
//! stays above them; a 2 MPa spike on a small chamber, whose prior σ reaches
//! 42 kPa on the press, is 47 σ.

/// A channel's innovation beyond this many of its σ, alone, is an outlier (1).
pub const OUTLIER_SIGMAS: f64 = 50.0;
/// On a suspect channel, an innovation beyond this many of its σ, alone, is an outlier (1).
pub const SUSPECT_SIGMAS: f64 = 25.0;
/// A channel is suspect while its second-to-last outlier is at most this old, s.
pub const SUSPECT_WINDOW_S: f64 = 30.0;
/// The other used channels' innovations stay within this many σ (1).
pub const OTHERS_WITHIN_SIGMAS: f64 = 5.0;
/// Or within the outlier's own σ count over this (1), up to
/// [`OTHERS_WITHIN_MOST_SIGMAS`]: a 5 mm spike on the position (a thousand σ
/// and more) is as lone while the pressures swing by 6 σ with a ripple the
/// model does not follow (the press at rest after a stroke). Taken, it
/// kicked the leak sizes by 0.15 L/min, which outlived the 2 s the detector
/// holds its evidence after a burst.
pub const OUTLIER_DOMINANCE: f64 = 10.0;
/// The most σ the other channels may be off for a channel to be an outlier
/// (1): past it the filter itself is lost, and leaving out the channel most
/// off would keep it lost (on random readings the rod's speed ran away to
/// 5e7 m/s).
pub const OTHERS_WITHIN_MOST_SIGMAS: f64 = 10.0;

/// The outlier watch over the three measured channels (x, p1, p2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutlierGate {
    /// Each channel was left out of the previous sample's update.
    left_out_last: [bool; 3],
    /// Channel readings left out so far.
    left_out: u64,
    /// Per channel: when its last two readings were left out, s (older first).
    last_two_s: [[f64; 2]; 3],
}

impl Default for OutlierGate {
    fn default() -> Self {
        OutlierGate {
            left_out_last: [false; 3],
            left_out: 0,
            last_two_s: [[f64::NEG_INFINITY; 2]; 3],
        }
    }
}

impl OutlierGate {
    /// Forgets the previous sample (after a restart or a re-anchoring); a
    /// suspect channel stays suspect.
    pub fn clear(&mut self) {
        self.left_out_last = [false; 3];
    }

    /// Channel readings left out of the update so far.
    pub fn left_out(&self) -> u64 {
        self.left_out
    }

    /// The channels that update the filter at time `t_s` (s): `use_channel`
    /// less an outlier, judged from the innovations `nu` (m, Pa, Pa) and
    /// their prior σ `sigma` (same units).
    pub fn gate(&mut self, t_s: f64, nu: &[f64; 3], sigma: &[f64; 3], use_channel: [bool; 3]) -> [bool; 3] {
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
            let within = (z[k] / OUTLIER_DOMINANCE).clamp(OTHERS_WITHIN_SIGMAS, OTHERS_WITHIN_MOST_SIGMAS);
            let others_agree = (0..3).all(|j| j == k || z[j] <= within);
            // (a stream whose time went back starts its suspicions afresh)
            let suspect = (0.0..=SUSPECT_WINDOW_S).contains(&(t_s - self.last_two_s[k][0]));
            let limit = if suspect { SUSPECT_SIGMAS } else { OUTLIER_SIGMAS };
            if z[k] > limit && others_agree && !self.left_out_last[k] {
                out[k] = false;
                left_out_now[k] = true;
                self.left_out += 1;
                self.last_two_s[k] = [self.last_two_s[k][1], t_s];
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
        assert_eq!(
            g.gate(0.0, &[0.0, 2e4, 2e6], &sigma, [true; 3]),
            [true, true, false]
        );
        // the same reading again: a lasting change, taken
        assert_eq!(g.gate(0.0, &[0.0, 2e4, 2e6], &sigma, [true; 3]), [true; 3]);
        // the model off on both pressures (a reversal): nothing left out
        assert_eq!(g.gate(0.0, &[0.0, 8e5, 9e5], &sigma, [true; 3]), [true; 3]);
        // a 5 mm spike on x (5000 σ) while the pressures swing by 9 σ: left out;
        // by 11 σ with a 100 σ jump on x, or with a 5 mm spike (the filter lost): taken
        assert_eq!(
            g.gate(0.0, &[5e-3, 9e4, -9e4], &sigma, [true; 3]),
            [false, true, true]
        );
        assert_eq!(g.gate(0.0, &[0.0; 3], &sigma, [true; 3]), [true; 3]);
        assert_eq!(g.gate(0.0, &[1e-4, 1.1e5, 0.0], &sigma, [true; 3]), [true; 3]);
        assert_eq!(g.gate(0.0, &[5e-3, 1.1e5, 0.0], &sigma, [true; 3]), [true; 3]);
        // just within the gate: taken
        assert_eq!(g.gate(0.0, &[0.0, 0.0, 4.9e5], &sigma, [true; 3]), [true; 3]);
        assert_eq!(g.left_out(), 2);
        // an unused channel stays unused and does not count as disagreeing
        assert_eq!(
            g.gate(0.0, &[5e-3, 0.0, 0.0], &sigma, [true, false, true]),
            [false, false, true]
        );
        assert_eq!(g.left_out(), 3);
    }

    #[test]
    fn a_channel_that_gave_two_outliers_is_gated_closer_for_a_while() {
        // the press at rest near its end: p2's prior σ 42.5 kPa, a 2 MPa spike is 47 σ
        let sigma = [5.8e-6, 16.3e3, 42.5e3];
        let spike = [1.0e-6, 4.3e3, -1.98e6];
        let big = [1.0e-6, 4.3e3, 2.5e6]; // 59 σ
        let quiet = [1.0e-6, 4.3e3, 1.0e3];
        let mut g = OutlierGate::default();
        // each reading below is one sample, followed by a quiet one
        let mut sample = |t: f64, nu: &[f64; 3]| {
            let out = g.gate(t, nu, &sigma, [true; 3]);
            assert_eq!(g.gate(t + 0.001, &quiet, &sigma, [true; 3]), [true; 3]);
            out
        };
        // not suspect: the 47 σ reading is taken (a model's lone error reaches that)
        assert_eq!(sample(10.0, &spike), [true; 3]);
        // two outliers past 50 σ within the window make p2 suspect
        assert_eq!(sample(11.0, &big), [true, true, false]);
        assert_eq!(sample(11.5, &spike), [true; 3]);
        assert_eq!(sample(20.0, &big), [true, true, false]);
        assert_eq!(sample(25.0, &spike), [true, true, false]);
        // x is not suspect: its 47 σ lone error is taken
        assert_eq!(sample(26.0, &[2.75e-4, 4.3e3, 1.0e3]), [true; 3]);
        // suspect until 30 s after the second-to-last outlier (20 s, then 25 s)
        assert_eq!(sample(49.9, &spike), [true, true, false]);
        assert_eq!(sample(80.0, &spike), [true; 3]);
        assert_eq!(g.left_out(), 4);
        // a suspect channel's reading that stays off is taken from its second sample on
        let mut g = OutlierGate::default();
        for t in [1.0, 2.0] {
            g.gate(t, &big, &sigma, [true; 3]);
            g.gate(t + 0.001, &quiet, &sigma, [true; 3]);
        }
        assert_eq!(g.gate(3.0, &spike, &sigma, [true; 3]), [true, true, false]);
        assert_eq!(g.gate(3.001, &spike, &sigma, [true; 3]), [true; 3]);
        // a stream whose time went back (a restart from 0 s) is not suspect
        assert_eq!(g.gate(0.5, &spike, &sigma, [true; 3]), [true; 3]);
    }
}
