//! Karnopp friction with the LaVal Stribeck form (docs/model.md#friction).

use crate::params::Friction;

/// Friction force F_f on the piston, N (positive opposes extension), for rod
/// velocity `v_m_s` and net driving force `drive_n` = A(p1 − p2) − F_l.
///
/// Outside the stick band (|v| > u_z) the Stribeck curve plus viscous term;
/// inside it the friction balances the drive up to f_st (stuck), or equals
/// ±f_st when the drive exceeds it (breaking away).
#[inline]
pub fn friction_force_n(f: &Friction, v_m_s: f64, drive_n: f64) -> f64 {
    if v_m_s.abs() > f.zero_velocity_m_s {
        let p = f.for_direction(v_m_s);
        let s = v_m_s.signum();
        (p.slip_n + (p.static_n - p.slip_n) * (-v_m_s.abs() / p.stribeck_velocity_m_s).exp()) * s
            + p.viscous_n_s_per_m * v_m_s
    } else {
        let p = f.for_direction(drive_n);
        if drive_n.abs() <= p.static_n {
            drive_n
        } else {
            p.static_n * drive_n.signum()
        }
    }
}

/// Partial derivative of the friction force with respect to velocity, N·s/m:
/// the Stribeck slope plus viscous term outside the stick band, zero inside it
/// (docs/model.md#jacobians).
#[inline]
pub fn friction_dv(f: &Friction, v_m_s: f64) -> f64 {
    if v_m_s.abs() > f.zero_velocity_m_s {
        let p = f.for_direction(v_m_s);
        -(p.static_n - p.slip_n) / p.stribeck_velocity_m_s * (-v_m_s.abs() / p.stribeck_velocity_m_s).exp()
            + p.viscous_n_s_per_m
    } else {
        0.0
    }
}

/// Whether the rod is held by stiction: |v| ≤ u_z and |drive| ≤ f_st.
#[inline]
pub fn is_stuck(f: &Friction, v_m_s: f64, drive_n: f64) -> bool {
    v_m_s.abs() <= f.zero_velocity_m_s && drive_n.abs() <= f.for_direction(drive_n).static_n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::FrictionParams;

    #[test]
    fn branches() {
        let f = Friction::default();
        // sliding fast: Coulomb + viscous, Stribeck term decayed
        let ff = friction_force_n(&f, 1.0, 0.0);
        let expect = 1.1e3 + 1.3e3 * (-25.0f64).exp() + 350.0;
        assert!((ff - expect).abs() < 1e-9);
        assert!((friction_force_n(&f, -1.0, 0.0) + expect).abs() < 1e-9);
        // just outside the stick band: close to stiction
        let near = friction_force_n(&f, 0.0011, 0.0);
        assert!((near - (1.1e3 + 1.3e3 * (-0.0011f64 / 0.04).exp() + 0.385)).abs() < 1e-9);
        // stuck: balances the drive
        assert_eq!(friction_force_n(&f, 0.0, 1500.0), 1500.0);
        assert!(is_stuck(&f, 0.0005, -2000.0));
        // breaking away: saturates at f_st
        assert_eq!(friction_force_n(&f, 0.0, 5000.0), 2400.0);
        assert_eq!(friction_force_n(&f, 0.0, -5000.0), -2400.0);
        assert!(!is_stuck(&f, 0.0, 2500.0));
    }

    #[test]
    fn asymmetric_direction() {
        let f = Friction {
            retract: Some(FrictionParams {
                static_n: 3000.0,
                slip_n: 1500.0,
                ..FrictionParams::default()
            }),
            ..Friction::default()
        };
        assert!((friction_force_n(&f, -1.0, 0.0) + 1500.0 + 350.0).abs() < 1e-3);
        assert!((friction_force_n(&f, 1.0, 0.0) - 1100.0 - 350.0).abs() < 1e-3);
        assert_eq!(friction_force_n(&f, 0.0, -2800.0), -2800.0);
        assert_eq!(friction_force_n(&f, 0.0, 2800.0), 2400.0);
    }

    #[test]
    fn derivative_matches_finite_difference() {
        let f = Friction::default();
        for v in [-0.8, -0.05, -0.002, 0.0015, 0.03, 0.5] {
            let h = 1e-7;
            let fd = (friction_force_n(&f, v + h, 0.0) - friction_force_n(&f, v - h, 0.0)) / (2.0 * h);
            let an = friction_dv(&f, v);
            assert!((fd - an).abs() <= 1e-5 * an.abs().max(1.0), "v={v}: {fd} vs {an}");
        }
        assert_eq!(friction_dv(&f, 0.0005), 0.0);
    }
}
