//! The discrete step's Jacobian F against central differences of the step, with sub-steps.

use super::*;

/// Checks the discrete Jacobian of [`ProcessModel::step`] at 300 random
/// states against central differences of the step itself; skips states whose
/// sub-steps pass near a branch switch or that the guard clamps. Returns how
/// many were checked and at how many a single linearisation, I + T·A(x(k)),
/// would have failed the same comparison.
fn check_step_jacobian<const N: usize>(
    m: &ProcessModel,
    band: Band,
    pressures: Pressures,
    seed: u64,
) -> (usize, usize) {
    const TOL: f64 = 1e-5;
    let mut rng = Rng::new(seed);
    let (mut checked, mut one_step_fails) = (0, 0);
    let n = m.substeps.max(1);
    let h = m.dt_s / n as f64;
    // (one sub-step as the step takes it: the spool exact in the layouts with leaks)
    let sub = ProcessModel {
        dt_s: h,
        substeps: 1,
        ..m.clone()
    };
    for _ in 0..300 {
        let s: SVector<f64, N> = random_state(&mut rng, &m.params, band, pressures);
        let u = rng.uniform_in(-10.0, 10.0);
        let mut x = s;
        let mut near = false;
        for _ in 0..n {
            near |= near_branch(m, &x);
            if N >= 10 {
                // (the valve's flows are taken at the spool's mean over the sub-step)
                let p = &m.params;
                let psi = spool_mean(p.spool_natural_freq_rad_s, p.spool_damping_ratio, h);
                let bias = p.spool_null_bias_m + if N >= 11 { x[I_BIAS] } else { 0.0 };
                let rest = bias + p.spool_gain_m_per_v * u;
                let mut mean = x;
                mean[0] = rest + psi[0] * (x[0] - rest) + psi[1] * x[5];
                near |= near_branch(m, &mean);
            }
            x = sub.step(&x, u).0;
        }
        let (next, an, guard) = m.step(&s, u);
        if near || guard.any() {
            continue;
        }
        let fd = fd_step_jacobian(m, &s, u);
        let ratio = worst_step_ratio(&an, &fd, &next, n, TOL);
        assert!(
            ratio <= 1.0,
            "N={N} substeps {n}: error {ratio} times the allowed\nanalytic {an:e}\nfd {fd:e}\nat {s:?}, u {u}"
        );
        let single = SMatrix::<f64, N, N>::identity() + m.linearise(&s, u).a * m.dt_s;
        one_step_fails += usize::from(worst_step_ratio(&single, &fd, &next, n, TOL) > 1.0);
        checked += 1;
    }
    (checked, one_step_fails)
}

#[test]
fn discrete_step_jacobian_matches_central_differences_of_the_step() {
    let p = ActuatorParams {
        load: crate::params::SpringLoad::thesis_simulation(),
        ..Default::default()
    };
    for substeps in [1, 4, 10] {
        let mut m = ProcessModel::new(p.clone(), 1e-3);
        m.substeps = substeps;
        let runs = [
            (
                6,
                check_step_jacobian::<6>(&m, Band::Sliding, Pressures::Inside, 51),
            ),
            (
                6,
                check_step_jacobian::<6>(&m, Band::Stick, Pressures::Inside, 52),
            ),
            (
                7,
                check_step_jacobian::<7>(&m, Band::Sliding, Pressures::Inside, 53),
            ),
            (
                7,
                check_step_jacobian::<7>(&m, Band::Sliding, Pressures::Mixed, 54),
            ),
            (
                11,
                check_step_jacobian::<11>(&m, Band::Sliding, Pressures::Inside, 55),
            ),
            (
                12,
                check_step_jacobian::<12>(&m, Band::Sliding, Pressures::Inside, 56),
            ),
        ];
        for (n, (checked, one_step_fails)) in runs {
            eprintln!(
                "{n} states, {substeps} sub-steps: {checked} states checked, \
                 I + T·A(x) off in {one_step_fails}"
            );
            assert!(
                checked > 150,
                "{n} states, {substeps} sub-steps: {checked} checked"
            );
            if substeps == 1 && n < 10 {
                // one forward Euler step: the product is the single linearisation
                assert_eq!(one_step_fails, 0);
            } else {
                // sub-steps, or the symplectic step of the layouts with leaks:
                // F is not I + T·A(x(k)), and the test can tell
                assert!(
                    one_step_fails > checked / 2,
                    "{n} states, {substeps} sub-steps: {one_step_fails} of {checked}"
                );
            }
        }
    }
    // With supply sag and entrained air.
    let mut p2 = p;
    p2.supply_sag_pa_per_m3_s = 2e10;
    p2.entrained_air_fraction = 0.01;
    let mut m2 = ProcessModel::new(p2, 1e-3);
    m2.substeps = 5;
    let (checked, _) = check_step_jacobian::<7>(&m2, Band::Sliding, Pressures::Inside, 61);
    assert!(checked > 150, "{checked}");
    let (checked, _) = check_step_jacobian::<6>(&m2, Band::Sliding, Pressures::Mixed, 62);
    assert!(checked > 100, "{checked}");
}
