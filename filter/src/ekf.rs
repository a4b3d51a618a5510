//! A generic square-root extended Kalman filter over static sizes.
//!
//! The covariance is carried as a factor S with P = S·Sᵀ, so it is symmetric
//! positive semi-definite by construction and never loses definiteness to
//! rounding, whatever the units (the thesis' P0 = 1e4·I mixes m² and Pa² over
//! twenty orders of magnitude; a Joseph-form update loses definiteness on it,
//! MODEL.md §8). On top of that, all covariance algebra runs in scaled units
//! z = x / scale, so that every state is O(1).
//!
//! - Predict: S⁻ = triangular factor of [F·S, Q^½]: the Cholesky factor of
//!   (F·S)(F·S)ᵀ + Q, or, should that fail to rounding, Householder reflections.
//! - Update: Potter's square-root update, one measurement at a time (R diagonal).
//!
//! Nothing here allocates: all matrices are nalgebra static sizes.

use nalgebra::{SMatrix, SVector};

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

/// A square-root EKF with `N` states and `M` measurements.
#[derive(Debug, Clone)]
pub struct Ekf<const N: usize, const M: usize> {
    /// State estimate, SI units.
    x: SVector<f64, N>,
    /// Covariance factor in scaled units, P_z = S·Sᵀ, by rows (`s[i]` is row i:
    /// the time update and the selector update read rows, contiguous here).
    s: [[f64; N]; N],
    /// Whether S is lower triangular (after a reset, a re-anchoring or a time
    /// update; a measurement update fills it in): a selector update then reads
    /// only the columns up to the highest measured state.
    lower: bool,
    /// Typical magnitude of each state (its unit of scaling), SI.
    x_scale: SVector<f64, N>,
    /// Process noise standard deviations per step, scaled.
    q_sqrt: SVector<f64, N>,
    /// Measurement noise variances, SI.
    r: SVector<f64, M>,
    /// Measurement noise standard deviations √r, SI (Potter's γ).
    r_sqrt: SVector<f64, M>,
    /// x_scale[j] / x_scale[i], precomputed for scaling Jacobians.
    ratio: SMatrix<f64, N, N>,
    /// The sparsity of the last Jacobian: bit i of `f_masks[j]` is set when
    /// F[i, j] ≠ 0, and `f_rows[j][..f_counts[j]]` lists those rows. A process
    /// model's Jacobian keeps its pattern from one step to the next, so the
    /// time update walks the list instead of testing every entry (a branch
    /// per entry, whose pattern the branch predictor does not hold).
    f_masks: [u64; N],
    f_rows: [[u8; N]; N],
    f_counts: [u8; N],
}

