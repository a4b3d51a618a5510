//! The leak-size detector's thresholds refined after arming, and the cone of
//! patterns leaks can make, on synthetic estimate streams with known spreads.

use detect::{
    leak_can_make, leak_can_make_with, misfits, misfits_with, signatures_lpm, signatures_with,
    ClassifierConfig, CommissioningLearner, EventKind, LeakEvent, LeakSizeDetector, Phase,
    NOMINAL_INTERNAL_FACTORS,
};
use filter::{Estimate, MAX_STATES};

const M3_S_PER_LPM: f64 = 1.0e-3 / 60.0;

/// Gaussian noise from a fixed seed (xorshift and Box-Muller).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn gauss(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

/// An 11-state estimate at `t_s` whose leak sizes are `q_lpm` (q_e1, q_e2, q_i at
/// the nominal drop), both chambers at mid pressure, tracking (NIS 3).
fn estimate(t_s: f64, q_lpm: [f64; 3]) -> Estimate {
    let mut state = [f64::NAN; MAX_STATES];
    let mut sigma = [f64::NAN; MAX_STATES];
    state[..7].copy_from_slice(&[0.0, 6.9e6, 6.9e6, 0.3, 0.0, 0.0, 0.0]);
    sigma[..7].copy_from_slice(&[1e-6, 5e3, 5e3, 1e-5, 1e-3, 1e-3, 10.0]);
    for k in 0..3 {
        state[7 + k] = q_lpm[k] * M3_S_PER_LPM;
        sigma[7 + k] = 0.002 * M3_S_PER_LPM;
    }
    state[10] = 0.0;
    sigma[10] = 1e-7;
    Estimate {
        t_s,
        n_states: 11,
        flags: 0,
        state,
        sigma,
        bulk_scale: f64::NAN,
        bulk_scale_sigma: f64::NAN,
        measured: [0.3, 6.9e6, 6.9e6],
        u_v: 0.0,
        residual: [0.0; 3],
        innovation: [0.0; 3],
        innovation_sigma: [1e-5, 5e3, 5e3],
        mae_pa: [0.0; 2],
        nis: 3.0,
        oil_temp_c: f64::NAN,
        oil_temp_sigma_k: f64::NAN,
        laminar_factor_sigma: f64::NAN,
        null_leakage_band_lpm: f64::NAN,
        offset_response_lpm_per_mpa: [[0.0; 3]; 2],
        span_response_lpm: [[0.0; 3]; 2],
        position_offset_response_lpm_per_mm: [0.0; 3],
        delay_response_lpm_per_ms: [[0.0; 3]; 2],
    }
}

/// Feeds `seconds` of 1 kHz estimates whose ext1 size is `ext1(t)` plus noise of
/// spread `spread(t)` L/min (slow: a new value every 20 ms, held), and returns the
/// events and the ext1 threshold at each whole second.
fn feed(
    det: &mut LeakSizeDetector,
    seconds: f64,
    spread: impl Fn(f64) -> f64,
    ext1: impl Fn(f64) -> f64,
) -> (Vec<LeakEvent>, Vec<f64>) {
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let (mut events, mut thresholds) = (Vec::new(), Vec::new());
    let mut held = [0.0; 3];
    for i in 0..(seconds * 1000.0) as usize {
        let t = i as f64 * 1e-3;
        if i % 20 == 0 {
            let s = spread(t);
            held = [s * noise.gauss(), s * noise.gauss(), 0.0];
        }
        let mut out = None;
        det.on_estimate(&estimate(t, [ext1(t) + held[0], held[1], held[2]]), &mut out);
        events.extend(out);
        if i % 1000 == 0 {
            thresholds.push(det.thresholds_lpm()[0]);
        }
    }
    (events, thresholds)
}

