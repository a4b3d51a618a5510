//! Tests of the square-root EKF: the triangularisation, agreement with the
//! covariance form, and the lean step against the dense reference.

use super::kernels::cholesky_columns;
use super::*;
use model::process::ProcessModel;
use model::rng::Rng;

#[test]
fn triangularisation_preserves_the_product() {
    let mut rng = Rng::new(7);
    for _ in 0..50 {
        let mut a = SMatrix::<f64, 5, 5>::zeros();
        let mut b = SMatrix::<f64, 5, 5>::zeros();
        for v in a.iter_mut().chain(b.iter_mut()) {
            *v = rng.normal() * 10f64.powi((rng.uniform() * 6.0) as i32 - 3);
        }
        let want = a * a.transpose() + b * b.transpose();
        lower_triangularise(&mut a, &mut b);
        let got = a * a.transpose();
        for i in 0..5 {
            for j in 0..5 {
                assert!(
                    (got[(i, j)] - want[(i, j)]).abs() <= 1e-10 * want.abs().max(),
                    "{i},{j}"
                );
                if j > i {
                    assert_eq!(a[(i, j)], 0.0);
                }
            }
        }
        assert_eq!(b, SMatrix::<f64, 5, 5>::zeros());
    }
}

/// Where the actuator's fast states couple, (row, column): spool ↔ pressures,
/// pressures ↔ rod, rod ↔ load.
const FAST_COUPLINGS: &[(usize, usize)] = &[
    (1, 0),
    (2, 0),
    (0, 5),
    (5, 0),
    (1, 4),
    (2, 4),
    (3, 4),
    (4, 1),
    (4, 2),
    (4, 6),
];

/// Where the leak sizes act on the pressures, (row, column).
const LEAK_COUPLINGS: &[(usize, usize)] = &[(1, 7), (2, 8), (1, 9), (2, 9)];

/// A Jacobian of the actuator's shape: the identity plus a coupling of
/// 1e-3·N(0, 1) in each state's own units at each of `couplings` (i, j),
/// drawn from `rng` in that order.
fn coupled_jacobian<const N: usize>(
    scale: &SVector<f64, N>,
    couplings: &[(usize, usize)],
    rng: &mut Rng,
) -> SMatrix<f64, N, N> {
    let mut f = SMatrix::<f64, N, N>::identity();
    for &(i, j) in couplings {
        f[(i, j)] = 1e-3 * rng.normal() * scale[i] / scale[j];
    }
    f
}

/// The tests' filter settings for states of typical size `scale`: process
/// noise 1e-4 and start uncertainty 0.1 of each scale, start at the scale,
/// measurement noise of a 10 µm encoder and 0.16 MPa transducers: (q, p0, x0, r).
#[allow(clippy::type_complexity)]
fn settings<const N: usize>(
    scale: &SVector<f64, N>,
) -> (SVector<f64, N>, SVector<f64, N>, SVector<f64, N>, SVector<f64, 3>) {
    (
        SVector::<f64, N>::from_fn(|i, _| (1e-4 * scale[i]).powi(2)),
        SVector::<f64, N>::from_fn(|i, _| (0.1 * scale[i]).powi(2)),
        SVector::<f64, N>::from_fn(|i, _| scale[i]),
        SVector::<f64, 3>::new(1e-10, 2.5e10, 2.5e10),
    )
}

