//! When a leak's real flow, never shown to the detector, reached the
//! detector's floors and stayed there for its confirmation time
//! ([`FloorClock`]); read from a recording's `q_leak` column or from a run's
//! true flows per sample (`truth_flow.csv[.gz]` beside `measured.csv[.gz]`:
//! `t,q_e1,q_e2,q_i`, s and L/min).
//!
//! A leak's flow follows its pressure drop. A ramping leak passes its floor
//! part-way up the ramp. An internal leak that opens across a resting rod
//! passes a few milliseconds of flow while it equalises the chambers, then
//! almost nothing until the rod moves: that blip is not a leak anyone could
//! declare, so the flow must hold.

use std::io::BufRead;
use std::path::{Path, PathBuf};

/// The truth-flow file of run folder `dir`, if it has one.
pub fn file(dir: &Path) -> Option<PathBuf> {
    ["truth_flow.csv.gz", "truth_flow.csv"]
        .iter()
        .map(|n| dir.join(n))
        .find(|p| p.is_file())
}

/// The first times a flow reached each of two floors and then held at or
/// above it for `hold_s` (s): the detector's floors for an external and for
/// an internal leak, held for its confirmation time.
#[derive(Debug, Clone, Copy)]
pub struct FloorClock {
    floors_lpm: [f64; 2],
    hold_s: f64,
    since_s: [f64; 2],
    reached_s: [f64; 2],
}

impl FloorClock {
    /// A clock for `floors_lpm` (L/min) held for `hold_s` (s).
    pub fn new(floors_lpm: [f64; 2], hold_s: f64) -> Self {
        FloorClock {
            floors_lpm,
            hold_s,
            since_s: [f64::NAN; 2],
            reached_s: [f64::NAN; 2],
        }
    }

    /// Takes the flow (L/min, either sign) at time `t_s` (s); a flow that is
    /// not a number (none logged) is no reading.
    pub fn push(&mut self, t_s: f64, flow_lpm: f64) {
        if !flow_lpm.is_finite() {
            return;
        }
        for i in 0..2 {
            if !self.reached_s[i].is_nan() {
                continue;
            }
            if flow_lpm.abs() < self.floors_lpm[i] {
                self.since_s[i] = f64::NAN;
                continue;
            }
            if self.since_s[i].is_nan() {
                self.since_s[i] = t_s;
            }
            if t_s - self.since_s[i] >= self.hold_s {
                self.reached_s[i] = self.since_s[i];
            }
        }
    }

    /// When each floor was reached to hold, s (NaN if it never was).
    pub fn reached_s(&self) -> [f64; 2] {
        self.reached_s
    }
}

/// A run's true leak flow per sample: the largest of the three (one leak per
/// run), its magnitude.
#[derive(Debug, Clone, Default)]
pub struct TrueFlows {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// The leak's true flow, L/min (magnitude).
    pub flow_lpm: Vec<f64>,
}

