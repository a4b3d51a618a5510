// Over 600 lines: the identification's shared types and the valve/oil fit sit together; the fit could move to a module of its own, as the mechanics did (mechanics.rs).
//! Identifies what a datasheet does not pin down, from a healthy recording of
//! a rig's normal operation (docs/plant.md, "Identification"): the valve's
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
//! windows (supply sag, a line drop) bias a value by more than its σ.

#![forbid(unsafe_code)]

mod mechanics;

pub use mechanics::{identify_mechanics, Mechanics, HALF_WINDOW, MIN_EQUATIONS, SLIDING_M_S};

use model::dynamics::{null_leakage_flows, orifice_flows, LeakSet};
use model::{ActuatorParams, Sample};
use nalgebra::{DMatrix, DVector};

/// Sample intervals summed into one equation, per chamber (20 ms at 1 kHz).
pub const WINDOW_SAMPLES: usize = 20;
/// Euler sub-steps per sample of the spool's model (h = 0.1 ms at 1 kHz).
const SPOOL_SUBSTEPS: u32 = 10;
/// A window counts as moving when the rod moved more than this, m.
const MOVING_M: f64 = 1.0e-4;
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
    /// dynamics, DAQ timing). Reported, not put into the filters.
    pub pressure_lag_s: [Found; 2],
    /// Windows of [`WINDOW_SAMPLES`] used, and how many of them moved.
    pub windows: usize,
    /// Windows in which the rod moved more than 0.1 mm.
    pub moving_windows: usize,
    /// RMS of the flow-balance error per window with the model as given, L/min.
    pub gap_before_lpm: f64,
    /// The same with the identified parameters, L/min.
    pub gap_after_lpm: f64,
    /// The part of the gap the sensors' noise alone makes, L/min.
    pub sensor_floor_lpm: f64,
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
}

/// Column indices of the unknowns.
const K_A: usize = 0;
const K_B: usize = 1;
const KB_A: usize = 2;
const KB_B: usize = 3;
const C_L: usize = 4;
const S: usize = 5;
const SAG: usize = 6;
const SPOOL_W: usize = 7;
const LAG1: usize = 8;
const LAG2: usize = 9;
const UNKNOWNS: usize = 10;
/// Relative step of the spool's natural frequency for its column.
const SPOOL_W_STEP: f64 = 0.01;
/// Step of the supply sag for its column (a finite difference), Pa/(m³/s).
const SAG_STEP: f64 = 1.0e8;

/// The least-squares rows: per window, chamber 1 and chamber 2.
struct Rows {
    x1: Vec<[f64; UNKNOWNS]>,
    y1: Vec<f64>,
    x2: Vec<[f64; UNKNOWNS]>,
    y2: Vec<f64>,
    moving: usize,
    floor2: [f64; 2],
}