#[test]
fn thresholds_are_refined_from_the_healthy_time_after_arming() {
    // The warm-up (3 s settling, 5 s learning: armed at 8 s) sees a spread of 0.05 L/min; from then on the
    // healthy estimate is four times quieter. A 0.2 L/min ext1 leak from 40 s sits
    // below the warm-up's threshold and well above the refined one.
    let spread = |t: f64| if t < 8.0 { 0.05 } else { 0.0125 };
    let leak = |t: f64| if t >= 40.0 { 0.2 } else { 0.0 };
    let cfg = ClassifierConfig::default();
    let mut det = LeakSizeDetector::new(cfg.clone());
    let (events, thr) = feed(&mut det, 50.0, spread, leak);
    let armed = thr[10];
    let refined = thr[39];
    assert!(
        armed > 0.22,
        "the warm-up's threshold {armed} L/min (spread 0.05)"
    );
    // z ≈ 5 spreads of 0.0125 (the Rice factor for the upcrossing rate), within 20 %.
    assert!(
        refined > 0.05 && refined < 0.08 && refined < 0.4 * armed,
        "refined threshold {refined} L/min"
    );
    // One leak: raised within 1 s (a step this clear may be raised with its kind
    // pending first), named ext1 under the same id.
    let raised: Vec<_> = events.iter().filter(|e| e.phase == Phase::Raised).collect();
    assert!(
        !raised.is_empty() && raised.iter().all(|e| e.event_id == raised[0].event_id),
        "{events:#?}"
    );
    assert!((40.0..41.0).contains(&raised[0].t_detect_s), "{:?}", raised[0]);
    let named = raised
        .iter()
        .find(|e| e.kind != EventKind::Leak)
        .expect("the kind is named");
    assert_eq!(named.kind, EventKind::Ext1, "{named:?}");

    // Turned off, the warm-up's threshold stays and the same leak is not seen.
    let mut det = LeakSizeDetector::new(ClassifierConfig {
        refine_after_s: 0.0,
        ..cfg
    });
    let (events, thr) = feed(&mut det, 50.0, spread, leak);
    assert!((thr[39] - armed).abs() < 1e-12, "{} vs {armed}", thr[39]);
    assert!(events.iter().all(|e| e.phase != Phase::Raised), "{events:#?}");
}

#[test]
fn only_patterns_leaks_can_make_are_evidence() {
    let thr = [0.06, 0.06, 0.06];
    // A single leak of each kind, and two together.
    for q in [[0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3], [0.2, 0.2, 0.1]] {
        assert!(leak_can_make(signatures_lpm(q), thr), "{q:?}");
    }
    // Healthy noise around zero is inside the tolerance.
    assert!(leak_can_make(signatures_lpm([-0.02, 0.03, -0.02]), thr));
    // Chamber 1 gaining flow while chamber 2 loses it (the internal-leak estimate
    // relaxing): no leak coefficient ≥ 0 makes it, although ext2 "rises" 0.15.
    let relaxing = signatures_lpm([0.0, 0.0, -0.15]);
    assert!(relaxing[1] > 0.1);
    assert!(!leak_can_make(relaxing, thr), "{relaxing:?}");
    // Both chambers gaining flow: a negative external leak.
    assert!(!leak_can_make(signatures_lpm([-0.1, -0.1, 0.0]), thr));
}

/// Time from a step of leak sizes `step_lpm` (q_e1, q_e2, q_i at the nominal
/// drop) at 20 s to the first alarm, s, on a healthy stream of spread 0.01 L/min
/// with the chambers at 9.9 and 3.0 MPa (every kind's drop near p_s/2).
fn delay_of_step(cfg: &ClassifierConfig, step_lpm: [f64; 3]) -> f64 {
    delay_of_step_with_band(cfg, step_lpm, 0.0)
}

