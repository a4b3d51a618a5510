//! The square-root filter's measurement updates: the dense one, and the
//! selector form with Potter's scalar steps.

use nalgebra::{SMatrix, SVector};

use super::kernels::{all_finite, dot, innovation_statistics, Fused, MulAdd, Separate};
use super::{fused_vector_unit, Ekf, EkfError, Innovation};

impl<const N: usize, const M: usize, const W: usize> Ekf<N, M, W> {
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

impl<const N: usize, const M: usize, const W: usize> Ekf<N, M, W> {
    /// The NIS of the innovation `nu` of measurements that read the states
    /// `states` (H a selector), against the prior's innovation covariance
    /// with `extra_var` added to its diagonal (measurement units squared),
    /// over the channels `use_channel` flags (1). Called before the update.
    pub fn selected_nis(
        &self,
        nu: &SVector<f64, M>,
        states: [usize; M],
        extra_var: [f64; M],
        use_channel: [bool; M],
    ) -> Result<f64, EkfError> {
        let c = SMatrix::<f64, M, M>::from_fn(|i, j| {
            let (si, sj) = (states[i], states[j]);
            let cross: f64 = self.s[..N].iter().map(|col| col[si] * col[sj]).sum();
            let c = self.x_scale[si] * self.x_scale[sj] * cross;
            if i == j {
                c + self.r[i] + extra_var[i]
            } else {
                c
            }
        });
        innovation_statistics(&c, nu, use_channel).map(|(_, nis)| nis)
    }
}
