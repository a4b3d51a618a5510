//! A generic square-root extended Kalman filter over static sizes.
//!
//! The covariance is carried as a factor S with P = S·Sᵀ, so it is symmetric
//! positive semi-definite by construction and never loses definiteness to
//! rounding, whatever the units (the thesis' P0 = 1e4·I mixes m² and Pa² over
//! twenty orders of magnitude; a Joseph-form update loses definiteness on it,
//! docs/model.md#covariance-at-the-thesis-start). On top of that, all
//! covariance algebra runs in scaled units z = x / scale, so that every state
//! is O(1).
//!
//! - Predict: S⁻ = triangular factor of [F·S, Q^½]: the Cholesky factor of
//!   (F·S)(F·S)ᵀ + Q, or, should that fail to rounding, Householder reflections.
//! - Update: Potter's square-root update, one measurement at a time (R diagonal).
//!
//! The factor is held by columns, padded to a width of whole vector
//! registers: every step of both updates adds a multiple of one column to
//! another, with no sum across a register. On x86-64 with AVX2 and FMA the
//! steps run compiled for them, each multiply-add fused.
//!
//! Nothing here allocates: all matrices are static sizes.
//!
//! The time update is in `predict`, the measurement updates in `update`,
//! the column kernels both use in `kernels`.

use nalgebra::{SMatrix, SVector};

/// `$body` with the constant `$R` the first row of column `$c`'s block of 4
/// rows (0, 4, 8, 12; 16 for any column from 16 on): the rows from there
/// down are the column's lower triangle in whole vector registers, and a
/// constant bound keeps the loops over them of fixed length.
macro_rules! from_block {
    ($c:expr, $R:ident => $body:expr) => {
        match $c / 4 {
            0 => {
                const $R: usize = 0;
                $body
            }
            1 => {
                const $R: usize = 4;
                $body
            }
            2 => {
                const $R: usize = 8;
                $body
            }
            3 => {
                const $R: usize = 12;
                $body
            }
            _ => {
                const $R: usize = 16;
                $body
            }
        }
    };
}

/// Rows summed in registers ahead of a wider factor's rest: two AVX2
/// registers of 4. The random-walk rows of F·S past them are copied from S,
/// and a row among them is summed over as many columns when no full column
/// lies beyond.
const LEAD_ROWS: usize = 8;

mod kernels;
mod predict;
mod update;

use kernels::all_finite;
pub use kernels::lower_triangularise;
pub(crate) use kernels::{fused_vector_unit, Fused, MulAdd, Separate};

/// What one measurement update saw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Innovation<const M: usize> {
    /// Innovation ν = y − h(x⁻), measurement units.
    pub nu: SVector<f64, M>,
    /// Standard deviation of each innovation, √diag(H P⁻ Hᵀ + R), measurement units.
    pub sigma: SVector<f64, M>,
    /// Normalised innovation squared νᵀ (H P⁻ Hᵀ + R)⁻¹ ν (χ² with M degrees of freedom when consistent).
    pub nis: f64,
}

/// Why the filter refused a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EkfError {
    /// The state or its covariance factor holds a NaN or an infinity.
    NotFinite,
    /// The innovation covariance could not be factorised.
    SingularInnovation,
}

/// A square-root EKF with `N` states and `M` measurements, its factor held
/// in `W` ≥ `N` rows and columns (default `N`): a width of whole vector
/// registers (8 for 6 or 7 states, 12 for 10 to 12) lets every column
/// operation run without a remainder. The padding is zero and nothing reads it.
#[derive(Debug, Clone)]
pub struct Ekf<const N: usize, const M: usize, const W: usize = N> {
    /// State estimate, SI units.
    x: SVector<f64, N>,
    /// Covariance factor in scaled units, P_z = S·Sᵀ, by columns (`s[k]` is
    /// column k; rows and columns `N..W` are zero). Every step is a sum of
    /// multiples of whole columns: no sum across a vector register.
    s: [[f64; W]; W],
    /// Columns `0..full_cols` of S may be full; the others are lower
    /// triangular (zero above the diagonal). A time update leaves S lower
    /// triangular (0); a selector update fills the columns up to the highest
    /// measured state, a general update all.
    full_cols: usize,
    /// Typical magnitude of each state (its unit of scaling), SI.
    x_scale: SVector<f64, N>,
    /// Process noise variances per step, scaled (q_i / scale_i²).
    q_var: [f64; N],
    /// Measurement noise variances, SI.
    r: SVector<f64, M>,
    /// Measurement noise standard deviations √r, SI (Potter's γ).
    r_sqrt: SVector<f64, M>,
    /// The measurement noise variances given at the start, SI: `r` less what
    /// [`Ekf::set_measurement_rates`] adds.
    r_given: SVector<f64, M>,
    /// x_scale[j] / x_scale[i] by columns (`ratio[j][i]`), zero in the
    /// padding: scales column j of a Jacobian.
    ratio: [[f64; W]; N],
    /// The first random-walk state: rows `walks_from..N` of every F are the
    /// identity's (N when none is declared).
    walks_from: usize,
    /// Room for G = F_z·S during a time update; it means nothing between
    /// steps. (A field, so that no step spends time zeroing it.)
    work: [[f64; W]; N],
}