impl<const N: usize, const M: usize> Ekf<N, M> {
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
        let ratio = SMatrix::<f64, N, N>::from_fn(|i, j| x_scale[j] / x_scale[i]);
        let mut f = Ekf {
            x: x0,
            s: [[0.0; N]; N],
            lower: true,
            x_scale,
            q_sqrt: SVector::zeros(),
            r: r_diag,
            r_sqrt: r_diag.map(|r| r.max(0.0).sqrt()),
            ratio,
            f_masks: [0; N],
            f_rows: [[0; N]; N],
            f_counts: [0; N],
        };
        for i in 0..N {
            f.q_sqrt[i] = q_diag[i].max(0.0).sqrt() / x_scale[i];
        }
        f.reset(x0, p0_diag);
        f
    }

    /// Restarts the filter at `x0` with covariance diag(`p0_diag`) (SI).
    pub fn reset(&mut self, x0: SVector<f64, N>, p0_diag: &SVector<f64, N>) {
        self.x = x0;
        self.s = [[0.0; N]; N];
        for i in 0..N {
            self.s[i][i] = p0_diag[i].max(0.0).sqrt() / self.x_scale[i];
        }
        self.lower = true;
    }

    /// S as a matrix (scaled units).
    fn factor(&self) -> SMatrix<f64, N, N> {
        SMatrix::from_fn(|i, j| self.s[i][j])
    }

    /// Sets S from a matrix (scaled units).
    fn set_factor(&mut self, m: &SMatrix<f64, N, N>, lower: bool) {
        for (i, row) in self.s.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = m[(i, j)];
            }
        }
        self.lower = lower;
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

    /// Standard deviation of each state, SI.
    pub fn sigma(&self) -> SVector<f64, N> {
        let mut out = SVector::<f64, N>::zeros();
        for i in 0..N {
            out[i] = self.sigma_of(i);
        }
        out
    }

    /// Standard deviation of state `i`, SI.
    pub fn sigma_of(&self, i: usize) -> f64 {
        dot(&self.s[i], &self.s[i]).sqrt() * self.x_scale[i]
    }

    /// Whether the state and the factor are finite.
    pub fn is_finite(&self) -> bool {
        // every value tested, without a branch per value (it vectorises)
        let finite = |m: &[f64]| m.iter().fold(true, |all, v| all & v.is_finite());
        finite(self.x.as_slice()) & finite(self.s.as_flattened())
    }

    /// Time update: the caller has propagated the state to `x_pred` (SI) with
    /// discrete Jacobian `f_jac` = ∂x(k+1)/∂x(k) (SI).
    ///
    /// On an x86-64 processor with AVX2 the same code runs compiled for it
    /// (twice the vector width; Rust contracts no multiply-add into an FMA, so
    /// the results are the same bit for bit either way).
    pub fn predict(&mut self, x_pred: SVector<f64, N>, f_jac: &SMatrix<f64, N, N>) -> Result<(), EkfError> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above), the only
            // requirement of a `target_feature(enable = "avx2")` function.
            return unsafe { self.predict_avx2(x_pred, f_jac) };
        }
        self.predict_lean(x_pred, f_jac)
    }

    /// [`Self::predict_lean`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn predict_avx2(&mut self, x_pred: SVector<f64, N>, f_jac: &SMatrix<f64, N, N>) -> Result<(), EkfError> {
        self.predict_lean(x_pred, f_jac)
    }

    /// The time update (the body of [`Self::predict`]).
    #[inline(always)]
    fn predict_lean(&mut self, x_pred: SVector<f64, N>, f_jac: &SMatrix<f64, N, N>) -> Result<(), EkfError> {
        // Rows of W = F_z·S with the scaled Jacobian F_z = D⁻¹ F D; F is sparse
        // (the process couples each state to a few others), so each of its
        // non-zeros adds a multiple of one row of S to one row of W.
        self.note_sparsity(f_jac.as_slice());
        let (f, ratio) = (f_jac.as_slice(), self.ratio.as_slice());
        let mut w = [[0.0; N]; N];
        for (j, (f_col, r_col)) in f.chunks_exact(N).zip(ratio.chunks_exact(N)).enumerate() {
            let s_j = &self.s[j];
            for &i in &self.f_rows[j][..usize::from(self.f_counts[j])] {
                let i = usize::from(i);
                let fz = f_col[i] * r_col[i];
                for (w, s) in w[i].iter_mut().zip(s_j) {
                    *w += fz * s;
                }
            }
        }
        // Fast path: P⁻ = W Wᵀ + Q is a sum of positive semi-definite terms; its
        // Cholesky factor is S⁻. Only its lower triangle is formed (the
        // factorisation reads nothing else), each entry a dot product of two
        // contiguous rows of W. Should rounding make the factorisation fail (a
        // state with almost no variance), triangularise [W, Q^½] by Householder
        // reflections, which cannot fail.
        let mut p = [[0.0; N]; N];
        for (i, (p_i, w_i)) in p.iter_mut().zip(&w).enumerate() {
            // two entries at a time, sharing the loads of row i
            let mut j = 0;
            while j < i {
                (p_i[j], p_i[j + 1]) = dot_pair(w_i, &w[j], &w[j + 1]);
                j += 2;
            }
            if j == i {
                p_i[i] = dot(w_i, w_i);
            }
            p_i[i] += self.q_sqrt[i] * self.q_sqrt[i];
        }
        if cholesky_rows(&mut p) {
            self.s = p;
            self.lower = true;
            self.x = x_pred;
            return self.finite_or_error();
        }
        let w1 = SMatrix::<f64, N, N>::from_fn(|i, c| w[i][c]);
        self.triangularise(x_pred, w1)
    }

    /// Brings the list of F's non-zeros (`f`, column-major) up to date: a test
    /// of every entry without a branch, and the list built again only when the
    /// pattern changed.
    #[inline(always)]
    fn note_sparsity(&mut self, f: &[f64]) {
        const { assert!(N <= 64, "the sparsity masks hold 64 rows") };
        let mut masks = [0u64; N];
        for (m, f_col) in masks.iter_mut().zip(f.chunks_exact(N)) {
            for (i, v) in f_col.iter().enumerate() {
                *m |= u64::from(*v != 0.0) << i;
            }
        }
        if masks == self.f_masks {
            return;
        }
        for (j, mask) in masks.iter().enumerate() {
            let mut n = 0;
            for i in 0..N {
                if mask & (1 << i) != 0 {
                    self.f_rows[j][n] = i as u8;
                    n += 1;
                }
            }
            self.f_counts[j] = n as u8;
        }
        self.f_masks = masks;
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
                fz[(i, j)] *= self.ratio[(i, j)];
            }
        }
        let w1 = fz * self.factor();
        let mut p = w1 * w1.transpose();
        for i in 0..N {
            p[(i, i)] += self.q_sqrt[i] * self.q_sqrt[i];
        }
        self.finish_predict(x_pred, p, w1)
    }

    /// The end of a time update from P⁻ (its lower triangle, scaled) and W = F·S:
    /// S⁻ by Cholesky, else by triangularising [W, Q^½]; the state becomes `x_pred`.
    #[cfg(test)]
    fn finish_predict(
        &mut self,
        x_pred: SVector<f64, N>,
        p: SMatrix<f64, N, N>,
        w1: SMatrix<f64, N, N>,
    ) -> Result<(), EkfError> {
        let mut p_rows = [[0.0; N]; N];
        for (i, row) in p_rows.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate().take(i + 1) {
                *v = p[(i, j)];
            }
        }
        if cholesky_rows(&mut p_rows) {
            self.s = p_rows;
            self.lower = true;
            self.x = x_pred;
            return self.finite_or_error();
        }
        self.triangularise(x_pred, w1)
    }

    /// S⁻ from [W, Q^½] by Householder reflections (the fallback that cannot fail).
    fn triangularise(&mut self, x_pred: SVector<f64, N>, mut w1: SMatrix<f64, N, N>) -> Result<(), EkfError> {
        let mut w2 = SMatrix::<f64, N, N>::from_diagonal(&self.q_sqrt);
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

impl<const N: usize, const M: usize> Ekf<N, M> {
    /// [`Ekf::update`] for a measurement that reads states directly:
    /// measurement i is state `states[i]` (H is a selector, as for the rod
    /// position and the two chamber pressures). Same result as `update` with
    /// that H (to rounding), without multiplying by its zeros: each scalar
    /// update reads one row of the factor instead of forming Sᵀ·h, and the NIS
    /// is summed from the scalar updates' own innovations and variances
    /// (νᵀC⁻¹ν = Σ eᵢ²/cᵢ over the sequential innovations eᵢ, variances cᵢ).
    ///
    /// Compiled for AVX2 where the processor has it, as [`Self::predict`].
    pub fn update_selected(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above), the only
            // requirement of a `target_feature(enable = "avx2")` function.
            return unsafe { self.update_selected_avx2(y, h_pred, states, use_channel) };
        }
        self.update_selected_lean(y, h_pred, states, use_channel)
    }

    /// [`Self::update_selected_lean`] compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn update_selected_avx2(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        self.update_selected_lean(y, h_pred, states, use_channel)
    }

    /// The selector update (the body of [`Self::update_selected`]).
    #[inline(always)]
    fn update_selected_lean(
        &mut self,
        y: &SVector<f64, M>,
        h_pred: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<Innovation<M>, EkfError> {
        let nu = y - h_pred;
        // σ of each innovation from the prior: C_ii = c_i²·|row s_i of S|² + r_i.
        let sigma = SVector::<f64, M>::from_fn(|i, _| {
            let (si, ci) = (states[i], self.x_scale[states[i]]);
            (ci * ci * dot(&self.s[si], &self.s[si]) + self.r[i])
                .max(0.0)
                .sqrt()
        });
        // The columns the measured rows of S can have non-zeros in: all, or, for
        // a lower triangular S, those up to the highest measured state (the
        // rank-one updates below write only these columns, so it stays so
        // from one scalar update to the next).
        let support = match states.iter().max() {
            Some(m) if self.lower => (m + 1).min(N),
            _ => N,
        };

        // The measured rows of a lower triangular S reach 4 columns in the
        // layouts here (the rod position is state 3): a pass with that many
        // columns fixed at compile time; any other reach takes all N.
        let nis = match support {
            4 => self.potter::<4>(&nu, states, use_channel)?,
            _ => self.potter::<N>(&nu, states, use_channel)?,
        };
        if !self.is_finite() {
            return Err(EkfError::NotFinite);
        }
        Ok(Innovation { nu, sigma, nis })
    }
}

