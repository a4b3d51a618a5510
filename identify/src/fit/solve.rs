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
