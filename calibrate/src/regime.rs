//! Localising the disagreement: residuals broken down by regime (direction
//! of motion, spool sign, stroke position, pressure level, frequency band,
//! time).

use model::params::ActuatorParams;
use serde::{Deserialize, Serialize};

use crate::shoot::{simulate_window, spool_trajectory, Prepared, ShootSettings};

/// The residual statistics of one bin of one regime.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegimeBin {
    /// The regime family: `direction`, `spool`, `position`, `pressure`, `band`, `time`.
    pub regime: String,
    /// The bin, e.g. `extending`, `x 0.10..0.20 m`.
    pub bin: String,
    /// Centre of the bin on its own axis (m/s, m, Pa, s; NaN when categorical).
    pub centre: f64,
    /// Samples in the bin.
    pub count: usize,
    /// Mean residual (model − measured) of x (m), p1 (Pa), p2 (Pa).
    pub mean: [f64; 3],
    /// RMS residual of x (m), p1 (Pa), p2 (Pa).
    pub rms: [f64; 3],
}

#[derive(Default, Clone, Copy)]
struct Acc {
    n: usize,
    s: [f64; 3],
    ss: [f64; 3],
}

impl Acc {
    fn add(&mut self, r: [f64; 3]) {
        self.n += 1;
        for ((s, ss), v) in self.s.iter_mut().zip(self.ss.iter_mut()).zip(r) {
            *s += v;
            *ss += v * v;
        }
    }
    fn bin(&self, regime: &str, bin: String, centre: f64) -> RegimeBin {
        let n = self.n.max(1) as f64;
        RegimeBin {
            regime: regime.to_string(),
            bin,
            centre,
            count: self.n,
            mean: [self.s[0] / n, self.s[1] / n, self.s[2] / n],
            rms: [
                (self.ss[0] / n).sqrt(),
                (self.ss[1] / n).sqrt(),
                (self.ss[2] / n).sqrt(),
            ],
        }
    }
}

/// Speed below which the rod counts as at rest in the breakdown, m/s.
pub const REST_SPEED_M_S: f64 = 0.005;
/// Number of stroke-position bins.
pub const POSITION_BINS: usize = 6;
/// Number of velocity bins (for the velocity plot).
pub const VELOCITY_BINS: usize = 8;

/// Re-anchored simulation of `windows` (x, p1, p2 per sample) and the
/// sample indices, every sample.
pub fn traces(
    p: &ActuatorParams,
    d: &Prepared,
    windows: &[(usize, usize)],
    set: &ShootSettings,
) -> Vec<(usize, [f64; 3])> {
    let leaks = model::dynamics::LeakSet::from_params(p);
    let spool = spool_trajectory(p, d, set.substeps);
    let mut out = Vec::new();
    for &w in windows {
        let sim = simulate_window(p, &leaks, d, &spool, w, set.substeps);
        for (k, y) in sim.into_iter().enumerate() {
            out.push((w.0 + k, y));
        }
    }
    out
}

