// Over 600 lines: one square-root filter with its predict (lean column form, the dense
// reference it is held to, the Householder fallback) and its updates (dense and selector,
// Potter's scalar steps) over one factor layout; the column kernels (product, Cholesky,
// triangularisation, from `product_column` on) could move to a module of their own.
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
            ratio,
            walks_from: N,
            work: [[0.0; W]; N],
        };
        f.reset(x0, p0_diag);
        f
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
        for col in &self.s[..N] {
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

    /// Time update: the caller has propagated the state to `x_pred` (SI) with
    /// discrete Jacobian `f_jac` = ∂x(k+1)/∂x(k) (SI).
    ///
    /// On an x86-64 processor with AVX2 and FMA the same code runs compiled
    /// for them, each multiply-add fused (one rounding instead of two; the
    /// portable build computes the same fused form where asked, [`Fused`]).
    pub fn predict(&mut self, x_pred: SVector<f64, N>, f_jac: &SMatrix<f64, N, N>) -> Result<(), EkfError> {
        #[cfg(target_arch = "x86_64")]
        if fused_vector_unit() {
            // SAFETY: the processor has AVX2 and FMA (checked just above),
            // the only requirement of a `target_feature` function.
            return unsafe { self.predict_fma(x_pred, f_jac) };
        }
        self.predict_lean::<Separate>(x_pred, f_jac)
    }

    /// [`Self::predict_lean`] compiled for AVX2 and FMA, its multiply-adds fused.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn predict_fma(&mut self, x_pred: SVector<f64, N>, f_jac: &SMatrix<f64, N, N>) -> Result<(), EkfError> {
        self.predict_lean::<Fused>(x_pred, f_jac)
    }

    /// The time update (the body of [`Self::predict`]), column by column:
    /// every operation adds a multiple of one whole column to another.
    #[inline(always)]
    pub(crate) fn predict_lean<A: MulAdd>(
        &mut self,
        x_pred: SVector<f64, N>,
        f_jac: &SMatrix<f64, N, N>,
    ) -> Result<(), EkfError> {
        debug_assert!(
            (self.walks_from..N).all(|r| (0..N).all(|c| f_jac[(r, c)] == if r == c { 1.0 } else { 0.0 })),
            "rows {}..{N} of F are not the identity's",
            self.walks_from
        );
        if W > LEAD_ROWS && self.walks_from <= LEAD_ROWS {
            self.scaled_product::<LEAD_ROWS, A>(f_jac);
        } else {
            self.scaled_product::<W, A>(f_jac);
        }
        let g = &self.work;
        // P⁻ = G·Gᵀ + Q by columns, p_c = Σ_k G[c][k]·g_k, formed in place of
        // S and factorised there. Should rounding make the factorisation fail
        // (a state with almost no variance), triangularise [G, Q^½] by
        // Householder reflections, which cannot fail.
        let (p, _) = self.s.split_at_mut(N);
        let p: &mut [[f64; W]; N] = match p.try_into() {
            Ok(p) => p,
            Err(_) => unreachable!("N ≤ W columns"),
        };
        for (c, p) in p.iter_mut().enumerate() {
            // only the lower triangle is read: the blocks of 4 rows from c's
            *p = from_block!(c, R => product_column::<N, W, R, A>(g, c));
            p[c] += self.q_var[c];
        }
        if cholesky_columns::<N, W, A>(p) {
            // every pivot was positive and finite, so is every entry of the
            // factor: only the state is left to test
            self.full_cols = 0;
            self.x = x_pred;
            return if all_finite(self.x.as_slice()) {
                Ok(())
            } else {
                Err(EkfError::NotFinite)
            };
        }
        let g = SMatrix::<f64, N, N>::from_fn(|i, c| g[c][i]);
        self.triangularise(x_pred, g)
    }

    /// G = F_z·S by columns into `work`, F_z = D⁻¹ F D the scaled Jacobian,
    /// summed in rows `0..R`. Rows `R..W` are S's: the caller has declared
    /// F's rows there the identity's (or R = W).
    #[inline(always)]
    fn scaled_product<const R: usize, A: MulAdd>(&mut self, f_jac: &SMatrix<f64, N, N>) {
        // F_z's rows 0..R by columns (nalgebra's are columns too)
        let mut fz = [[0.0; R]; N];
        for ((fz, f), r) in fz
            .iter_mut()
            .zip(f_jac.as_slice().chunks_exact(N))
            .zip(&self.ratio)
        {
            for i in 0..R.min(N) {
                fz[i] = f[i] * r[i];
            }
        }
        // g_c = Σ_j S[j][c]·fz_j, over the rows j where column c of S can be
        // non-zero (from c down, where it is lower triangular)
        let full = self.full_cols.min(N);
        for (c, (g, s)) in self.work.iter_mut().zip(&self.s[..N]).enumerate() {
            let mut acc = [0.0; R]; // in registers
            if c < full {
                // a full column: every row (a loop of fixed length), two a
                // turn (the same sums in the same order)
                let pairs = fz.chunks_exact(2);
                let rest = pairs.remainder();
                for (pair, s_j) in pairs.zip(s[..N].chunks_exact(2)) {
                    for r in 0..R {
                        acc[r] = A::mul_add(pair[0][r], s_j[0], acc[r]);
                        acc[r] = A::mul_add(pair[1][r], s_j[1], acc[r]);
                    }
                }
                for (fz, s_j) in rest.iter().zip(&s[N - rest.len()..N]) {
                    for r in 0..R {
                        acc[r] = A::mul_add(fz[r], *s_j, acc[r]);
                    }
                }
            } else {
                for j in c..N {
                    let s_j = s[j];
                    for r in 0..R {
                        acc[r] = A::mul_add(fz[j][r], s_j, acc[r]);
                    }
                }
            }
            g[..R].copy_from_slice(&acc);
            g[R..].copy_from_slice(&s[R..]);
        }
    }

    /// The time update as first written (the dense product W·Wᵀ), kept as the
    /// reference the lean one is tested against.
    #[cfg(test)]
    fn predict_reference(
        &mut self,
        x_pred: SVector<f64, N>,
        f_jac: &SMatrix<f64, N, N>,
    ) -> Result<(), EkfError> {
        let mut fz = *f_jac;
        for i in 0..N {
            for j in 0..N {
                fz[(i, j)] *= self.x_scale[j] / self.x_scale[i];
            }
        }
        let w1 = fz * self.factor();
        let mut p = w1 * w1.transpose();
        for i in 0..N {
            p[(i, i)] += self.q_var[i];
        }
        match p.cholesky() {
            Some(c) => {
                self.set_factor(&c.l(), true);
                self.x = x_pred;
                self.finite_or_error()
            }
            None => self.triangularise(x_pred, w1),
        }
    }

    /// S⁻ from [W, Q^½] by Householder reflections (the fallback that cannot fail).
    fn triangularise(&mut self, x_pred: SVector<f64, N>, mut w1: SMatrix<f64, N, N>) -> Result<(), EkfError> {
        let mut w2 = SMatrix::<f64, N, N>::from_fn(|i, j| if i == j { self.q_var[i].sqrt() } else { 0.0 });
        lower_triangularise(&mut w1, &mut w2);
        self.set_factor(&w1, true);
        self.x = x_pred;
        self.finite_or_error()
    }

    fn finite_or_error(&self) -> Result<(), EkfError> {
        if self.is_finite() {
            Ok(())
        } else {
            Err(EkfError::NotFinite)
        }
    }

    /// Measurement update with measurement `y`, predicted measurement `h_pred` = h(x⁻)
    /// and Jacobian `h_jac` = ∂h/∂x (SI); measurements whose `use_channel` flag is false
    /// are left out. Returns the innovation of the whole vector.
    pub fn update(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        h_jac: &SMatrix<f64, M, N>,
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        // Scaled measurement Jacobian H_z = H D (measurement units per scaled state).
        let mut hz = *h_jac;
        for i in 0..M {
            for j in 0..N {
                hz[(i, j)] *= self.x_scale[j];
            }
        }
        let mut s = self.factor();
        // Innovation statistics from the prior: C = H_z S Sᵀ H_zᵀ + R.
        let nu = y - h_pred;
        let hs = hz * s;
        let mut c = hs * hs.transpose();
        for i in 0..M {
            c[(i, i)] += self.r[i];
        }
        let (sigma, nis) = innovation_statistics(&c, &nu, use_channel)?;

        // Potter's update, one scalar measurement at a time.
        let mut dz = SVector::<f64, N>::zeros(); // scaled state correction so far
        for i in 0..M {
            if !use_channel[i] {
                continue;
            }
            let h = hz.row(i).transpose();
            let phi = s.transpose() * h;
            let denom = phi.dot(&phi) + self.r[i];
            if denom <= 0.0 || !denom.is_finite() {
                self.set_factor(&s, false);
                return Err(EkfError::SingularInnovation);
            }
            let a = 1.0 / denom;
            let gamma = 1.0 / (1.0 + (a * self.r[i]).sqrt());
            let k = s * phi * a;
            let resid = nu[i] - h.dot(&dz);
            dz += k * resid;
            // S ← S − γ k φᵀ, a rank-one update in place (no N×N temporary)
            s.ger(-gamma, &k, &phi, 1.0);
        }
        self.set_factor(&s, false);
        for j in 0..N {
            self.x[j] += dz[j] * self.x_scale[j];
        }
        if !self.is_finite() {
            return Err(EkfError::NotFinite);
        }
        Ok(Innovation { nu, sigma, nis })
    }
}

