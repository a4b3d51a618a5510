//! The windows' weighted least squares: the fit over chosen columns, and
//! each chamber's RMS error.
//!
//! The transducers' lag columns are made of measured rates, whose noise
//! would bias a plain least squares toward no lag (errors in variables).
//! Their instruments, the same columns with rates read from other samples
//! (±3 in place of the five-point stencil's ±1 and ±2), follow the same
//! rates with an independent noise: the fit solves the instrumental
//! variables' equations Zᵀ·A·θ = Zᵀ·y, Z being A with the lag columns
//! replaced by their instruments (Z = A without lag columns).

use nalgebra::{DMatrix, DVector};

use super::{Rows, LAG1, LAG2, UNKNOWNS};

/// Weighted least squares over the columns `cols` with the other unknowns
/// fixed at `fixed`, the lag columns by their instruments (module docs):
/// (solution over all unknowns, their standard deviations, RMS residual per
/// chamber in m³ per window).
pub(super) fn solve(
    rows: &Rows,
    cols: &[Vec<usize>],
    fixed: &[f64; UNKNOWNS],
    weights: [f64; 2],
) -> Option<Fitted> {
    let m = rows.y1.len() + rows.y2.len();
    let k = cols.len();
    if m <= k {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(m, k);
    let mut z_mat = DMatrix::<f64>::zeros(m, k);
    let mut y = DVector::<f64>::zeros(m);
    let free: Vec<usize> = cols.iter().flatten().copied().collect();
    let chambers = [
        (&rows.x1, &rows.y1, weights[0], 0),
        (&rows.x2, &rows.y2, weights[1], 1),
    ];
    let mut r = 0;
    for (xs, ys, w, ch) in chambers {
        for (j, (x, yv)) in xs.iter().zip(ys.iter()).enumerate() {
            // the row's instruments: its chamber's lag column from other samples
            let mut z = *x;
            z[[LAG1, LAG2][ch]] = rows.z_lag[j][ch];
            for (c, group) in cols.iter().enumerate() {
                z_mat[(r, c)] = w * group.iter().map(|&u| z[u]).sum::<f64>();
            }
            let mut known = 0.0;
            for (u, fx) in fixed.iter().enumerate() {
                if !free.contains(&u) {
                    known += x[u] * fx;
                }
            }
            for (c, group) in cols.iter().enumerate() {
                a[(r, c)] = w * group.iter().map(|&u| x[u]).sum::<f64>();
            }
            y[r] = w * (yv - known);
            r += 1;
        }
    }
    // Columns scaled to unit norm for the conditioning of the normal equations.
    let scale: Vec<f64> = (0..k)
        .map(|c| {
            let n = a.column(c).norm();
            if n > 0.0 {
                n
            } else {
                1.0
            }
        })
        .collect();
    for (c, s) in scale.iter().enumerate() {
        a.column_mut(c).scale_mut(1.0 / s);
        z_mat.column_mut(c).scale_mut(1.0 / s);
    }
    // θ = (ZᵀA)⁻¹·Zᵀy; its covariance σ²·(ZᵀA)⁻¹·ZᵀZ·(ZᵀA)⁻ᵀ
    let zta_inv = (z_mat.transpose() * &a).try_inverse()?;
    let sol = &zta_inv * (z_mat.transpose() * &y);
    let inv = &zta_inv * (z_mat.transpose() * &z_mat) * zta_inv.transpose();
    let resid = &y - &a * &sol;
    let dof = (m - k) as f64;
    let var = resid.norm_squared() / dof;
    let mut theta = *fixed;
    let mut sigma = [f64::NAN; UNKNOWNS];
    for c in 0..k {
        for &u in &cols[c] {
            theta[u] = sol[c] / scale[c];
            sigma[u] = (var * inv[(c, c)]).sqrt() / scale[c];
        }
    }
    Some(Fitted {
        theta,
        sigma,
        rms: [
            chamber_rms(&rows.x1, &rows.y1, &theta),
            chamber_rms(&rows.x2, &rows.y2, &theta),
        ],
    })
}

/// One fit's unknowns, their σ and each chamber's RMS error.
pub(super) struct Fitted {
    /// Every unknown: fitted, or as fixed.
    pub(super) theta: [f64; UNKNOWNS],
    /// Standard deviation of each fitted unknown (NaN for a fixed one).
    pub(super) sigma: [f64; UNKNOWNS],
    /// RMS window error per chamber at `theta`, m³.
    pub(super) rms: [f64; 2],
}

/// RMS of one chamber's window errors at the unknowns `theta`, m³.
pub(super) fn chamber_rms(xs: &[[f64; UNKNOWNS]], ys: &[f64], theta: &[f64; UNKNOWNS]) -> f64 {
    if xs.is_empty() {
        return 0.0;
    }
    let ss: f64 = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| {
            let e: f64 = x.iter().zip(theta).map(|(a, b)| a * b).sum::<f64>() - y;
            e * e
        })
        .sum();
    (ss / xs.len() as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::super::K_A;
    use super::*;
    use model::rng::Rng;

    /// Chamber-1 rows y = a + τ·s, the lag column read as s plus noise as
    /// large as s, its instrument as 0.8·s plus a noise of its own; the
    /// lag's coefficient (τ = 0.5) and that of the fit with the regressor as
    /// its own instrument.
    fn lag_coefficients() -> (f64, f64) {
        let mut rng = Rng::new(7);
        let mut rows = Rows::default();
        for _ in 0..20_000 {
            let (a, s) = (1.0 + rng.normal(), rng.normal());
            let mut x = [0.0; UNKNOWNS];
            x[K_A] = a;
            x[LAG1] = s + rng.normal();
            rows.x1.push(x);
            rows.y1.push(a + 0.5 * s);
            rows.z_lag.push([0.8 * s + rng.normal(), 0.0]);
        }
        let cols = [vec![K_A], vec![LAG1]];
        let iv = solve(&rows, &cols, &[0.0; UNKNOWNS], [1.0, 1.0]).expect("solved");
        rows.z_lag = rows.x1.iter().map(|x| [x[LAG1], 0.0]).collect();
        let ls = solve(&rows, &cols, &[0.0; UNKNOWNS], [1.0, 1.0]).expect("solved");
        (iv.theta[LAG1], ls.theta[LAG1])
    }

    #[test]
    fn a_noisy_lag_column_is_read_without_bias_through_its_instrument() {
        let (iv, ls) = lag_coefficients();
        // the instrument: within 5 %; least squares: halved by the noise
        assert!((iv / 0.5 - 1.0).abs() < 0.05, "instrumented: {iv}");
        assert!((ls / 0.25 - 1.0).abs() < 0.1, "least squares: {ls}");
    }
}
