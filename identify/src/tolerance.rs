//! How far the pressure transducers' tolerances move the null leakage the
//! flow balance finds.
//!
//! The null leakage's flows go with p_s − p and p − p_r: absolute pressures.
//! A transducer's zero offset or span error moves them, and one recording
//! cannot tell it apart (an offset cancels in the pressure changes the rest
//! of the balance uses). Where a chamber rests near p_s/2 (a lift holding
//! its load) the null leakage's net flow is small, and an offset of a few
//! tens of kPa moves the fitted conductance by tens of per cent. The fit's
//! own σ does not hold that; this module measures it.

use crate::fit::identify_once;
use crate::{Found, Identification, Row, SensorNoise};
use model::ActuatorParams;

/// The datasheet's tolerances of each pressure transducer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TransducerTolerance {
    /// The largest zero offset, Pa.
    pub zero_offset_max_pa: f64,
    /// The largest span error, as a fraction of the reading (1).
    pub span_error_max_fraction: f64,
}

impl TransducerTolerance {
    /// True when the datasheet gives neither tolerance.
    pub fn is_unknown(&self) -> bool {
        !(self.zero_offset_max_pa > 0.0 || self.span_error_max_fraction > 0.0)
    }
}

/// The readings of `rows` with channel `channel` (0: p1, 1: p2) read through
/// a zero offset `offset_pa` (Pa) and a span error `span` (1).
fn misread(rows: &[Row], channel: usize, offset_pa: f64, span: f64) -> Vec<Row> {
    rows.iter()
        .map(|r| {
            let mut r = *r;
            let p = if channel == 0 {
                &mut r.sample.p1_pa
            } else {
                &mut r.sample.p2_pa
            };
            *p = *p * (1.0 + span) + offset_pa;
            r
        })
        .collect()
}

/// How far the transducers' tolerances move the null leakage, m³/(s·Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NullLeakageTolerance {
    /// Its standard deviation: each tolerance uniform within ± its maximum
    /// (σ = max/√3, the mean square of its two moves), the four independent.
    pub sigma_m3_s_pa: f64,
    /// The most they move it: each tolerance's larger move, the four adding up.
    pub worst_m3_s_pa: f64,
}

/// How far the transducers' tolerances `tol` move the null leakage of the
/// identification `id` found on `rows` (sample period `dt_s`, s) against the
/// model `p`. The flow balance is fitted again with each channel's readings
/// moved by its largest zero offset, then by its largest span error, each
/// both ways: eight fits. The response need not be linear (the line's column
/// may come and go with them): each tolerance counts its larger move. `None` without tolerances, when the null leakage was not
/// identified, or when a moved fit does not identify it.
pub fn null_leakage_tolerance(
    p: &ActuatorParams,
    dt_s: f64,
    rows: &[Row],
    noise: SensorNoise,
    id: &Identification,
    tol: TransducerTolerance,
) -> Option<NullLeakageTolerance> {
    if tol.is_unknown() {
        return None;
    }
    // the fits run at the spool frequency `identify` settled on
    let mut at = p.clone();
    if let Some(w) = id.spool_natural_freq_rad_s.estimate() {
        at.spool_natural_freq_rad_s = w.value;
    }
    let fit = |rows: &[Row]| null_leakage(&at, dt_s, rows, noise, &id.sample_jitter_s);
    let base = fit(rows)?;
    let (mut sum_sq, mut worst) = (0.0, 0.0);
    for channel in 0..2 {
        for (offset_pa, span) in [(tol.zero_offset_max_pa, 0.0), (0.0, tol.span_error_max_fraction)] {
            if offset_pa == 0.0 && span == 0.0 {
                continue;
            }
            // both ways: the fit's columns (the line's) may come and go with them
            let up = fit(&misread(rows, channel, offset_pa, span))? - base;
            let down = fit(&misread(rows, channel, -offset_pa, -span))? - base;
            sum_sq += (up * up + down * down) / 6.0;
            worst += up.abs().max(down.abs());
        }
    }
    Some(NullLeakageTolerance {
        sigma_m3_s_pa: sum_sq.sqrt(),
        worst_m3_s_pa: worst,
    })
}

/// The null leakage one fit finds on `rows` against `p`, m³/(s·Pa), with the
/// DAQ's jitter `jitter` read on the recording.
fn null_leakage(
    p: &ActuatorParams,
    dt_s: f64,
    rows: &[Row],
    noise: SensorNoise,
    jitter: &Found,
) -> Option<f64> {
    match identify_once(p, dt_s, rows, noise, jitter)
        .ok()?
        .null_leakage_m3_s_pa
    {
        Found::Identified(e) => Some(e.value),
        Found::NotIdentifiable(_) => None,
    }
}
