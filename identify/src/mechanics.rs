//! The rod's force balance: moving mass, friction (Coulomb, Stribeck, viscous)
//! and a constant load, from a healthy recording (docs/plant.md,
//! "Identification").
//!
//! At every used sample (the rod sliding, away from the end stops):
//!
//! A1·p1 − A2·p2 − F_l = m·a + F_c·sgn v + ΔF·e^(−|v|/α)·sgn v + d·v + F_s + k·max(0, x − x_c)
//!
//! v and a come from a centred quadratic fit (Savitzky-Golay) over
//! [`HALF_WINDOW`] samples either side of the measured position, the pressures
//! from the same fit's centre value. The equation is linear in m, F_c, ΔF, d
//! and F_s for a given Stribeck velocity α: α is the one of a log grid with the
//! least squared error. Outliers (a stop, a burst) are weighted down (Huber,
//! three passes).
//!
//! A workpiece: where the model has no load of its own, a contact spring
//! k·max(0, x − x_c) is a sixth column, x_c the best of a grid over the
//! stroke. It is kept when it removes 15 % or more of the force gap and k is
//! resolved (5 σ). Without it, a press's contact force is taken for static
//! friction (a slow press-in looks like a Stribeck peak). The model's own load
//! is taken off the pressure force.
//!
//! F_s is the static force: the weight m·g·sin φ plus any constant load. The
//! weight's column (g·sin φ, constant) cannot be told from a constant load's,
//! so the mass comes from the accelerations alone.
//!
//! A sample is used only while the velocity keeps its sign over the fit's
//! window (|a|·half window < |v|/2): friction jumps at a reversal or a start,
//! and a fit across the jump smears it into the mass and the viscous term.
//!
//! The mass is only as good as the model of the fast dynamics (hydraulic
//! resonance, transducer lag and ripple are not in the force balance; over
//! ±10 ms the plant rigs' masses come out 1.5-2x too large): the fit is
//! repeated over ±20 ms, and a mass that moves by more than 10 % is not
//! identified.
//!
//! What the data cannot separate:
//! - a constant load and an asymmetry of the Coulomb friction (one fit
//!   per direction would have three unknowns for two levels): the Coulomb
//!   friction is fitted symmetric and F_0 takes the rest;
//! - the viscous coefficient and the hoses' line drop when the transducers sit
//!   at the valve manifold (the drop is proportional to the flow, so to v): d
//!   is the apparent one, the one the filter sees.

use crate::{Estimate, Found, Row};
use model::ActuatorParams;
use nalgebra::{SMatrix, SVector};

/// Samples either side of the centre of the quadratic fit for v and a (±30 ms
/// at 1 kHz): long enough that the rig's fast dynamics (hydraulic resonance,
/// transducer lag, pump ripple) average out.
pub const HALF_WINDOW: usize = 30;
/// The check fit (±20 ms) whose mass must agree with the main one's.
const CHECK_HALF_WINDOW: usize = 20;
/// Largest relative disagreement of the two fits' masses that counts as identified (1).
const MASS_AGREEMENT: f64 = 0.1;
/// A sample is used while the rod slides faster than this, m/s.
pub const SLIDING_M_S: f64 = 2.0e-3;
/// Samples closer than this to an end of the stroke are not used, m.
const STOP_MARGIN_M: f64 = 2.0e-3;
/// Every this many samples one equation (the fits overlap; more adds no information).
const STRIDE: usize = 5;
/// Fewest equations (sliding samples) a fit needs.
pub const MIN_EQUATIONS: usize = 2_000;
/// The Stribeck velocities tried, m/s (log grid).
const ALPHA_GRID: (f64, f64, usize) = (1.0e-3, 0.2, 40);
/// Huber's constant, in robust standard deviations.
const HUBER_K: f64 = 2.5;

/// Contact positions tried for a workpiece spring, evenly over the stroke.
const CONTACT_GRID: usize = 24;
/// Share of the force gap a contact spring must remove to be kept (1).
const CONTACT_GAIN: f64 = 0.15;