/// Builds the windows' equations from the recording.
fn build_rows(p: &ActuatorParams, dt_s: f64, rows: &[Row], noise: SensorNoise) -> Rows {
    let leaks = LeakSet::from_params(p);
    let (a1, a2) = p.areas_m2();
    let wn = p.spool_natural_freq_rad_s;
    let h = dt_s / SPOOL_SUBSTEPS as f64;
    let mut unit_cl = p.clone();
    unit_cl.valve_null_leakage_m3_s_pa = 1.0;
    let mut sagged = p.clone();
    sagged.supply_sag_pa_per_m3_s += SAG_STEP;
    let (mut x_sp, mut v_sp) = match rows.first() {
        Some(r) => (p.spool_null_bias_m + p.spool_gain_m_per_v * r.sample.u_v, 0.0),
        None => (0.0, 0.0),
    };
    // the spool once more, with its natural frequency SPOOL_W_STEP higher
    let (mut x_spw, mut v_spw) = (x_sp, v_sp);
    let wnw = wn * (1.0 + SPOOL_W_STEP);
    let mut out = Rows {
        x1: Vec::new(),
        y1: Vec::new(),
        x2: Vec::new(),
        y2: Vec::new(),
        moving: 0,
        floor2: [0.0; 2],
    };
    let (mut acc1, mut acc2) = ([0.0; UNKNOWNS], [0.0; UNKNOWNS]);
    let (mut rhs1, mut rhs2, mut dx, mut n) = (0.0, 0.0, 0.0, 0usize);
    let (mut v1_sum, mut v2_sum) = (0.0, 0.0);
    // Measured pressure rates, Pa/s: central differences over ±2 samples (0 at
    // the ends). A transducer lagging by τ reads p − τ·ṗ, so a window's true
    // pressure change is the measured one plus τ·(ṗ at its end − ṗ at its start).
    let rate = |k: usize, f: fn(&Sample) -> f64| -> f64 {
        if k < 2 || k + 2 >= rows.len() {
            return 0.0;
        }
        (f(&rows[k + 2].sample) - f(&rows[k - 2].sample)) / (4.0 * dt_s)
    };
    let (mut pd1_first, mut pd2_first) = (0.0, 0.0);
    for (k, pair) in rows.windows(2).enumerate() {
        let (s0, s1) = (&pair[0].sample, &pair[1].sample);
        // The spool over this interval, under the command of its first sample.
        let mut x_sp_mean = 0.0;
        let mut x_spw_mean = 0.0;
        for _ in 0..SPOOL_SUBSTEPS {
            let acc = -2.0 * p.spool_damping_ratio * wn * v_sp - wn * wn * (x_sp - p.spool_null_bias_m)
                + p.spool_gain_m_per_v * wn * wn * s0.u_v;
            v_sp += h * acc;
            x_sp += h * v_sp;
            x_sp_mean += x_sp;
            let accw = -2.0 * p.spool_damping_ratio * wnw * v_spw - wnw * wnw * (x_spw - p.spool_null_bias_m)
                + p.spool_gain_m_per_v * wnw * wnw * s0.u_v;
            v_spw += h * accw;
            x_spw += h * v_spw;
            x_spw_mean += x_spw;
        }
        x_sp_mean /= SPOOL_SUBSTEPS as f64;
        x_spw_mean /= SPOOL_SUBSTEPS as f64;
        if pair[1].after_gap {
            // A window never spans a gap: its partial sums are dropped.
            (acc1, acc2, rhs1, rhs2, dx, n, v1_sum, v2_sum) =
                ([0.0; UNKNOWNS], [0.0; UNKNOWNS], 0.0, 0.0, 0.0, 0, 0.0, 0.0);
            continue;
        }
        let (p1, p2) = (0.5 * (s0.p1_pa + s1.p1_pa), 0.5 * (s0.p2_pa + s1.p2_pa));
        let (v1, v2) = p.chamber_volumes_m3(0.5 * (s0.x_m + s1.x_m));
        let q = orifice_flows(p, x_sp_mean, p1, p2);
        let hx = 1.0e-7;
        let (qp, qm) = (
            orifice_flows(p, x_sp_mean + hx, p1, p2),
            orifice_flows(p, x_sp_mean - hx, p1, p2),
        );
        let (g1, g2) = (
            (qp.q1_m3_s - qm.q1_m3_s) / (2.0 * hx),
            (qp.q2_m3_s - qm.q2_m3_s) / (2.0 * hx),
        );
        let qw = orifice_flows(p, x_spw_mean, p1, p2);
        if n == 0 {
            pd1_first = rate(k, |s| s.p1_pa);
            pd2_first = rate(k, |s| s.p2_pa);
        }
        let nl = null_leakage_flows(&unit_cl, x_sp_mean, p1, p2);
        let qs = orifice_flows(&sagged, x_sp_mean, p1, p2);
        let lq = leaks.flows(p1, p2, p.return_pressure_pa);
        acc1[K_A] += q.q1_m3_s * dt_s;
        acc1[KB_A] += g1 * dt_s;
        acc1[C_L] += nl.q1_m3_s * dt_s;
        acc1[SAG] += (qs.q1_m3_s - q.q1_m3_s) / SAG_STEP * dt_s;
        acc1[S] -= v1 * (s1.p1_pa - s0.p1_pa) / p.bulk_modulus_pa;
        acc1[SPOOL_W] += (qw.q1_m3_s - q.q1_m3_s) / SPOOL_W_STEP * dt_s;
        acc2[SPOOL_W] += (qw.q2_m3_s - q.q2_m3_s) / SPOOL_W_STEP * dt_s;
        acc2[K_B] += q.q2_m3_s * dt_s;
        acc2[KB_B] += g2 * dt_s;
        acc2[C_L] += nl.q2_m3_s * dt_s;
        acc2[SAG] += (qs.q2_m3_s - q.q2_m3_s) / SAG_STEP * dt_s;
        acc2[S] += v2 * (s1.p2_pa - s0.p2_pa) / p.bulk_modulus_pa;
        rhs1 += (lq.int_m3_s + lq.ext1_m3_s) * dt_s;
        rhs2 += (lq.int_m3_s - lq.ext2_m3_s) * dt_s;
        dx += s1.x_m - s0.x_m;
        v1_sum += v1;
        v2_sum += v2;
        n += 1;
        if n == WINDOW_SAMPLES {
            acc1[LAG1] -= v1 * (rate(k + 1, |s| s.p1_pa) - pd1_first) / p.bulk_modulus_pa;
            acc2[LAG2] += v2 * (rate(k + 1, |s| s.p2_pa) - pd2_first) / p.bulk_modulus_pa;
            out.x1.push(acc1);
            out.y1.push(a1 * dx + rhs1);
            out.x2.push(acc2);
            out.y2.push(a2 * dx + rhs2);
            if dx.abs() > MOVING_M {
                out.moving += 1;
            }
            // Sensor floor of one window: two position and two pressure readings.
            let (vm1, vm2) = (v1_sum / n as f64, v2_sum / n as f64);
            let sp = noise.pressure_pa / p.bulk_modulus_pa;
            out.floor2[0] += 2.0 * ((a1 * noise.position_m).powi(2) + (vm1 * sp).powi(2));
            out.floor2[1] += 2.0 * ((a2 * noise.position_m).powi(2) + (vm2 * sp).powi(2));
            (acc1, acc2, rhs1, rhs2, dx, n, v1_sum, v2_sum) =
                ([0.0; UNKNOWNS], [0.0; UNKNOWNS], 0.0, 0.0, 0.0, 0, 0.0, 0.0);
        }
    }
    out
}