impl<const N: usize, const M: usize, const W: usize> Ekf<N, M, W> {
    /// A filter starting at `x0` (SI) with covariance diag(`p0_diag`), process noise
    /// diag(`q_diag`) per step and measurement noise diag(`r_diag`), all in SI squared
    /// units; `x_scale` gives each state's typical magnitude for the internal scaling.
    pub fn new(
        x0: SVector<f64, N>,
        p0_diag: &SVector<f64, N>,
        q_diag: &SVector<f64, N>,
        r_diag: SVector<f64, M>,
        x_scale: SVector<f64, N>,
    ) -> Self {
        const { assert!(W >= N, "the factor's width holds every state") };
        let mut ratio = [[0.0; W]; N];
        for (j, col) in ratio.iter_mut().enumerate() {
            for (i, v) in col.iter_mut().enumerate().take(N) {
                *v = x_scale[j] / x_scale[i];
            }
        }
        let mut q_var = [0.0; N];
        for (i, q) in q_var.iter_mut().enumerate() {
            let sd = q_diag[i].max(0.0).sqrt() / x_scale[i];
            *q = sd * sd;
        }
        let mut f = Ekf {
            x: x0,
            s: [[0.0; W]; W],
            full_cols: 0,
            x_scale,
            q_var,
            r: r_diag,
            r_sqrt: r_diag.map(|r| r.max(0.0).sqrt()),
            r_given: r_diag,
            ratio,
            walks_from: N,
            work: [[0.0; W]; N],
        };
        f.reset(x0, p0_diag);
        f
    }

    /// Sets each measurement's noise variance to the one given at the start
    /// plus (`rates[i]` · `jitter_s`)²: a reading taken δ off its stamp is
    /// off by its rate times δ (rates in SI per s, the jitter in s, RMS).
    pub fn set_measurement_rates(&mut self, rates: [f64; M], jitter_s: f64) {
        for (i, rate) in rates.iter().enumerate() {
            let r = self.r_given[i] + (rate * jitter_s).powi(2);
            self.r[i] = r;
            self.r_sqrt[i] = r.max(0.0).sqrt();
        }
    }

    /// Declares states `first..N` random walks: rows `first..N` of every
    /// Jacobian F given to [`Self::predict`] are the identity's. The time
    /// update then takes those rows of F·S from S, past the first
    /// [`LEAD_ROWS`], instead of summing them: for 10 to 12 states a third of
    /// F·S's multiply-adds. Debug builds check each F against it.
    pub fn set_random_walks_from(&mut self, first: usize) {
        self.walks_from = first.min(N);
    }

    /// Restarts the filter at `x0` with covariance diag(`p0_diag`) (SI).
    pub fn reset(&mut self, x0: SVector<f64, N>, p0_diag: &SVector<f64, N>) {
        self.x = x0;
        self.s = [[0.0; W]; W];
        for i in 0..N {
            self.s[i][i] = p0_diag[i].max(0.0).sqrt() / self.x_scale[i];
        }
        self.full_cols = 0;
    }

    /// S as a matrix (scaled units).
    fn factor(&self) -> SMatrix<f64, N, N> {
        SMatrix::from_fn(|i, j| self.s[j][i])
    }

    /// Sets S from a matrix (scaled units); `lower`: it is lower triangular.
    fn set_factor(&mut self, m: &SMatrix<f64, N, N>, lower: bool) {
        self.s = [[0.0; W]; W];
        for (j, col) in self.s.iter_mut().enumerate().take(N) {
            for (i, v) in col.iter_mut().enumerate().take(N) {
                *v = m[(i, j)];
            }
        }
        self.full_cols = if lower { 0 } else { N };
    }

