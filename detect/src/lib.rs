//! The detectors of the classifier stage: turn the estimator's output into leak events.
//!
//! This crate is pure (no bus, command line or config files); the `classifier`
//! crate is the process around it and re-exports everything here.
//!
//! Two detectors read the same [`filter::Estimate`] stream:
//!
//! - [`LeakSizeDetector`] (leakwatch's own): the 10-state filter estimates the
//!   three leak sizes q_e1, q_e2, q_i directly (m³/s at the nominal drop). After
//!   a healthy warm-up has learned each estimate's offset and spread (a healthy
//!   rig that differs from the model, e.g. a spool null bias, leaves a steady
//!   offset), a leak is declared when one size rises above
//!   max(c·spread, `min_size_lpm` (external) or `min_internal_size_lpm` of real
//!   flow at the measured pressures)
//!   (c from `false_alarms_per_hour`, at least `threshold_sigma`) for
//!   `confirm_s` of evidence. The spreads are refined from the healthy time
//!   after arming (`refine_after_s`; only ever lowered), and only a mismatch
//!   that leak coefficients ≥ 0 can make counts ([`leak_can_make`]). The rise is measured from a healthy baseline that follows
//!   the estimate slowly (time constant `baseline_tau_s`, frozen while a leak
//!   is reported, and while a rise is past `baseline_hold` of its threshold once
//!   the baseline has settled): an off-nominal rig makes the healthy estimate
//!   wander with the operating point over tens of seconds, a leak steps or
//!   ramps in seconds. Whatever the baseline has absorbed since the warm-up is judged
//!   against the larger `slow_leak_lpm`, so a leak that grows over minutes is
//!   still reported (detail `slowly growing`). Isolation: the kind whose rise
//!   is largest relative to its threshold. Size: the rise above the baseline,
//!   with the filter's σ. Onset: the last time the rise was below a
//!   quarter of the threshold.
//! - [`MaeDetector`] (the thesis' baseline, docs/model.md#the-baseline-detector):
//!   the moving averages of |residual| of p1 and p2; thresholds = `margin` × the
//!   largest healthy MAE seen in the warm-up; p1 only → ext1, p2 only → ext2,
//!   both → internal. It cannot size a leak.
//!
//! Both debounce: one leak gives one `raised` event, then `updated` events as
//! the size estimate moves, and `cleared` when it goes away. Sensor checks
//! raise `sensor-stuck`, `sensor-saturated` and `sensor-dead` events, and a
//! filter reset raises `estimator-reset` (and restarts the warm-up).

#![forbid(unsafe_code)]
// The detectors walk parallel per-kind arrays by index; iterators would hide that.
#![allow(clippy::needless_range_loop)]

mod config;
mod events;
mod leak_size;
mod mae;
pub mod offset;
pub mod spikes;
mod stage;
mod track;

pub use config::{ClassifierConfig, Commissioning};
pub use events::{EventKind, LeakEvent, Phase};
pub use leak_size::{
    rice_threshold, thresholds, BlindCause, BlindSeconds, CommissioningLearner, LeakSizeDetector, Stretch,
    STRETCH_SHARE, STRETCH_THRESHOLD_RATIO,
};
pub use mae::MaeDetector;
pub use stage::Classifier;

/// Half-width of the band the valve command must swing through to count as a reversal, V.
pub const COMMAND_REVERSAL_BAND_V: f64 = 1.0;
/// Time over which the baseline is taken again after a stretch the model could not
/// follow (it follows the estimates with a 0.5 s time constant meanwhile, and no
/// evidence counts), s.
pub const REACQUIRE_S: f64 = 4.0;

/// Time constant of the command reversal rate, s.
pub const COMMAND_RATE_WINDOW_S: f64 = 2.0;

/// Time constant of the NIS average that the NIS-ratio gate compares, s.
pub const NIS_RATIO_WINDOW_S: f64 = 5.0;
/// While a leak's kind is pending, the rises are averaged over this time, s: the
/// mismatch a leak leaves swings with the operating point (a sine or step period),
/// its kind is read from the average.
pub const KIND_AVERAGE_S: f64 = 1.0;

