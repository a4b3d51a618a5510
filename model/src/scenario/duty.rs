//! Smooth duty cycles of plant rigs: a press cycle against a workpiece and
//! pseudorandom point-to-point handling, as references made of 3rd-order
//! (jerk-limited) moves.

use crate::params::SpringLoad;
use crate::rng::Rng;

/// One move of a profiled reference: from `from_m` at `t_start_s` to `to_m`,
/// `duration_s` later, along a 3rd-order profile (piecewise-constant jerk
/// +j, −j, +j over a quarter, a half and a quarter of the move: the
/// acceleration is continuous, the velocity rises from 0 to its peak
/// 2·|to − from|/duration at mid-move and falls back to 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// Start of the move, s.
    pub t_start_s: f64,
    /// Duration of the move, s.
    pub duration_s: f64,
    /// Position at the start, m.
    pub from_m: f64,
    /// Position at the end, m.
    pub to_m: f64,
}

/// The normalised 3rd-order profile s(τ), τ in [0, 1] (clamped): 0 to 1 with
/// zero velocity and acceleration at both ends, peak velocity 2 at τ = 1/2.
fn s_curve(tau: f64) -> f64 {
    let tau = tau.clamp(0.0, 1.0);
    let first_half = |t: f64| {
        if t <= 0.25 {
            16.0 / 3.0 * t * t * t
        } else {
            let u = t - 0.25;
            1.0 / 12.0 + u + 4.0 * u * u - 16.0 / 3.0 * u * u * u
        }
    };
    if tau <= 0.5 {
        first_half(tau)
    } else {
        1.0 - first_half(1.0 - tau)
    }
}

impl Move {
    /// The end of the move, s.
    pub fn t_end_s(&self) -> f64 {
        self.t_start_s + self.duration_s
    }

    /// The reference at `t_s` (s) within or around the move, m: `from_m`
    /// before it, `to_m` after it.
    pub fn position_m(&self, t_s: f64) -> f64 {
        let tau = (t_s - self.t_start_s) / self.duration_s;
        self.from_m + (self.to_m - self.from_m) * s_curve(tau)
    }

    /// The move's peak speed (at mid-move), m/s.
    pub fn peak_velocity_m_s(&self) -> f64 {
        2.0 * (self.to_m - self.from_m).abs() / self.duration_s
    }
}

/// The press cycle's rod positions, m: home, just before the workpiece, the
/// workpiece's surface and the pressed-in target.
pub const PRESS_HOME_M: f64 = 0.05;
/// Where the approach ends, just before the workpiece, m.
pub const PRESS_APPROACH_M: f64 = 0.195;
/// Where the rod touches the workpiece, m.
pub const PRESS_CONTACT_M: f64 = 0.20;
/// Where the press-in ends, m.
pub const PRESS_TARGET_M: f64 = 0.202;
/// The workpiece's contact stiffness, N/m.
pub const PRESS_WORKPIECE_N_PER_M: f64 = 2.0e6;
/// The press cycle's nominal phase durations, s: approach, press-in, hold,
/// retract, dwell; each cycle draws each of them times U[0.9, 1.1].
pub const PRESS_PHASES_S: [f64; 5] = [0.6, 0.2, 1.0, 0.6, 0.5];
/// The spread of each phase's duration, as a factor range.
pub const PRESS_TIMING_FACTOR: (f64, f64) = (0.9, 1.1);

/// The workpiece of the press cycle: 2e6 N/m touching at 0.20 m.
pub fn press_workpiece() -> SpringLoad {
    SpringLoad {
        stiffness_n_per_m: PRESS_WORKPIECE_N_PER_M,
        contact_m: PRESS_CONTACT_M,
        ..SpringLoad::default()
    }
}

