//! Outliers on a transducer: single readings that jump away and straight back.
//!
//! A pressure in oil or a rod's position cannot leave its course for one
//! sample and return: it has mass and compressibility behind it. A reading
//! that does (a loose connector, interference) is an outlier. One is judged a
//! sample late, from the reading before it and the one after:
//!
//! - it jumps by more than [`SPIKE_JUMP_RMS`] typical sample-to-sample changes
//!   and by more than the channel's floor (1 % of a pressure transducer's
//!   range, [`X_SPIKE_FLOOR_M`] for the rod),
//! - the next reading jumps back by as much, the other way,
//! - and lands within a quarter of the jump of where the reading was before.
//!
//! [`SPIKES_TO_RAISE`] outliers within [`SPIKE_WINDOW_S`] raise `sensor-spikes`.

/// A jump counts when it exceeds this many RMS sample-to-sample changes (1).
pub const SPIKE_JUMP_RMS: f64 = 10.0;
/// Time constant of the RMS sample-to-sample change, s.
pub const CHANGE_RMS_WINDOW_S: f64 = 1.0;
/// Least jump of the rod's reading that counts as an outlier, m (an encoder's
/// count flickering at rest is not one).
pub const X_SPIKE_FLOOR_M: f64 = 1e-3;
/// Least jump of a pressure reading that counts, as a share of the transducer's range (1).
pub const PRESSURE_SPIKE_FLOOR: f64 = 0.01;
/// Outliers within [`SPIKE_WINDOW_S`] that raise the event.
pub const SPIKES_TO_RAISE: usize = 3;
/// Window the outliers are counted over, s; the event clears after this long without one.
pub const SPIKE_WINDOW_S: f64 = 30.0;

/// One channel's outlier watch.
#[derive(Debug, Clone, Copy)]
pub struct SpikeWatch {
    /// The two readings before the present one (older first).
    before: [f64; 2],
    /// Mean square sample-to-sample change (units²).
    change_ms: f64,
    /// Times of the latest outliers, s (NaN: none).
    recent_s: [f64; SPIKES_TO_RAISE],
    /// The largest outlier since the event was raised (or in the window), units.
    pub largest: f64,
    /// Time the typical change has been learned over, s (no outlier is judged before [`CHANGE_RMS_WINDOW_S`]).
    learned_s: f64,
}

impl Default for SpikeWatch {
    fn default() -> Self {
        SpikeWatch {
            before: [f64::NAN; 2],
            change_ms: f64::NAN,
            recent_s: [f64::NAN; SPIKES_TO_RAISE],
            largest: 0.0,
            learned_s: 0.0,
        }
    }
}

impl SpikeWatch {
    /// Reads the reading `v` at time `t_s` (s), `dt_s` after the last, with
    /// the least jump that counts `floor` (units); returns the size of an
    /// outlier found at the previous sample (units), if any.
    pub fn on_reading(&mut self, t_s: f64, dt_s: f64, v: f64, floor: f64) -> Option<f64> {
        let [a, b] = self.before;
        self.before = [b, v];
        if !(a.is_finite() && b.is_finite() && v.is_finite()) {
            return None;
        }
        let (up, back) = (b - a, v - b);
        let limit = (SPIKE_JUMP_RMS * self.change_ms.sqrt()).max(floor);
        let spike = self.learned_s >= CHANGE_RMS_WINDOW_S
            && up.abs() > limit
            && back.abs() > limit
            && up.signum() != back.signum()
            && (v - a).abs() < 0.25 * up.abs().min(back.abs());
        if spike {
            // (the outlier's jumps stay out of the typical change)
            self.recent_s.rotate_left(1);
            self.recent_s[SPIKES_TO_RAISE - 1] = t_s - dt_s;
            self.largest = self.largest.max(up.abs());
            return Some(up.abs());
        }
        self.learned_s += dt_s;
        let k = (dt_s / CHANGE_RMS_WINDOW_S).clamp(0.0, 1.0);
        self.change_ms = if self.change_ms.is_finite() {
            self.change_ms + k * (back * back - self.change_ms)
        } else {
            back * back
        };
        None
    }

    /// Whether [`SPIKES_TO_RAISE`] outliers fell within [`SPIKE_WINDOW_S`] up to `t_s`.
    pub fn is_spiking(&self, t_s: f64) -> bool {
        self.recent_s
            .iter()
            .all(|s| s.is_finite() && t_s - s <= SPIKE_WINDOW_S)
    }

    /// Time of the oldest of the last [`SPIKES_TO_RAISE`] outliers, s (NaN:
    /// fewer seen): where an event raised on them began.
    pub fn first_of_recent_s(&self) -> f64 {
        self.recent_s[0]
    }

    /// Whether the last outlier is more than [`SPIKE_WINDOW_S`] old at `t_s`.
    pub fn is_quiet(&self, t_s: f64) -> bool {
        let last = self.recent_s[SPIKES_TO_RAISE - 1];
        !(last.is_finite() && t_s - last <= SPIKE_WINDOW_S)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A noisy ramp with outliers at given samples: each is found once, at the next sample, with its size.
    #[test]
    fn outliers_on_a_noisy_ramp_are_found_and_a_fast_ramp_is_not() {
        let mut w = SpikeWatch::default();
        let dt = 1e-3;
        let mut found = Vec::new();
        let mut rng = model::rng::Rng::new(7);
        for i in 0..20_000 {
            let t = i as f64 * dt;
            // a pressure rising at 1e8 Pa/s for 50 ms at 5 s (a valve step), noise of 10 kPa
            let ramp = if (5.0..5.05).contains(&t) {
                (t - 5.0) * 1e8
            } else if t >= 5.05 {
                5e6
            } else {
                0.0
            };
            let mut v = 1e7 + ramp + 1e4 * rng.normal();
            if i == 8000 || i == 12_000 || i == 12_500 {
                v += 2e6;
            }
            if let Some(size) = w.on_reading(t, dt, v, 2e5) {
                found.push((i - 1, size));
            }
        }
        let at: Vec<usize> = found.iter().map(|f| f.0).collect();
        assert_eq!(at, vec![8000, 12_000, 12_500]);
        for (_, size) in &found {
            assert!((size - 2e6).abs() < 1e5, "{size}");
        }
        assert!(
            (w.first_of_recent_s() - 8.0).abs() < 1e-9,
            "{}",
            w.first_of_recent_s()
        );
        assert!(w.is_spiking(12.6));
        assert!(!w.is_spiking(38.1));
        assert!(w.is_quiet(43.0));
    }
}