/// Weighted least squares over the columns `cols` with the other unknowns
/// fixed at `fixed`: (solution over all unknowns, their standard deviations, RMS
/// residual per chamber in m³ per window).
fn solve(rows: &Rows, cols: &[Vec<usize>], fixed: &[f64; UNKNOWNS], weights: [f64; 2]) -> Option<Fitted> {
    let m = rows.y1.len() + rows.y2.len();
    let k = cols.len();
    if m <= k {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(m, k);
    let mut y = DVector::<f64>::zeros(m);
    let free: Vec<usize> = cols.iter().flatten().copied().collect();
    let chambers = [(&rows.x1, &rows.y1, weights[0]), (&rows.x2, &rows.y2, weights[1])];
    let mut r = 0;
    for (xs, ys, w) in chambers {
        for (x, yv) in xs.iter().zip(ys.iter()) {
            let mut known = 0.0;
            for (u, fx) in fixed.iter().enumerate() {
                if !free.contains(&u) {
                    known += x[u] * fx;
                }
            }
            for (c, group) in cols.iter().enumerate() {
                a[(r, c)] = w * group.iter().map(|&u| x[u]).sum::<f64>();
            }
            y[r] = w * (yv - known);
            r += 1;
        }
    }
    // Columns scaled to unit norm for the conditioning of the normal equations.
    let scale: Vec<f64> = (0..k)
        .map(|c| {
            let n = a.column(c).norm();
            if n > 0.0 {
                n
            } else {
                1.0
            }
        })
        .collect();
    for (c, s) in scale.iter().enumerate() {
        a.column_mut(c).scale_mut(1.0 / s);
    }
    let ata = a.transpose() * &a;
    let inv = ata.clone().try_inverse()?;
    let sol = &inv * (a.transpose() * &y);
    let resid = &y - &a * &sol;
    let dof = (m - k) as f64;
    let var = resid.norm_squared() / dof;
    let mut theta = *fixed;
    let mut sigma = [f64::NAN; UNKNOWNS];
    for c in 0..k {
        for &u in &cols[c] {
            theta[u] = sol[c] / scale[c];
            sigma[u] = (var * inv[(c, c)]).sqrt() / scale[c];
        }
    }
    Some(Fitted {
        theta,
        sigma,
        rms: [
            chamber_rms(&rows.x1, &rows.y1, &theta),
            chamber_rms(&rows.x2, &rows.y2, &theta),
        ],
    })
}

struct Fitted {
    /// Every unknown: fitted, or as fixed.
    theta: [f64; UNKNOWNS],
    /// Standard deviation of each fitted unknown (NaN for a fixed one).
    sigma: [f64; UNKNOWNS],
    rms: [f64; 2],
}

/// RMS of one chamber's window errors at the unknowns `theta`, m³.
fn chamber_rms(xs: &[[f64; UNKNOWNS]], ys: &[f64], theta: &[f64; UNKNOWNS]) -> f64 {
    if xs.is_empty() {
        return 0.0;
    }
    let ss: f64 = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| {
            let e: f64 = x.iter().zip(theta).map(|(a, b)| a * b).sum::<f64>() - y;
            e * e
        })
        .sum();
    (ss / xs.len() as f64).sqrt()
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
    let mut id = identify_once(p, dt_s, rows, noise)?;
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
            ..identify_once(&at, dt_s, rows, noise)?
        };
    }
    id.oil_temp_c = mean_oil_temp_c(rows);
    Ok(id)
}

