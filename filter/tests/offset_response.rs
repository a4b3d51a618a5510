//! The filter's responses to a transducer's misreading
//! (`Estimate::offset_response_lpm_per_mpa`, `Estimate::span_response_lpm`,
//! `Estimate::position_offset_response_lpm_per_mm`,
//! `Estimate::delay_response_lpm_per_ms`) against finite differences: the
//! same recording run twice, once with x, p1 or p2 misread from the start,
//! moves the leak sizes by the response times the misreading.

use filter::{Estimate, Estimator, Tuning};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};

/// The channels' names, by index into the measurement [x, p1, p2].
const NAMES: [&str; 3] = ["x", "p1", "p2"];

/// Leak sizes (L/min) and estimates over a recording whose channel `ch` (0:
/// x, 1: p1, 2: p2) reads `misread(v)` for a true v (m or Pa).
fn run(
    samples: &[model::Sample],
    ch: usize,
    misread: impl FnMut(f64) -> f64,
) -> (Vec<[f64; 3]>, Vec<Estimate>) {
    run_with(Tuning::sensor_derived(), samples, ch, misread)
}

/// [`run`] with the filter's tuning `tuning`.
fn run_with(
    tuning: Tuning,
    samples: &[model::Sample],
    ch: usize,
    mut misread: impl FnMut(f64) -> f64,
) -> (Vec<[f64; 3]>, Vec<Estimate>) {
    let mut est = Estimator::new(ActuatorParams::default(), tuning).unwrap();
    let (mut sizes, mut estimates) = (Vec::new(), Vec::new());
    for s in samples {
        let mut s = *s;
        match ch {
            0 => s.x_m = misread(s.x_m),
            1 => s.p1_pa = misread(s.p1_pa),
            _ => s.p2_pa = misread(s.p2_pa),
        }
        let e = est.on_sample(&s);
        sizes.push(std::array::from_fn(|k| e.state[7 + k] * 6e4));
        estimates.push(e);
    }
    (sizes, estimates)
}

/// The loaded-random scenario's first 40 s, seed 4.
fn recording() -> Vec<model::Sample> {
    let rig = ActuatorParams::default();
    let scenario = Scenario::by_name("loaded-random", 4, 40.0).unwrap();
    let mut sim = Simulator::with_default_sensors(rig, scenario, FaultSchedule::default(), 4).unwrap();
    (0..40_000).map(|_| sim.step()).collect()
}

/// The same recording run twice: as read, and with channel `ch` (0: x, 1: p1,
/// 2: p2) reading `misread(v)` for a true v (m or Pa).
struct Pair {
    ch: usize,
    /// Leak sizes as read, L/min.
    base: Vec<[f64; 3]>,
    /// Leak sizes misread, L/min.
    moved: Vec<[f64; 3]>,
    /// The estimates as read.
    estimates: Vec<Estimate>,
}

impl Pair {
    fn new(samples: &[model::Sample], ch: usize, misread: impl FnMut(f64) -> f64) -> Pair {
        let (base, estimates) = run(samples, ch, |p| p);
        let (moved, _) = run(samples, ch, misread);
        Pair {
            ch,
            base,
            moved,
            estimates,
        }
    }

    /// The RMS of (seen − predicted) over the RMS of predicted, each
    /// sample's three sizes from 10 s on (the filter has converged), with
    /// `predicted(estimate, k)` the change of size k (L/min).
    fn miss(&self, predicted: impl Fn(&Estimate, usize) -> f64) -> f64 {
        let (mut err2, mut pred2) = (0.0, 0.0);
        for i in 10_000..self.base.len() {
            for k in 0..3 {
                let p = predicted(&self.estimates[i], k);
                err2 += (self.moved[i][k] - self.base[i][k] - p).powi(2);
                pred2 += p * p;
            }
        }
        assert!(pred2 > 0.0, "{}: the response is zero", NAMES[self.ch]);
        (err2 / pred2).sqrt()
    }

    /// What is left of the change when it is fitted with one coefficient on
    /// `response(estimate, k)` (least squares over each sample's three sizes
    /// from 10 s on), as a share of the change's energy (1).
    fn left_by_fit(&self, response: impl Fn(&Estimate, usize) -> f64) -> f64 {
        let (mut dr, mut dd, mut rr) = (0.0, 0.0, 0.0);
        for i in 10_000..self.base.len() {
            for k in 0..3 {
                let d = response(&self.estimates[i], k);
                let y = self.moved[i][k] - self.base[i][k];
                dr += d * y;
                dd += d * d;
                rr += y * y;
            }
        }
        1.0 - dr * dr / (dd * rr)
    }