/// Unknowns: m, F_c, ΔF, d, F_s and a contact spring's stiffness k.
const N: usize = 6;
type Mat = SMatrix<f64, N, N>;
type Vec5 = SVector<f64, N>;

/// The rod's mechanics identified on one recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Mechanics {
    /// Moving mass, kg.
    pub mass_kg: Found,
    /// Coulomb (slip) friction f_sl, N (both directions).
    pub coulomb_n: Found,
    /// Static friction f_st = f_sl + ΔF, N.
    pub static_n: Found,
    /// Stribeck velocity α, m/s (the grid point; σ not given: 0).
    pub stribeck_velocity_m_s: Found,
    /// Apparent viscous coefficient d, N·s/m (see the module docs).
    pub viscous_n_s_per_m: Found,
    /// Static force F_s: the weight plus any constant load (positive against extension), N.
    pub static_force_n: Found,
    /// A workpiece: a contact spring's stiffness (N/m, with its σ) and where
    /// the rod touches it (m, a grid point of the stroke); `None` when none
    /// explains enough of the force gap or the model has a load of its own.
    pub contact_spring: Option<(Estimate, f64)>,
    /// The mass of the check fit (±80 ms), kg (see the module docs).
    pub check_fit_mass_kg: f64,
    /// Equations used (sliding samples, one per [`STRIDE`]).
    pub equations: usize,
    /// RMS force error with the model's mass and friction, N.
    pub gap_before_n: f64,
    /// The same with the identified ones, N.
    pub gap_after_n: f64,
}

/// One equation: the regressors and the pressure force (less the model's own load).
struct Eq {
    x: f64,
    a: f64,
    v: f64,
    force: f64,
}

/// Quadratic-fit weights over ±`half` samples for the centre value, the first and the second derivative (per sample²).
fn savitzky_golay(half: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let h = half as i64;
    let n = (2 * half + 1) as f64;
    let s2: f64 = (-h..=h).map(|i| (i * i) as f64).sum();
    let c = s2 / n;
    let s4c: f64 = (-h..=h).map(|i| ((i * i) as f64 - c).powi(2)).sum();
    let s4: f64 = (-h..=h).map(|i| ((i * i) as f64).powi(2)).sum();
    let mut w0 = vec![0.0; 2 * half + 1];
    let mut w1 = vec![0.0; 2 * half + 1];
    let mut w2 = vec![0.0; 2 * half + 1];
    for (j, i) in (-h..=h).enumerate() {
        let i2 = (i * i) as f64;
        // centre of the least-squares quadratic: (S4 − S2·i²)/(n·S4 − S2²)
        w0[j] = (s4 - s2 * i2) / (n * s4 - s2 * s2);
        w1[j] = i as f64 / s2;
        w2[j] = 2.0 * (i2 - c) / s4c;
    }
    (w0, w1, w2)
}

/// The equations of `rows` (sample period `dt_s`, s) under the model `p`.
fn equations(p: &ActuatorParams, dt_s: f64, rows: &[Row], half: usize) -> Vec<Eq> {
    let (w0, w1, w2) = savitzky_golay(half);
    let mut out = Vec::new();
    let mut i = half;
    while i + half < rows.len() {
        let win = &rows[i - half..=i + half];
        let clean = win[1..].iter().all(|r| !r.after_gap)
            && win.iter().all(|r| {
                let s = &r.sample;
                s.x_m.is_finite() && s.p1_pa.is_finite() && s.p2_pa.is_finite()
            });
        if clean {
            let (mut x, mut v, mut a, mut p1, mut p2) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for (j, r) in win.iter().enumerate() {
                x += w0[j] * r.sample.x_m;
                v += w1[j] * r.sample.x_m;
                a += w2[j] * r.sample.x_m;
                p1 += w0[j] * r.sample.p1_pa;
                p2 += w0[j] * r.sample.p2_pa;
            }
            let (v, a) = (v / dt_s, a / (dt_s * dt_s));
            let in_stroke = x > p.x_min_m + STOP_MARGIN_M && x < p.x_max_m - STOP_MARGIN_M;
            let steady_sign = a.abs() * half as f64 * dt_s < 0.5 * v.abs();
            if v.abs() > SLIDING_M_S && in_stroke && steady_sign {
                out.push(Eq {
                    x,
                    a,
                    v,
                    force: p.pressure_force_n(p1, p2) - p.load.force_n(x, v),
                });
            }
        }
        i += STRIDE;
    }
    out
}