/// The column Cholesky: L·Lᵀ = A for positive definite matrices (padded to 8
/// rows, the padding left zero), and `false` for a matrix with a pivot that
/// is zero, negative, infinite or NaN, wherever that pivot comes.
#[test]
fn the_column_cholesky_factors_or_refuses() {
    let mut rng = Rng::new(11);
    for _ in 0..50 {
        let b = SMatrix::<f64, 7, 7>::from_fn(|_, _| rng.normal());
        let a = b * b.transpose() + SMatrix::<f64, 7, 7>::identity() * 0.1;
        let mut cols = [[0.0; 8]; 7];
        for (c, col) in cols.iter_mut().enumerate() {
            for r in 0..7 {
                col[r] = a[(r, c)];
            }
        }
        assert!(cholesky_columns::<7, 8, Separate>(&mut cols));
        let l = SMatrix::<f64, 7, 7>::from_fn(|r, c| cols[c][r]);
        let back = l * l.transpose();
        assert!((back - a).abs().max() <= 1e-12 * a.abs().max());
        assert!(cols.iter().all(|col| col[7] == 0.0));
        for (c, col) in cols.iter().enumerate() {
            assert!(col[..c].iter().all(|v| *v == 0.0));
        }
    }
    // a diagonal matrix with one bad pivot, first, in the middle or last
    for bad in [0.0, -1.0, f64::INFINITY, f64::NAN] {
        for at in [0, 3, 6] {
            let mut cols = [[0.0; 8]; 7];
            for (c, col) in cols.iter_mut().enumerate() {
                col[c] = if c == at { bad } else { 2.0 };
            }
            assert!(
                !cholesky_columns::<7, 8, Separate>(&mut cols),
                "pivot {bad} at {at}"
            );
        }
    }
    // positive definite but for the last pivot: [[1, 1], [1, 1]]
    let mut cols = [[1.0, 1.0], [1.0, 1.0]];
    assert!(!cholesky_columns::<2, 2, Separate>(&mut cols));
}

/// A damped linear system of 3 states read on 2 (F, H, Q, R, P0, scale; SI).
struct LinearSystem {
    f: SMatrix<f64, 3, 3>,
    h: SMatrix<f64, 2, 3>,
    q: SVector<f64, 3>,
    r: SVector<f64, 2>,
    p0: SVector<f64, 3>,
    scale: SVector<f64, 3>,
}

fn linear_system() -> LinearSystem {
    LinearSystem {
        f: SMatrix::<f64, 3, 3>::new(1.0, 0.01, 0.0, 0.0, 1.0, 0.01, 0.0, -0.2, 0.95),
        h: SMatrix::<f64, 2, 3>::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0),
        q: SVector::<f64, 3>::new(1e-6, 1e-4, 1e-3),
        r: SVector::<f64, 2>::new(1e-2, 4e-2),
        p0: SVector::<f64, 3>::new(1.0, 2.0, 3.0),
        scale: SVector::<f64, 3>::new(1.0, 10.0, 0.1),
    }
}

/// The square-root filter agrees with the textbook covariance-form EKF on a
/// linear system.
#[test]
fn matches_the_covariance_form_on_a_linear_system() {
    let LinearSystem {
        f,
        h,
        q,
        r,
        p0,
        scale,
    } = linear_system();
    let x0 = SVector::<f64, 3>::new(0.1, -0.2, 0.3);
    let mut ekf = Ekf::<3, 2>::new(x0, &p0, &q, r, scale);
    let mut x = x0;
    let mut p = SMatrix::<f64, 3, 3>::from_diagonal(&p0);
    let mut rng = Rng::new(3);
    for _ in 0..200 {
        x = f * x;
        p = f * p * f.transpose() + SMatrix::from_diagonal(&q);
        ekf.predict(f * ekf.state(), &f).unwrap();
        let y = SVector::<f64, 2>::new(rng.normal(), rng.normal());
        let nu = y - h * x;
        let s = h * p * h.transpose() + SMatrix::from_diagonal(&r);
        let k = p * h.transpose() * s.try_inverse().unwrap();
        x += k * nu;
        p = (SMatrix::identity() - k * h) * p;
        let inn = ekf.update(&y, &(h * ekf.state()), &h, [true, true]).unwrap();
        assert!((inn.nis - nu.dot(&(s.try_inverse().unwrap() * nu))).abs() < 1e-9 * (1.0 + inn.nis));
        assert!((ekf.state() - x).norm() < 1e-9 * (1.0 + x.norm()));
        assert!((ekf.covariance() - p).norm() < 1e-9 * p.norm());
    }
}