    /// Re-anchors the fast states after a gap: states `0..keep_from` restart at
    /// `x0` (SI) with covariance diag(`p0_diag`) (SI squared) and no correlation
    /// with the rest; states `keep_from..N` keep their estimate and their joint
    /// covariance (the slow parameters, e.g. leak sizes, survive a gap).
    /// Falls back to a full reset if the kept block is not positive definite.
    pub fn reanchor(&mut self, x0: SVector<f64, N>, p0_diag: &SVector<f64, N>, keep_from: usize) {
        let pz = self.scaled_covariance();
        let mut p = SMatrix::<f64, N, N>::zeros();
        for i in 0..N {
            if i < keep_from {
                let d = p0_diag[i].max(0.0).sqrt() / self.x_scale[i];
                p[(i, i)] = d * d;
            } else {
                for j in keep_from..N {
                    p[(i, j)] = pz[(i, j)];
                }
            }
        }
        let kept = self.x;
        match p.cholesky() {
            Some(c) if self.x.iter().skip(keep_from).all(|v| v.is_finite()) => {
                self.set_factor(&c.l(), true);
                self.x = x0;
                for i in keep_from..N {
                    self.x[i] = kept[i];
                }
            }
            _ => self.reset(x0, p0_diag),
        }
    }

    /// The state estimate, SI.
    pub fn state(&self) -> &SVector<f64, N> {
        &self.x
    }

    /// Overwrites the state estimate (for guards that keep it physical), SI.
    pub fn set_state(&mut self, x: SVector<f64, N>) {
        self.x = x;
    }

    /// The covariance P in SI units (computed from the factor).
    pub fn covariance(&self) -> SMatrix<f64, N, N> {
        let pz = self.scaled_covariance();
        let mut p = pz;
        for i in 0..N {
            for j in 0..N {
                p[(i, j)] = pz[(i, j)] * self.x_scale[i] * self.x_scale[j];
            }
        }
        p
    }

    /// The covariance in scaled units, P_z = S·Sᵀ.
    pub fn scaled_covariance(&self) -> SMatrix<f64, N, N> {
        let s = self.factor();
        s * s.transpose()
    }

    /// Standard deviation of each state, SI: the rows' norms of S, summed
    /// over its columns. (Inlined: the filter's step compiles it with its own
    /// vector unit.)
    #[inline(always)]
    pub fn sigma(&self) -> SVector<f64, N> {
        let mut var = [0.0; W];
        for col in &self.s[..N] {
            for (v, s) in var.iter_mut().zip(col) {
                *v += s * s;
            }
        }
        SVector::<f64, N>::from_fn(|i, _| var[i].sqrt() * self.x_scale[i])
    }

    /// Standard deviation of state `i`, SI.
    pub fn sigma_of(&self, i: usize) -> f64 {
        self.row_norm2(i).sqrt() * self.x_scale[i]
    }

    /// |row i of S|², scaled (the variance of state i): for a row among the
    /// first [`LEAD_ROWS`] of a wider S whose full columns are among the
    /// first [`LEAD_ROWS`], over those columns (the zeros beyond them would
    /// add nothing, exactly).
    fn row_norm2(&self, i: usize) -> f64 {
        if W > LEAD_ROWS && i < LEAD_ROWS && self.full_cols <= LEAD_ROWS {
            self.row_norm2_within::<LEAD_ROWS>(i)
        } else {
            self.row_norm2_within::<N>(i)
        }
    }

    /// |row i of S|² over its first `K` columns, in 4 lanes.
    #[inline(always)]
    fn row_norm2_within<const K: usize>(&self, i: usize) -> f64 {
        let mut acc = [0.0; 4];
        for (k, col) in self.s[..K].iter().enumerate() {
            acc[k % 4] += col[i] * col[i];
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3])
    }

    /// Column `i` of the gain of the update just made, SI (state units per
    /// unit of measurement `i`): K[:, i] = P⁺[:, s]/r_i for measured state `s`,
    /// the batch gain the scalar updates amount to (R is diagonal).
    #[inline(always)]
    pub fn gain_column(&self, s: usize, i: usize) -> SVector<f64, N> {
        let mut g = SVector::<f64, N>::zeros();
        // only the columns that may be non-zero in row s: the full ones and,
        // of the lower triangular rest, those up to s (the others' products
        // are zeros, which would leave the sums' bits as they are)
        let columns = self.full_cols.max(s + 1).min(N);
        for col in &self.s[..columns] {
            let c = col[s];
            for (j, v) in g.iter_mut().enumerate() {
                *v += col[j] * c;
            }
        }
        let k = self.x_scale[s] / self.r[i];
        for (j, v) in g.iter_mut().enumerate() {
            *v *= self.x_scale[j] * k;
        }
        g
    }

    /// Whether the state and the factor are finite.
    pub fn is_finite(&self) -> bool {
        // every value tested, without a branch per value (it vectorises)
        all_finite(self.x.as_slice()) & all_finite(self.s.as_flattened())
    }
}

#[cfg(test)]
mod tests;