/// The regime breakdown of the residuals of model `p` on `windows`.
pub fn breakdown(
    p: &ActuatorParams,
    d: &Prepared,
    windows: &[(usize, usize)],
    set: &ShootSettings,
) -> Vec<RegimeBin> {
    let tr = traces(p, d, windows, set);
    let spool = spool_trajectory(p, d, set.substeps);
    if tr.is_empty() {
        return Vec::new();
    }
    let res: Vec<(usize, [f64; 3])> = tr
        .iter()
        .map(|(i, y)| (*i, [y[0] - d.x_m[*i], y[1] - d.p1_pa[*i], y[2] - d.p2_pa[*i]]))
        .collect();
    let mut out = Vec::new();

    // direction of motion
    let mut dir = [Acc::default(); 3];
    // spool sign
    let mut sp = [Acc::default(); 2];
    for (i, r) in &res {
        let v = d.v_m_s[*i];
        let k = if v > REST_SPEED_M_S {
            0
        } else if v < -REST_SPEED_M_S {
            1
        } else {
            2
        };
        dir[k].add(*r);
        sp[usize::from(spool[*i][0] < 0.0)].add(*r);
    }
    for (k, name) in ["extending", "retracting", "at rest"].iter().enumerate() {
        out.push(dir[k].bin("direction", name.to_string(), f64::NAN));
    }
    for (k, name) in [
        "spool >= 0 (supply to chamber 1)",
        "spool < 0 (supply to chamber 2)",
    ]
    .iter()
    .enumerate()
    {
        out.push(sp[k].bin("spool", name.to_string(), f64::NAN));
    }

    // stroke position bins over the measured range
    let (lo, hi) = d.x_range_m();
    let span = (hi - lo).max(1e-6);
    let mut pos = [Acc::default(); POSITION_BINS];
    for (i, r) in &res {
        let b = (((d.x_m[*i] - lo) / span * POSITION_BINS as f64) as usize).min(POSITION_BINS - 1);
        pos[b].add(*r);
    }
    for (b, acc) in pos.iter().enumerate() {
        let a = lo + span * b as f64 / POSITION_BINS as f64;
        let z = lo + span * (b + 1) as f64 / POSITION_BINS as f64;
        out.push(acc.bin("position", format!("x {a:.3}..{z:.3} m"), 0.5 * (a + z)));
    }

    // velocity bins (symmetric range)
    let vmax = res
        .iter()
        .map(|(i, _)| d.v_m_s[*i].abs())
        .fold(0.0, f64::max)
        .max(1e-3);
    let mut vel = [Acc::default(); VELOCITY_BINS];
    for (i, r) in &res {
        let f = (d.v_m_s[*i] + vmax) / (2.0 * vmax);
        let b = ((f * VELOCITY_BINS as f64) as usize).min(VELOCITY_BINS - 1);
        vel[b].add(*r);
    }
    for (b, acc) in vel.iter().enumerate() {
        let a = -vmax + 2.0 * vmax * b as f64 / VELOCITY_BINS as f64;
        let z = -vmax + 2.0 * vmax * (b + 1) as f64 / VELOCITY_BINS as f64;
        out.push(acc.bin("velocity", format!("v {a:.3}..{z:.3} m/s"), 0.5 * (a + z)));
    }

    // pressure level: mean chamber pressure in thirds of the supply
    let ps = p.supply_pressure_pa;
    let mut pr = [Acc::default(); 3];
    for (i, r) in &res {
        let pm = 0.5 * (d.p1_pa[*i] + d.p2_pa[*i]);
        let b = ((pm / ps * 3.0).max(0.0) as usize).min(2);
        pr[b].add(*r);
    }
    for (b, acc) in pr.iter().enumerate() {
        let a = ps * b as f64 / 3.0;
        let z = ps * (b + 1) as f64 / 3.0;
        out.push(acc.bin(
            "pressure",
            format!("mean p {:.1}..{:.1} MPa", a / 1e6, z / 1e6),
            0.5 * (a + z),
        ));
    }

    // frequency band: slow part (50 ms moving average within a window) vs the rest
    let mut slow = Acc::default();
    let mut fast = Acc::default();
    let mut start = 0;
    while start < res.len() {
        let mut end = start + 1;
        while end < res.len() && res[end].0 == res[end - 1].0 + 1 {
            end += 1;
        }
        let seg = &res[start..end];
        let half = (0.025 / d.dt_s).round().max(1.0) as usize;
        for k in 0..seg.len() {
            let a = k.saturating_sub(half);
            let z = (k + half + 1).min(seg.len());
            let mut m = [0.0; 3];
            for (_, r) in &seg[a..z] {
                for c in 0..3 {
                    m[c] += r[c];
                }
            }
            let nn = (z - a) as f64;
            let m = [m[0] / nn, m[1] / nn, m[2] / nn];
            slow.add(m);
            let r = seg[k].1;
            fast.add([r[0] - m[0], r[1] - m[1], r[2] - m[2]]);
        }
        start = end;
    }
    out.push(slow.bin("band", "below ~20 Hz".to_string(), f64::NAN));
    out.push(fast.bin("band", "above ~20 Hz".to_string(), f64::NAN));

    // time: quarters of the span covered
    let t0 = d.t_s[res[0].0];
    let t1 = d.t_s[res[res.len() - 1].0];
    let tspan = (t1 - t0).max(1e-9);
    let mut tq = [Acc::default(); 4];
    for (i, r) in &res {
        let b = (((d.t_s[*i] - t0) / tspan * 4.0) as usize).min(3);
        tq[b].add(*r);
    }
    for (b, acc) in tq.iter().enumerate() {
        let a = t0 + tspan * b as f64 / 4.0;
        let z = t0 + tspan * (b + 1) as f64 / 4.0;
        out.push(acc.bin("time", format!("t {a:.1}..{z:.1} s"), 0.5 * (a + z)));
    }
    out
}