/// Cubic metres per second in one litre per minute.
const M3_S_PER_LPM: f64 = 1.0e-3 / 60.0;

/// The pressure factors (r1, r2) of the thesis rig's convention: an internal
/// leak of nominal size q moves the chamber-flow signatures by (q, −q).
pub const NOMINAL_INTERNAL_FACTORS: [f64; 2] = [1.0, 1.0];

/// How badly each single-leak hypothesis (ext1, ext2, int) fits rises `r` =
/// [w1, w2, int] of the chamber flows, L/min: the part of the flow mismatch it
/// leaves unexplained (ext1 leaves w2, ext2 leaves w1, an internal leak leaves
/// the part across its direction (r1, −r2), see [`signatures_with`]).
pub fn misfits_with(r: [f64; 3], factors: [f64; 2]) -> [f64; 3] {
    let (w1, w2) = (r[0], r[1]);
    let [r1, r2] = factors;
    [
        w2.abs(),
        w1.abs(),
        (r2 * w1 + r1 * w2).abs() / (r1 * r1 + r2 * r2).sqrt(),
    ]
}

/// [`misfits_with`] in the thesis rig's convention ([`NOMINAL_INTERNAL_FACTORS`]).
pub fn misfits(r: [f64; 3]) -> [f64; 3] {
    misfits_with(r, NOMINAL_INTERNAL_FACTORS)
}

/// The size of each single-leak hypothesis that best explains estimated leak
/// sizes `q_lpm` = [q_e1, q_e2, q_i] (L/min at nominal drop), judged by the
/// flows they take from each chamber: w1 = q_e1 + r1·q_i out of chamber 1 and
/// w2 = q_e2 − r2·q_i out of chamber 2, with the internal leak's pressure
/// factors `factors` = (r1, r2). An external leak at chamber 1 is
/// (w1, w2) = (q, 0), at chamber 2 (0, q), an internal leak (r1·q, −r2·q); so
/// the sizes are [w1, w2, (r1·w1 − r2·w2)/(r1² + r2²)]. (The three estimates
/// are strongly correlated: a combination that changes no chamber's flow is
/// not seen by the data, and the estimates wander along it; the chamber flows
/// are what the data pins down.)
///
/// The factors are the ratios of the internal leak's drop to each chamber's
/// own, r_i = ssqrt(p1 − p2)/√p_i, where the chambers rest at pressures whose
/// difference keeps its sign (a single-rod cylinder carrying a load): then
/// that combination is (−r1, r2, 1)·q_i and the signatures cancel it. Where it
/// changes sign with the load (the thesis rig, p1 ≈ p2), the nominal (1, 1).
pub fn signatures_with(q_lpm: [f64; 3], factors: [f64; 2]) -> [f64; 3] {
    let [r1, r2] = factors;
    let w1 = q_lpm[0] + r1 * q_lpm[2];
    let w2 = q_lpm[1] - r2 * q_lpm[2];
    [w1, w2, (r1 * w1 - r2 * w2) / (r1 * r1 + r2 * r2)]
}

/// [`signatures_with`] in the thesis rig's convention ([`NOMINAL_INTERNAL_FACTORS`]).
pub fn signatures_lpm(q_lpm: [f64; 3]) -> [f64; 3] {
    signatures_with(q_lpm, NOMINAL_INTERNAL_FACTORS)
}

