//! The estimator's side of the wire: [`StageEstimate`] ⇄ [`EstimateFrame`],
//! the one place where the two are converted.
//!
//! The flag bits are shared ([`filter::FLAG_RESET`] … equal `frames::estimate_flags`,
//! checked at compile time below), so flags are copied, not recoded; the wire's
//! end-of-stream bit is dropped on the way in. The thesis filter's σ and
//! innovation σ are not carried (NaN on the way back).
//!
//! The conversions are a trait, [`EstimateWire`]: the estimate types live in the
//! pure `filter` crate and the frame in `frames`, so neither may hold a `From`
//! between them here.

use filter::{Estimate, StageEstimate, FLAGS_ALL, MAX_STATES};
use frames::{estimate_flags, EstimateFrame, THESIS_STATES};

// `filter` is pure and does not see the wire: its flag bits must be the wire's.
const _: () = {
    assert!(filter::FLAG_RESET == estimate_flags::RESET);
    assert!(filter::FLAG_SKIPPED == estimate_flags::SKIPPED);
    assert!(filter::FLAG_CLAMPED == estimate_flags::CLAMPED);
    assert!(filter::FLAG_CONVERGING == estimate_flags::CONVERGING);
    assert!(filter::FLAG_AFTER_GAP == estimate_flags::AFTER_GAP);
    assert!(filter::FLAG_END_STOP == estimate_flags::END_STOP);
    assert!(filter::FLAG_REANCHORED == estimate_flags::REANCHORED);
    assert!(filter::FLAG_OIL_PAST_RANGE == estimate_flags::OIL_PAST_RANGE);
    assert!(FLAGS_ALL & estimate_flags::END_OF_STREAM == 0);
    assert!(MAX_STATES == frames::MAX_STATES);
};

/// [`StageEstimate`] ⇄ [`EstimateFrame`].
pub trait EstimateWire: Sized {
    /// Writes both filters' estimates into `out` (for example a frame in shared
    /// memory), leaving its sequence number and clock fields alone.
    fn write_frame(&self, out: &mut EstimateFrame);

    /// The two estimates a frame carries; `missing_before` is the number of
    /// frames the subscriber found missing just before it.
    fn from_frame(f: &EstimateFrame, missing_before: u64) -> Self;

    /// A frame with these estimates, sequence 0 and clocks 0 (the publisher sets those).
    fn to_frame(&self) -> EstimateFrame {
        let mut f = EstimateFrame::default();
        self.write_frame(&mut f);
        f
    }
}

impl EstimateWire for StageEstimate {
    fn write_frame(&self, out: &mut EstimateFrame) {
        let (l, t) = (&self.leak, &self.thesis);
        out.t_s = l.t_s;
        out.n_states = l.n_states;
        out.flags = l.flags & FLAGS_ALL;
        out.state = l.state;
        out.state_sigma = l.sigma;
        out.residual = l.residual;
        out.innovation = l.innovation;
        out.innovation_sigma = l.innovation_sigma;
        out.measured = l.measured;
        out.u_v = l.u_v;
        out.nis = l.nis;
        out.mae_pa = l.mae_pa;
        out.th_flags = t.flags & FLAGS_ALL;
        out.th_state.copy_from_slice(&t.state[..THESIS_STATES]);
        out.th_residual = t.residual;
        out.th_innovation = t.innovation;
        out.th_mae_pa = t.mae_pa;
        out.th_nis = t.nis;
        out.bulk_scale = l.bulk_scale;
        out.bulk_scale_sigma = l.bulk_scale_sigma;
        out.oil_temp_c = l.oil_temp_c;
        out.oil_temp_sigma_k = l.oil_temp_sigma_k;
        out.laminar_factor_sigma = l.laminar_factor_sigma;
        out.null_leakage_band_lpm = l.null_leakage_band_lpm;
        [
            out.offset_response_p1_lpm_per_mpa,
            out.offset_response_p2_lpm_per_mpa,
        ] = l.offset_response_lpm_per_mpa;
        [out.span_response_p1_lpm, out.span_response_p2_lpm] = l.span_response_lpm;
        out.offset_response_x_lpm_per_mm = l.position_offset_response_lpm_per_mm;
        [out.delay_response_p1_lpm_per_ms, out.delay_response_p2_lpm_per_ms] = l.delay_response_lpm_per_ms;
    }

