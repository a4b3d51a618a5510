//! The workflow itself: greedy forward selection of effects ([`run`]), one
//! effect on its own ([`fit_effect`]), and the traces and spool RMS of the result.

use std::time::Instant;

use model::params::ActuatorParams;
use model::Sample;

use crate::input::{setup, Setup};
use crate::select::{form_caveat, gap_on, mean_sq, n_eff, named, prefer_simpler, screen_and_fit, Scored};
use crate::shoot::{self, residuals, Prepared, ShootSettings};
use crate::{
    regime, units, CalibrateError, CalibrateOptions, Calibration, CandidateScore, DataSummary, Effect,
    EffectFit, FoundEffect, Gap, Method, Round, Traces, NOT_IDENTIFIABLE,
};

/// Runs the whole workflow on `measured` samples with `model` as the starting model.
pub fn run(
    measured: &[Sample],
    model: &ActuatorParams,
    opts: &CalibrateOptions,
) -> Result<Calibration, CalibrateError> {
    run_with_progress(measured, model, opts, &|_| {})
}

/// [`run`], telling `progress` what it is doing (one line per step: the
/// data used, each round of the selection and its verdict).
pub fn run_with_progress(
    measured: &[Sample],
    model: &ActuatorParams,
    opts: &CalibrateOptions,
    progress: &dyn Fn(&str),
) -> Result<Calibration, CalibrateError> {
    let t0 = Instant::now();
    let s = setup(measured, model, opts)?;
    progress(&format!(
        "using {:.1} s ({} samples): {} windows fit, {} validate",
        s.seconds,
        s.data.t_s.len(),
        s.data.fit_windows().len(),
        s.data.val_windows().len()
    ));
    let d = &s.data;
    let mut pool = candidate_pool(opts)?;
    let mut current = model.clone();
    let gap_before = gap_on(&current, d, d.val_windows(), &s.set);
    let breakdown_before = regime::breakdown(&current, d, d.val_windows(), &s.set);
    let mut gap_cur = gap_before;
    let mut fit_cost_cur = mean_sq(&residuals(&current, d, d.fit_windows(), &s.set).0);
    let mut effects = Vec::new();
    let mut rounds = Vec::new();
    let ne = n_eff(d);
    while effects.len() < opts.max_effects && !pool.is_empty() {
        progress(&format!(
            "round {}: fitting {} candidates (validation gap {:.3}) ... {:.1} s",
            rounds.len() + 1,
            pool.len(),
            gap_cur.normalised,
            t0.elapsed().as_secs_f64()
        ));
        let mut scored = screen_and_fit(&pool, &current, &s, opts, opts.screen_keep.max(1));
        let red = |x: &Scored| 1.0 - x.val.normalised / gap_cur.normalised.max(1e-300);
        scored.sort_by(|a, b| red(b).total_cmp(&red(a)));
        let (cands, chosen) = judge_candidates(&scored, &current, &s, opts, gap_cur, fit_cost_cur, ne);
        rounds.push(Round {
            gap_before: gap_cur.normalised,
            candidates: cands,
        });
        let Some(chosen) = chosen else {
            progress("nothing else explains a significant part of the gap");
            break;
        };
        let (i, not_identifiable) = settle_form(chosen, &scored, &current, &s, opts);
        let c = &scored[i];
        let r = red(c);
        let caveat = if c.effect.name() == "friction-asymmetry" {
            None
        } else {
            form_caveat(c, &scored, &current, d, &s.set, opts)
        };
        let previous = current.clone();
        current = c.effect.apply(&current, &c.theta);
        let engineering = units::describe(c.effect.name(), &previous, &current, d.mean_pressures_pa());
        fit_cost_cur = c.fit_cost;
        gap_cur = c.val;
        effects.push(FoundEffect {
            name: c.effect.name().to_string(),
            form: c.effect.form().to_string(),
            parameters: named(c.effect, &c.theta),
            parameter_std: named(c.effect, &c.std),
            gap_reduction: r,
            cumulative_gap_reduction: 1.0 - gap_cur.normalised / gap_before.normalised.max(1e-300),
            gap_after: gap_cur,
            signature: c.effect.signature().to_string(),
            caveat,
            not_identifiable,
            engineering,
        });
        let name = c.effect.name();
        progress(&format!("added {name}: the gap shrinks by {:.0} %", 100.0 * r));
        pool.retain(|e| e.name() != name);
    }
    let breakdown_after = regime::breakdown(&current, d, d.val_windows(), &s.set);
    let traces = if opts.keep_traces {
        make_traces(model, &current, d, &s.set)
    } else {
        Traces::default()
    };
    let spool_rms_m = spool_rms(model, &current, d, &s.set);
    Ok(Calibration {
        effects,
        gap_before,
        gap_after: gap_cur,
        gap_reduction: 1.0 - gap_cur.normalised / gap_before.normalised.max(1e-300),
        rounds,
        breakdown_before,
        breakdown_after,
        spool_rms_m,
        data: data_summary(&s, opts),
        options: opts.clone(),
        model_before: model.clone(),
        model_after: current,
        traces,
        warnings: s.warnings.clone(),
        elapsed_s: t0.elapsed().as_secs_f64(),
    })
}