impl TrueFlows {
    /// Reads `t,q_e1,q_e2,q_i` (s, L/min) from `path` (plain or gzip).
    pub fn read(path: &Path) -> Result<TrueFlows, String> {
        let at = |line: usize, what: &str| format!("{}: line {line}: {what}", path.display());
        let reader = dataset::open_text(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let mut lines = reader.lines();
        let header = match lines.next() {
            Some(h) => h.map_err(|e| at(1, &e.to_string()))?,
            None => return Err(at(1, "empty file, expected the header `t,q_e1,q_e2,q_i`")),
        };
        let names: Vec<&str> = header.trim().split(',').map(str::trim).collect();
        let column = |name: &str| {
            names
                .iter()
                .position(|n| *n == name)
                .ok_or_else(|| at(1, &format!("no column `{name}` (header: `{}`)", header.trim())))
        };
        let t_col = column("t")?;
        let q_cols = [column("q_e1")?, column("q_e2")?, column("q_i")?];
        let mut flows = TrueFlows::default();
        for (i, line) in lines.enumerate() {
            let line = line.map_err(|e| at(i + 2, &e.to_string()))?;
            let cells: Vec<&str> = line.split(',').collect();
            let cell = |c: usize| -> Result<f64, String> {
                cells
                    .get(c)
                    .and_then(|v| v.trim().parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| at(i + 2, &format!("column {} is not a number", c + 1)))
            };
            let mut flow: f64 = 0.0;
            for c in q_cols {
                flow = flow.max(cell(c)?.abs());
            }
            flows.t_s.push(cell(t_col)?);
            flows.flow_lpm.push(flow);
        }
        Ok(flows)
    }

    /// [`FloorClock::reached_s`] over these flows from `t_on_s` (s) on.
    pub fn floor_times(&self, t_on_s: f64, mut clock: FloorClock) -> [f64; 2] {
        for (&t, &q) in self.t_s.iter().zip(&self.flow_lpm) {
            if t >= t_on_s {
                clock.push(t, q);
            }
        }
        clock.reached_s()
    }

    /// What the detector's size at `t_end_s` (s) stands for, L/min: its
    /// coefficient now times the exponential mean of √Δp with time constant
    /// `tau_s` (s). For the truth that is the flow's exponential mean with
    /// each sample scaled to the leak's opening now: a leak that opens at
    /// `t_on_s` (s) over `ramp_s` (s) passed q(t)·o(t_end)/o(t) at o(t_end).
    /// Samples where it was under 5 % open do not count. NaN before any.
    pub fn mean_lpm(&self, t_end_s: f64, tau_s: f64, t_on_s: f64, ramp_s: f64) -> f64 {
        let opening = |t: f64| {
            if ramp_s > 0.0 {
                ((t - t_on_s) / ramp_s).clamp(0.0, 1.0)
            } else if t >= t_on_s {
                1.0
            } else {
                0.0
            }
        };
        let (now, from) = (opening(t_end_s), t_end_s - 10.0 * tau_s);
        let (mut mean, mut last_t) = (f64::NAN, f64::NAN);
        for (&t, &q) in self.t_s.iter().zip(&self.flow_lpm) {
            if t > t_end_s {
                break;
            }
            let o = opening(t);
            if t < from || o < 0.05 {
                continue;
            }
            let q = q * now / o;
            mean = if mean.is_nan() {
                q
            } else {
                let a = ((t - last_t) / tau_s.max(1e-3)).clamp(0.0, 1.0);
                mean + a * (q - mean)
            };
            last_t = t;
        }
        mean
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floors_are_reached_where_the_true_flow_gets_there_and_holds() {
        let dir = scratch::ScratchDir::new("truth_flow");
        let p = dir.path().join("truth_flow.csv");
        let rows = "t,q_e1,q_e2,q_i\n0.0,0,0,0.05\n1.0,0,0,0.5\n1.1,0,0,-0.01\n1.5,0,0,-0.035\n\
                    2.0,0,0,-0.046\n2.2,0,0,-0.05\n2.4,0,0,0.2\n3.0,0,0,0.2\n";
        std::fs::write(&p, rows).unwrap();
        let flows = TrueFlows::read(&p).unwrap();
        let t = flows.floor_times(1.0, FloorClock::new([0.03, 0.04], 0.2));
        assert_eq!(
            t,
            [1.5, 2.0],
            "before the onset a flow does not count, nor a blip that does not hold"
        );
        let never = flows.floor_times(1.0, FloorClock::new([0.03, 0.5], 0.2));
        assert!(never[1].is_nan());
        let mut unlogged = FloorClock::new([0.03, 0.04], 0.2);
        for i in 0..1000 {
            unlogged.push(f64::from(i) * 1e-3, f64::NAN);
        }
        assert!(
            unlogged.reached_s().iter().all(|t| t.is_nan()),
            "no flow logged is no flow reached"
        );
        assert_eq!(file(dir.path()), Some(p));
    }

    #[test]
    fn the_mean_is_the_flow_the_detector_s_size_stands_for() {
        // a leak ramping in over 4 s from 10 s to 0.3 L/min; its flow swings
        // ±50 % with the pressure drop at 10 Hz
        let t_s: Vec<f64> = (0..20_000).map(|i| f64::from(i) * 1e-3).collect();
        let flow_lpm = t_s
            .iter()
            .map(|&t| {
                let open = ((t - 10.0) / 4.0).clamp(0.0, 1.0);
                0.3 * open * (1.0 + 0.5 * (10.0 * std::f64::consts::TAU * t).sin())
            })
            .collect();
        let flows = TrueFlows { t_s, flow_lpm };
        let at = |t: f64| flows.mean_lpm(t, 2.0, 10.0, 4.0);
        // half open: what it passes at half its size, the swing averaged out
        assert!((at(12.0) - 0.15).abs() < 0.01, "{}", at(12.0));
        assert!((at(19.0) - 0.3).abs() < 0.01, "{}", at(19.0));
        assert!(at(10.1).is_nan(), "under 5 % open nothing counts");
    }

    #[test]
    fn a_malformed_file_names_its_line_and_column() {
        let dir = scratch::ScratchDir::new("truth_flow_bad");
        let p = dir.path().join("truth_flow.csv");
        std::fs::write(&p, "t,q_e1,q_e2\n0,0,0\n").unwrap();
        let e = TrueFlows::read(&p).unwrap_err();
        assert!(e.contains("line 1") && e.contains("q_i"), "{e}");
        std::fs::write(&p, "t,q_e1,q_e2,q_i\n0,0,x,0\n").unwrap();
        let e = TrueFlows::read(&p).unwrap_err();
        assert!(e.contains("line 2") && e.contains("column 3"), "{e}");
    }
}
