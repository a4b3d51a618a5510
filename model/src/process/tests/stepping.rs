//! The discrete step: end stops, θ's velocity column, the random walks, the symplectic step.

use super::*;

/// The end stops are in the model as the rig has them (a spring-damper beyond
/// each end of the stroke): pressed δ into a stop and moving in at 1 mm/s, the
/// rod's acceleration is (A(p1 − p2) − F_e ∓ (k·δ + c·|v|))/m with its slopes
/// −k/m and −c/m in A; the step there takes [`STOP_SUBSTEPS`] sub-steps, and its
/// Jacobian matches central differences of the step to 0.1 % (10 and 12 states;
/// both stops; the stiff stop makes the differences themselves that coarse).
/// A single 1 ms Euler step could not follow the stop: its modes are near −3000 1/s.
#[test]
fn the_end_stops_are_in_the_model_and_stepped_finely() {
    fn check<const N: usize>() {
        let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
        let p = &m.params;
        let (k, c, area, mass) = (
            p.end_stop_stiffness_n_per_m,
            p.end_stop_damping_n_s_per_m,
            p.piston_area_m2,
            p.mass_kg,
        );
        // pressed in as far as the pressures push it (k·δ = A·Δp − F_e), still moving in at 1 mm/s
        let depth = (area * 6.0e6 - 500.0) / k;
        for (x, v, p1, p2, push) in [
            (p.x_max_m + depth, 1e-3, 9.0e6, 3.0e6, -1.0),
            (p.x_min_m - depth, -1e-3, 3.0e6, 9.0e6, 1.0),
        ] {
            let mut s = SVector::<f64, N>::zeros();
            s[1] = p1;
            s[2] = p2;
            s[3] = x;
            s[4] = v;
            s[I_FE] = 500.0;
            // the spool held 0.2 V open (off its sign switch at null, where the valve law has a kink)
            s[0] = 0.2 * p.spool_gain_m_per_v;
            if N == 12 {
                s[I_BULK] = 1.0;
            }
            let lin = m.linearise(&s, 0.2);
            let expected = (area * (p1 - p2) - 500.0 + push * (k * depth + c * 1e-3)) / mass;
            assert!(
                (lin.f[4] - expected).abs() < 1e-9 * expected.abs(),
                "{N}: {} vs {expected}",
                lin.f[4]
            );
            assert_eq!(lin.a[(4, 3)], -k / mass);
            assert_eq!(lin.a[(4, 4)], -c / mass);
            // The step's Jacobian, on a stop without its damper (the damper acts only
            // while the rod moves into the stop: a kink at v = 0, which the rod
            // crosses within the step as it settles)
            let undamped = ProcessModel::new(
                ActuatorParams {
                    end_stop_damping_n_s_per_m: 0.0,
                    ..p.clone()
                },
                1e-3,
            );
            let (next, an, guard) = undamped.step(&s, 0.2);
            assert!(!guard.any(), "{guard:?} {next:?}");
            let fd = fd_step_jacobian(&undamped, &s, 0.2);
            let ratio = worst_step_ratio(&an, &fd, &next, STOP_SUBSTEPS, 1e-3);
            assert!(
                ratio <= 1.0,
                "N={N} at x {x}: error {ratio} times the allowed\n{an:e}\n{fd:e}"
            );
            // one Euler step of 1 ms would put I + T·A's position-velocity block far
            // outside the unit circle (T²·k/m = 10)
            let single = SMatrix::<f64, N, N>::identity() + lin.a * m.dt_s;
            assert!(single[(4, 3)].abs() * m.dt_s > 5.0, "{single:e}");
            // and its position-velocity block (complex eigenvalues, |λ|² = det = 5) would
            // more than double an error every sample
            let block = single.fixed_view::<2, 2>(3, 3).into_owned();
            assert!(block.determinant().abs() > 4.0, "{block}");
        }
        // inside the stroke the stop adds nothing
        let mut s = SVector::<f64, N>::zeros();
        s[3] = 0.3;
        s[4] = 0.1;
        if N == 12 {
            s[I_BULK] = 1.0;
        }
        let lin = m.linearise(&s, 0.0);
        assert_eq!((lin.a[(4, 3)], lin.a[(4, 4)]), (0.0, 0.0));
    }
    check::<10>();
    check::<12>();
    // the thesis' 7-state layout keeps the thesis' model, without stops
    let m = ProcessModel::new(ActuatorParams::default(), 1e-3);
    let mut s7 = SVector::<f64, 7>::zeros();
    s7[3] = m.params.x_max_m + 1e-3;
    s7[4] = 0.1;
    let lin = m.linearise(&s7, 0.0);
    assert_eq!((lin.f[4], lin.a[(4, 3)], lin.a[(4, 4)]), (0.0, 0.0, 0.0));
}