/// The effects the selection may choose from: all, or those `opts.candidates` names.
fn candidate_pool(opts: &CalibrateOptions) -> Result<Vec<Effect>, CalibrateError> {
    Ok(if opts.candidates.is_empty() {
        Effect::ALL.to_vec()
    } else {
        let mut v = Vec::new();
        for n in &opts.candidates {
            let e = Effect::by_name(n);
            if e.is_empty() {
                return Err(CalibrateError::UnknownEffect(n.clone()));
            }
            v.extend(e);
        }
        v
    })
}

/// One round's verdict on each of the `scored` candidates (best first) against
/// the model so far, with its validation gap `gap_cur` and fitting cost
/// `fit_cost_cur` (`ne` effective residuals for the BIC): their scores, and
/// the index of the one added, if any.
fn judge_candidates(
    scored: &[Scored],
    current: &ActuatorParams,
    s: &Setup,
    opts: &CalibrateOptions,
    gap_cur: Gap,
    fit_cost_cur: f64,
    ne: f64,
) -> (Vec<CandidateScore>, Option<usize>) {
    let red = |x: &Scored| 1.0 - x.val.normalised / gap_cur.normalised.max(1e-300);
    let mut chosen: Option<usize> = None;
    let mut cands = Vec::new();
    for (i, c) in scored.iter().enumerate() {
        let k = c.theta.len() as f64;
        let dbic = ne * (c.fit_cost.max(1e-300) / fit_cost_cur.max(1e-300)).ln() + k * ne.ln();
        let r = red(c);
        let (spool_only, r_judged, abs_judged) = judged_reduction(c, s, gap_cur, r);
        let status = if !c.identifiable {
            format!(
                "{NOT_IDENTIFIABLE} (`{}` moves the residuals by {:.2e} per step of {:.3e})",
                c.effect.parameter_names()[c.weakest.0],
                c.weakest.1,
                c.effect.resolution(current)[c.weakest.0]
            )
        } else if c.screened_out {
            "screened out (explains less on the fitting part)".to_string()
        } else if c.size_steps < opts.min_size_steps {
            format!(
                "too small to claim (parameters moved {:.2} resolution steps; needs {})",
                c.size_steps, opts.min_size_steps
            )
        } else if r_judged < opts.min_gap_reduction || abs_judged < opts.min_gap_reduction_normalised {
            if spool_only {
                format!(
                    "explains too little ({:.0} % of the spool channel's gap)",
                    100.0 * r_judged
                )
            } else {
                format!("explains too little ({:.0} % of the gap)", 100.0 * r)
            }
        } else if dbic >= 0.0 {
            "not significant (BIC)".to_string()
        } else if chosen.is_none() {
            chosen = Some(i);
            "added".to_string()
        } else {
            "significant, but a better candidate was added".to_string()
        };
        cands.push(CandidateScore {
            name: c.effect.name().to_string(),
            form: c.effect.form().to_string(),
            parameters: named(c.effect, &c.theta),
            gap_reduction: r,
            delta_bic: dbic,
            identifiable: c.identifiable,
            status,
        });
    }
    (cands, chosen)
}