impl<const N: usize, const M: usize, const W: usize> Ekf<N, M, W> {
    /// [`Ekf::update`] for a measurement that reads states directly:
    /// measurement i is state `states[i]` (H is a selector, as for the rod
    /// position and the two chamber pressures). Same result as `update` with
    /// that H (to rounding), without multiplying by its zeros: each scalar
    /// update reads one row of the factor instead of forming Sᵀ·h, and the NIS
    /// is summed from the scalar updates' own innovations and variances
    /// (νᵀC⁻¹ν = Σ eᵢ²/cᵢ over the sequential innovations eᵢ, variances cᵢ).
    ///
    /// Compiled for AVX2 and FMA where the processor has them, as [`Self::predict`].
    pub fn update_selected(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        #[cfg(target_arch = "x86_64")]
        if fused_vector_unit() {
            // SAFETY: the processor has AVX2 and FMA (checked just above),
            // the only requirement of a `target_feature` function.
            return unsafe { self.update_selected_fma(y, h_pred, states, use_channel) };
        }
        self.update_selected_lean::<Separate>(y, h_pred, states, use_channel)
    }

    /// [`Self::update_selected_lean`] compiled for AVX2 and FMA, its multiply-adds fused.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn update_selected_fma(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        self.update_selected_lean::<Fused>(y, h_pred, states, use_channel)
    }

    /// The selector update (the body of [`Self::update_selected`]).
    #[inline(always)]
    pub(crate) fn update_selected_lean<A: MulAdd>(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        self.update_selected_choosing::<A>(y, h_pred, states, |_, _| use_channel)
    }

    /// [`Self::update_selected_lean`] with the channels that update chosen
    /// by `choose` from the innovations and their prior σ (measurement
    /// units), both computed once here.
    #[inline(always)]
    pub(crate) fn update_selected_choosing<A: MulAdd>(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        choose: impl FnOnce(&SVector<f64, M>, &SVector<f64, M>) -> [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        let nu = y - h_pred;
        // The columns the measured rows of S can have non-zeros in: those up
        // to the highest measured state, and any full ones (the rank-one
        // updates below write only these columns, so the rest stay lower
        // triangular from one scalar update to the next).
        let support = match states.iter().max() {
            Some(m) => (m + 1).max(self.full_cols).min(N),
            None => N,
        };

        // The measured rows reach 4 columns in the layouts here (the rod
        // position is state 3): a pass with that many columns fixed at
        // compile time; any other reach takes all N.
        // σ of each innovation from the prior, then the updates.
        let (sigma, nis) = match support {
            4 if N >= 4 => {
                let sigma = self.innovation_sigma::<4>(states);
                let use_channel = choose(&nu, &sigma);
                (sigma, self.potter::<4, A>(&nu, states, use_channel)?)
            }
            _ => {
                let sigma = self.innovation_sigma::<N>(states);
                let use_channel = choose(&nu, &sigma);
                (sigma, self.potter::<N, A>(&nu, states, use_channel)?)
            }
        };
        // Each scalar update passed a positive finite variance, so the
        // factor's new columns are finite; a non-finite innovation shows in
        // the state and the NIS.
        if !(all_finite(self.x.as_slice()) && nis.is_finite()) {
            return Err(EkfError::NotFinite);
        }
        Ok(Innovation { nu, sigma, nis })
    }
}