/// The velocity's part of θ's column is what the column loses when v is 0:
/// a step's ∂(p1, p2)/∂θ at v minus the same at v = 0 (one sub-step, in stroke).
#[test]
fn bulk_column_from_velocity_is_the_velocity_term_of_the_step_jacobian() {
    let m = ProcessModel::new(ActuatorParams::vertical_lift(), 1e-3);
    let mut s = SVector::<f64, 12>::zeros();
    s[0] = 2e-6;
    s[1] = 8.5e6;
    s[2] = 12.5e6;
    s[3] = 0.2;
    s[4] = 0.05;
    s[11] = 0.9;
    let (_, f, _) = m.step(&s, 0.5);
    let mut still = s;
    still[4] = 0.0;
    let (_, f0, _) = m.step(&still, 0.5);
    let (c1, c2) = m.bulk_column_from_velocity(&s);
    for (row, c) in [(1, c1), (2, c2)] {
        let want = f[(row, I_BULK)] - f0[(row, I_BULK)];
        assert!(
            (c - want).abs() <= 1e-9 * want.abs(),
            "row {row}: {c} against {want}"
        );
        assert!(c.abs() > 1e3, "row {row}: {c} Pa per unit θ");
    }
}

#[test]
fn the_random_walk_states_step_as_they_are() {
    // x(k+1) = x(k) and rows of the identity in F, exactly: in free travel
    // (one Euler step) and in an end stop (the product of sub-steps).
    fn check<const N: usize>(m: &ProcessModel, rng: &mut Rng) -> usize {
        let mut in_stop = 0;
        for k in 0..200 {
            let band = if k % 2 == 0 { Band::Sliding } else { Band::Stick };
            let mut s = random_state::<N>(rng, &m.params, band, Pressures::Mixed);
            if k % 4 == 3 {
                s[3] = m.params.x_max_m + 1e-4;
            } else if k % 4 == 1 {
                s[3] = m.params.x_min_m - 1e-4;
            }
            in_stop += usize::from(s[3] > m.params.x_max_m || s[3] < m.params.x_min_m);
            let u = rng.uniform_in(-10.0, 10.0);
            let (x, f, _) = m.step(&s, u);
            for r in FIRST_RANDOM_WALK..N {
                assert_eq!(x[r].to_bits(), s[r].to_bits(), "{N} states: state {r} moved");
                for c in 0..N {
                    let identity = if r == c { 1.0 } else { 0.0 };
                    assert!(f[(r, c)] == identity, "{N} states: F[{r}][{c}] = {}", f[(r, c)]);
                }
            }
            // the other rows are not the identity's (the check can tell)
            assert!(f[(4, 1)] != 0.0, "{N} states: F[4][1] = 0");
        }
        in_stop
    }
    let p = ActuatorParams::default();
    let mut rng = Rng::new(71);
    for substeps in [1, 4] {
        let mut m = ProcessModel::new(p.clone(), 1e-3);
        m.substeps = substeps;
        assert_eq!(check::<7>(&m, &mut rng), 100);
        assert_eq!(check::<10>(&m, &mut rng), 100);
        assert_eq!(check::<11>(&m, &mut rng), 100);
        assert_eq!(check::<12>(&m, &mut rng), 100);
    }
}