impl<const N: usize, const M: usize> Ekf<N, M> {
    /// Potter's update, one scalar measurement at a time (φ = Sᵀh is a row of
    /// S), for an S whose measured rows have non-zeros in their first `K`
    /// columns only (the rank-one updates write only these, so it stays so);
    /// returns the NIS, Σ eᵢ²/cᵢ over the sequential innovations.
    #[inline(always)]
    fn potter<const K: usize>(
        &mut self,
        nu: &SVector<f64, M>,
        states: [usize; M],
        use_channel: [bool; M],
    ) -> Result<f64, EkfError> {
        let mut dz = [0.0; N]; // scaled state correction so far
        let mut phi = [0.0; K];
        let mut nis = 0.0;
        for i in 0..M {
            if !use_channel[i] {
                continue;
            }
            let (si, ci) = (states[i], self.x_scale[states[i]]);
            for (p, s) in phi.iter_mut().zip(&self.s[si]) {
                *p = ci * s;
            }
            let denom = dot(&phi, &phi) + self.r[i];
            if !(denom > 0.0 && denom.is_finite()) {
                return Err(EkfError::SingularInnovation);
            }
            // k = a·S·φ with a = 1/denom, and S ← S − γ k φᵀ with Potter's
            // γ = 1/(1 + √(a·r)): a·γ = 1/(denom + √denom·√r), one division
            // after the square root instead of two around it.
            let a = 1.0 / denom;
            let ag = 1.0 / (denom + denom.sqrt() * self.r_sqrt[i]);
            let mut u = [0.0; N]; // S·φ
            for (u, row) in u.iter_mut().zip(&self.s) {
                let mut acc = 0.0;
                for (x, p) in row.iter().zip(&phi) {
                    acc += x * p;
                }
                *u = acc;
            }
            let resid = nu[i] - ci * dz[si];
            nis += resid * resid * a;
            let step = resid * a;
            for (d, u) in dz.iter_mut().zip(&u) {
                *d += u * step;
            }
            for (row, u) in self.s.iter_mut().zip(&u) {
                let g = ag * u;
                for (v, p) in row.iter_mut().zip(&phi) {
                    *v -= g * p;
                }
            }
            self.lower = false;
        }
        for ((x, d), c) in self.x.iter_mut().zip(&dz).zip(&self.x_scale) {
            *x += d * c;
        }
        Ok(nis)
    }
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
fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (a4.remainder(), b4.remainder());
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    for (k, (x, y)) in ar.iter().zip(br).enumerate() {
        acc[k] += x * y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// The dot products a·b and a·c, each summed as [`dot`] sums it (so the same
/// bit for bit), with the loads of `a` shared.
#[inline(always)]
fn dot_pair<const N: usize>(a: &[f64; N], b: &[f64; N], c: &[f64; N]) -> (f64, f64) {
    let mut ab = [0.0; 4];
    let mut ac = [0.0; 4];
    let (a4, b4, c4) = (a.chunks_exact(4), b.chunks_exact(4), c.chunks_exact(4));
    let (ar, br, cr) = (a4.remainder(), b4.remainder(), c4.remainder());
    for ((x, y), z) in a4.zip(b4).zip(c4) {
        for k in 0..4 {
            ab[k] += x[k] * y[k];
            ac[k] += x[k] * z[k];
        }
    }
    for (k, ((x, y), z)) in ar.iter().zip(br).zip(cr).enumerate() {
        ab[k] += x * y;
        ac[k] += x * z;
    }
    (
        (ab[0] + ab[1]) + (ab[2] + ab[3]),
        (ac[0] + ac[1]) + (ac[2] + ac[3]),
    )
}

/// Overwrites the lower triangle of `a` (rows; the symmetric matrix A whose
/// lower triangle it holds) with its Cholesky factor L, L·Lᵀ = A. The upper
/// triangle is scratch (what it held is ignored) and is left zero. Returns false (and `a` is garbage) if
/// A is not numerically positive definite (a pivot not positive and finite).
///
/// Computed as A = L₁·D·L₁ᵀ (L₁ unit lower triangular), then L = L₁·D^½: the
/// chain from one pivot to the next is one division, a product and a
/// difference; the square roots come after, independent of each other.
/// Right-looking: each column, once scaled, updates the trailing rows, each
/// over its whole length (a fixed-length loop without a remainder; the
/// column is zero up to the pivot, so the entries left of it keep their
/// values, and what lands right of the diagonal is cleared at the end).
#[allow(clippy::needless_range_loop)] // index loops: bounds the optimiser sees through
#[inline(always)]
fn cholesky_rows<const N: usize>(a: &mut [[f64; N]; N]) -> bool {
    let mut pivots = [0.0; N];
    for j in 0..N {
        let d = a[j][j];
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        pivots[j] = d;
        let inv = 1.0 / d;
        let mut col = [0.0; N];
        for i in j + 1..N {
            col[i] = a[i][j];
        }
        for i in j + 1..N {
            let l = col[i] * inv;
            // the whole row: col is 0 up to j, and what lands right of the
            // diagonal is cleared below
            for c in 0..N {
                a[i][c] -= l * col[c];
            }
            a[i][j] = l;
        }
    }
    for i in 0..N {
        for j in 0..N {
            if j < i {
                a[i][j] *= pivots[j].sqrt();
            } else if j > i {
                a[i][j] = 0.0;
            }
        }
        a[i][i] = pivots[i].sqrt();
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