    /// The coefficient on `response(estimate, k)` that fits the change best
    /// (least squares over each sample's three sizes from 10 s on).
    fn fitted(&self, response: impl Fn(&Estimate, usize) -> f64) -> f64 {
        let (mut dr, mut dd) = (0.0, 0.0);
        for i in 10_000..self.base.len() {
            for k in 0..3 {
                let d = response(&self.estimates[i], k);
                dr += d * (self.moved[i][k] - self.base[i][k]);
                dd += d * d;
            }
        }
        dr / dd
    }

    /// [`Pair::miss`], asserted under 10 %.
    fn assert_predicted(&self, predicted: impl Fn(&Estimate, usize) -> f64) -> f64 {
        let rel = self.miss(predicted);
        assert!(
            rel < 0.1,
            "{}: the response misses the change by {:.0} % (RMS)",
            NAMES[self.ch],
            100.0 * rel
        );
        rel
    }
}

#[test]
fn an_offset_moves_the_leak_sizes_as_the_response_predicts() {
    let samples = recording();
    let offset_pa = 2.0e4;
    for ch in [1, 2] {
        let pair = Pair::new(&samples, ch, |p| p + offset_pa);
        pair.assert_predicted(|e, k| e.offset_response_lpm_per_mpa[ch - 1][k] * offset_pa * 1e-6);
    }
}

#[test]
fn an_offset_fits_its_own_channels_response_and_not_the_others() {
    // The offset watch tells p1 from p2 by these fits. −0.2 MPa: its own
    // channel's response leaves 0.5 % (p1) and 0.1 % (p2) of the change, the
    // other's 55 %. At −0.5 MPa p1's response bends (5 % left; p2's 1 %).
    let samples = recording();
    for offset_pa in [-2.0e5, -5.0e5] {
        for ch in [1, 2] {
            let pair = Pair::new(&samples, ch, |p| p + offset_pa);
            let own = pair.left_by_fit(|e, k| e.offset_response_lpm_per_mpa[ch - 1][k]);
            let other = pair.left_by_fit(|e, k| e.offset_response_lpm_per_mpa[2 - ch][k]);
            assert!(
                own < 0.1 && other > 0.4,
                "p{ch} read {} kPa off: its own response's fit leaves {:.1} %, the other's {:.1} %",
                offset_pa * 1e-3,
                100.0 * own,
                100.0 * other
            );
        }
    }
}

#[test]
fn a_span_error_moves_the_leak_sizes_as_its_response_predicts() {
    // a 0.2 % span error: the offset it makes moves with the pressure, so the
    // offset's response times the pressure now misses the change
    let samples = recording();
    let gain_error = 0.002;
    for ch in [1, 2] {
        let pair = Pair::new(&samples, ch, |p| (1.0 + gain_error) * p);
        let rel = pair.assert_predicted(|e, k| e.span_response_lpm[ch - 1][k] * gain_error);
        let rel_now =
            pair.miss(|e, k| e.offset_response_lpm_per_mpa[ch - 1][k] * gain_error * e.measured[ch] * 1e-6);
        assert!(
            rel_now > 2.0 * rel,
            "p{ch}: the offset's response at the pressure now misses by {:.0} %, the span's by {:.0} %",
            100.0 * rel_now,
            100.0 * rel
        );
    }
}

#[test]
fn a_position_offset_moves_the_leak_sizes_as_its_response_predicts() {
    // 1 mm on x: the model reads both chambers' volumes 1 mm off. The
    // response over-predicts the change on every size, by the same share at
    // 0.01 mm as at 1 mm (so not the model's curvature): 18 % RMS here, 10 %
    // on the loaded sine. The offset watch fits its pattern, so a scale
    // error moves the offset it names by as much, not the naming.
    let samples = recording();
    let offset_mm = 1.0;
    let pair = Pair::new(&samples, 0, |x| x + offset_mm * 1e-3);
    let rel = pair.miss(|e, k| e.position_offset_response_lpm_per_mm[k] * offset_mm);
    assert!(
        rel < 0.25,
        "x: the response misses the change by {:.0} % (RMS)",
        100.0 * rel
    );
}

