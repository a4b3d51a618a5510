//! The square-root filter's time update: S⁻ from [F·S, Q^½] by the lean
//! column form, held to the dense reference, with the Householder fallback.

use nalgebra::{SMatrix, SVector};

use super::kernels::{all_finite, cholesky_columns, product_column, Fused, MulAdd, Separate};
use super::{fused_vector_unit, lower_triangularise, Ekf, EkfError, LEAD_ROWS};

impl<const N: usize, const M: usize, const W: usize> Ekf<N, M, W> {
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
    pub(super) fn predict_reference(
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
}