/// The regressors of `e` for Stribeck velocity `alpha` and a contact spring
/// touching at `contact_m` (m; `None`: no spring, its column 0).
fn regressors(e: &Eq, alpha: f64, contact_m: Option<f64>) -> Vec5 {
    let s = e.v.signum();
    let spring = contact_m.map_or(0.0, |c| (e.x - c).max(0.0));
    Vec5::from([e.a, s, (-e.v.abs() / alpha).exp() * s, e.v, 1.0, spring])
}

/// Weighted least squares for Stribeck velocity `alpha` with weights `w` and
/// a contact spring at `contact_m` (without one, its stiffness is held at 0 by
/// a unit prior on its empty column): (θ, covariance with unit residual
/// variance, weighted SSR).
fn solve(eqs: &[Eq], alpha: f64, contact_m: Option<f64>, w: &[f64]) -> Option<(Vec5, Mat, f64)> {
    let mut ata = Mat::zeros();
    let mut aty = Vec5::zeros();
    for (e, wi) in eqs.iter().zip(w) {
        let r = regressors(e, alpha, contact_m);
        ata += *wi * r * r.transpose();
        aty += *wi * e.force * r;
    }
    if contact_m.is_none() {
        ata[(N - 1, N - 1)] += 1.0;
    }
    let inv = ata.try_inverse()?;
    let theta = inv * aty;
    let ssr: f64 = eqs
        .iter()
        .zip(w)
        .map(|(e, wi)| wi * (e.force - regressors(e, alpha, contact_m).dot(&theta)).powi(2))
        .sum();
    Some((theta, inv, ssr))
}

