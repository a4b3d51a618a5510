//! The spool's exact step: its second-order dynamics are linear, so a sample
//! step with the command held (zero-order hold) is Φ = e^(A·h) exactly, where
//! forward Euler at ω_n·h ≈ 0.6-0.8 lags a command step by one sample and
//! then overshoots (docs/model.md#the-spools-step).

use nalgebra::{SMatrix, SVector};

use super::{ProcessModel, I_BIAS};

/// The transition of the spool's state (x_sp − x_eq, v_sp) over one step of h
/// seconds, Φ = e^(A·h) with A = [[0, 1], [−ω_n², −2ζω_n]], and the parameters
/// it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SpoolStep {
    /// ω_n (rad/s), ζ and h (s) of Φ.
    key: [f64; 3],
    /// Φ, row-major: ∂(x_sp, v_sp)(k+1)/∂(x_sp, v_sp)(k).
    phi: [[f64; 2]; 2],
    /// The spool's mean over the step per unit of (x_sp − x_eq, v_sp) at its
    /// start, the first row of (1/h)·∫Φ = (1/h)·A⁻¹(Φ − I) (dimensionless, s).
    mean: [f64; 2],
}

impl SpoolStep {
    /// Φ for natural frequency `wn` (rad/s), damping ratio `zeta` and step `h_s` (s).
    pub(crate) fn of(wn: f64, zeta: f64, h_s: f64) -> SpoolStep {
        let phi = transition(wn, zeta, h_s);
        // A⁻¹ = [[−2ζω, −1], [ω², 0]]/ω²: its first row times (Φ − I), over h
        let k = 1.0 / (h_s * wn * wn);
        let mean = [
            k * (-2.0 * zeta * wn * (phi[0][0] - 1.0) - phi[1][0]),
            k * (-2.0 * zeta * wn * phi[0][1] - (phi[1][1] - 1.0)),
        ];
        SpoolStep {
            key: [wn, zeta, h_s],
            phi,
            mean,
        }
    }

    /// Whether this Φ is the one of `wn`, `zeta` and `h_s`.
    #[inline(always)]
    pub(crate) fn is_for(&self, wn: f64, zeta: f64, h_s: f64) -> bool {
        self.key == [wn, zeta, h_s]
    }
}

/// e^(A·h) of the 2×2 spool matrix A = [[0, 1], [−ω², −2ζω]]: with
/// σ = ζω and the eigenvalues −σ ± s (s = ω·√(ζ² − 1), imaginary below
/// ζ = 1), e^(A·h) = e^(−σh)·[c·I + (A + σI)·g] with c = cosh(sh) and
/// g = sinh(sh)/s (cos and sin/|s| when s is imaginary, c = 1 and g = h at s = 0).
fn transition(wn: f64, zeta: f64, h: f64) -> [[f64; 2]; 2] {
    let sigma = zeta * wn;
    let disc = (zeta * zeta - 1.0) * wn * wn;
    let (c, g) = if disc.abs() < 1e-12 * wn * wn {
        (1.0, h)
    } else if disc < 0.0 {
        let s = (-disc).sqrt();
        ((s * h).cos(), (s * h).sin() / s)
    } else {
        let s = disc.sqrt();
        ((s * h).cosh(), (s * h).sinh() / s)
    };
    let e = (-sigma * h).exp();
    // A + σI = [[σ, 1], [−ω², −σ]]
    [
        [e * (c + sigma * g), e * g],
        [-e * wn * wn * g, e * (c - sigma * g)],
    ]
}

impl ProcessModel {
    /// The spool's transition over a (sub-)step of `h_s` seconds: the cached one
    /// when it is for the parameters as they are now.
    #[inline(always)]
    pub(crate) fn spool_step(&self, h_s: f64) -> SpoolStep {
        let p = &self.params;
        if self
            .spool
            .is_for(p.spool_natural_freq_rad_s, p.spool_damping_ratio, h_s)
        {
            self.spool
        } else {
            SpoolStep::of(p.spool_natural_freq_rad_s, p.spool_damping_ratio, h_s)
        }
    }

