//! Identifies what a datasheet does not pin down, from a healthy recording of
//! a rig's normal operation (docs/identification.md): the valve's
//! flow gain per port, its null leakage, the spool's null bias and the oil's
//! effective stiffness with the dead volumes.
//!
//! The method is the chambers' flow balance (continuity), which holds whatever
//! the mass, friction and load are. Over a window of W sample intervals:
//!
//! - chamber 1: κ_A·ΣQ_A·T + κ_A·b·ΣG_A·T + C_L·ΣN_1·T + Δr·ΣR_1·T − s·ΣV1·Δp1/β − τ1·V1·Δṗ1/β = A1·Δx + ΣL_1·T
//! - chamber 2: κ_B·ΣQ_B·T + κ_B·b·ΣG_B·T + C_L·ΣN_2·T + Δr·ΣR_2·T + s·ΣV2·Δp2/β + τ2·V2·Δṗ2/β = A2·Δx + ΣL_2·T
//!
//! Q_A, Q_B are the model's orifice flows (into chamber 1, out of chamber 2) at
//! the spool position the model's spool dynamics give for the recorded
//! command, G = ∂Q/∂x_sp, N the null leakage per unit C_L, R = ∂Q/∂r the
//! flows' slope in the supply sag r (Pa per m³/s of pump flow), L the model's own
//! leaks, V the chamber volumes at the measured rod position, β the model's
//! bulk modulus. The unknowns are the flow-gain multiples κ_A, κ_B (one κ for a
//! double-rod cylinder), the products κ·b with the spool null bias b, the null
//! leakage C_L, the sag's change Δr, the compliance multiple s (effective
//! β = β_model/s) and each transducer's lag τ (Δṗ: the measured pressure
//! rate's change over the window; a reading lagging by τ is p − τ·ṗ). The
//! system is linear in them: weighted least squares, each chamber's rows
//! weighted by the inverse of its residual RMS.
//!
//! The standard deviations are the least-squares ones. They assume white
//! window errors, so they are a floor: model errors that persist over many
//! windows (supply sag, a line drop) bias a value by more than its σ. The
//! transducers' zero offsets and span errors move the null leakage by more
//! than its σ too: [`null_leakage_tolerance`] measures by how much.

#![forbid(unsafe_code)]

mod fit;
mod jitter;
mod mechanics;
mod tolerance;

pub use mechanics::{identify_mechanics, Mechanics, HALF_WINDOW, MIN_EQUATIONS, SLIDING_M_S};
pub use tolerance::{null_leakage_tolerance, NullLeakageTolerance, TransducerTolerance};

use model::{ActuatorParams, Sample};

/// Sample intervals summed into one equation, per chamber (20 ms at 1 kHz).
pub const WINDOW_SAMPLES: usize = 20;
/// Fewest moving windows an identification needs.
pub const MIN_MOVING_WINDOWS: usize = 100;
/// Largest relative standard deviation of a flow gain or the compliance that
/// counts as identified (1).
pub const MAX_RELATIVE_SIGMA: f64 = 0.05;
/// The null leakage counts as resolved from zero beyond this many of its σ
/// (the σ are a floor, see the module docs; a rig without null leakage came
/// out at 3 σ).
pub const RESOLVED_SIGMAS: f64 = 5.0;
/// A flow-gain multiple outside this range is refused as implausible (1): the
/// datasheet, the command's scale or its sign is wrong, not the tolerance.
pub const PLAUSIBLE_GAIN: (f64, f64) = (0.5, 2.0);
/// A compliance multiple outside this range is refused as implausible (1).
pub const PLAUSIBLE_COMPLIANCE: (f64, f64) = (0.3, 5.0);
/// The spool's natural frequency, as a multiple of the model's, that
/// identification accepts (a catalogue's −90° frequency is typical, not exact).
pub const PLAUSIBLE_SPOOL_FREQUENCY: (f64, f64) = (0.5, 1.5);
/// The longest transducer lag identification accepts, s (a datasheet's 10-90 %
/// response of a few ms is a lag of about a millisecond).
pub const MAX_LAG_S: f64 = 0.01;

/// One recorded sample and whether samples are missing before it.
#[derive(Debug, Clone, Copy)]
pub struct Row {
    /// The sample (SI).
    pub sample: Sample,
    /// Samples are missing between the previous row and this one.
    pub after_gap: bool,
}

