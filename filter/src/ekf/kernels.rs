//! The column kernels of the square-root filter: products, Cholesky
//! factorisation and triangularisation over a factor held by columns, with
//! the multiply-add each is compiled with.

use nalgebra::{SMatrix, SVector};

use super::EkfError;

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
pub(super) fn product_column<const N: usize, const W: usize, const R: usize, A: MulAdd>(
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
pub(super) fn all_positive_finite(values: &[f64]) -> bool {
    all_finite(values) && values.iter().fold(f64::INFINITY, |m, v| m.min(*v)) > 0.0
}

/// Whether every value is finite: v·0 is 0 for a finite v and NaN for an
/// infinity or a NaN, summed in 4 independent lanes (no branch per value,
/// and no sum waiting on each addition in turn).
#[inline(always)]
pub(super) fn all_finite(values: &[f64]) -> bool {
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
pub(super) fn innovation_statistics<const M: usize>(
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
pub(super) fn dot<const N: usize, A: MulAdd>(a: &[f64; N], b: &[f64; N]) -> f64 {
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
pub(super) fn cholesky_columns<const N: usize, const W: usize, A: MulAdd>(a: &mut [[f64; W]; N]) -> bool {
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
pub(super) fn scale_below<const W: usize, const R: usize>(col: &mut [f64; W], scale: f64) {
    for v in &mut col[R.min(W)..] {
        *v *= scale;
    }
}

/// Column `c` of `a` less the multiples of the finished columns before it
/// (`inverses`: their pivots' inverses), in rows `R..W`; rows above keep
/// `a`'s values.
#[inline(always)]
pub(super) fn eliminated_column<const N: usize, const W: usize, const R: usize, A: MulAdd>(
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
pub(super) fn cholesky_rows<const N: usize>(a: &mut [[f64; N]; N]) -> bool {
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