    /// The spool's mean position over a (sub-)step from `s` with the command
    /// `u_v` (V) held, m, and its partials w.r.t. x_sp, v_sp and the null bias
    /// state (dimensionless, s, dimensionless): the valve passes the flow of the
    /// spool as it moves through the step, not as it stood at its start.
    #[inline(always)]
    pub(crate) fn mean_spool<const N: usize>(
        &self,
        step: &SpoolStep,
        s: &SVector<f64, N>,
        u_v: f64,
    ) -> (f64, [f64; 3]) {
        let p = &self.params;
        let bias = p.spool_null_bias_m + if N >= 11 { s[I_BIAS] } else { 0.0 };
        let x_eq = bias + p.spool_gain_m_per_v * u_v;
        let m = &step.mean;
        let mean = x_eq + m[0] * (s[0] - x_eq) + m[1] * s[5];
        (mean, [m[0], m[1], 1.0 - m[0]])
    }

    /// Rows 0 and 5 of a (sub-)step from `s` into `x` and its Jacobian `jac`
    /// (overwritten), exact for the spool's linear dynamics with the command
    /// `u_v` (V) held: x_sp and v_sp relax to x_eq = b + K·u along Φ.
    #[inline(always)]
    pub(crate) fn exact_spool_rows<const N: usize>(
        &self,
        step: &SpoolStep,
        s: &SVector<f64, N>,
        u_v: f64,
        x: &mut SVector<f64, N>,
        jac: &mut SMatrix<f64, N, N>,
    ) {
        let p = &self.params;
        let bias = p.spool_null_bias_m + if N >= 11 { s[I_BIAS] } else { 0.0 };
        let x_eq = bias + p.spool_gain_m_per_v * u_v;
        let (z, v) = (s[0] - x_eq, s[5]);
        let phi = &step.phi;
        x[0] = x_eq + phi[0][0] * z + phi[0][1] * v;
        x[5] = phi[1][0] * z + phi[1][1] * v;
        for c in 0..N {
            jac[(0, c)] = 0.0;
            jac[(5, c)] = 0.0;
        }
        jac[(0, 0)] = phi[0][0];
        jac[(0, 5)] = phi[0][1];
        jac[(5, 0)] = phi[1][0];
        jac[(5, 5)] = phi[1][1];
        if N >= 11 {
            jac[(0, I_BIAS)] = 1.0 - phi[0][0];
            jac[(5, I_BIAS)] = -phi[1][0];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spool's (x_sp − x_eq, v_sp) from `start` over 1 ms by 200,000
    /// midpoint steps, with the mean of x_sp − x_eq over the step.
    fn integrated(wn: f64, zeta: f64, start: [f64; 2]) -> ([f64; 2], f64) {
        let n = 200_000;
        let h = 1e-3 / n as f64;
        let accel = |z: f64, v: f64| -wn * wn * z - 2.0 * zeta * wn * v;
        let (mut z, mut v, mut area) = (start[0], start[1], 0.0);
        for _ in 0..n {
            let (zm, vm) = (z + 0.5 * h * v, v + 0.5 * h * accel(z, v));
            area += h * zm;
            z += h * vm;
            v += h * accel(zm, vm);
        }
        ([z, v], area / 1e-3)
    }

    /// Φ and the step's mean against the dynamics integrated in fine steps,
    /// under-, critically and over-damped.
    #[test]
    fn the_transition_and_the_mean_are_the_dynamics_integrated() {
        for (wn, zeta) in [(700.0, 0.7), (628.3, 0.5), (816.8, 1.0), (500.0, 1.8)] {
            let step = SpoolStep::of(wn, zeta, 1e-3);
            // a unit offset, then a unit velocity (whose responses are 1/ω_n smaller)
            for (col, start, scale) in [(0, [1.0, 0.0], 1.0), (1, [0.0, 1.0], 1.0 / wn)] {
                let ([z, v], mean) = integrated(wn, zeta, start);
                assert!(
                    (step.phi[0][col] - z).abs() < 1e-8 * scale,
                    "x_sp: ω {wn} ζ {zeta} column {col}"
                );
                assert!(
                    (step.phi[1][col] - v).abs() < 1e-8 * scale * wn,
                    "v_sp: ω {wn} ζ {zeta} column {col}"
                );
                assert!(
                    (step.mean[col] - mean).abs() < 1e-8 * scale,
                    "mean: ω {wn} ζ {zeta} column {col}"
                );
            }
        }
    }

    /// Forward Euler at 1 ms leaves the spool where it was one sample after a
    /// command step; the exact step has it 17 % of the way (the thesis valve).
    #[test]
    fn a_command_step_moves_the_spool_within_the_sample() {
        let step = SpoolStep::of(200.0 * std::f64::consts::PI, 0.7, 1e-3);
        let moved = 1.0 - step.phi[0][0];
        assert!((0.15..0.20).contains(&moved), "{moved}");
    }
}