    fn from_frame(f: &EstimateFrame, missing_before: u64) -> StageEstimate {
        let leak = Estimate {
            t_s: f.t_s,
            n_states: f.n_states,
            flags: f.flags & FLAGS_ALL,
            measured: f.measured,
            u_v: f.u_v,
            state: f.state,
            sigma: f.state_sigma,
            bulk_scale: f.bulk_scale,
            bulk_scale_sigma: f.bulk_scale_sigma,
            oil_temp_c: f.oil_temp_c,
            oil_temp_sigma_k: f.oil_temp_sigma_k,
            laminar_factor_sigma: f.laminar_factor_sigma,
            null_leakage_band_lpm: f.null_leakage_band_lpm,
            offset_response_lpm_per_mpa: [f.offset_response_p1_lpm_per_mpa, f.offset_response_p2_lpm_per_mpa],
            span_response_lpm: [f.span_response_p1_lpm, f.span_response_p2_lpm],
            position_offset_response_lpm_per_mm: f.offset_response_x_lpm_per_mm,
            delay_response_lpm_per_ms: [f.delay_response_p1_lpm_per_ms, f.delay_response_p2_lpm_per_ms],
            residual: f.residual,
            innovation: f.innovation,
            innovation_sigma: f.innovation_sigma,
            mae_pa: f.mae_pa,
            nis: f.nis,
        };
        let mut th_state = [f64::NAN; MAX_STATES];
        th_state[..THESIS_STATES].copy_from_slice(&f.th_state);
        let thesis = Estimate {
            n_states: THESIS_STATES as u32,
            flags: f.th_flags & FLAGS_ALL,
            state: th_state,
            sigma: [f64::NAN; MAX_STATES],
            residual: f.th_residual,
            innovation: f.th_innovation,
            innovation_sigma: [f64::NAN; 3],
            mae_pa: f.th_mae_pa,
            nis: f.th_nis,
            // (the thesis filter has no θ, oil state or offset response)
            bulk_scale: f64::NAN,
            bulk_scale_sigma: f64::NAN,
            oil_temp_c: f64::NAN,
            oil_temp_sigma_k: f64::NAN,
            laminar_factor_sigma: f64::NAN,
            null_leakage_band_lpm: f64::NAN,
            offset_response_lpm_per_mpa: [[f64::NAN; 3]; 2],
            span_response_lpm: [[f64::NAN; 3]; 2],
            position_offset_response_lpm_per_mm: [f64::NAN; 3],
            delay_response_lpm_per_ms: [[f64::NAN; 3]; 2],
            ..leak
        };
        StageEstimate {
            leak,
            thesis,
            missing_before,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use filter::{EstimatorStage, Tuning, FLAG_AFTER_GAP, FLAG_CONVERGING};
    use model::{ActuatorParams, Sample};

    /// Same floats, NaN equal to NaN.
    fn same(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    }

    #[test]
    fn estimates_round_trip_through_frames() {
        let mut stage = EstimatorStage::new(
            ActuatorParams::default(),
            Tuning::sensor_derived(),
            Tuning::thesis(),
        )
        .expect("stage");
        let mut e = stage.on_sample(&Sample::new(0.0, 0.5, 0.25, 7.0e6, 6.8e6));
        for k in 1..50 {
            e = stage.on_sample(&Sample::new(k as f64 * 1e-3, 0.5, 0.25, 7.0e6, 6.8e6));
        }
        e.leak.flags |= FLAG_AFTER_GAP;
        let mut f = e.to_frame();
        f.flags |= frames::estimate_flags::END_OF_STREAM;
        let back = StageEstimate::from_frame(&f, 3);
        assert_eq!(back.missing_before, 3);
        // the end-of-stream bit stays on the wire; every estimator bit comes back
        assert_eq!(back.leak.flags, e.leak.flags);
        assert_ne!(
            back.leak.flags & FLAG_CONVERGING,
            0,
            "still converging after 50 samples"
        );
        let (a, b) = (&e.leak, &back.leak);
        assert_eq!((a.t_s, a.n_states, a.u_v), (b.t_s, b.n_states, b.u_v));
        assert!(same(&a.state, &b.state) && same(&a.sigma, &b.sigma));
        assert!(same(&a.residual, &b.residual) && same(&a.innovation, &b.innovation));
        assert!(same(&a.innovation_sigma, &b.innovation_sigma) && same(&a.measured, &b.measured));
        assert!(same(&[a.nis], &[b.nis]) && same(&a.mae_pa, &b.mae_pa));
        // the oil's state and band and the offset response: what the detector reads
        let oil = |x: &Estimate| {
            [
                x.bulk_scale,
                x.bulk_scale_sigma,
                x.oil_temp_c,
                x.oil_temp_sigma_k,
                x.laminar_factor_sigma,
                x.null_leakage_band_lpm,
            ]
        };
        assert!(a.bulk_scale.is_finite() && a.offset_response_lpm_per_mpa[0].iter().any(|v| *v != 0.0));
        assert!(same(&oil(a), &oil(b)));
        assert!(same(
            a.offset_response_lpm_per_mpa.as_flattened(),
            b.offset_response_lpm_per_mpa.as_flattened()
        ));
        let (a, b) = (&e.thesis, &back.thesis);
        assert_eq!(a.flags, b.flags);
        assert!(same(&a.state[..THESIS_STATES], &b.state[..THESIS_STATES]));
        assert!(same(&a.residual, &b.residual) && same(&[a.nis], &[b.nis]) && same(&a.mae_pa, &b.mae_pa));
        assert!(b.sigma.iter().all(|s| s.is_nan()), "the thesis σ is not carried");
        // writing into a frame keeps its sequence and clocks
        let mut g = EstimateFrame {
            seq: 9,
            acq_mono_ns: 10,
            ..EstimateFrame::default()
        };
        e.write_frame(&mut g);
        assert_eq!((g.seq, g.acq_mono_ns, g.t_s), (9, 10, e.leak.t_s));
    }
}