/// Whether rises `rise` = [w1, w2, int] of the chamber flows (L/min,
/// [`signatures_with`] with `factors`) are a pattern that leaks can make,
/// within one threshold `threshold_lpm` (ext1, ext2, int; L/min) of it. Every
/// leak coefficient is ≥ 0, so the rises lie in the cone spanned by ext1
/// (1, 0), ext2 (0, 1) and int (r1, −r2). With the nominal factors: leaks take
/// flow out of chamber 1 or none (w1 = q_e1 + q_i ≥ 0) and out of the two
/// chambers together (w1 + w2 = q_e1 + q_e2 ≥ 0). A pattern far outside that
/// cone (the filter's internal-leak estimate relaxing after its start makes
/// w1 fall while w2 rises) is model error, not a leak.
pub fn leak_can_make_with(rise: [f64; 3], threshold_lpm: [f64; 3], factors: [f64; 2]) -> bool {
    let [r1, r2] = factors;
    let tol = threshold_lpm[0].max(threshold_lpm[1]);
    // The side of the internal leak's ray, scaled so that the nominal factors give w1 + w2.
    let across = (r2 * rise[0] + r1 * rise[1]) / (0.5 * (r1.abs() + r2.abs()));
    if r1 >= 0.0 {
        rise[0] >= -threshold_lpm[0] && across >= -tol
    } else {
        // The internal leak feeds chamber 1 (p2 > p1): the cone is bounded by ext1's ray.
        rise[1] >= -threshold_lpm[1] && -across >= -tol
    }
}

/// [`leak_can_make_with`] in the thesis rig's convention ([`NOMINAL_INTERNAL_FACTORS`]).
pub fn leak_can_make(rise: [f64; 3], threshold_lpm: [f64; 3]) -> bool {
    leak_can_make_with(rise, threshold_lpm, NOMINAL_INTERNAL_FACTORS)
}

/// Names of the measured channels, in measurement order.
pub const CHANNELS: [&str; 3] = ["x", "p1", "p2"];

/// What the oil's temperature adds to each leak kind's threshold (ext1, ext2,
/// int), L/min at p_s/2: the model's null leakage band `null_leakage_band_lpm`
/// (L/min) plus the laminar factor's σ `laminar_factor_sigma` (1) times each
/// healthy offset `offsets_lpm` (L/min, learned at the commissioning's
/// temperature: flow the model lacks, which may be laminar). Non-finite
/// inputs count as 0 (docs/plant.md, "What the temperature leaves uncertain").
pub fn oil_band_lpm(
    laminar_factor_sigma: f64,
    null_leakage_band_lpm: f64,
    offsets_lpm: [f64; 3],
) -> [f64; 3] {
    let finite_or_zero = |v: f64| if v.is_finite() { v.abs() } else { 0.0 };
    let sigma = finite_or_zero(laminar_factor_sigma);
    let band = finite_or_zero(null_leakage_band_lpm);
    std::array::from_fn(|k| band + sigma * finite_or_zero(offsets_lpm[k]))
}

/// What the transducers' delay adds to each leak kind's threshold (ext1, ext2,
/// int), L/min at p_s/2: its uncertainty `delay_uncertainty_ms` (ms) times
/// what each kind's response to a delay on both transducers
/// (`delay_response_lpm_per_ms`, L/min per ms on p1 and on p2, as
/// [`filter::Estimate::delay_response_lpm_per_ms`]; in the kinds' signatures
/// with `factors`, [`signatures_with`]) has beyond `reach_lpm_per_ms` (L/min
/// per ms, the response the commissioning's spreads saw). Non-finite
/// responses count as 0.
pub fn delay_band_lpm(
    delay_uncertainty_ms: f64,
    delay_response_lpm_per_ms: [[f64; 3]; 2],
    factors: [f64; 2],
    reach_lpm_per_ms: [f64; 3],
) -> [f64; 3] {
    let [on_p1, on_p2] = delay_response_lpm_per_ms;
    let both: [f64; 3] = std::array::from_fn(|k| {
        let r = on_p1[k] + on_p2[k];
        if r.is_finite() {
            r
        } else {
            0.0
        }
    });
    let signature = signatures_with(both, factors);
    std::array::from_fn(|k| delay_uncertainty_ms * (signature[k].abs() - reach_lpm_per_ms[k]).max(0.0))
}