/// Press cycles from home (0.05 m) for at least `seconds` (s): a dwell, then
/// per cycle approach to 0.195 m, press-in to 0.202 m, hold, retract home,
/// dwell, each phase's duration times U[0.9, 1.1] drawn from `seed`.
pub fn press_moves(seed: u64, seconds: f64) -> Vec<Move> {
    let mut rng = Rng::new(seed ^ 0x9E55_C7C1);
    let (lo, hi) = PRESS_TIMING_FACTOR;
    let [approach, press_in, hold, retract, dwell] = PRESS_PHASES_S;
    let mut t = dwell * rng.uniform_in(lo, hi);
    let mut out = Vec::new();
    while t < seconds + 1.0 {
        for (d, from, to) in [
            (approach, PRESS_HOME_M, PRESS_APPROACH_M),
            (press_in, PRESS_APPROACH_M, PRESS_TARGET_M),
        ] {
            let m = Move {
                t_start_s: t,
                duration_s: d * rng.uniform_in(lo, hi),
                from_m: from,
                to_m: to,
            };
            t = m.t_end_s();
            out.push(m);
        }
        t += hold * rng.uniform_in(lo, hi);
        let back = Move {
            t_start_s: t,
            duration_s: retract * rng.uniform_in(lo, hi),
            from_m: PRESS_TARGET_M,
            to_m: PRESS_HOME_M,
        };
        t = back.t_end_s() + dwell * rng.uniform_in(lo, hi);
        out.push(back);
    }
    out
}

/// The handling cycle's range of targets, m.
pub const HANDLING_RANGE_M: (f64, f64) = (0.03, 0.27);
/// The handling cycle's range of peak velocities, m/s.
pub const HANDLING_PEAK_VELOCITY_M_S: (f64, f64) = (0.1, 0.35);
/// The handling cycle's range of holds between moves, s.
pub const HANDLING_HOLD_S: (f64, f64) = (0.5, 3.0);
/// The handling cycle's shortest move, m (a target closer is drawn again).
pub const HANDLING_MIN_MOVE_M: f64 = 0.02;
/// Where the handling cycle starts, m.
pub const HANDLING_START_M: f64 = 0.15;

/// Pseudorandom point-to-point moves from 0.15 m for at least `seconds` (s):
/// a hold of U[0.5, 3] s, then a move to a target in U[0.03, 0.27] m (at
/// least 0.02 m away) with a peak velocity of U[0.1, 0.35] m/s, and so on.
pub fn handling_moves(seed: u64, seconds: f64) -> Vec<Move> {
    let mut rng = Rng::new(seed ^ 0x4A2D_11E6);
    let mut t = rng.uniform_in(HANDLING_HOLD_S.0, HANDLING_HOLD_S.1);
    let mut at = HANDLING_START_M;
    let mut out = Vec::new();
    while t < seconds + 1.0 {
        let mut to = at;
        while (to - at).abs() < HANDLING_MIN_MOVE_M {
            to = rng.uniform_in(HANDLING_RANGE_M.0, HANDLING_RANGE_M.1);
        }
        let v = rng.uniform_in(HANDLING_PEAK_VELOCITY_M_S.0, HANDLING_PEAK_VELOCITY_M_S.1);
        let m = Move {
            t_start_s: t,
            duration_s: 2.0 * (to - at).abs() / v,
            from_m: at,
            to_m: to,
        };
        t = m.t_end_s() + rng.uniform_in(HANDLING_HOLD_S.0, HANDLING_HOLD_S.1);
        at = to;
        out.push(m);
    }
    out
}