/// The NIS of a selector measurement from the prior is νᵀ(H P Hᵀ + R + D)⁻¹ν
/// of the covariance form, D the extra variances; with D = 0 it is the
/// update's own NIS; a channel left out is left out of it.
#[test]
fn the_selected_nis_is_the_covariance_forms() {
    let LinearSystem {
        f,
        h,
        q,
        r,
        p0,
        scale,
    } = linear_system();
    let mut ekf = Ekf::<3, 2>::new(SVector::zeros(), &p0, &q, r, scale);
    let mut rng = Rng::new(5);
    for step in 0..50 {
        ekf.predict(f * ekf.state(), &f).unwrap();
        let y = SVector::<f64, 2>::new(rng.normal(), rng.normal());
        let nu = y - h * ekf.state();
        let extra = [0.0, 0.5 * (step % 3) as f64];
        let c = h * ekf.covariance() * h.transpose()
            + SMatrix::from_diagonal(&r)
            + SMatrix::from_diagonal(&SVector::from(extra));
        let want = nu.dot(&(c.try_inverse().unwrap() * nu));
        let got = ekf.selected_nis(&nu, [0, 2], extra, [true, true]).unwrap();
        assert!((got - want).abs() < 1e-9 * (1.0 + want), "{got} against {want}");
        let alone = ekf.selected_nis(&nu, [0, 2], extra, [true, false]).unwrap();
        assert!((alone - nu[0] * nu[0] / c[(0, 0)]).abs() < 1e-9 * (1.0 + alone));
        let plain = ekf.selected_nis(&nu, [0, 2], [0.0; 2], [true, true]).unwrap();
        let inn = ekf.update(&y, &(h * ekf.state()), &h, [true, true]).unwrap();
        assert!((plain - inn.nis).abs() < 1e-9 * (1.0 + inn.nis));
    }
}

/// The lean time update and the selector update give the reference's result
/// (dense W·Wᵀ, dense H) to 1e-12 of each state's scale over a long run (a sparse 11-state Jacobian of the actuator's shape,
/// three selector measurements, states spanning twenty orders of magnitude).
/// Declaring states 6.. random walks (F's rows there the identity's) gives
/// the same bits.
#[test]
fn the_lean_predict_equals_the_reference_over_a_long_run() {
    const N: usize = 11;
    let scale =
        SVector::<f64, N>::from_column_slice(&[1e-4, 1e7, 1e7, 0.1, 0.1, 1e-2, 1e3, 1e-6, 1e-6, 1e-6, 1e-5]);
    let mut rng = Rng::new(11);
    // couplings where the actuator has them: spool <-> pressures, pressures <-> rod, rod <-> load, leaks -> pressures
    let f = coupled_jacobian(
        &scale,
        &[FAST_COUPLINGS, LEAK_COUPLINGS, &[(0, 10), (1, 3), (2, 3)]].concat(),
        &mut rng,
    );
    let (q, p0, x0, r) = settings(&scale);
    let h = ProcessModel::measurement_matrix::<N>();
    // the lean filter in the width the estimator gives 11 states
    let (mut lean, mut reference) = (
        Ekf::<N, 3, 12>::new(x0, &p0, &q, r, scale),
        Ekf::<N, 3>::new(x0, &p0, &q, r, scale),
    );
    let mut walks = lean.clone();
    walks.set_random_walks_from(6);
    for k in 0..20_000 {
        let xl = f * lean.state();
        lean.predict(xl, &f).expect("lean predict");
        let xw = f * walks.state();
        walks.predict(xw, &f).expect("predict with random walks");
        let xr = f * reference.state();
        reference.predict_reference(xr, &f).expect("reference predict");
        let y = SVector::<f64, 3>::new(
            0.1 + 1e-5 * rng.normal(),
            1e7 + 5e4 * rng.normal(),
            1e7 + 5e4 * rng.normal(),
        );
        if k % 3 != 2 {
            lean.update_selected(&y, &(h * lean.state()), [3, 1, 2], [true, true, k % 5 != 0])
                .expect("lean update");
            walks
                .update_selected(&y, &(h * walks.state()), [3, 1, 2], [true, true, k % 5 != 0])
                .expect("update with random walks");
            reference
                .update(&y, &(h * reference.state()), &h, [true, true, k % 5 != 0])
                .expect("reference update");
        }
        for i in 0..N {
            let d = (lean.state()[i] - reference.state()[i]).abs() / scale[i];
            assert!(d <= 1e-12, "step {k}, state {i}: {d:e} of scale");
            assert_eq!(
                walks.state()[i].to_bits(),
                lean.state()[i].to_bits(),
                "step {k}, state {i}"
            );
        }
        assert_eq!(walks.s, lean.s, "step {k}: the factors differ");
    }
    let (pl, pr) = (lean.scaled_covariance(), reference.scaled_covariance());
    assert!(
        (pl - pr).abs().max() <= 1e-12 * pr.abs().max(),
        "{:e}",
        (pl - pr).abs().max()
    );
}