/// As [`delay_of_step`], with estimates whose null-leakage band is `band_lpm`
/// (L/min: the oil has moved from the commissioning's temperature).
fn delay_of_step_with_band(cfg: &ClassifierConfig, step_lpm: [f64; 3], band_lpm: f64) -> f64 {
    let mut det = LeakSizeDetector::new(cfg.clone());
    let mut noise = Noise(0x2545_f491_4f6c_dd1d);
    let mut held = [0.0; 3];
    for i in 0..25_000 {
        let t = i as f64 * 1e-3;
        if i % 20 == 0 {
            held = [0.01 * noise.gauss(), 0.01 * noise.gauss(), 0.0];
        }
        let on = if t >= 20.0 { 1.0 } else { 0.0 };
        let mut e = estimate(t, std::array::from_fn(|k| held[k] + on * step_lpm[k]));
        (e.state[1], e.state[2]) = (9.9e6, 3.0e6);
        (e.measured[1], e.measured[2]) = (9.9e6, 3.0e6);
        e.null_leakage_band_lpm = band_lpm;
        let mut out = None;
        det.on_estimate(&e, &mut out);
        if let Some(ev) = out.filter(|ev| ev.phase == Phase::Raised) {
            assert!(t >= 20.0, "a false alarm at {t} s: {ev:?}");
            return t - 20.0;
        }
    }
    f64::INFINITY
}

#[test]
fn an_external_leak_that_alone_explains_the_mismatch_is_confirmed_sooner() {
    // A step far above the threshold counts 2 s of evidence per second: an external
    // leak needs 0.1 s of evidence (0.05 s), an internal one 0.2 s (0.1 s).
    let cfg = ClassifierConfig::default();
    assert_eq!(
        (cfg.confirm_s, cfg.confirm_external_s, cfg.confirm_gain_cap),
        (0.2, 0.1, 2.0)
    );
    for step in [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0]] {
        let d = delay_of_step(&cfg, step);
        assert!((0.045..0.06).contains(&d), "external {step:?}: {d} s");
    }
    let d = delay_of_step(&cfg, [0.0, 0.0, 0.5]);
    assert!((0.095..0.11).contains(&d), "internal: {d} s");
    // With the external confirmation as long as the rest, it waits as long.
    let same = ClassifierConfig {
        confirm_external_s: 0.2,
        ..cfg
    };
    let d = delay_of_step(&same, [0.5, 0.0, 0.0]);
    assert!((0.095..0.11).contains(&d), "external at 0.2 s: {d} s");
}

/// A filter that resets on every sample (one that cannot start on a rig) gives
/// one reset event per run of resets, not one per sample; a later, separate
/// reset is a new event.
#[test]
fn a_run_of_filter_resets_is_one_event() {
    let mut c = detect::Classifier::new(ClassifierConfig::default()).expect("classifier");
    let mut resets = 0;
    let mut count = |ev: LeakEvent| {
        if ev.kind == EventKind::EstimatorReset {
            resets += 1;
        }
    };
    let thesis_reset = |t: f64| {
        let mut e = estimate(t, [0.0; 3]);
        e.flags = filter::FLAG_RESET | filter::FLAG_SKIPPED;
        e
    };
    for k in 0..1000 {
        let t = k as f64 * 1e-3;
        c.on_estimates(&estimate(t, [0.0; 3]), &thesis_reset(t), &mut count);
    }
    for k in 1000..1100 {
        let t = k as f64 * 1e-3;
        c.on_estimates(&estimate(t, [0.0; 3]), &estimate(t, [0.0; 3]), &mut count);
    }
    for k in 1100..1200 {
        let t = k as f64 * 1e-3;
        c.on_estimates(&estimate(t, [0.0; 3]), &thesis_reset(t), &mut count);
    }
    assert_eq!(resets, 2, "1000 resets, then 100 without, then 100 more");
}