/// A value with its standard deviation, in the unit its field names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its standard deviation (least squares, see the module docs).
    pub sigma: f64,
}

/// What became of one parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Found {
    /// Identified, with its uncertainty.
    Identified(Estimate),
    /// Not identifiable from this recording, and why; the model keeps its value.
    NotIdentifiable(String),
}

/// A multiple of the model's value `e` (1) judged: too uncertain (σ above
/// [`MAX_RELATIVE_SIGMA`] of it) or outside `plausible` is not identified, the
/// line naming `what` and the advice.
fn judge(e: Estimate, plausible: (f64, f64), what: &str, uncertain: &str, advice: &str) -> Found {
    if e.sigma > MAX_RELATIVE_SIGMA * e.value.abs() {
        Found::NotIdentifiable(format!(
            "{what} came out {:.3} ± {:.3} of the model's: {uncertain}",
            e.value, e.sigma
        ))
    } else if !(plausible.0..=plausible.1).contains(&e.value) {
        Found::NotIdentifiable(format!(
            "{what} came out {:.3} of the model's: outside {}-{}; {advice}",
            e.value, plausible.0, plausible.1
        ))
    } else {
        Found::Identified(e)
    }
}

impl Found {
    /// The same finding with its value and σ multiplied by `k` (a multiple
    /// of the model's turned into the model's unit).
    pub fn scaled(&self, k: f64) -> Found {
        match self {
            Found::Identified(e) => Found::Identified(Estimate {
                value: e.value * k,
                sigma: e.sigma * k,
            }),
            other => other.clone(),
        }
    }

    /// The estimate, if identified.
    pub fn estimate(&self) -> Option<Estimate> {
        match self {
            Found::Identified(e) => Some(*e),
            Found::NotIdentifiable(_) => None,
        }
    }
}

/// The rig's parameters identified on one recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// Port A's flow gain as a multiple of the model's (1).
    pub valve_gain_a: Found,
    /// Port B's flow gain as a multiple of the model's (1); for a double-rod
    /// cylinder the same as port A's (one gain is fitted).
    pub valve_gain_b: Found,
    /// The spool's null bias beyond the model's, m.
    pub null_bias_m: Found,
    /// The valve's null leakage conductance C_L, m³/(s·Pa).
    pub null_leakage_m3_s_pa: Found,
    /// The oil's effective bulk modulus with the dead volumes, Pa.
    pub bulk_modulus_pa: Found,
    /// The supply pressure's drop per unit of pump flow, Pa/(m³/s).
    pub supply_sag_pa_per_m3_s: Found,
    /// The spool's natural frequency ω_n, rad/s: from when the flow follows the
    /// command (a linearised column, the flow's change per 1 % of ω_n).
    pub spool_natural_freq_rad_s: Found,
    /// The pressure transducers' apparent first-order lag per channel (p1,
    /// p2), s: the measured pressure's change lags the flow balance's by τ·Δṗ.
    /// Apparent: it takes up whatever else delays a reading (the line's own
    /// dynamics, DAQ timing). `commission` puts it into the leak filter's
    /// NIS (`[leak_filter] pressure_lag_s`).
    pub pressure_lag_s: [Found; 2],
    /// The line resistance between the transducers (at the valve's manifold)
    /// and the chambers, Pa/(m³/s): the transducers read p1 + R·Q1 and
    /// p2 − R·Q2, Q the valve's flows. Fitted so that the line's drop does
    /// not bias the null leakage; where resolved, every other value is the
    /// fit's with it and [`Identification::apply`] puts it into the model.
    pub line_resistance_pa_s_per_m3: Found,
    /// Windows of [`WINDOW_SAMPLES`] used, and how many of them moved.
    pub windows: usize,
    /// Windows in which the rod moved more than 0.1 mm.
    pub moving_windows: usize,
    /// RMS of the flow-balance error per window with the model as given, L/min.
    pub gap_before_lpm: f64,
    /// The same with the identified parameters, L/min.
    pub gap_after_lpm: f64,
    /// The part of the gap the sensors' noise and the DAQ's timing jitter
    /// alone make, L/min.
    pub sensor_floor_lpm: f64,
    /// The DAQ's sample-time jitter, s (RMS of the instants about their
    /// grid): from the position's second differences, which grow with the
    /// rod's speed as v·δ. Counted in the sensor floor where identified.
    pub sample_jitter_s: Found,
    /// The recording's mean oil temperature, °C, when its rows carry one
    /// (`temp_c` in at least half of them): the temperature the identified
    /// values hold at.
    pub oil_temp_c: Option<f64>,
}