/// One linearised fit of [`identify`] around the model `p`.
fn identify_once(
    p: &ActuatorParams,
    dt_s: f64,
    rows: &[Row],
    noise: SensorNoise,
) -> Result<Identification, String> {
    if dt_s.is_nan() || dt_s <= 0.0 {
        return Err(format!("sample period {dt_s} s: must be positive"));
    }
    let built = build_rows(p, dt_s, rows, noise);
    let windows = built.y1.len();
    if built.moving < MIN_MOVING_WINDOWS {
        return Err(format!(
            "the rod moved in {} windows of {} ms, {MIN_MOVING_WINDOWS} needed: record the rig's duty cycle, not a hold",
            built.moving,
            WINDOW_SAMPLES as f64 * dt_s * 1e3
        ));
    }
    let double_rod = p.rod_side_area_m2.is_none() && p.area_gradient_b_m2_per_m.is_none();
    let mut cols: Vec<Vec<usize>> = if double_rod {
        vec![vec![K_A, K_B], vec![KB_A, KB_B]]
    } else {
        vec![vec![K_A], vec![K_B], vec![KB_A], vec![KB_B]]
    };
    cols.push(vec![S]);
    cols.push(vec![SAG]);
    cols.push(vec![SPOOL_W]);
    cols.push(vec![LAG1]);
    cols.push(vec![LAG2]);
    let with_cl = {
        let mut c = cols.clone();
        c.push(vec![C_L]);
        c
    };
    let mut model = [0.0; UNKNOWNS];
    model[K_A] = 1.0;
    model[K_B] = 1.0;
    model[C_L] = p.valve_null_leakage_m3_s_pa;
    model[S] = 1.0;
    let to_lpm = 60_000.0 / (WINDOW_SAMPLES as f64 * dt_s);
    let rms_before = [
        chamber_rms(&built.x1, &built.y1, &model),
        chamber_rms(&built.x2, &built.y2, &model),
    ];
    let fail =
        || "the flow balance could not be solved (the recording does not excite the valve)".to_string();
    // Two passes: equal weights, then each chamber weighted by its residual RMS.
    let first = solve(&built, &with_cl, &model, [1.0, 1.0]).ok_or_else(fail)?;
    let w = [1.0 / first.rms[0].max(1e-30), 1.0 / first.rms[1].max(1e-30)];
    let mut fit = solve(&built, &with_cl, &model, w).ok_or_else(fail)?;
    let estimate = |fit: &Fitted, u: usize| Estimate {
        value: fit.theta[u],
        sigma: fit.sigma[u],
    };
    let cl = estimate(&fit, C_L);
    // The values of C_L this recording allows: within 5 σ of the estimate, not below 0.
    let allowed = (
        (cl.value - RESOLVED_SIGMAS * cl.sigma).max(0.0),
        (cl.value + RESOLVED_SIGMAS * cl.sigma).max(0.0),
    );
    let kept = p.valve_null_leakage_m3_s_pa.clamp(allowed.0, allowed.1);
    let null_leakage = if cl.value > RESOLVED_SIGMAS * cl.sigma {
        Found::Identified(cl)
    } else if kept != p.valve_null_leakage_m3_s_pa {
        // Not resolved from zero, but the model's C_L (a catalogue's maximum, say)
        // is outside what the recording allows: the nearest allowed value.
        model[C_L] = kept;
        fit = solve(&built, &cols, &model, w).ok_or_else(fail)?;
        Found::Identified(Estimate {
            value: kept,
            sigma: cl.sigma,
        })
    } else {
        // Not resolved: fitted again with the model's C_L.
        fit = solve(&built, &cols, &model, w).ok_or_else(fail)?;
        Found::NotIdentifiable(format!(
            "the null leakage came out {:.2e} ± {:.2e} m³/(s·Pa), not resolved from zero (5 σ): the rig rests too little at null, or leaks less than the sensors resolve",
            cl.value, cl.sigma
        ))
    };
    let gain = |u: usize, port: &str| {
        judge(
            estimate(&fit, u),
            PLAUSIBLE_GAIN,
            &format!("port {port}'s flow gain"),
            "too uncertain (the valve moved too little)",
            "check the valve's rated flow, spool stroke and the command's scale and sign",
        )
    };
    let (valve_gain_a, valve_gain_b) = if double_rod {
        let g = gain(K_A, "A and B");
        (g.clone(), g)
    } else {
        (gain(K_A, "A"), gain(K_B, "B"))
    };
    // b from κ_A·b (the better-determined port when the two differ).
    let null_bias_m = Found::Identified(Estimate {
        value: fit.theta[KB_A] / fit.theta[K_A],
        sigma: fit.sigma[KB_A] / fit.theta[K_A].abs(),
    });
    let compliance = judge(
        estimate(&fit, S),
        PLAUSIBLE_COMPLIANCE,
        "the oil's compliance",
        "too uncertain",
        "check the dead volumes and the bulk modulus",
    );
    let bulk_modulus_pa = match compliance {
        Found::Identified(_) if p.entrained_air_fraction != 0.0 => Found::NotIdentifiable(
            "the model has entrained air: its pressure-dependent stiffness is left as it is".to_string(),
        ),
        Found::Identified(s) => Found::Identified(Estimate {
            value: p.bulk_modulus_pa / s.value,
            sigma: p.bulk_modulus_pa * s.sigma / (s.value * s.value),
        }),
        other => other,
    };
    let lag = |u: usize, channel: &str| {
        let e = estimate(&fit, u);
        if !(0.0..=MAX_LAG_S).contains(&e.value) {
            Found::NotIdentifiable(format!(
                "{channel}'s lag came out {:.2} ± {:.2} ms: outside 0-{} ms, another effect (a line drop, the workpiece) takes its place",
                e.value * 1e3,
                e.sigma * 1e3,
                MAX_LAG_S * 1e3
            ))
        } else if e.value <= RESOLVED_SIGMAS * e.sigma {
            Found::NotIdentifiable(format!(
                "{channel}'s lag came out {:.2} ± {:.2} ms, not resolved from zero (5 σ)",
                e.value * 1e3,
                e.sigma * 1e3
            ))
        } else {
            Found::Identified(e)
        }
    };
    let pressure_lag_s = [lag(LAG1, "p1"), lag(LAG2, "p2")];
    let sag = Estimate {
        value: p.supply_sag_pa_per_m3_s + fit.theta[SAG],
        sigma: fit.sigma[SAG],
    };
    let supply_sag_pa_per_m3_s = if sag.value > RESOLVED_SIGMAS * sag.sigma {
        Found::Identified(sag)
    } else {
        Found::NotIdentifiable(format!(
            "the supply sag came out {:.3e} ± {:.2e} Pa/(m³/s), not resolved from zero (5 σ)",
            sag.value, sag.sigma
        ))
    };
    let spool_natural_freq_rad_s = match judge(
        Estimate {
            value: 1.0 + fit.theta[SPOOL_W],
            sigma: fit.sigma[SPOOL_W],
        },
        PLAUSIBLE_SPOOL_FREQUENCY,
        "the spool's natural frequency",
        "too uncertain (the command changed too little)",
        "check the valve's -90° frequency",
    ) {
        Found::Identified(e) => Found::Identified(Estimate {
            value: e.value * p.spool_natural_freq_rad_s,
            sigma: e.sigma * p.spool_natural_freq_rad_s,
        }),
        other => other,
    };
    let pooled = |r: [f64; 2]| ((r[0] * r[0] + r[1] * r[1]) / 2.0).sqrt() * to_lpm;
    let floor = [
        (built.floor2[0] / windows as f64).sqrt(),
        (built.floor2[1] / windows as f64).sqrt(),
    ];
    Ok(Identification {
        valve_gain_a,
        valve_gain_b,
        null_bias_m,
        null_leakage_m3_s_pa: null_leakage,
        bulk_modulus_pa,
        supply_sag_pa_per_m3_s,
        spool_natural_freq_rad_s,
        pressure_lag_s,
        windows,
        moving_windows: built.moving,
        gap_before_lpm: pooled(rms_before),
        gap_after_lpm: pooled(fit.rms),
        sensor_floor_lpm: pooled(floor),
        oil_temp_c: None,
    })
}

impl Identification {
    /// `p` with what was identified put in: the area gradients scaled by the
    /// flow gains, the null leakage, the bulk modulus, the supply sag, and the
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