/// The lean step still equals the reference when the Jacobian's sparsity
/// changes from one step to the next and when a measurement update meets a
/// factor that is not lower triangular (two updates without a time update
/// between them); padded to 8 rows it gives the unpadded filter's bits.
#[test]
fn the_lean_step_follows_a_changing_sparsity_and_a_full_factor() {
    const N: usize = 7;
    let scale = SVector::<f64, N>::from_column_slice(&[1e-5, 1e6, 1e6, 1e-3, 1e-2, 1e-2, 1e2]);
    let mut rng = Rng::new(5);
    let mut couplings = Rng::new(6);
    let mut jacobian = |pattern: usize| {
        let mut f = SMatrix::<f64, N, N>::identity();
        for (k, &(i, j)) in FAST_COUPLINGS.iter().enumerate() {
            if !(k + pattern).is_multiple_of(3) {
                f[(i, j)] = 1e-3 * couplings.normal() * scale[i] / scale[j];
            }
        }
        f
    };
    let (q, p0, x0, r) = settings(&scale);
    let h = ProcessModel::measurement_matrix::<N>();
    // the lean filter padded to 8 rows, as the estimator runs 7 states, and
    // the same unpadded: the padding changes no bit
    let mut unpadded = Ekf::<N, 3>::new(x0, &p0, &q, r, scale);
    let (mut lean, mut reference) = (
        Ekf::<N, 3, 8>::new(x0, &p0, &q, r, scale),
        Ekf::<N, 3>::new(x0, &p0, &q, r, scale),
    );
    for k in 0..3_000 {
        let f = jacobian(k / 7);
        let xl = f * lean.state();
        lean.predict(xl, &f).expect("lean predict");
        unpadded.predict(xl, &f).expect("unpadded predict");
        let xr = f * reference.state();
        reference.predict_reference(xr, &f).expect("reference predict");
        let updates = if k.is_multiple_of(4) { 2 } else { 1 };
        for _ in 0..updates {
            let y = SVector::<f64, 3>::new(
                1e-3 + 1e-5 * rng.normal(),
                1e6 + 5e4 * rng.normal(),
                1e6 + 5e4 * rng.normal(),
            );
            let il = lean
                .update_selected(&y, &(h * lean.state()), [3, 1, 2], [true; 3])
                .expect("lean update");
            let iu = unpadded
                .update_selected(&y, &(h * unpadded.state()), [3, 1, 2], [true; 3])
                .expect("unpadded update");
            assert_eq!(il, iu, "step {k}");
            assert_eq!(lean.state(), unpadded.state(), "step {k}");
            let ir = reference
                .update(&y, &(h * reference.state()), &h, [true; 3])
                .expect("reference update");
            assert!((il.nis - ir.nis).abs() <= 1e-9 * (1.0 + ir.nis), "step {k}: NIS");
            assert!(
                (il.sigma - ir.sigma).abs().max() <= 1e-12 * ir.sigma.abs().max(),
                "step {k}: σ"
            );
        }
        for i in 0..N {
            let d = (lean.state()[i] - reference.state()[i]).abs() / scale[i];
            assert!(d <= 1e-12, "step {k}, state {i}: {d:e} of scale");
        }
    }
    let (pl, pr) = (lean.scaled_covariance(), reference.scaled_covariance());
    assert!((pl - pr).abs().max() <= 1e-12 * pr.abs().max());
}