/// Whether candidate `c` is judged on the spool channel alone, and the share
/// (1) and normalised amount of the gap `gap_cur` it removes as judged (`r`:
/// its share of the whole gap).
fn judged_reduction(c: &Scored, s: &Setup, gap_cur: Gap, r: f64) -> (bool, f64, f64) {
    let d = &s.data;
    // an effect of the spool alone, with the spool measured: judged on
    // the spool channel, which measures it directly (the other
    // channels sit at their sensor floor and would dilute it)
    let spool_only = s.set.method == Method::EquationError
        && d.has_spool()
        && matches!(c.effect, Effect::SpoolBias | Effect::ValveBandwidth);
    let (r_judged, abs_judged) = if spool_only && gap_cur.spool_m > 0.0 {
        (
            1.0 - c.val.spool_m / gap_cur.spool_m,
            (gap_cur.spool_m - c.val.spool_m) / s.set.scale_sp_m,
        )
    } else {
        (r, gap_cur.normalised - c.val.normalised)
    };
    (spool_only, r_judged, abs_judged)
}

/// The form of the chosen effect `i` that is kept, with the parameters stated
/// as not identifiable: a richer form (more parameters) only when the data
/// tell it from the simpler one.
fn settle_form(
    mut i: usize,
    scored: &[Scored],
    current: &ActuatorParams,
    s: &Setup,
    opts: &CalibrateOptions,
) -> (usize, Vec<String>) {
    // a richer form (more parameters) is kept only when the data tell it
    // from the simpler one; otherwise the simpler one, and the extra
    // parameters are stated as not identifiable
    let mut not_identifiable = Vec::new();
    if let Some((j, why)) = prefer_simpler(i, scored, current, &s.data, &s.set, opts) {
        let extra: Vec<&str> = scored[i]
            .effect
            .parameter_names()
            .iter()
            .filter(|n| !scored[j].effect.parameter_names().contains(n))
            .copied()
            .collect();
        for n in extra {
            not_identifiable.push(format!("{n}: {NOT_IDENTIFIABLE} ({why})"));
        }
        i = j;
    } else if let Some(rich) = scored.iter().find(|o| {
        o.effect.name() == scored[i].effect.name()
            && o.effect.parameter_names().len() > scored[i].effect.parameter_names().len()
    }) {
        // the simpler form explained the record better than the richer one
        for n in rich
            .effect
            .parameter_names()
            .iter()
            .filter(|n| !scored[i].effect.parameter_names().contains(n))
        {
            not_identifiable.push(format!(
                "{n}: {NOT_IDENTIFIABLE} (fitting it does not lower the validation gap: {:.3} with it, \
                 {:.3} without); it keeps the model's value",
                rich.val.normalised, scored[i].val.normalised
            ));
        }
    }
    (i, not_identifiable)
}