/// The first raised event of a healthy stream (spread 0.01 L/min) whose internal
/// size is `q_i(t)` L/min, over `seconds`: (time s, kind).
fn first_raised(seconds: f64, q_i: impl Fn(f64) -> f64) -> Option<(f64, EventKind)> {
    let mut det = LeakSizeDetector::new(ClassifierConfig::default());
    let mut noise = Noise(0x5851_f42d_4c95_7f2d);
    let mut held = [0.0; 3];
    for i in 0..(seconds * 1000.0) as usize {
        let t = i as f64 * 1e-3;
        if i % 20 == 0 {
            held = [0.01 * noise.gauss(), 0.01 * noise.gauss(), 0.0];
        }
        let mut e = estimate(t, [held[0], held[1], q_i(t)]);
        (e.state[1], e.state[2]) = (9.9e6, 3.0e6);
        (e.measured[1], e.measured[2]) = (9.9e6, 3.0e6);
        let mut out = None;
        det.on_estimate(&e, &mut out);
        if let Some(ev) = out.filter(|ev| ev.phase == Phase::Raised) {
            return Some((t, ev.kind));
        }
    }
    None
}

#[test]
fn a_kick_no_leak_can_make_does_not_move_the_baseline() {
    // A transient the model cannot follow kicks the internal-leak estimate to
    // −0.6 L/min for 8 s (chamber 1 gains flow, chamber 2 loses it: no leak makes
    // that), and it relaxes back with a 3 s time constant. A baseline that
    // followed the kick (15 s time constant) would be ~0.3 L/min low when the
    // estimate comes back: a false internal leak of ~20 thresholds.
    let kick = |t: f64| {
        if t < 60.0 {
            0.0
        } else if t < 68.0 {
            -0.6
        } else {
            -0.6 * (-(t - 68.0) / 3.0).exp()
        }
    };
    assert_eq!(first_raised(100.0, kick), None);
    // A real internal leak of 0.3 L/min after it is raised within 1 s and named.
    let leak = |t: f64| kick(t) + if t >= 90.0 { 0.3 } else { 0.0 };
    let (t, _) = first_raised(100.0, leak).expect("the leak after the kick is raised");
    assert!((90.0..91.0).contains(&t), "raised at {t} s");
}

#[test]
fn the_internal_leaks_pressure_factors_cancel_what_no_chamber_sees() {
    // The nominal factors are the thesis convention, bit for bit.
    for q in [[0.3, -0.1, 0.25], [-0.02, 0.03, -0.2]] {
        let w = signatures_lpm(q);
        assert_eq!(signatures_with(q, NOMINAL_INTERNAL_FACTORS), w);
        assert_eq!(misfits_with(w, NOMINAL_INTERNAL_FACTORS), misfits(w));
    }
    // A lift holding its load: p1 = 8.4, p2 = 12.4 MPa. r_i = ssqrt(p1 − p2)/√p_i.
    let (p1, p2) = (8.4e6_f64, 12.4e6_f64);
    let s = -(p2 - p1).sqrt();
    let r = [s / p1.sqrt(), s / p2.sqrt()];
    // The combination (−r1, r2, 1)·q_i changes no chamber's flow: no signature moves.
    let unseen = signatures_with([-r[0] * 0.5, r[1] * 0.5, 0.5], r);
    assert!(unseen.iter().all(|v| v.abs() < 1e-12), "{unseen:?}");
    // A 0.3 L/min internal leak: its own size, inside the cone, fitted best by
    // the internal hypothesis; in the nominal geometry it is no leak at all.
    let thr = [0.04; 3];
    let w = signatures_with([0.0, 0.0, 0.3], r);
    assert!((w[2] - 0.3).abs() < 1e-12, "{w:?}");
    assert!(leak_can_make_with(w, thr, r));
    let m = misfits_with(w, r);
    assert!(m[2] < 1e-12 && m[0] > 0.1 && m[1] > 0.1, "{m:?}");
    assert!(!leak_can_make(w, thr));
    // External leaks stay in the cone; a negative one does not.
    assert!(leak_can_make_with(signatures_with([0.3, 0.0, 0.0], r), thr, r));
    assert!(leak_can_make_with(signatures_with([0.0, 0.3, 0.0], r), thr, r));
    assert!(!leak_can_make_with(signatures_with([0.0, -0.3, 0.0], r), thr, r));
    assert!(!leak_can_make_with(signatures_with([0.0, 0.0, -0.3], r), thr, r));
}