/// Whether [`Ekf::predict`] and [`Ekf::update_selected`] run fused here.
fn dispatch_fuses() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        fused_vector_unit()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The time and selector updates give the same bits whichever way they were
/// compiled (the dispatched entry points against their portable bodies with
/// fused multiply-adds, which the C library rounds as the instruction does),
/// and the portable form with separate products and sums, which a processor
/// without FMA runs, agrees to 1e-12 of each state's scale.
#[test]
fn the_dispatched_step_equals_the_portable_one_bit_for_bit() {
    const N: usize = 12;
    let scale = SVector::<f64, N>::from_column_slice(&[
        1e-5, 1e6, 1e6, 1e-3, 1e-2, 1e-2, 1e2, 1e-6, 1e-6, 1e-6, 1e-6, 1.0,
    ]);
    let mut rng = Rng::new(9);
    let f = coupled_jacobian(
        &scale,
        &[FAST_COUPLINGS, LEAK_COUPLINGS, &[(5, 10), (1, 11)]].concat(),
        &mut rng,
    );
    let (q, p0, x0, r) = settings(&scale);
    let (mut dispatched, mut portable, mut separate) = (
        Ekf::<N, 3>::new(x0, &p0, &q, r, scale),
        Ekf::<N, 3>::new(x0, &p0, &q, r, scale),
        Ekf::<N, 3>::new(x0, &p0, &q, r, scale),
    );
    for k in 0..2_000u32 {
        let x = f * dispatched.state();
        dispatched.predict(x, &f).expect("predict");
        let fused_vectors = dispatch_fuses();
        if fused_vectors {
            portable.predict_lean::<Fused>(x, &f).expect("predict");
        } else {
            portable.predict_lean::<Separate>(x, &f).expect("predict");
        }
        let xs = f * separate.state();
        separate.predict_lean::<Separate>(xs, &f).expect("predict");
        let y = SVector::<f64, 3>::new(
            0.1 + 1e-5 * rng.normal(),
            1e7 + 5e4 * rng.normal(),
            1e7 + 5e4 * rng.normal(),
        );
        let h = ProcessModel::measure(dispatched.state());
        let a = dispatched
            .update_selected(&y, &h, [3, 1, 2], [true, true, !k.is_multiple_of(5)])
            .expect("update");
        let use_channel = [true, true, !k.is_multiple_of(5)];
        let b = if fused_vectors {
            portable.update_selected_lean::<Fused>(&y, &h, [3, 1, 2], use_channel)
        } else {
            portable.update_selected_lean::<Separate>(&y, &h, [3, 1, 2], use_channel)
        }
        .expect("update");
        let hs = ProcessModel::measure(separate.state());
        separate
            .update_selected_lean::<Separate>(&y, &hs, [3, 1, 2], use_channel)
            .expect("update");
        for i in 0..N {
            let d = (separate.state()[i] - dispatched.state()[i]).abs() / scale[i];
            assert!(d <= 1e-12, "step {k}, state {i}: {d:e} of scale");
        }
        assert_eq!(a, b, "step {k}");
        assert_eq!(dispatched.state(), portable.state(), "step {k}");
        assert_eq!(dispatched.s, portable.s, "step {k}");
    }
}

/// A Jacobian whose declared random-walk rows are not the identity's is
/// refused in a debug build (the contract [`Ekf::set_random_walks_from`] states).
#[cfg(debug_assertions)]
#[test]
#[should_panic(expected = "rows 6..11 of F are not the identity's")]
fn a_random_walk_row_that_moves_is_refused_in_debug_builds() {
    const N: usize = 11;
    let scale = SVector::<f64, N>::from_element(1.0);
    let (q, p0, x0, r) = settings(&scale);
    let mut e = Ekf::<N, 3, 12>::new(x0, &p0, &q, r, scale);
    e.set_random_walks_from(6);
    let mut f = SMatrix::<f64, N, N>::identity();
    f[(9, 1)] = 1e-3;
    let _ = e.predict(f * e.state(), &f);
}