/// The reference of a sequence of moves (sorted, each starting where the one
/// before ended) at `t_s`, m: the first move's start before it, the last
/// one's end after it, and between moves the position the last one reached.
pub fn reference_of(moves: &[Move], t_s: f64) -> f64 {
    let i = moves.partition_point(|m| m.t_start_s <= t_s);
    match i.checked_sub(1).and_then(|j| moves.get(j)) {
        Some(m) => m.position_m(t_s),
        None => moves.first().map_or(f64::NAN, |m| m.from_m),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_is_smooth_and_peaks_at_twice_the_mean_speed() {
        assert_eq!(s_curve(0.0), 0.0);
        assert!((s_curve(0.5) - 0.5).abs() < 1e-15);
        assert!((s_curve(1.0) - 1.0).abs() < 1e-15);
        assert!((s_curve(0.25) - 1.0 / 12.0).abs() < 1e-15);
        // velocity (central difference) peaks at 2 mid-move and is 0 at the ends
        let v = |t: f64| (s_curve(t + 1e-7) - s_curve(t - 1e-7)) / 2e-7;
        assert!((v(0.5) - 2.0).abs() < 1e-6, "{}", v(0.5));
        assert!(v(1e-4).abs() < 1e-6 && v(1.0 - 1e-4).abs() < 1e-6);
        // acceleration continuous at the quarter: both sides 8
        let a = |t: f64| (v(t + 1e-4) - v(t - 1e-4)) / 2e-4;
        assert!((a(0.25 - 1e-3) - a(0.25 + 1e-3)).abs() < 0.1);
        assert!((a(0.25) - 8.0).abs() < 1e-2, "{}", a(0.25));
        let m = Move {
            t_start_s: 1.0,
            duration_s: 0.5,
            from_m: 0.2,
            to_m: 0.1,
        };
        assert!((m.peak_velocity_m_s() - 0.4).abs() < 1e-15);
        assert_eq!(m.position_m(0.0), 0.2);
        assert_eq!(m.position_m(2.0), 0.1);
        assert!((m.position_m(1.25) - 0.15).abs() < 1e-15);
    }

    /// Largest step of the reference between samples 1 ms apart, m.
    fn largest_step(moves: &[Move], seconds: f64) -> f64 {
        let n = (seconds * 1000.0) as usize;
        (1..n)
            .map(|k| {
                (reference_of(moves, k as f64 * 1e-3) - reference_of(moves, (k - 1) as f64 * 1e-3)).abs()
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_press_cycle_is_continuous_within_its_positions_and_timings() {
        let moves = press_moves(5, 60.0);
        // each cycle: approach, press-in, retract
        assert_eq!(moves.len() % 3, 0);
        assert!(moves.len() / 3 >= 60 / 4, "{} cycles", moves.len() / 3);
        for w in moves.windows(2) {
            assert_eq!(w[0].to_m, w[1].from_m);
            assert!(w[1].t_start_s >= w[0].t_end_s());
        }
        for c in moves.chunks(3) {
            let [a, p, r] = [c[0], c[1], c[2]];
            assert_eq!((a.from_m, a.to_m, p.to_m, r.to_m), (0.05, 0.195, 0.202, 0.05));
            for (m, nominal) in [(a, 0.6), (p, 0.2), (r, 0.6)] {
                assert!((0.9 * nominal..=1.1 * nominal).contains(&m.duration_s), "{m:?}");
            }
            let hold = r.t_start_s - p.t_end_s();
            assert!((0.9 - 1e-9..=1.1 + 1e-9).contains(&hold), "hold {hold}");
        }
        // the fastest phase, a 0.152 m retract in 0.54 s, peaks at 0.563 m/s: 0.563 mm a sample
        let step = largest_step(&moves, 60.0);
        assert!(step < 0.565e-3, "{step}");
        assert_eq!(reference_of(&moves, 0.0), 0.05);
        assert_eq!(moves, press_moves(5, 60.0));
        assert_ne!(moves, press_moves(6, 60.0));
    }

    #[test]
    fn handling_moves_stay_in_range_at_their_drawn_speeds() {
        let moves = handling_moves(9, 300.0);
        assert!(moves.len() > 40, "{}", moves.len());
        assert_eq!(moves[0].from_m, 0.15);
        for w in moves.windows(2) {
            assert_eq!(w[0].to_m, w[1].from_m);
            let hold = w[1].t_start_s - w[0].t_end_s();
            assert!((0.5 - 1e-9..3.0 + 1e-9).contains(&hold), "hold {hold}");
        }
        for m in &moves {
            assert!((0.03..0.27).contains(&m.to_m), "{m:?}");
            assert!((m.to_m - m.from_m).abs() >= 0.02);
            let v = m.peak_velocity_m_s();
            assert!((0.1 - 1e-12..0.35 + 1e-12).contains(&v), "{v}");
        }
        // 0.35 m/s is 0.35 mm a sample at the peak
        let step = largest_step(&moves, 300.0);
        assert!(step <= 0.35e-3 + 1e-12, "{step}");
        assert_eq!(moves, handling_moves(9, 300.0));
        assert_ne!(moves, handling_moves(10, 300.0));
    }
}
