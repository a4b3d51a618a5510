//! Fitting and judging candidates: the screening and full fits of every
//! candidate effect, the validation gap, and the choice between the forms of an effect.

use std::collections::BTreeMap;

use model::params::ActuatorParams;

use crate::fit::{self, Problem};
use crate::input::Setup;
use crate::shoot::{gap_of, residuals, Prepared, ShootSettings};
use crate::{equation, CalibrateOptions, Effect, Gap, Method, NOT_IDENTIFIABLE};

pub(crate) fn gap_on(
    p: &ActuatorParams,
    d: &Prepared,
    windows: &[(usize, usize)],
    set: &ShootSettings,
) -> Gap {
    let (r, _) = residuals(p, d, windows, set);
    if set.method == Method::EquationError {
        let (ch, j) = equation::gap_of(&r, d, set);
        return Gap {
            x_m: 0.0,
            p1_pa: ch[0],
            p2_pa: ch[1],
            normalised: j,
            force_n: ch[2],
            spool_m: ch[3],
        };
    }
    let (ch, j) = gap_of(&r, set);
    Gap {
        x_m: ch[0],
        p1_pa: ch[1],
        p2_pa: ch[2],
        normalised: j,
        force_n: 0.0,
        spool_m: 0.0,
    }
}

pub(crate) fn mean_sq(r: &[f64]) -> f64 {
    if r.is_empty() {
        0.0
    } else {
        r.iter().map(|a| a * a).sum::<f64>() / r.len() as f64
    }
}

pub(crate) fn named(effect: Effect, v: &[f64]) -> BTreeMap<String, f64> {
    effect
        .parameter_names()
        .iter()
        .zip(v)
        .map(|(n, x)| (n.to_string(), *x))
        .collect()
}

/// A fitted candidate with its scores.
#[derive(Clone)]
pub(crate) struct Scored {
    pub(crate) effect: Effect,
    pub(crate) theta: Vec<f64>,
    pub(crate) std: Vec<f64>,
    pub(crate) fit_cost: f64,
    pub(crate) val: Gap,
    pub(crate) identifiable: bool,
    pub(crate) weakest: (usize, f64),
    pub(crate) screened_out: bool,
    /// Largest parameter change from the current model, in resolution steps.
    pub(crate) size_steps: f64,
}

/// Effective number of independent residuals of the fitting part for the
/// BIC: a few per window and channel (residuals inside a window are strongly
/// correlated).
pub(crate) fn n_eff(d: &Prepared) -> f64 {
    (d.fit_windows().len() * 3 * 5) as f64
}

pub(crate) fn screen_and_fit(
    effects: &[Effect],
    base: &ActuatorParams,
    s: &Setup,
    opts: &CalibrateOptions,
    keep: usize,
) -> Vec<Scored> {
    let d = &s.data;
    // Screening: a short fit (2 iterations) from each starting point.
    let mut first: Vec<(Effect, fit::FitOutcome)> = Vec::new();
    for &e in effects {
        let prob = Problem {
            base,
            data: d,
            windows: d.fit_windows(),
            set: s.set,
            effect: e,
        };
        let starts = e.starting_points(base, d.x_range_m());
        let per_start = if starts.len() > 1 { 1 } else { 2 };
        let mut best: Option<fit::FitOutcome> = None;
        for start in starts.iter() {
            let o = prob.lm(start, per_start);
            if best.as_ref().is_none_or(|b| o.cost < b.cost) {
                best = Some(o);
            }
        }
        if let Some(b) = best {
            let b = if per_start == 1 {
                let more = prob.lm(&b.theta, 1);
                if more.cost <= b.cost {
                    fit::FitOutcome {
                        evaluations: more.evaluations + b.evaluations,
                        ..more
                    }
                } else {
                    b
                }
            } else {
                b
            };
            first.push((e, b));
        }
    }
    first.sort_by(|a, b| a.1.cost.total_cmp(&b.1.cost));
    let mut out = Vec::new();
    for (rank, (e, o)) in first.into_iter().enumerate() {
        let screened_out = rank >= keep;
        let o = if screened_out {
            o
        } else {
            let prob = Problem {
                base,
                data: d,
                windows: d.fit_windows(),
                set: s.set,
                effect: e,
            };
            let full = prob.lm(&o.theta, opts.max_iterations);
            if full.cost <= o.cost {
                full
            } else {
                o
            }
        };
        let weakest = o
            .sensitivity
            .iter()
            .copied()
            .enumerate()
            .fold((0, f64::INFINITY), |a, (i, v)| if v < a.1 { (i, v) } else { a });
        let identifiable = weakest.1 >= opts.min_sensitivity;
        let p = e.apply(base, &o.theta);
        let val = gap_on(&p, d, d.val_windows(), &s.set);
        let size_steps = e
            .read(base)
            .iter()
            .zip(&o.theta)
            .zip(e.resolution(base))
            .map(|((a, b), r)| (b - a).abs() / r)
            .fold(0.0, f64::max);
        out.push(Scored {
            effect: e,
            theta: o.theta,
            std: o.std,
            fit_cost: o.cost,
            val,
            identifiable,
            weakest,
            screened_out,
            size_steps,
        });
    }
    out
}