/// The hydraulic mode (the oil's stiffness against the moving mass) without
/// damping: the symplectic step of the layouts with leaks keeps its amplitude,
/// the forward Euler step of the thesis' layouts lets it grow by
/// √(1 + (ωT)²) per step (the lift at mid-stroke: ω ≈ 270 rad/s, ×1.036).
#[test]
fn the_symplectic_step_keeps_an_undamped_hydraulic_mode_and_forward_euler_grows_it() {
    let mut p = ActuatorParams::vertical_lift();
    p.friction.static_n = 0.0;
    p.friction.slip_n = 0.0;
    p.friction.viscous_n_s_per_m = 0.0;
    p.valve_null_leakage_m3_s_pa = 0.0;
    p.valve_underlap_m = 0.0;
    let m = ProcessModel::new(p, 1e-3);
    fn growth<const N: usize>(m: &ProcessModel) -> f64 {
        let mut s = SVector::<f64, N>::zeros();
        (s[1], s[2], s[3]) = (8.0e6, 12.0e6, 0.2);
        // the load that holds the rod at rest at these pressures, then 50 kPa more in chamber 1
        let lin = m.linearise(&s, 0.0);
        s[I_FE] -= lin.f[4] / lin.a[(4, I_FE)];
        assert!(m.linearise(&s, 0.0).f[4].abs() < 1e-9);
        s[1] += 50e3;
        let (mut first, mut last) = (0.0f64, 0.0f64);
        for k in 0..500 {
            let (next, _, guard) = m.step(&s, 0.0);
            if guard.any() {
                // grown to a clamp (a pressure at 0 or past the supply)
                return f64::INFINITY;
            }
            s = next;
            let dp = (s[1] - 8.0e6).abs();
            if k < 100 {
                first = first.max(dp);
            } else if k >= 400 {
                last = last.max(dp);
            }
        }
        last / first
    }
    let symplectic = growth::<10>(&m);
    let forward = growth::<7>(&m);
    assert!(
        (0.8..1.25).contains(&symplectic),
        "symplectic: amplitude ×{symplectic}"
    );
    assert!(forward > 100.0, "forward Euler: amplitude ×{forward}");
}