/// What data the calibration used: samples, seconds (s), sample period and
/// window length (s), and how the windows were split into fitting and validation.
fn data_summary(s: &Setup, opts: &CalibrateOptions) -> DataSummary {
    let d = &s.data;
    let vs = d.val_windows().first().map(|w| d.t_s[w.0]).unwrap_or(0.0);
    DataSummary {
        samples: d.t_s.len(),
        seconds: s.seconds,
        sample_period_s: d.dt_s,
        window_s: (d.windows.first().map(|w| w.1 - w.0).unwrap_or(0)) as f64 * d.dt_s,
        fit_windows: d.fit_windows().len(),
        validation_windows: d.val_windows().len(),
        validation_start_s: vs,
        split: if opts.split_block_windows == 0 {
            format!("first {:.0} % fit, the tail validates", 100.0 * opts.fit_fraction)
        } else {
            format!(
                "in every block of {} windows, the first {:.0} % fit and the rest validate",
                opts.split_block_windows,
                100.0 * opts.fit_fraction
            )
        },
    }
}

fn make_traces(before: &ActuatorParams, after: &ActuatorParams, d: &Prepared, set: &ShootSettings) -> Traces {
    let w = d.val_windows();
    let tb = regime::traces(before, d, w, set);
    let ta = regime::traces(after, d, w, set);
    let mut tr = Traces::default();
    let nan = [f64::NAN; 3];
    for (k, ((i, b), (_, a))) in tb.iter().zip(&ta).enumerate() {
        if k > 0 && *i != tb[k - 1].0 + 1 {
            tr.t_s.push(f64::NAN);
            tr.measured.push(nan);
            tr.before.push(nan);
            tr.after.push(nan);
        }
        tr.t_s.push(d.t_s[*i]);
        tr.measured.push([d.x_m[*i], d.p1_pa[*i], d.p2_pa[*i]]);
        tr.before.push(*b);
        tr.after.push(*a);
    }
    tr
}

fn spool_rms(
    before: &ActuatorParams,
    after: &ActuatorParams,
    d: &Prepared,
    set: &ShootSettings,
) -> Option<[f64; 2]> {
    if !d.x_sp_m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let f = |p: &ActuatorParams| {
        let sp = shoot::spool_trajectory(p, d, set.substeps);
        let e: Vec<f64> = sp.iter().zip(&d.x_sp_m).map(|(a, b)| a[0] - b).collect();
        shoot::rms(&e)
    };
    Some([f(before), f(after)])
}

/// Fits one named effect (both forms for `bulk-modulus`, the better kept)
/// on the fitting part and scores it on the validation part. Fails with
/// [`CalibrateError::NotIdentifiable`] when the data does not excite it.
pub fn fit_effect(
    measured: &[Sample],
    model: &ActuatorParams,
    effect_name: &str,
    opts: &CalibrateOptions,
) -> Result<EffectFit, CalibrateError> {
    let s = setup(measured, model, opts)?;
    let d = &s.data;
    let effects = Effect::by_name(effect_name);
    if effects.is_empty() {
        return Err(CalibrateError::UnknownEffect(effect_name.to_string()));
    }
    let scored = screen_and_fit(&effects, model, &s, opts, effects.len());
    let best = scored
        .iter()
        .filter(|c| c.identifiable)
        .min_by(|a, b| a.val.normalised.total_cmp(&b.val.normalised));
    let Some(c) = best else {
        let reason = scored
            .iter()
            .map(|c| {
                format!(
                    "`{}` changes the normalised residuals by only {:.2e} per step of {:.3e} (needs {:.2e})",
                    c.effect.parameter_names()[c.weakest.0],
                    c.weakest.1,
                    c.effect.resolution(model)[c.weakest.0],
                    opts.min_sensitivity
                )
            })
            .collect::<Vec<_>>()
            .join("; ");
        return Err(CalibrateError::NotIdentifiable {
            effect: effect_name.to_string(),
            reason,
        });
    };
    let gap_before = gap_on(model, d, d.val_windows(), &s.set);
    Ok(EffectFit {
        name: c.effect.name().to_string(),
        form: c.effect.form().to_string(),
        parameters: named(c.effect, &c.theta),
        parameter_std: named(c.effect, &c.std),
        gap_before,
        gap_after: c.val,
        gap_reduction: 1.0 - c.val.normalised / gap_before.normalised.max(1e-300),
    })
}