/// Huber weights for the residuals of `theta` (scale: 1.4826 × their median absolute value).
fn huber(eqs: &[Eq], alpha: f64, contact_m: Option<f64>, theta: &Vec5) -> Vec<f64> {
    let res: Vec<f64> = eqs
        .iter()
        .map(|e| e.force - regressors(e, alpha, contact_m).dot(theta))
        .collect();
    let mut abs: Vec<f64> = res.iter().map(|r| r.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let scale = (1.4826 * abs[abs.len() / 2]).max(1e-9);
    res.iter()
        .map(|r| {
            let z = r.abs() / scale;
            if z <= HUBER_K {
                1.0
            } else {
                HUBER_K / z
            }
        })
        .collect()
}

/// The best Stribeck velocity of the grid for weights `w`, with its fit.
fn best_alpha(eqs: &[Eq], contact_m: Option<f64>, w: &[f64]) -> Option<(f64, Vec5, Mat, f64)> {
    let (lo, hi, n) = ALPHA_GRID;
    (0..n)
        .filter_map(|k| {
            let alpha = lo * (hi / lo).powf(k as f64 / (n - 1) as f64);
            solve(eqs, alpha, contact_m, w).map(|(t, c, s)| (alpha, t, c, s))
        })
        .min_by(|a, b| a.3.total_cmp(&b.3))
}

/// Identifies the rod's mass, friction and constant load on `rows` (a healthy
/// recording at sample period `dt_s`, s) against the model `p`; see the module docs.
pub fn identify_mechanics(p: &ActuatorParams, dt_s: f64, rows: &[Row]) -> Result<Mechanics, String> {
    if dt_s.is_nan() || dt_s <= 0.0 {
        return Err(format!("sample period {dt_s} s: must be positive"));
    }
    let eqs = equations(p, dt_s, rows, HALF_WINDOW);
    if eqs.len() < MIN_EQUATIONS {
        return Err(format!(
            "the rod slid (faster than {} mm/s, away from the stops) at {} samples, {MIN_EQUATIONS} needed: record the rig's duty cycle, not a hold",
            SLIDING_M_S * 1e3,
            eqs.len() * STRIDE
        ));
    }
    let f = p.friction.extend();
    let model = Vec5::from([
        p.mass_kg,
        f.slip_n,
        f.static_n - f.slip_n,
        f.viscous_n_s_per_m,
        p.gravity_force_n(),
        0.0,
    ]);
    let gap_before_n = rms_of(&eqs, &model, f.stribeck_velocity_m_s, None);
    let fail = || "the force balance could not be solved (the rod's motion does not excite it)".to_string();
    // a workpiece's spring is searched for only where the model has no load of its own
    let stroke = (p.load.stiffness_n_per_m == 0.0).then_some((p.x_min_m, p.x_max_m));
    let ((alpha, theta, cov, ssr, w), contact_m) = fit_with_contact(&eqs, stroke).ok_or_else(fail)?;
    let check = robust_fit(&equations(p, dt_s, rows, CHECK_HALF_WINDOW), contact_m).ok_or_else(fail)?;
    let check_mass = check.1[0];
    let sw: f64 = w.iter().sum();
    let var = ssr / (sw - N as f64).max(1.0);
    let est = |k: usize| Estimate {
        value: theta[k],
        sigma: (cov[(k, k)] * var).sqrt(),
    };
    let positive = |e: Estimate, what: &str| {
        if e.value > 0.0 && e.sigma < 0.2 * e.value {
            Found::Identified(e)
        } else {
            Found::NotIdentifiable(format!(
                "{what} came out {:.4e} ± {:.1e}: not resolved (the duty cycle does not separate it)",
                e.value, e.sigma
            ))
        }
    };
    let mass = est(0);
    let mass_kg = if (check_mass - mass.value).abs() > MASS_AGREEMENT * mass.value {
        Found::NotIdentifiable(format!(
            "the moving mass came out {:.1} kg over ±{HALF_WINDOW} ms and {check_mass:.1} kg over ±{CHECK_HALF_WINDOW} ms: the rig's fast dynamics are not in the force balance",
            mass.value
        ))
    } else if mass.value > 0.5 * p.mass_kg && mass.value < 2.0 * p.mass_kg && mass.sigma < 0.1 * mass.value {
        Found::Identified(mass)
    } else {
        Found::NotIdentifiable(format!(
            "the moving mass came out {:.1} ± {:.1} kg (the model's {:.1} kg): the rod accelerates too little, or the mass is far from the datasheet's",
            mass.value, mass.sigma, p.mass_kg
        ))
    };
    let coulomb = est(1);
    let delta = est(2);
    let static_n = if delta.value >= 0.0 {
        positive(
            Estimate {
                value: coulomb.value + delta.value,
                sigma: (cov[(1, 1)] + cov[(2, 2)] + 2.0 * cov[(1, 2)]).max(0.0).sqrt() * var.sqrt(),
            },
            "the static friction",
        )
    } else {
        Found::NotIdentifiable(format!(
            "the friction rises with speed at low speed ({:.0} N): no Stribeck drop to fit",
            delta.value
        ))
    };
    let stribeck_velocity_m_s = match static_n {
        Found::Identified(_) => Found::Identified(Estimate {
            value: alpha,
            sigma: 0.0,
        }),
        _ => Found::NotIdentifiable("without a Stribeck drop there is no Stribeck velocity".to_string()),
    };
    let contact_spring = match contact_m {
        Some(c) => Found::Identified(est(N - 1)).estimate().map(|k| (k, c)),
        None => None,
    };
    Ok(Mechanics {
        contact_spring,
        mass_kg,
        coulomb_n: positive(coulomb, "the Coulomb friction"),
        static_n,
        stribeck_velocity_m_s,
        viscous_n_s_per_m: positive(est(3), "the viscous friction"),
        static_force_n: Found::Identified(est(4)),
        check_fit_mass_kg: check_mass,
        equations: eqs.len(),
        gap_before_n,
        gap_after_n: rms_of(&eqs, &theta, alpha, contact_m),
    })
}

/// The fit with the best Stribeck velocity, reweighted three times (Huber):
/// (α, θ, covariance, SSR, weights).
fn robust_fit(eqs: &[Eq], contact_m: Option<f64>) -> Option<RobustFit> {
    let mut w = vec![1.0; eqs.len()];
    let mut fit = best_alpha(eqs, contact_m, &w)?;
    for _ in 0..3 {
        w = huber(eqs, fit.0, contact_m, &fit.1);
        fit = best_alpha(eqs, contact_m, &w)?;
    }
    Some((fit.0, fit.1, fit.2, fit.3, w))
}

/// The RMS force error of `theta` at Stribeck velocity `alpha` and contact
/// `contact_m` over `eqs`, N (every equation counted alike).
fn rms_of(eqs: &[Eq], theta: &Vec5, alpha: f64, contact_m: Option<f64>) -> f64 {
    (eqs.iter()
        .map(|e| (e.force - regressors(e, alpha, contact_m).dot(theta)).powi(2))
        .sum::<f64>()
        / eqs.len().max(1) as f64)
        .sqrt()
}

/// A robust fit: (α, θ, covariance, SSR, weights).
type RobustFit = (f64, Vec5, Mat, f64, Vec<f64>);

/// The fit of [`robust_fit`], with a contact spring (a workpiece) where one
/// explains [`CONTACT_GAIN`] or more of the force gap and its stiffness is
/// resolved (5 σ): the contact the one of [`CONTACT_GRID`] positions over the
/// stroke `x_range_m` (m) with the least error; `None` for no search (the
/// model has a load of its own). Returns the fit and the contact, m.
fn fit_with_contact(eqs: &[Eq], x_range_m: Option<(f64, f64)>) -> Option<(RobustFit, Option<f64>)> {
    let plain = robust_fit(eqs, None)?;
    let Some((lo, hi)) = x_range_m else {
        return Some((plain, None));
    };
    let plain_rms = rms_of(eqs, &plain.1, plain.0, None);
    let best = (1..CONTACT_GRID)
        .map(|k| lo + (hi - lo) * k as f64 / CONTACT_GRID as f64)
        .filter(|c| eqs.iter().filter(|e| e.x > *c).count() >= MIN_CONTACT_EQUATIONS)
        .filter_map(|c| robust_fit(eqs, Some(c)).map(|f| (rms_of(eqs, &f.1, f.0, Some(c)), c, f)))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    match best {
        Some((rms, c, f)) => {
            let var = f.3 / (f.4.iter().sum::<f64>() - N as f64).max(1.0);
            let (k, k_sigma) = (f.1[N - 1], (f.2[(N - 1, N - 1)] * var).sqrt());
            if rms < (1.0 - CONTACT_GAIN) * plain_rms && k > 5.0 * k_sigma {
                Some((f, Some(c)))
            } else {
                Some((plain, None))
            }
        }
        None => Some((plain, None)),
    }
}

/// Fewest equations in contact a spring is fitted on.
const MIN_CONTACT_EQUATIONS: usize = 50;

impl Mechanics {
    /// `p` with what was identified put in: the mass and, in both directions,
    /// the Coulomb and static friction, the Stribeck velocity and the apparent
    /// viscous coefficient (the static force is left to the filters' load
    /// estimate).
    pub fn apply(&self, p: &ActuatorParams) -> ActuatorParams {
        let mut out = p.clone();
        if let Some(m) = self.mass_kg.estimate() {
            out.mass_kg = m.value;
        }
        let mut f = p.friction.extend();
        if let (Some(c), Some(s)) = (self.coulomb_n.estimate(), self.static_n.estimate()) {
            f.slip_n = c.value;
            f.static_n = s.value;
        }
        if let Some(a) = self.stribeck_velocity_m_s.estimate() {
            f.stribeck_velocity_m_s = a.value;
        }
        if let Some(d) = self.viscous_n_s_per_m.estimate() {
            f.viscous_n_s_per_m = d.value;
        }
        out.friction.set_extend(f);
        out.friction.retract = None;
        if let Some((k, contact_m)) = self.contact_spring {
            out.load.stiffness_n_per_m = k.value;
            out.load.contact_m = contact_m;
        }
        out
    }
}