/// Per-window mean squared normalised residual of model `p` over every window of the record.
fn per_window_cost(p: &ActuatorParams, d: &Prepared, set: &ShootSettings) -> Vec<f64> {
    let (r, idx) = residuals(p, d, &d.windows, set);
    if set.method == Method::EquationError {
        return r
            .chunks_exact(equation::per_window(d))
            .map(|c| c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64)
            .collect();
    }
    let mut out = vec![(0.0, 0usize); d.windows.len()];
    let mut w = 0;
    for (k, i) in idx.iter().enumerate() {
        while w + 1 < d.windows.len() && *i >= d.windows[w].1 {
            w += 1;
        }
        for v in &r[3 * k..3 * k + 3] {
            out[w].0 += v * v;
            out[w].1 += 1;
        }
    }
    out.into_iter()
        .filter(|(_, n)| *n > 0)
        .map(|(s, n)| s / n as f64)
        .collect()
}

/// Least relative reduction of the validation gap a richer form of an effect
/// must add over its simpler form to be kept.
pub const MIN_RICHER_FORM_GAIN: f64 = 0.05;

/// For a chosen candidate with a simpler form of the same effect (fewer
/// parameters, e.g. `friction-asymmetry` without its own viscous term):
/// the simpler one's index and why, unless the richer form lowers the
/// validation gap by at least [`MIN_RICHER_FORM_GAIN`] and beats it over
/// every window (paired t ≥ `min_form_t`).
pub(crate) fn prefer_simpler(
    i: usize,
    scored: &[Scored],
    base: &ActuatorParams,
    d: &Prepared,
    set: &ShootSettings,
    opts: &CalibrateOptions,
) -> Option<(usize, String)> {
    let c = &scored[i];
    let np = c.effect.parameter_names().len();
    let (j, simple) = scored.iter().enumerate().find(|(_, o)| {
        o.effect != c.effect
            && o.effect.name() == c.effect.name()
            && o.effect.parameter_names().len() < np
            && !o.screened_out
            && o.identifiable
    })?;
    let gain = 1.0 - c.val.normalised / simple.val.normalised.max(1e-300);
    let a = per_window_cost(&c.effect.apply(base, &c.theta), d, set);
    let b = per_window_cost(&simple.effect.apply(base, &simple.theta), d, set);
    let t = paired_t(&b, &a);
    if gain >= MIN_RICHER_FORM_GAIN && t >= opts.min_form_t {
        return None;
    }
    Some((
        j,
        format!(
            "fitting it lowers the validation gap by only {:.1} % (needs {:.0} %; paired t {t:.1} over every window); \
             it keeps the model's value",
            100.0 * gain,
            100.0 * MIN_RICHER_FORM_GAIN
        ),
    ))
}

/// Paired t statistic of `b − a` (0 when fewer than three pairs).
fn paired_t(b: &[f64], a: &[f64]) -> f64 {
    if a.len() != b.len() || a.len() < 3 {
        return 0.0;
    }
    let n = a.len() as f64;
    let diff: Vec<f64> = b.iter().zip(a).map(|(x, y)| x - y).collect();
    let mean = diff.iter().sum::<f64>() / n;
    let var = diff.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    mean / (var / n).sqrt().max(1e-300)
}

/// Whether the data tell the chosen form of a multi-form effect from its
/// other form: over every window, the other form's residual must be
/// consistently larger (paired t ≥ `min_form_t`) or clearly larger (RMS
/// ratio ≥ `min_form_gap_ratio`). Otherwise returns the caveat.
pub(crate) fn form_caveat(
    c: &Scored,
    scored: &[Scored],
    base: &ActuatorParams,
    d: &Prepared,
    set: &ShootSettings,
    opts: &CalibrateOptions,
) -> Option<String> {
    let other = scored
        .iter()
        .find(|o| o.effect != c.effect && o.effect.name() == c.effect.name())?;
    let a = per_window_cost(&c.effect.apply(base, &c.theta), d, set);
    let b = per_window_cost(&other.effect.apply(base, &other.theta), d, set);
    if a.len() != b.len() || a.len() < 3 {
        return None;
    }
    let n = a.len() as f64;
    let diff: Vec<f64> = b.iter().zip(&a).map(|(x, y)| x - y).collect();
    let mean = diff.iter().sum::<f64>() / n;
    let var = diff.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    let t = mean / (var / n).sqrt().max(1e-300);
    let rms = |v: &[f64]| (v.iter().sum::<f64>() / n).sqrt();
    let ratio = rms(&b) / rms(&a).max(1e-300);
    if t >= opts.min_form_t || ratio >= opts.min_form_gap_ratio {
        return None;
    }
    let pm = d.p1_pa.iter().chain(&d.p2_pa).sum::<f64>() / (2.0 * d.p1_pa.len().max(1) as f64);
    Some(format!(
        "form {NOT_IDENTIFIABLE}: `{}` explains the record about as well as `{}` (RMS residual over \
         every window {:.3} vs {:.3}, paired t {:.1}; needs t ≥ {} or a ratio ≥ {}); the fitted \
         value describes the effect near the pressures visited (mean chamber pressure {:.1} MPa), \
         not its pressure dependence",
        other.effect.form(),
        c.effect.form(),
        rms(&b),
        rms(&a),
        t,
        opts.min_form_t,
        opts.min_form_gap_ratio,
        pm * 1e-6
    ))
}