/// The commissioning learner's factors on 30 s of estimates at pressures `p` (Pa).
fn learned_factors(p: impl Fn(f64) -> (f64, f64)) -> [f64; 2] {
    let mut learner = CommissioningLearner::new(1.0);
    for i in 0..30_000 {
        let t = i as f64 * 1e-3;
        let mut e = estimate(t, [0.0; 3]);
        (e.state[1], e.state[2]) = p(t);
        learner.on_estimate(&e);
    }
    let c = learner
        .finish(&ClassifierConfig::default(), 10.0, "test")
        .expect("commissioned");
    assert_eq!(c.internal_factors, learner.internal_factors());
    c.internal_factors
}

#[test]
fn commissioning_takes_the_factors_where_the_pressure_difference_keeps_its_sign() {
    // A held load: p1 − p2 = −4 MPa ± 1 MPa.
    let r = learned_factors(|t| (8.4e6 + 1e6 * (3.0 * t).sin(), 12.4e6));
    let s_mean = -(4.0e6_f64).sqrt();
    assert!((r[0] / (s_mean / 8.4e6_f64.sqrt()) - 1.0).abs() < 0.05, "{r:?}");
    assert!((r[1] / (s_mean / 12.4e6_f64.sqrt()) - 1.0).abs() < 0.05, "{r:?}");
    // A double-rod rig reversing its load: the nominal factors.
    let r = learned_factors(|t| (10.5e6 + 1.5e6 * (3.0 * t).sin(), 10.5e6 - 1.5e6 * (3.0 * t).sin()));
    assert_eq!(r, NOMINAL_INTERNAL_FACTORS);
}

/// The oil's band widens every threshold by itself: a 0.1 L/min ext1 step is
/// found on a healthy stream of spread 0.01 L/min, not when the model's null
/// leakage is uncertain by 0.15 L/min; a 0.5 L/min step is found either way.
#[test]
fn the_oils_null_leakage_band_widens_the_thresholds() {
    let cfg = ClassifierConfig::default();
    let plain = delay_of_step_with_band(&cfg, [0.1, 0.0, 0.0], 0.0);
    assert!(plain < 1.0, "{plain} s");
    let banded = delay_of_step_with_band(&cfg, [0.1, 0.0, 0.0], 0.15);
    assert!(banded.is_infinite(), "{banded} s");
    let large = delay_of_step_with_band(&cfg, [0.5, 0.0, 0.0], 0.15);
    assert!(large < 1.0, "{large} s");
}

/// Commissioning on a healthy stream of spread 0.01 L/min around 0.02 L/min,
/// kicked down by 0.5 L/min for 1 s in every 10 (a transient the filter cannot
/// follow): the offset is the median and the spread the noise's, not the dips'
/// (the standard deviation would be about 0.15 L/min, 15 times wider).
#[test]
fn commissioning_learns_the_rises_spread_not_the_dips() {
    let mut noise = Noise(0x005e_ed0f_d1b5);
    let mut learner = CommissioningLearner::new(1.0);
    for i in 0..120_000 {
        let t = i as f64 * 1e-3;
        let dip = if t % 10.0 >= 9.0 { -0.5 } else { 0.0 };
        let q = [0.02 + 0.01 * noise.gauss() + dip, 0.0, 0.0];
        learner.on_estimate(&estimate(t, q));
    }
    let c = learner
        .finish(&ClassifierConfig::default(), 10.0, "test")
        .expect("commissioned");
    // ext1's signature is q_e1 alone when the others are zero.
    assert!((c.offsets_lpm[0] - 0.02).abs() < 0.002, "{:?}", c.offsets_lpm);
    assert!((c.spreads_lpm[0] / 0.01 - 1.0).abs() < 0.1, "{:?}", c.spreads_lpm);
}