/// The layouts with leaks step the spool exactly (its dynamics are linear):
/// after 1 ms from rest under a full command step, position and velocity
/// match 1000 RK4 steps of 1 µs to 1e-9 of the step, with the null bias
/// estimate's column (11 states) 1 − Φ₀₀ and −Φ₁₀; the thesis' 7 states keep
/// forward Euler, whose spool overshoots: at ω_n·T = 0.7 it moves 17 % further.
#[test]
fn the_layouts_with_leaks_step_the_spool_exactly() {
    let mut p = ActuatorParams::vertical_lift();
    p.spool_natural_freq_rad_s = 700.0;
    let m = ProcessModel::new(p.clone(), 1e-3);
    let (wn, zeta, k) = (
        p.spool_natural_freq_rad_s,
        p.spool_damping_ratio,
        p.spool_gain_m_per_v,
    );
    let u = 10.0;
    // the reference: RK4 of the spool alone
    let deriv = |y: [f64; 2]| {
        [
            y[1],
            -2.0 * zeta * wn * y[1] - wn * wn * (y[0] - p.spool_null_bias_m - k * u),
        ]
    };
    let mut y = [0.0, 0.0];
    let h = 1e-6;
    for _ in 0..1000 {
        let k1 = deriv(y);
        let k2 = deriv([y[0] + 0.5 * h * k1[0], y[1] + 0.5 * h * k1[1]]);
        let k3 = deriv([y[0] + 0.5 * h * k2[0], y[1] + 0.5 * h * k2[1]]);
        let k4 = deriv([y[0] + h * k3[0], y[1] + h * k3[1]]);
        for i in 0..2 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    let mut s = SVector::<f64, 11>::zeros();
    (s[1], s[2], s[3]) = (8.0e6, 12.0e6, 0.2);
    let (next, jac, _) = m.step(&s, u);
    assert!((next[0] - y[0]).abs() < 1e-9 * k * u, "{} vs {}", next[0], y[0]);
    assert!(
        (next[5] - y[1]).abs() < 1e-9 * k * u * wn,
        "{} vs {}",
        next[5],
        y[1]
    );
    let phi = spool_transition(wn, zeta, 1e-3);
    assert_eq!(jac[(0, 0)], phi[0][0]);
    assert_eq!(jac[(5, 5)], phi[1][1]);
    assert!((jac[(0, I_BIAS)] - (1.0 - phi[0][0])).abs() < 1e-15);
    assert!((jac[(5, I_BIAS)] + phi[1][0]).abs() < 1e-12 * wn);
    assert_eq!(jac[(0, 1)], 0.0);
    // the thesis' 7 states: forward Euler, whose spool overshoots the exact one's peak
    let (mut exact, mut euler) = (s, SVector::<f64, 7>::from_iterator(s.iter().take(7).copied()));
    let (mut exact_peak, mut euler_peak) = (0.0f64, 0.0f64);
    for _ in 0..20 {
        exact = m.step(&exact, u).0;
        euler = m.step(&euler, u).0;
        exact_peak = exact_peak.max(exact[0]);
        euler_peak = euler_peak.max(euler[0]);
    }
    let rest = p.spool_null_bias_m + k * u;
    let (exact_over, euler_over) = (exact_peak / rest - 1.0, euler_peak / rest - 1.0);
    // ζ = 0.7: the exact overshoot is e^(−πζ/√(1−ζ²)) = 4.6 %
    assert!((exact_over - 0.046).abs() < 0.005, "exact overshoot {exact_over}");
    assert!(euler_over > 0.1, "Euler overshoot {euler_over}");
}

/// The spool's transition matrix is exp(A·h) on both sides of critical
/// damping and at it: its columns solve the spool's equation (checked by
/// Φ(2h) = Φ(h)², and Φ(h) ≈ I + A·h + A²h²/2 for small h).
#[test]
fn the_spools_transition_is_the_matrix_exponential() {
    for zeta in [0.3, 0.7, 1.0, 1.5] {
        let wn = 700.0;
        let a = [[0.0, 1.0], [-wn * wn, -2.0 * zeta * wn]];
        let mul = |x: [[f64; 2]; 2], y: [[f64; 2]; 2]| -> [[f64; 2]; 2] {
            std::array::from_fn(|i| std::array::from_fn(|j| x[i][0] * y[0][j] + x[i][1] * y[1][j]))
        };
        let (one, two) = (spool_transition(wn, zeta, 1e-3), spool_transition(wn, zeta, 2e-3));
        let squared = mul(one, one);
        for i in 0..2 {
            for j in 0..2 {
                let scale = if i == 1 && j == 0 { wn * wn } else { 1.0 };
                assert!(
                    (squared[i][j] - two[i][j]).abs() < 1e-12 * scale.max(wn),
                    "ζ {zeta}: {squared:?} {two:?}"
                );
            }
        }
        let h = 1e-6;
        let small = spool_transition(wn, zeta, h);
        let a2 = mul(a, a);
        for i in 0..2 {
            for j in 0..2 {
                let taylor = if i == j { 1.0 } else { 0.0 } + a[i][j] * h + a2[i][j] * h * h / 2.0;
                // (the next term, A³h³/6: under ((1 + 2ζ)·ω_n·h)³ in units of ω_n^(i−j))
                let tol = ((1.0 + 2.0 * zeta) * wn * h).powi(3) * wn.powi(i as i32 - j as i32);
                assert!((small[i][j] - taylor).abs() < tol, "ζ {zeta} [{i}][{j}]");
            }
        }
    }
}