impl<const N: usize, const M: usize, const W: usize> Ekf<N, M, W> {
    /// σ of each innovation from the prior, C_ii = c_i²·|row s_i of S|² + r_i
    /// (measurement units), for an S whose measured rows have non-zeros in
    /// their first `K` columns only: |row|² over those (the zeros beyond
    /// them would add nothing, exactly).
    #[inline(always)]
    fn innovation_sigma<const K: usize>(&self, states: [usize; M]) -> SVector<f64, M> {
        SVector::<f64, M>::from_fn(|i, _| {
            let (si, ci) = (states[i], self.x_scale[states[i]]);
            (ci * ci * self.row_norm2_within::<K>(si) + self.r[i])
                .max(0.0)
                .sqrt()
        })
    }

    /// Potter's update, one scalar measurement at a time (φ = Sᵀh is a row of
    /// S), for an S whose measured rows have non-zeros in their first `K`
    /// columns only (the rank-one updates write only these, so it stays so);
    /// returns the NIS, Σ eᵢ²/cᵢ over the sequential innovations.
    #[inline(always)]
    fn potter<const K: usize, A: MulAdd>(
        &mut self,
        nu: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<f64, EkfError> {
        let mut dz = [0.0; W]; // scaled state correction so far
        let mut nis = 0.0;
        for i in 0..M {
            if !use_channel[i] {
                continue;
            }
            let (si, ci) = (states[i], self.x_scale[states[i]]);
            let mut phi = [0.0; K];
            for (p, col) in phi.iter_mut().zip(&self.s) {
                *p = ci * col[si];
            }
            let denom = dot::<K, A>(&phi, &phi) + self.r[i];
            // (positive and finite; `< ∞` rather than `is_finite`, which compiles longer)
            if !(denom > 0.0 && denom < f64::INFINITY) {
                return Err(EkfError::SingularInnovation);
            }
            // k = a·S·φ with a = 1/denom, and S ← S − γ k φᵀ with Potter's
            // γ = 1/(1 + √(a·r)): a·γ = 1/(denom + √denom·√r), one division
            // after the square root instead of two around it.
            let a = 1.0 / denom;
            let ag = 1.0 / (denom + denom.sqrt() * self.r_sqrt[i]);
            let mut u = [0.0; W]; // S·φ = Σ_k φ_k·s_k
            for (col, p) in self.s.iter().zip(&phi) {
                for (u, s) in u.iter_mut().zip(col) {
                    *u = A::mul_add(*s, *p, *u);
                }
            }
            let resid = nu[i] - ci * dz[si];
            nis += resid * resid * a;
            let step = resid * a;
            for (d, u) in dz.iter_mut().zip(&u) {
                *d = A::mul_add(*u, step, *d);
            }
            for (col, p) in self.s.iter_mut().zip(&phi) {
                let g = ag * p;
                for (v, u) in col.iter_mut().zip(&u) {
                    *v = A::mul_add(-g, *u, *v);
                }
            }
            self.full_cols = self.full_cols.max(K);
        }
        for ((x, d), c) in self.x.iter_mut().zip(&dz).zip(&self.x_scale) {
            *x += d * c;
        }
        Ok(nis)
    }
}

/// Whether this x86-64 processor has AVX2 and FMA (detected once, then cached by std).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn fused_vector_unit() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// How the filter's kernels compute a·b + c.
pub(crate) trait MulAdd {
    /// a·b + c.
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
}

/// a·b + c rounded once (an FMA instruction where the code is compiled for
/// one, else the C library's correctly rounded `fma`: the same bits).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))] // dispatched to on x86-64 only
pub(crate) struct Fused;

/// a·b rounded, then the sum rounded: what a processor without FMA does fast.
pub(crate) struct Separate;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

/// Column c of G·Gᵀ (G by columns) in the rows from `R` on (the others zero).
#[inline(always)]
fn product_column<const N: usize, const W: usize, const R: usize, A: MulAdd>(
    g: &[[f64; W]; N],
    c: usize,
) -> [f64; W] {
    // in registers; two columns of G a turn (the same sums in the same
    // order), so that the loop's own count and jump come half as often
    let mut acc = [0.0; W];
    let pairs = g.chunks_exact(2);
    let rest = pairs.remainder();
    for pair in pairs {
        let (a0, a1) = (pair[0][c], pair[1][c]);
        for r in R.min(W)..W {
            acc[r] = A::mul_add(pair[0][r], a0, acc[r]);
            acc[r] = A::mul_add(pair[1][r], a1, acc[r]);
        }
    }
    for g_k in rest {
        let a = g_k[c];
        for r in R.min(W)..W {
            acc[r] = A::mul_add(g_k[r], a, acc[r]);
        }
    }
    acc
}

/// Whether every value is positive and finite, tested together: finite by
/// [`all_finite`], positive by their least. (A test per value, `v > 0.0 &&
/// v.is_finite()`, compiles to some 20 integer instructions each.)
#[inline(always)]
fn all_positive_finite(values: &[f64]) -> bool {
    all_finite(values) && values.iter().fold(f64::INFINITY, |m, v| m.min(*v)) > 0.0
}

/// Whether every value is finite: v·0 is 0 for a finite v and NaN for an
/// infinity or a NaN, summed in 4 independent lanes (no branch per value,
/// and no sum waiting on each addition in turn).
#[inline(always)]
fn all_finite(values: &[f64]) -> bool {
    let mut lanes = [0.0; 4];
    let chunks = values.chunks_exact(4);
    let rest = chunks.remainder();
    for c in chunks {
        for (l, v) in lanes.iter_mut().zip(c) {
            *l += v * 0.0;
        }
    }
    for (l, v) in lanes.iter_mut().zip(rest) {
        *l += v * 0.0;
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) == 0.0
}

/// The σ of each innovation (√ of C's diagonal) and the NIS νᵀC⁻¹ν over the
/// channels in use (the others replaced by unit rows), as |L⁻¹ν|² with C = L·Lᵀ.
fn innovation_statistics<const M: usize>(
    c: &SMatrix<f64, M, M>,
    nu: &SVector<f64, M>,
    use_channel: [bool; M],
) -> Result<(SVector<f64, M>, f64), EkfError> {
    let sigma = SVector::<f64, M>::from_fn(|i, _| c[(i, i)].max(0.0).sqrt());
    let mut cu = [[0.0; M]; M];
    let mut z = [0.0; M];
    for i in 0..M {
        for j in 0..=i {
            cu[i][j] = if use_channel[i] && use_channel[j] {
                c[(i, j)]
            } else {
                f64::from(u8::from(i == j))
            };
        }
        z[i] = if use_channel[i] { nu[i] } else { 0.0 };
    }
    if !cholesky_rows(&mut cu) {
        return Err(EkfError::SingularInnovation);
    }
    let mut nis = 0.0;
    for i in 0..M {
        let mut v = z[i];
        for j in 0..i {
            v -= cu[i][j] * z[j];
        }
        z[i] = v / cu[i][i];
        nis += z[i] * z[i];
    }
    Ok((sigma, nis))
}

/// The dot product of two rows, in four independent partial sums (a single
/// running sum would wait on each addition in turn).
#[inline(always)]
fn dot<const N: usize, A: MulAdd>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (a4.remainder(), b4.remainder());
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            acc[k] = A::mul_add(x[k], y[k], acc[k]);
        }
    }
    for (k, (x, y)) in ar.iter().zip(br).enumerate() {
        acc[k] = A::mul_add(*x, *y, acc[k]);
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// Overwrites `a` (the columns of a symmetric N×N matrix A, padded to `W`
/// rows that are zero) with its Cholesky factor L by columns, L·Lᵀ = A.
/// Only the lower triangle of A is read; L is zero above the diagonal and
/// in the padding. Returns false (and `a` is garbage) if A is not
/// numerically positive definite (a pivot not positive and finite).
///
/// Computed as A = L₁·D·L₁ᵀ (L₁ unit lower triangular), then L = L₁·D^½: the
/// chain from one pivot to the next is one division, a product and a
/// difference; the square roots come after, independent of each other.
/// Left-looking: each column, held in registers, takes from every earlier
/// finished column a multiple of it, in the rows from the column's block of
/// 4 down (the rows above the diagonal there take garbage, cleared at the
/// end), so every operation is a multiple of one column added to another.
/// These are the right-looking order's operations, in the same order for
/// each column (the same bits), without storing and loading a column once
/// per pivot before it.
/// The pivots are tested together at the end (a bad one makes the later ones
/// garbage, never a panic): one test instead of one per pivot.
#[inline(always)]
fn cholesky_columns<const N: usize, const W: usize, A: MulAdd>(a: &mut [[f64; W]; N]) -> bool {
    let (mut pivots, mut inverses) = ([0.0; N], [0.0; N]);
    for c in 0..N {
        // only the rows from c's block of 4 down are read again
        let col = from_block!(c, R => eliminated_column::<N, W, R, A>(a, &inverses, c));
        a[c] = col;
        pivots[c] = col[c];
        inverses[c] = 1.0 / col[c];
    }
    // every pivot finite (NaN and infinities fail all_finite) and the least positive
    if !all_positive_finite(&pivots) {
        return false;
    }
    // column j of L is column j of L₁·D (as it stands) times 1/d_j·√d_j
    // (below the diagonal: the rows above are cleared, from j's block of 4 down)
    for (j, col) in a.iter_mut().enumerate() {
        let root = pivots[j].sqrt();
        let scale = inverses[j] * root;
        from_block!(j, R => scale_below::<W, R>(col, scale));
        col[..j].fill(0.0);
        col[j] = root;
    }
    true
}

/// Multiplies rows `R..W` of `col` by `scale`.
#[inline(always)]
fn scale_below<const W: usize, const R: usize>(col: &mut [f64; W], scale: f64) {
    for v in &mut col[R.min(W)..] {
        *v *= scale;
    }
}

/// Column `c` of `a` less the multiples of the finished columns before it
/// (`inverses`: their pivots' inverses), in rows `R..W`; rows above keep
/// `a`'s values.
#[inline(always)]
fn eliminated_column<const N: usize, const W: usize, const R: usize, A: MulAdd>(
    a: &[[f64; W]; N],
    inverses: &[f64; N],
    c: usize,
) -> [f64; W] {
    let mut col = a[c];
    for (j, done) in a[..c].iter().enumerate() {
        let l = done[c] * inverses[j];
        for r in R.min(W)..W {
            col[r] = A::mul_add(-l, done[r], col[r]);
        }
    }
    col
}

/// The Cholesky factor of the lower triangle of `a` (rows) in place, by
/// [`cholesky_columns`] on its transpose (a symmetric matrix is its own).
fn cholesky_rows<const N: usize>(a: &mut [[f64; N]; N]) -> bool {
    let mut cols = [[0.0; N]; N];
    for (i, row) in a.iter().enumerate() {
        for (j, v) in row.iter().enumerate().take(i + 1) {
            cols[j][i] = *v;
            cols[i][j] = *v;
        }
    }
    if !cholesky_columns::<N, N, Separate>(&mut cols) {
        return false;
    }
    for (i, row) in a.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = cols[j][i];
        }
    }
    true
}