/// A first-order lag τ·ẏ = p − y with time constant `tau_s`, as the
/// simulator lags a transducer: solved exactly for a value linear between
/// samples of period `dt_s`. It delays a ramp by τ. The lag and that delay, s.
fn lag(tau_s: f64, dt_s: f64) -> (impl FnMut(f64) -> f64, f64) {
    let e = (-dt_s / tau_s).exp();
    let (mut read, mut was) = (f64::NAN, f64::NAN);
    let lagged = move |p: f64| {
        if read.is_nan() {
            (read, was) = (p, p);
        }
        let slope = (p - was) / dt_s;
        read = p - tau_s * slope + (read - was + tau_s * slope) * e;
        was = p;
        read
    };
    (lagged, tau_s)
}

#[test]
fn a_delayed_pressure_moves_the_leak_sizes_as_its_response_predicts() {
    // A 0.5 ms lag on p1, then on p2. The response's shape holds: one
    // coefficient on it leaves 2.5 % (p1) and 0.2 % (p2) of the change's
    // energy. The coefficient reads 1.37 and 1.12 times τ: the lag damps the
    // fast part of a swing as well as delaying it, which a delay's
    // first-order response leaves out.
    let samples = recording();
    for ch in [1, 2] {
        let (lagged, delay_s) = lag(5e-4, 1e-3);
        let pair = Pair::new(&samples, ch, lagged);
        let left = pair.left_by_fit(|e, k| e.delay_response_lpm_per_ms[ch - 1][k]);
        let scale = pair.fitted(|e, k| e.delay_response_lpm_per_ms[ch - 1][k]) / (delay_s * 1e3);
        assert!(
            left < 0.05 && (1.0..2.0).contains(&scale),
            "p{ch}: the response's fit leaves {:.1} % of the change, at {scale:.2} times the delay",
            100.0 * left
        );
    }
}

#[test]
fn the_delay_taken_off_leaves_the_leak_sizes_of_readings_without_it() {
    // Both transducers lagging 0.5 ms; the filter told the delay takes its
    // imprint off the sizes it publishes (Tuning::lag_correction_s): 3.5 % of
    // the imprint's energy is left.
    let samples = recording();
    let lagged_run = |correction_s: f64| {
        let tuning = Tuning {
            lag_correction_s: correction_s,
            ..Tuning::sensor_derived()
        };
        let (mut p1, delay_s) = lag(5e-4, 1e-3);
        let (mut p2, _) = lag(5e-4, 1e-3);
        let lagged: Vec<model::Sample> = samples
            .iter()
            .map(|s| model::Sample {
                p1_pa: p1(s.p1_pa),
                p2_pa: p2(s.p2_pa),
                ..*s
            })
            .collect();
        (run_with(tuning, &lagged, 1, |p| p), delay_s)
    };
    let ((raw, estimates), delay_s) = lagged_run(0.0);
    let ((corrected, corrected_estimates), _) = lagged_run(delay_s);
    let (clean, _) = run(&samples, 1, |p| p);
    let (mut before, mut after) = (0.0, 0.0);
    for i in 10_000..samples.len() {
        for k in 0..3 {
            // the correction is the response times the delay, to rounding
            let taken = (estimates[i].delay_response_lpm_per_ms[0][k]
                + estimates[i].delay_response_lpm_per_ms[1][k])
                * delay_s
                * 1e3;
            assert!(
                (raw[i][k] - corrected[i][k] - taken).abs() < 1e-9,
                "sample {i}, size {k}: {} taken, {taken} predicted",
                raw[i][k] - corrected[i][k]
            );
            before += (raw[i][k] - clean[i][k]).powi(2);
            after += (corrected[i][k] - clean[i][k]).powi(2);
        }
        // the filter's own fit is the same: its NIS does not see the correction
        assert_eq!(estimates[i].nis.to_bits(), corrected_estimates[i].nis.to_bits());
    }
    assert!(
        after < 0.05 * before,
        "the delay's imprint on the sizes: {:.4} L/min RMS without the correction, {:.4} with it",
        (before / 30_000.0).sqrt(),
        (after / 30_000.0).sqrt()
    );
}
