//! Comparison by equation error over short re-anchored windows: every
//! equation of the model is checked on the *measured* signals, one window
//! (50 ms by default) at a time, so nothing is simulated freely and the
//! chaos of a stick-slipping rod cannot pile up.
//!
//! Per window `[a, b)` of the record, with measured x, p1, p2 (and the
//! measured spool when the log has it, else the model's spool driven by the
//! command):
//! - **chamber 1 / chamber 2**: the pressure change the continuity equation
//!   predicts from the valve flows, the piston's displacement and the leaks,
//!   Σ β_eff/V·(Q − leaks)·dt ∓ Σ β_eff/V·A·Δx, minus the measured change
//!   (Pa, normalised by `scale_p_pa`);
//! - **force**: the mean over the window of A1·p1 − A2·p2 − weight − friction − spring
//!   load, minus m·Δv/T (N, normalised by `scale_f_n`), with friction from the
//!   Karnopp law at the measured velocity (stuck samples balance the drive up
//!   to f_st);
//! - **spool** (when measured): the model's spool minus the measured spool at
//!   `SPOOL_POINTS` samples of the window (m, normalised by `scale_sp_m`).
//!
//! Each residual is a one-window prediction error started from the measured
//! state, so it depends on the effect's physics, not on the phase of the
//! stick-slip cycle.

use model::dynamics::{effective_bulk_modulus_pa, valve_flows, LeakSet};
use model::friction::friction_force_n;
use model::params::ActuatorParams;

use crate::shoot::{spool_trajectory, Prepared, ShootSettings};

/// A chamber within this of tank or supply pressure in a window is left out
/// of that window's continuity check, Pa.
pub const SATURATION_MARGIN_PA: f64 = 0.3e6;

/// Spool residuals per window (evenly spaced samples of the window).
pub const SPOOL_POINTS: usize = 5;

/// A measured velocity within this many σ of its noise
/// ([`ShootSettings::velocity_noise_m_s`]) is read as at rest by the force
/// balance: the friction then holds the drive up to static friction. Without
/// it a noisy sensor's rod at rest reads as sliding, its friction flipping
/// between ±static friction from sample to sample.
pub const STICK_BAND_SIGMAS: f64 = 3.0;

/// Residuals per window: chamber 1, chamber 2, force, then the spool points
/// when the spool is measured.
pub fn per_window(d: &Prepared) -> usize {
    3 + if d.has_spool() { SPOOL_POINTS } else { 0 }
}

