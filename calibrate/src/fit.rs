//! Levenberg–Marquardt fit of one effect's parameters on the fitting
//! windows, with forward-difference Jacobians in resolution-scaled units.

use model::params::ActuatorParams;
use nalgebra::{DMatrix, DVector};

use crate::effects::Effect;
use crate::shoot::{residuals, Prepared, ShootSettings};

/// The outcome of one fit.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// Fitted parameters, SI.
    pub theta: Vec<f64>,
    /// Mean squared normalised residual on the fitting windows at `theta`.
    pub cost: f64,
    /// RMS change of the normalised residuals per resolution step of each
    /// parameter (the sensitivity the identifiability test reads).
    pub sensitivity: Vec<f64>,
    /// Approximate standard deviation of each parameter, SI (from the
    /// Gauss–Newton covariance, inflated for the correlation of the residuals).
    pub std: Vec<f64>,
    /// Model evaluations spent.
    pub evaluations: usize,
}

/// Fitting context: data, windows and settings.
pub struct Problem<'a> {
    /// The model the effect is added to.
    pub base: &'a ActuatorParams,
    /// The prepared record.
    pub data: &'a Prepared,
    /// The windows fitted.
    pub windows: &'a [(usize, usize)],
    /// Shooting settings.
    pub set: ShootSettings,
    /// The effect.
    pub effect: Effect,
}

impl Problem<'_> {
    fn eval(&self, theta: &[f64]) -> Vec<f64> {
        let p = self.effect.apply(self.base, theta);
        residuals(&p, self.data, self.windows, &self.set).0
    }

    fn clamp(&self, theta: &mut [f64]) {
        for (t, (lo, hi)) in theta.iter_mut().zip(self.effect.bounds(self.base)) {
            *t = t.clamp(lo, hi);
        }
    }

    /// Runs LM from `start` for at most `max_iter` iterations.
    pub fn lm(&self, start: &[f64], max_iter: usize) -> FitOutcome {
        let res = self.effect.resolution(self.base);
        let bounds = self.effect.bounds(self.base);
        let np = start.len();
        let mut theta = start.to_vec();
        self.clamp(&mut theta);
        let mut r = self.eval(&theta);
        let m = r.len().max(1) as f64;
        let mut cost = r.iter().map(|a| a * a).sum::<f64>() / m;
        let mut evals = 1;
        let mut lambda = 1e-3;
        let mut jac = DMatrix::<f64>::zeros(r.len(), np);
        let mut have_jac = false;
        for _ in 0..max_iter {
            // Jacobian d r / d z, z = (θ − θ0)/res
            for j in 0..np {
                let mut h = 0.5 * res[j];
                if theta[j] + h > bounds[j].1 {
                    h = -h;
                }
                let mut tp = theta.clone();
                tp[j] += h;
                let rp = self.eval(&tp);
                evals += 1;
                let scale = res[j] / h;
                for (i, (a, b)) in rp.iter().zip(&r).enumerate() {
                    jac[(i, j)] = (a - b) * scale;
                }
            }
            have_jac = true;
            let rv = DVector::from_column_slice(&r);
            let g = jac.transpose() * &rv;
            let a = jac.transpose() * &jac;
            let mut accepted = false;
            let mut rel_decrease = 0.0;
            for _ in 0..6 {
                let mut lhs = a.clone();
                for k in 0..np {
                    lhs[(k, k)] += lambda * (a[(k, k)] + 1e-9);
                }
                let Some(step) = lhs.lu().solve(&(-&g)) else {
                    lambda *= 10.0;
                    continue;
                };
                let mut tn: Vec<f64> = theta
                    .iter()
                    .zip(step.iter())
                    .zip(&res)
                    .map(|((t, s), q)| t + s * q)
                    .collect();
                self.clamp(&mut tn);
                let rn = self.eval(&tn);
                evals += 1;
                let cn = rn.iter().map(|a| a * a).sum::<f64>() / m;
                if cn.is_finite() && cn < cost {
                    rel_decrease = (cost - cn) / cost.max(1e-300);
                    theta = tn;
                    r = rn;
                    cost = cn;
                    lambda = (lambda / 5.0).max(1e-7);
                    accepted = true;
                    break;
                }
                lambda *= 8.0;
            }
            if !accepted || rel_decrease < 1e-4 {
                break;
            }
        }
        let (sensitivity, std) = if have_jac {
            let n = jac.nrows().max(1) as f64;
            let sens: Vec<f64> = (0..np)
                .map(|j| (jac.column(j).norm_squared() / n).sqrt())
                .collect();
            // covariance of z: σ² (JᵀJ)⁻¹, σ² = cost; residuals of one window are
            // strongly correlated, so inflate by the samples compared per window.
            let per_window = (n / 3.0 / self.windows.len().max(1) as f64).max(1.0);
            let a = jac.transpose() * &jac;
            let std = match a.try_inverse() {
                Some(inv) => (0..np)
                    .map(|j| (inv[(j, j)].max(0.0) * cost * per_window).sqrt() * res[j])
                    .collect(),
                None => vec![f64::INFINITY; np],
            };
            (sens, std)
        } else {
            (vec![0.0; np], vec![f64::INFINITY; np])
        };
        FitOutcome {
            theta,
            cost,
            sensitivity,
            std,
            evaluations: evals,
        }
    }
}
