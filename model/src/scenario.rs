//! The test scenarios of the thesis (docs/model.md#scenarios), a lift-and-lower cycle and
//! two plant duty cycles (a press cycle, pseudorandom handling), by name, with
//! the proportional position controller of the closed-loop runs.

use crate::params::SpringLoad;
use crate::rng::Rng;

pub mod duty;

pub use duty::Move;

/// Proportional gain of the thesis' position controller, V/m.
pub const KP_V_PER_M: f64 = 50.0;
/// Proportional gain of the position controller of the plant duty cycles
/// (`press`, `handling`), V/m: their smooth references are followed within
/// about 2 cm at 0.5 m/s on the in-repo plant rigs.
pub const KP_PROFILE_V_PER_M: f64 = 250.0;
/// Saturation of the valve command, V.
pub const U_MAX_V: f64 = 10.0;
/// Length of one sweep of the open-loop chirp, s (0.5 to 10.5 Hz).
pub const CHIRP_PERIOD_S: f64 = 40.0;

/// The named scenarios.
pub const SCENARIO_NAMES: [&str; 9] = [
    "open-loop-sine",
    "open-loop-chirp",
    "closed-loop-sine",
    "closed-loop-random",
    "loaded-sine",
    "loaded-random",
    "lift",
    "press",
    "handling",
];

/// How the valve is driven.
#[derive(Debug, Clone, PartialEq)]
pub enum Drive {
    /// u = amplitude·sin(2π f t + phase) V.
    OpenLoopSine {
        amplitude_v: f64,
        freq_hz: f64,
        phase_rad: f64,
    },
    /// u = amplitude·sin(π(1 + t/4)·t) V: 0.5 Hz rising to 10.5 Hz over 40 s; a
    /// longer run repeats the sweep every 40 s (t taken modulo 40 s; u is 0 at the
    /// wrap, so the command stays continuous) instead of rising past the 10.5 Hz
    /// the thesis' rig was driven at.
    OpenLoopChirp { amplitude_v: f64 },
    /// Closed loop on r = offset + amplitude·sin(2π t / period).
    ClosedLoopSine {
        offset_m: f64,
        amplitude_m: f64,
        period_s: f64,
    },
    /// Closed loop on a piecewise-constant reference: (start time s, level m), sorted.
    ClosedLoopSteps { levels: Vec<(f64, f64)> },
    /// Closed loop, with gain `kp_v_per_m` (V/m), on a smooth reference: the
    /// `moves` (sorted, each starting where the one before ended) and holds between them.
    ClosedLoopProfile { moves: Vec<Move>, kp_v_per_m: f64 },
}

/// A scenario: drive, load environment, initial position and default length.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Its name (one of [`SCENARIO_NAMES`]).
    pub name: String,
    /// How the valve is driven.
    pub drive: Drive,
    /// The spring in front of the rod (zero stiffness if unloaded).
    pub spring: SpringLoad,
    /// Rod position at t = 0, m.
    pub initial_position_m: f64,
    /// Default run length, s.
    pub default_seconds: f64,
    /// Default leak onset for demonstrations, s.
    pub default_onset_s: f64,
}

/// The scenario name is not one of [`SCENARIO_NAMES`].
#[derive(Debug, Clone, PartialEq)]
pub struct UnknownScenario(pub String);

impl std::fmt::Display for UnknownScenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "unknown scenario `{}`: expected one of {}",
            self.0,
            SCENARIO_NAMES.join(", ")
        )
    }
}

impl std::error::Error for UnknownScenario {}

fn random_levels(seed: u64, seconds: f64, lo_m: f64, hi_m: f64, hold: (f64, f64)) -> Vec<(f64, f64)> {
    let mut rng = Rng::new(seed ^ 0x5CE7_A210);
    let mut t = 0.0;
    let mut out = Vec::new();
    while t < seconds + 1.0 {
        out.push((t, rng.uniform_in(lo_m, hi_m)));
        t += if hold.0 == hold.1 {
            hold.0
        } else {
            rng.uniform_in(hold.0, hold.1)
        };
    }
    out
}