/// Normalised equation-error residuals of `windows`, [`per_window`] per window.
pub fn residuals(
    p: &ActuatorParams,
    d: &Prepared,
    windows: &[(usize, usize)],
    set: &ShootSettings,
) -> Vec<f64> {
    let leaks = LeakSet::from_params(p);
    let model_spool = spool_trajectory(p, d, set.substeps);
    let measured_spool = d.has_spool();
    let spool_at = |i: usize| -> f64 {
        if measured_spool {
            d.x_sp_m[i]
        } else {
            model_spool[i][0]
        }
    };
    let dt = d.dt_s;
    let (a1, a2) = p.areas_m2();
    let gravity = p.gravity_force_n();
    let pr = p.return_pressure_pa;
    let per = per_window(d);
    let ps = p.supply_pressure_pa;
    let at_rest_m_s = STICK_BAND_SIGMAS * set.velocity_noise_m_s;
    let mut r = Vec::with_capacity(windows.len() * per);
    for &(a, b) in windows {
        // a chamber at tank or supply pressure: the orifice law is stiff
        // there (a few kPa of sensor noise are litres per minute of flow), so
        // its continuity says nothing; left out of this window
        let (mut lo1, mut hi1, mut lo2, mut hi2) =
            (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for i in a..=b {
            lo1 = lo1.min(d.p1_pa[i]);
            hi1 = hi1.max(d.p1_pa[i]);
            lo2 = lo2.min(d.p2_pa[i]);
            hi2 = hi2.max(d.p2_pa[i]);
        }
        let use1 = lo1 > pr + SATURATION_MARGIN_PA && hi1 < ps - SATURATION_MARGIN_PA;
        let use2 = lo2 > pr + SATURATION_MARGIN_PA && hi2 < ps - SATURATION_MARGIN_PA;
        let mut dp1 = 0.0;
        let mut dp2 = 0.0;
        let mut force = 0.0;
        for i in a..b {
            let (x, p1, p2, xsp) = (d.x_m[i], d.p1_pa[i], d.p2_pa[i], spool_at(i));
            // continuity over [i, i+1] (b < the record's length): flows at the midpoint
            {
                let j = i + 1;
                let xm = 0.5 * (x + d.x_m[j]);
                let p1m = 0.5 * (p1 + d.p1_pa[j]);
                let p2m = 0.5 * (p2 + d.p2_pa[j]);
                let sm = 0.5 * (xsp + spool_at(j));
                let vf = valve_flows(p, sm, p1m, p2m);
                let lq = leaks.flows(p1m, p2m, pr);
                let (v1, v2) = p.chamber_volumes_m3(xm);
                let k1 = effective_bulk_modulus_pa(p, p1m) / v1;
                let k2 = effective_bulk_modulus_pa(p, p2m) / v2;
                let dx = d.x_m[j] - x;
                dp1 += k1 * ((vf.q1_m3_s - lq.int_m3_s - lq.ext1_m3_s) * dt - a1 * dx);
                dp2 += k2 * ((-vf.q2_m3_s + lq.int_m3_s - lq.ext2_m3_s) * dt + a2 * dx);
            }
            let v = d.v_m_s[i];
            let load = p.load.force_n(x, v);
            let end_stop = model::dynamics::end_stop_force_n(p, x, v);
            let drive = p.pressure_force_n(p1, p2) - gravity - load + end_stop;
            let fr = friction_force_n(&p.friction, if v.abs() <= at_rest_m_s { 0.0 } else { v }, drive);
            force += drive - fr;
        }
        let n = (b - a) as f64;
        let span = n * dt;
        let e1 = dp1 - (d.p1_pa[b] - d.p1_pa[a]);
        let e2 = dp2 - (d.p2_pa[b] - d.p2_pa[a]);
        let dv = d.v_m_s[b] - d.v_m_s[a];
        let ef = force / n - p.mass_kg * dv / span;
        let mut push = |v: f64| r.push(if v.is_finite() { v } else { 1.0e6 });
        push(if use1 { e1 / set.scale_p_pa } else { 0.0 });
        push(if use2 { e2 / set.scale_p_pa } else { 0.0 });
        push(ef / set.scale_f_n);
        if measured_spool {
            // the spool points weigh as much as one channel together
            let w = 1.0 / (SPOOL_POINTS as f64).sqrt();
            for k in 0..SPOOL_POINTS {
                let i = a + (k * (b - a)) / SPOOL_POINTS;
                push(w * (model_spool[i][0] - d.x_sp_m[i]) / set.scale_sp_m);
            }
        }
    }
    r
}

/// Per-channel RMS in SI ([chamber 1 Pa, chamber 2 Pa, force N, spool m];
/// spool 0 when not measured) and the combined normalised RMS (every channel
/// weighs the same) of a residual vector from [`residuals`].
pub fn gap_of(r: &[f64], d: &Prepared, set: &ShootSettings) -> ([f64; 4], f64) {
    let per = per_window(d);
    let channels = if d.has_spool() { 4 } else { 3 };
    let mut ss = [0.0; 4];
    let mut windows = 0usize;
    for c in r.chunks_exact(per) {
        windows += 1;
        for (k, v) in c.iter().enumerate() {
            ss[k.min(3)] += v * v;
        }
    }
    let nw = windows.max(1) as f64;
    let rms = |k: usize| (ss[k] / nw).sqrt();
    let all = (ss.iter().sum::<f64>() / (nw * channels as f64)).sqrt();
    (
        [
            rms(0) * set.scale_p_pa,
            rms(1) * set.scale_p_pa,
            rms(2) * set.scale_f_n,
            rms(3) * set.scale_sp_m,
        ],
        all,
    )
}