/// The mean oil temperature of `rows`, °C, when at least half of them carry one.
fn mean_oil_temp_c(rows: &[Row]) -> Option<f64> {
    let (n, sum) = rows
        .iter()
        .map(|r| r.sample.temp_c)
        .filter(|t| t.is_finite())
        .fold((0usize, 0.0), |(n, sum), t| (n + 1, sum + t));
    (n > 0 && 2 * n >= rows.len()).then(|| sum / n as f64)
}

/// The sensors' noise, for the sensor floor.
#[derive(Debug, Clone, Copy)]
pub struct SensorNoise {
    /// Position noise, m (RMS).
    pub position_m: f64,
    /// Pressure noise, Pa (RMS).
    pub pressure_pa: f64,
    /// The position sensor's count, m (its quantisation step).
    pub position_step_m: f64,
}

/// Identifies the rig on `rows` (a healthy recording at sample period `dt_s`,
/// s) against the model `p`; see the module docs. The spool's natural
/// frequency enters the flow nonlinearly: the fit is repeated from the found
/// one until it moves less than 0.5 % (at most 4 fits).
pub fn identify(
    p: &ActuatorParams,
    dt_s: f64,
    rows: &[Row],
    noise: SensorNoise,
) -> Result<Identification, String> {
    // the jitter is the recording's, whatever the model: read once
    let jitter = jitter::sample_jitter(rows, dt_s, noise);
    let mut id = fit::identify_once(p, dt_s, rows, noise, &jitter)?;
    let mut at = p.clone();
    for _ in 0..3 {
        let Some(w) = id.spool_natural_freq_rad_s.estimate() else {
            break;
        };
        if (w.value / at.spool_natural_freq_rad_s - 1.0).abs() < 0.005 {
            break;
        }
        at.spool_natural_freq_rad_s = w.value;
        id = Identification {
            gap_before_lpm: id.gap_before_lpm,
            ..fit::identify_once(&at, dt_s, rows, noise, &jitter)?
        };
    }
    id.oil_temp_c = mean_oil_temp_c(rows);
    Ok(id)
}

impl Identification {
    /// `p` with what was identified put in: the area gradients scaled by the
    /// flow gains, the null leakage, the bulk modulus, the supply sag, the line
    /// resistance (0 where not resolved: the fit is then without it), and the
    /// oil law's reference temperature when the recording carried one (the
    /// null bias is left to the leak filter's commissioning, which identifies
    /// it with the filter's own model of the spool).
    pub fn apply(&self, p: &ActuatorParams) -> ActuatorParams {
        let mut out = p.clone();
        let (wa, wb) = p.area_gradients_m2_per_m();
        if let Some(g) = self.valve_gain_a.estimate() {
            out.area_gradient_m2_per_m = wa * g.value;
        }
        if p.area_gradient_b_m2_per_m.is_some() || p.rod_side_area_m2.is_some() {
            let g = self.valve_gain_b.estimate().map_or(1.0, |g| g.value);
            out.area_gradient_b_m2_per_m = Some(wb * g);
        }
        if let Some(c) = self.null_leakage_m3_s_pa.estimate() {
            out.valve_null_leakage_m3_s_pa = c.value;
        }
        if let Some(b) = self.bulk_modulus_pa.estimate() {
            out.bulk_modulus_pa = b.value;
        }
        if let Some(s) = self.supply_sag_pa_per_m3_s.estimate() {
            out.supply_sag_pa_per_m3_s = s.value;
        }
        // the other values were fitted with the line's drop where it was
        // resolved, without it where not
        out.line_resistance_pa_s_per_m3 = self
            .line_resistance_pa_s_per_m3
            .estimate()
            .map_or(0.0, |r| r.value);
        if let Some(t) = self.oil_temp_c {
            out.oil_temperature.reference_c = t;
        }
        // the spool's natural frequency is reported, not put in: taken into the
        // filters it made detection on plant_dev/double slightly worse (docs/plant.md)
        out
    }
}

#[cfg(test)]
mod tests;