impl Scenario {
    /// Builds a named scenario; `seed` draws the levels of the random ones
    /// (generated for `max_seconds` of reference).
    pub fn by_name(name: &str, seed: u64, max_seconds: f64) -> Result<Scenario, UnknownScenario> {
        let unloaded = SpringLoad::default();
        let loaded = SpringLoad::thesis_simulation();
        let span = max_seconds.max(60.0);
        let (drive, spring, x0, secs, onset) = match name {
            "open-loop-sine" => (
                Drive::OpenLoopSine {
                    amplitude_v: 3.0,
                    freq_hz: 1.0,
                    phase_rad: 0.1,
                },
                unloaded,
                0.3,
                40.0,
                18.0,
            ),
            "open-loop-chirp" => (
                Drive::OpenLoopChirp { amplitude_v: 3.0 },
                unloaded,
                0.3,
                40.0,
                18.0,
            ),
            "closed-loop-sine" => (
                Drive::ClosedLoopSine {
                    offset_m: 0.3,
                    amplitude_m: 0.2,
                    period_s: 2.0,
                },
                unloaded,
                0.3,
                40.0,
                18.0,
            ),
            "closed-loop-random" => (
                Drive::ClosedLoopSteps {
                    levels: random_levels(seed, span, 0.05, 0.5, (2.0, 2.0)),
                },
                unloaded,
                0.3,
                40.0,
                18.0,
            ),
            "loaded-sine" => (
                Drive::ClosedLoopSine {
                    offset_m: 0.3,
                    amplitude_m: 0.2,
                    period_s: 10.0,
                },
                loaded,
                0.3,
                60.0,
                20.0,
            ),
            "loaded-random" => (
                Drive::ClosedLoopSteps {
                    levels: random_levels(seed, span, 0.1, 0.5, (0.2, 4.0)),
                },
                loaded,
                0.3,
                60.0,
                20.0,
            ),
            // Lift and lower: moves between random heights in 0.05-0.35 m (any rig
            // with a stroke of 0.4 m or more), each held 1.5-3 s; with a vertical
            // rig (`ActuatorParams::vertical_lift`) every rise lifts the load.
            "lift" => (
                Drive::ClosedLoopSteps {
                    levels: random_levels(seed, span, 0.05, 0.35, (1.5, 3.0)),
                },
                unloaded,
                0.2,
                60.0,
                20.0,
            ),
            // A press cycle (any rig with a stroke of 0.3 m or more): approach from
            // 0.05 to 0.195 m, press into a workpiece of 2e6 N/m touching at 0.20 m
            // to 0.202 m, hold, retract, dwell (scenario::duty).
            "press" => (
                Drive::ClosedLoopProfile {
                    moves: duty::press_moves(seed, span),
                    kp_v_per_m: KP_PROFILE_V_PER_M,
                },
                duty::press_workpiece(),
                duty::PRESS_HOME_M,
                60.0,
                20.0,
            ),
            // Point-to-point handling within 0.03-0.27 m (scenario::duty).
            "handling" => (
                Drive::ClosedLoopProfile {
                    moves: duty::handling_moves(seed, span),
                    kp_v_per_m: KP_PROFILE_V_PER_M,
                },
                unloaded,
                duty::HANDLING_START_M,
                60.0,
                20.0,
            ),
            other => return Err(UnknownScenario(other.to_string())),
        };
        Ok(Scenario {
            name: name.to_string(),
            drive,
            spring,
            initial_position_m: x0,
            default_seconds: secs,
            default_onset_s: onset,
        })
    }

    /// Whether the valve command comes from the position controller.
    pub fn is_closed_loop(&self) -> bool {
        matches!(
            self.drive,
            Drive::ClosedLoopSine { .. } | Drive::ClosedLoopSteps { .. } | Drive::ClosedLoopProfile { .. }
        )
    }

    /// The position reference at `t_s`, m (NaN in open loop).
    pub fn reference_m(&self, t_s: f64) -> f64 {
        match &self.drive {
            Drive::ClosedLoopSine {
                offset_m,
                amplitude_m,
                period_s,
            } => offset_m + amplitude_m * (2.0 * std::f64::consts::PI * t_s / period_s).sin(),
            Drive::ClosedLoopSteps { levels } => {
                let i = levels.partition_point(|(t0, _)| *t0 <= t_s);
                levels[i.saturating_sub(1)].1
            }
            Drive::ClosedLoopProfile { moves, .. } => duty::reference_of(moves, t_s),
            _ => f64::NAN,
        }
    }

    /// The valve command at `t_s` given the measured rod position `x_meas_m`, V
    /// (open loop: the scheduled input; closed loop: K_p·(r − x) saturated at ±10 V,
    /// K_p [`KP_V_PER_M`] or a profile's own).
    pub fn command_v(&self, t_s: f64, x_meas_m: f64) -> f64 {
        match &self.drive {
            Drive::OpenLoopSine {
                amplitude_v,
                freq_hz,
                phase_rad,
            } => amplitude_v * (2.0 * std::f64::consts::PI * freq_hz * t_s + phase_rad).sin(),
            Drive::OpenLoopChirp { amplitude_v } => {
                let t = t_s.rem_euclid(CHIRP_PERIOD_S);
                amplitude_v * (std::f64::consts::PI * (1.0 + t / 4.0) * t).sin()
            }
            Drive::ClosedLoopProfile { kp_v_per_m, .. } => {
                (kp_v_per_m * (self.reference_m(t_s) - x_meas_m)).clamp(-U_MAX_V, U_MAX_V)
            }
            _ => (KP_V_PER_M * (self.reference_m(t_s) - x_meas_m)).clamp(-U_MAX_V, U_MAX_V),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_inputs() {
        for n in SCENARIO_NAMES {
            let s = Scenario::by_name(n, 1, 60.0).unwrap();
            assert_eq!(s.name, n);
            let u = s.command_v(0.7, 0.3);
            assert!(u.abs() <= 10.0);
        }
        let e = Scenario::by_name("open-loop-square", 1, 60.0).unwrap_err();
        assert!(e.to_string().contains("open-loop-sine"));
        let s = Scenario::by_name("open-loop-sine", 0, 40.0).unwrap();
        assert!((s.command_v(0.25, 0.0) - 3.0 * (0.5f64 * std::f64::consts::PI + 0.1).sin()).abs() < 1e-12);
        let c = Scenario::by_name("closed-loop-sine", 0, 40.0).unwrap();
        assert!((c.command_v(0.5, 0.45) - 50.0 * (0.5 - 0.45)).abs() < 1e-9);
        assert_eq!(c.command_v(0.5, 0.0), 10.0);
    }

    #[test]
    fn random_levels_respect_ranges() {
        let s = Scenario::by_name("loaded-random", 3, 60.0).unwrap();
        if let Drive::ClosedLoopSteps { levels } = &s.drive {
            assert!(levels.len() > 15);
            for w in levels.windows(2) {
                let hold = w[1].0 - w[0].0;
                assert!((0.2..=4.0).contains(&hold));
            }
            assert!(levels.iter().all(|(_, l)| (0.1..0.5).contains(l)));
        } else {
            panic!("steps expected");
        }
        // same seed, same levels; other seed, other levels
        assert_eq!(s, Scenario::by_name("loaded-random", 3, 60.0).unwrap());
        assert_ne!(s, Scenario::by_name("loaded-random", 4, 60.0).unwrap());
    }
}
