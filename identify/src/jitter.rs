//! The DAQ's sample-time jitter, from the position's third differences.
//!
//! A DAQ that reads a sample at t + δ but stamps it t reads the position as
//! x + v·δ. The third difference x[k+2] − 3·x[k+1] + 3·x[k] − x[k−1] then
//! holds the motion (its jerk times T³), the sensor's own noise (20·σ_x² in
//! its mean square, the counts' included) and v times the same difference
//! of the δ (20·σ_δ²·v², each δ drawn anew). Over the samples where the rod
//! moves at a steady speed, the mean square is fitted as c + 20·σ_δ²·v² by
//! least squares: σ_δ² is the slope. No model enters: only the readings.
//! (A second difference keeps more of the motion: the rod's ring at the
//! hydraulic mode, 100-150 Hz, passes it at half its amplitude and the third
//! at a third, while the noise's share grows from 6 to 20.)

use crate::{Estimate, Found, Row, SensorNoise, RESOLVED_SIGMAS};

/// Half-width of the stencils the velocity and the acceleration are read
/// over, samples (their noise is that of readings this far apart).
const STENCIL: usize = 10;
/// Sum of the third difference's squared weights (1 + 9 + 9 + 1).
const WEIGHT: f64 = 20.0;
/// Readings one third difference spans.
const DIFFERENCE_SPAN: usize = 4;
/// Largest acceleration of a sample the fit reads, m/s²: the rod moves
/// steadily there.
const STEADY_M_S2: f64 = 0.5;
/// Fewest counts the rod moves per sample for the fit to read it: the
/// counts' error is then independent from one reading to the next.
const COUNTS_PER_SAMPLE: f64 = 2.0;
/// Largest count of the position sensor, as a multiple of its noise (RMS,
/// the counts' included), for which the fit is read: coarser counts are not
/// dithered by the noise, and their error follows the speed in a pattern.
const MOST_STEP_PER_SIGMA: f64 = 2.0;
/// Fewest samples the fit needs.
const MIN_SAMPLES: usize = 500;
/// Largest jitter accepted, as a share of the sample period (1).
const MOST_SHARE_OF_PERIOD: f64 = 0.2;

/// The RMS deviation of the sample instants from their grid, s, on the rows
/// `rows` at sample period `dt_s` (s), read by a position sensor of `noise`.
/// Not identified where the sensor's counts are coarse against its noise,
/// where the rod never moved fast and steadily enough, or where the slope is
/// not resolved from zero.
pub(crate) fn sample_jitter(rows: &[Row], dt_s: f64, noise: SensorNoise) -> Found {
    let step = noise.position_step_m;
    if step > MOST_STEP_PER_SIGMA * noise.position_m {
        return Found::NotIdentifiable(format!(
            "the position sensor's counts ({:.1} µm) are coarse against its noise ({:.1} µm RMS): \
             their error follows the speed",
            step * 1e6,
            noise.position_m * 1e6
        ));
    }
    let least_speed = COUNTS_PER_SAMPLE * step / dt_s;
    let span = 2.0 * STENCIL as f64 * dt_s;
    // (20·v², (Δ³x)²) per sample read
    let mut points: Vec<(f64, f64)> = Vec::new();
    // every fourth sample: the differences then share no reading, and the
    // fit's σ holds for independent points
    for k in (STENCIL..rows.len().saturating_sub(STENCIL)).step_by(DIFFERENCE_SPAN) {
        if rows[k + 1 - STENCIL..=k + STENCIL].iter().any(|r| r.after_gap) {
            continue;
        }
        let x = |j: usize| rows[j].sample.x_m;
        let (before, at, after) = (x(k - STENCIL), x(k), x(k + STENCIL));
        let v = (after - before) / span;
        let a = (after - 2.0 * at + before) / (STENCIL as f64 * dt_s).powi(2);
        let d3 = x(k + 2) - 3.0 * x(k + 1) + 3.0 * at - x(k - 1);
        if v.abs() >= least_speed && a.abs() <= STEADY_M_S2 && d3.is_finite() {
            points.push((WEIGHT * v * v, d3 * d3));
        }
    }
    let n = points.len();
    if n < MIN_SAMPLES {
        return Found::NotIdentifiable(format!(
            "the rod moved steadily at {:.1} mm/s or more in {n} samples, {MIN_SAMPLES} needed",
            least_speed * 1e3
        ));
    }
    let (slope, sigma) = fitted_slope(&points);
    if slope < -RESOLVED_SIGMAS * sigma {
        return Found::NotIdentifiable(format!(
            "the position's noise falls with the speed ({:.1} ± {:.1} µs²): the rod's own motion is in it, not a jitter",
            slope * 1e12,
            sigma * 1e12
        ));
    }
    if slope.is_nan() || slope <= RESOLVED_SIGMAS * sigma {
        return Found::NotIdentifiable(format!(
            "not resolved from zero ({:.1} ± {:.1} µs²)",
            slope * 1e12,
            sigma * 1e12
        ));
    }
    let jitter = slope.sqrt();
    if jitter > MOST_SHARE_OF_PERIOD * dt_s {
        return Found::NotIdentifiable(format!(
            "came out {:.0} µs, more than {:.0} % of the sample period: the position's noise grows with the speed for another reason",
            jitter * 1e6,
            MOST_SHARE_OF_PERIOD * 100.0
        ));
    }
    Found::Identified(Estimate {
        value: jitter,
        sigma: sigma / (2.0 * jitter),
    })
}

/// The least-squares slope of y on z over `points` (z, y), with an intercept,
/// and its standard deviation (white residuals assumed: a floor, as every σ
/// of this crate).
fn fitted_slope(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (mz, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (z, y)| (a + z / n, b + y / n));
    let (szz, szy) = points.iter().fold((0.0, 0.0), |(a, b), (z, y)| {
        (a + (z - mz) * (z - mz), b + (z - mz) * (y - my))
    });
    if szz <= 0.0 {
        return (0.0, f64::INFINITY);
    }
    let slope = szy / szz;
    let residual2: f64 = points
        .iter()
        .map(|(z, y)| (y - my - slope * (z - mz)).powi(2))
        .sum();
    (slope, (residual2 / (n - 2.0).max(1.0) / szz).sqrt())
}