/// Replaces the N×2N matrix [w1 | w2] by [L | 0] with L lower triangular and
/// L·Lᵀ = w1·w1ᵀ + w2·w2ᵀ (Householder reflections applied from the right).
pub fn lower_triangularise<const N: usize>(w1: &mut SMatrix<f64, N, N>, w2: &mut SMatrix<f64, N, N>) {
    for i in 0..N {
        // The reflector acts on columns i..N of w1 and all columns of w2, along row i.
        let mut norm2 = 0.0;
        for j in i..N {
            norm2 += w1[(i, j)] * w1[(i, j)];
        }
        for j in 0..N {
            norm2 += w2[(i, j)] * w2[(i, j)];
        }
        let norm = norm2.sqrt();
        if norm == 0.0 {
            continue;
        }
        let x0 = w1[(i, i)];
        let alpha = if x0 > 0.0 { -norm } else { norm };
        // v = x − α e_i; vᵀv = 2 (norm² − α x0)
        let v0 = x0 - alpha;
        let vtv = 2.0 * (norm2 - alpha * x0);
        if vtv == 0.0 {
            continue;
        }
        for r in i..N {
            // dot of row r with v
            let mut d = w1[(r, i)] * v0;
            for j in i + 1..N {
                d += w1[(r, j)] * w1[(i, j)];
            }
            for j in 0..N {
                d += w2[(r, j)] * w2[(i, j)];
            }
            let g = 2.0 * d / vtv;
            if r == i {
                continue; // row i is set below
            }
            w1[(r, i)] -= g * v0;
            for j in i + 1..N {
                w1[(r, j)] -= g * w1[(i, j)];
            }
            for j in 0..N {
                w2[(r, j)] -= g * w2[(i, j)];
            }
        }
        w1[(i, i)] = alpha;
        for j in i + 1..N {
            w1[(i, j)] = 0.0;
        }
        for j in 0..N {
            w2[(i, j)] = 0.0;
        }
    }
}

#[cfg(test)]
mod tests;
