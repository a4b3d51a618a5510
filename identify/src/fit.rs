//! One linearised fit of the chambers' flow balance (the module docs of the
//! crate): the windows' equations, their weighted least squares and the
//! judgement of each unknown.

use model::dynamics::{null_leakage_flows, orifice_flows, LeakSet};
use model::{ActuatorParams, Sample};

use crate::{
    judge, Estimate, Found, Identification, Row, SensorNoise, MAX_LAG_S, MIN_MOVING_WINDOWS,
    PLAUSIBLE_COMPLIANCE, PLAUSIBLE_GAIN, PLAUSIBLE_SPOOL_FREQUENCY, RESOLVED_SIGMAS, WINDOW_SAMPLES,
};

mod solve;

use solve::{chamber_rms, solve, Fitted};

/// Euler sub-steps per sample of the spool's model (h = 0.1 ms at 1 kHz).
const SPOOL_SUBSTEPS: u32 = 10;
/// A window counts as moving when the rod moved more than this, m.
const MOVING_M: f64 = 1.0e-4;
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
const LINE: usize = 10;
const UNKNOWNS: usize = 11;
/// Relative step of the spool's natural frequency for its column.
const SPOOL_W_STEP: f64 = 0.01;
/// Step of the supply sag for its column (a finite difference), Pa/(m³/s).
const SAG_STEP: f64 = 1.0e8;
/// Step of the line resistance for its column (a finite difference), Pa/(m³/s).
const LINE_STEP: f64 = 1.0e8;

/// The least-squares rows: per window, chamber 1 and chamber 2.
#[derive(Default)]
struct Rows {
    x1: Vec<[f64; UNKNOWNS]>,
    y1: Vec<f64>,
    x2: Vec<[f64; UNKNOWNS]>,
    y2: Vec<f64>,
    /// Per window, the instruments of chamber 1's and chamber 2's lag
    /// columns (the columns with the rates over ±3 samples), m³/s.
    z_lag: Vec<[f64; 2]>,
    moving: usize,
    floor2: [f64; 2],
}

/// Builds the windows' equations from the recording.
///
/// The sensor floor counts each window's two position and two pressure
/// readings: their noise, and the DAQ's timing jitter `jitter_s` (s) times
/// their rates at the window's ends.
fn build_rows(p: &ActuatorParams, dt_s: f64, rows: &[Row], noise: SensorNoise, jitter_s: f64) -> Rows {
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
    let mut out = Rows::default();
    let (mut acc1, mut acc2) = ([0.0; UNKNOWNS], [0.0; UNKNOWNS]);
    let (mut rhs1, mut rhs2, mut dx, mut n) = (0.0, 0.0, 0.0, 0usize);
    let (mut v1_sum, mut v2_sum) = (0.0, 0.0);
    // Measured rates for the DAQ jitter's floor, per s.
    let rate = |k: usize, f: fn(&Sample) -> f64| central_rate(rows, k, 2, dt_s, f);
    let mut first = 0;
    let (mut pd1_first, mut pd2_first, mut xd_first) = (0.0, 0.0, 0.0);
    // The valve's flows over the previous interval, m³/s (for the line drop's rate).
    let mut q_prev: Option<[f64; 2]> = None;
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
            q_prev = None;
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
            xd_first = rate(k, |s| s.x_m);
            first = k;
        }
        let nl = null_leakage_flows(&unit_cl, x_sp_mean, p1, p2);
        let qs = orifice_flows(&sagged, x_sp_mean, p1, p2);
        let lq = leaks.flows(p1, p2, p.return_pressure_pa);
        let line = line_drop_columns(p, &unit_cl, x_sp_mean, [p1, p2], [q.q1_m3_s, q.q2_m3_s], nl);
        let q_now = line.valve_flows_m3_s;
        let q_before = q_prev.unwrap_or(q_now);
        q_prev = Some(q_now);
        // The chambers' pressures are p1 − R·Q1 and p2 + R·Q2: the flows read
        // at them, and their change through the oil's compliance.
        acc1[LINE] += line.flow_per_r[0] * dt_s + v1 * (q_now[0] - q_before[0]) / p.bulk_modulus_pa;
        acc2[LINE] += line.flow_per_r[1] * dt_s + v2 * (q_now[1] - q_before[1]) / p.bulk_modulus_pa;
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
            let (lag1, z1) = lag_rate_changes(rows, first, k + 1, dt_s, |s| s.p1_pa);
            let (lag2, z2) = lag_rate_changes(rows, first, k + 1, dt_s, |s| s.p2_pa);
            acc1[LAG1] -= v1 * lag1 / p.bulk_modulus_pa;
            acc2[LAG2] += v2 * lag2 / p.bulk_modulus_pa;
            out.z_lag
                .push([-v1 * z1 / p.bulk_modulus_pa, v2 * z2 / p.bulk_modulus_pa]);
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
            // the jitter: each reading off by its rate times δ
            let xd_last = rate(k + 1, |s| s.x_m);
            let (pd1_last, pd2_last) = (rate(k + 1, |s| s.p1_pa), rate(k + 1, |s| s.p2_pa));
            let (c1, c2) = (vm1 / p.bulk_modulus_pa, vm2 / p.bulk_modulus_pa);
            let j2 = jitter_s * jitter_s;
            let position2 = xd_first * xd_first + xd_last * xd_last;
            out.floor2[0] += j2 * (a1 * a1 * position2 + c1 * c1 * (pd1_first.powi(2) + pd1_last.powi(2)));
            out.floor2[1] += j2 * (a2 * a2 * position2 + c2 * c2 * (pd2_first.powi(2) + pd2_last.powi(2)));
            (acc1, acc2, rhs1, rhs2, dx, n, v1_sum, v2_sum) =
                ([0.0; UNKNOWNS], [0.0; UNKNOWNS], 0.0, 0.0, 0.0, 0, 0.0, 0.0);
        }
    }
    out
}

/// The rate of `f` at sample `k` by the central difference over ±`h`
/// samples of period `dt_s` (s), per s (0 at the ends).
fn central_rate(rows: &[Row], k: usize, h: usize, dt_s: f64, f: fn(&Sample) -> f64) -> f64 {
    if k < h || k + h >= rows.len() {
        return 0.0;
    }
    (f(&rows[k + h].sample) - f(&rows[k - h].sample)) / (2.0 * h as f64 * dt_s)
}

/// The change of a reading's rate (`f`, per s) from sample `first` to
/// `last`, for the transducer's lag column, and its instrument.
///
/// A transducer lagging by τ reads y, p = y + τ·ẏ: a window's true pressure
/// change is the measured one plus τ·(ẏ at its end − ẏ at its start). The
/// regressor's rate is the five-point stencil's (its gain is 0.95 at a
/// press's 180 Hz mode, where ±2 samples read 0.34 of it); the
/// instrument's, the central difference over ±3 samples, whose noise is not
/// the regressor's (module docs of `solve`).
fn lag_rate_changes(rows: &[Row], first: usize, last: usize, dt_s: f64, f: fn(&Sample) -> f64) -> (f64, f64) {
    let five_point = |k: usize| {
        if k < 2 || k + 2 >= rows.len() {
            return 0.0;
        }
        let y = |j: usize| f(&rows[j].sample);
        (8.0 * (y(k + 1) - y(k - 1)) - (y(k + 2) - y(k - 2))) / (12.0 * dt_s)
    };
    let instrument = |k: usize| central_rate(rows, k, 3, dt_s, f);
    (
        five_point(last) - five_point(first),
        instrument(last) - instrument(first),
    )
}

/// One linearised fit of [`crate::identify`] around the model `p`, with the
/// DAQ's jitter `sample_jitter_s` read once on the recording.
pub(crate) fn identify_once(
    p: &ActuatorParams,
    dt_s: f64,
    rows: &[Row],
    noise: SensorNoise,
    sample_jitter_s: &Found,
) -> Result<Identification, String> {
    if dt_s.is_nan() || dt_s <= 0.0 {
        return Err(format!("sample period {dt_s} s: must be positive"));
    }
    let jitter_s = sample_jitter_s.estimate().map_or(0.0, |e| e.value);
    let built = build_rows(p, dt_s, rows, noise, jitter_s);
    let windows = built.y1.len();
    if built.moving < MIN_MOVING_WINDOWS {
        return Err(format!(
            "the rod moved in {} windows of {} ms, {MIN_MOVING_WINDOWS} needed: record the rig's duty cycle, not a hold",
            built.moving,
            WINDOW_SAMPLES as f64 * dt_s * 1e3
        ));
    }
    let double_rod = p.rod_side_area_m2.is_none() && p.area_gradient_b_m2_per_m.is_none();
    let mut model = model_unknowns(p);
    let to_lpm = 60_000.0 / (WINDOW_SAMPLES as f64 * dt_s);
    let rms_before = [
        chamber_rms(&built.x1, &built.y1, &model),
        chamber_rms(&built.x2, &built.y2, &model),
    ];
    let mut at_line = model;
    let (cl_with_line, with_line) = fit_flow_balance(p, &built, double_rod, &mut at_line, true)?;
    let line_resistance_pa_s_per_m3 = line_resistance(&with_line);
    let (null_leakage, fit) = if line_resistance_pa_s_per_m3.estimate().is_some() {
        // The leak filter predicts the readings with the line's drop: every
        // unknown is the fit's with it.
        (cl_with_line, with_line)
    } else {
        // No line drop resolved: the fit without its column.
        fit_flow_balance(p, &built, double_rod, &mut model, false)?
    };
    let (valve_gain_a, valve_gain_b) = valve_gains(&fit, double_rod);
    // b from κ_A·b (the better-determined port when the two differ).
    let null_bias_m = Found::Identified(Estimate {
        value: fit.theta[KB_A] / fit.theta[K_A],
        sigma: fit.sigma[KB_A] / fit.theta[K_A].abs(),
    });
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
        bulk_modulus_pa: bulk_modulus(p, &fit),
        supply_sag_pa_per_m3_s: supply_sag(p, &fit),
        spool_natural_freq_rad_s: spool_natural_freq(p, &fit),
        pressure_lag_s: [pressure_lag(&fit, LAG1, "p1"), pressure_lag(&fit, LAG2, "p2")],
        line_resistance_pa_s_per_m3,
        windows,
        moving_windows: built.moving,
        gap_before_lpm: pooled(rms_before),
        gap_after_lpm: pooled(fit.rms),
        sensor_floor_lpm: pooled(floor),
        sample_jitter_s: sample_jitter_s.clone(),
        oil_temp_c: None,
    })
}

/// The unknowns at the model as given: flow gains and compliance 1, the
/// model's null leakage (m³/(s·Pa)), every other unknown 0.
fn model_unknowns(p: &ActuatorParams) -> [f64; UNKNOWNS] {
    let mut model = [0.0; UNKNOWNS];
    model[K_A] = 1.0;
    model[K_B] = 1.0;
    model[C_L] = p.valve_null_leakage_m3_s_pa;
    model[S] = 1.0;
    model
}

/// The fitted column groups: without and with the null leakage C_L (one
/// flow gain and one κ·b for both ports of a double-rod cylinder).
fn column_groups(double_rod: bool, line: bool) -> (Vec<Vec<usize>>, Vec<Vec<usize>>) {
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
    if line {
        cols.push(vec![LINE]);
    }
    let with_cl = {
        let mut c = cols.clone();
        c.push(vec![C_L]);
        c
    };
    (cols, with_cl)
}

/// The error of a flow balance that cannot be solved.
fn unsolvable() -> String {
    "the flow balance could not be solved (the recording does not excite the valve)".to_string()
}

/// The line drop's columns at one interval: the valve's flows (into
/// chamber 1, out of chamber 2, m³/s, with the model's null leakage) and the
/// change of the flows per unit of line resistance R at R = 0 when the
/// transducers read the chambers plus the drop (m³/s per Pa/(m³/s)).
struct LineDrop {
    valve_flows_m3_s: [f64; 2],
    flow_per_r: [f64; 2],
}

/// [`LineDrop`] for the model `p` (`unit_cl`: `p` with a unit null
/// leakage) at the spool position `x_sp_m` (m), the measured pressures
/// `p_pa` (Pa), the orifice flows `q_m3_s` (m³/s) and the unit null leakage
/// flows `nl` there.
fn line_drop_columns(
    p: &ActuatorParams,
    unit_cl: &ActuatorParams,
    x_sp_m: f64,
    p_pa: [f64; 2],
    q_m3_s: [f64; 2],
    nl: model::dynamics::NullLeakage,
) -> LineDrop {
    let cl = p.valve_null_leakage_m3_s_pa;
    let flows = [q_m3_s[0] + cl * nl.q1_m3_s, q_m3_s[1] + cl * nl.q2_m3_s];
    let (c1, c2) = (p_pa[0] - LINE_STEP * flows[0], p_pa[1] + LINE_STEP * flows[1]);
    let qc = orifice_flows(p, x_sp_m, c1, c2);
    let nlc = null_leakage_flows(unit_cl, x_sp_m, c1, c2);
    LineDrop {
        valve_flows_m3_s: flows,
        flow_per_r: [
            (qc.q1_m3_s - q_m3_s[0] + cl * (nlc.q1_m3_s - nl.q1_m3_s)) / LINE_STEP,
            (qc.q2_m3_s - q_m3_s[1] + cl * (nlc.q2_m3_s - nl.q2_m3_s)) / LINE_STEP,
        ],
    }
}

/// The unknown `u` of `fit` as an estimate.
fn estimate(fit: &Fitted, u: usize) -> Estimate {
    Estimate {
        value: fit.theta[u],
        sigma: fit.sigma[u],
    }
}

/// The weighted least squares of the flow balance, with the line drop's
/// column when `line`: the null leakage C_L (m³/(s·Pa)) as found, and the
/// final fit (refitted with C_L fixed, in `model`, when it is not resolved
/// from zero).
fn fit_flow_balance(
    p: &ActuatorParams,
    built: &Rows,
    double_rod: bool,
    model: &mut [f64; UNKNOWNS],
    line: bool,
) -> Result<(Found, Fitted), String> {
    let (cols, with_cl) = column_groups(double_rod, line);
    // Two passes: equal weights, then each chamber weighted by its residual RMS.
    let first = solve(built, &with_cl, model, [1.0, 1.0]).ok_or_else(unsolvable)?;
    let w = [1.0 / first.rms[0].max(1e-30), 1.0 / first.rms[1].max(1e-30)];
    let mut fit = solve(built, &with_cl, model, w).ok_or_else(unsolvable)?;
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
        fit = solve(built, &cols, model, w).ok_or_else(unsolvable)?;
        Found::Identified(Estimate {
            value: kept,
            sigma: cl.sigma,
        })
    } else {
        // Not resolved: fitted again with the model's C_L.
        fit = solve(built, &cols, model, w).ok_or_else(unsolvable)?;
        Found::NotIdentifiable(format!(
            "the null leakage came out {:.2e} ± {:.2e} m³/(s·Pa), not resolved from zero (5 σ): the rig rests too little at null, or leaks less than the sensors resolve",
            cl.value, cl.sigma
        ))
    };
    Ok((null_leakage, fit))
}

/// Ports A's and B's flow gains as multiples of the model's (1), judged; one
/// gain for both ports of a double-rod cylinder.
fn valve_gains(fit: &Fitted, double_rod: bool) -> (Found, Found) {
    let gain = |u: usize, port: &str| {
        judge(
            estimate(fit, u),
            PLAUSIBLE_GAIN,
            &format!("port {port}'s flow gain"),
            "too uncertain (the valve moved too little)",
            "check the valve's rated flow, spool stroke and the command's scale and sign",
        )
    };
    if double_rod {
        let g = gain(K_A, "A and B");
        (g.clone(), g)
    } else {
        (gain(K_A, "A"), gain(K_B, "B"))
    }
}

/// The oil's effective bulk modulus, Pa, from the compliance multiple (not
/// identified when the model has entrained air).
fn bulk_modulus(p: &ActuatorParams, fit: &Fitted) -> Found {
    let compliance = judge(
        estimate(fit, S),
        PLAUSIBLE_COMPLIANCE,
        "the oil's compliance",
        "too uncertain",
        "check the dead volumes and the bulk modulus",
    );
    match compliance {
        Found::Identified(_) if p.entrained_air_fraction != 0.0 => Found::NotIdentifiable(
            "the model has entrained air: its pressure-dependent stiffness is left as it is".to_string(),
        ),
        Found::Identified(s) => Found::Identified(Estimate {
            value: p.bulk_modulus_pa / s.value,
            sigma: p.bulk_modulus_pa * s.sigma / (s.value * s.value),
        }),
        other => other,
    }
}

/// The apparent lag of the transducer `channel` (unknown `u`), s: identified
/// when within 0 to [`MAX_LAG_S`] and resolved from zero.
fn pressure_lag(fit: &Fitted, u: usize, channel: &str) -> Found {
    let e = estimate(fit, u);
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
}

/// The supply sag, Pa/(m³/s): the model's plus the fitted change, identified
/// when resolved from zero.
fn supply_sag(p: &ActuatorParams, fit: &Fitted) -> Found {
    let sag = Estimate {
        value: p.supply_sag_pa_per_m3_s + fit.theta[SAG],
        sigma: fit.sigma[SAG],
    };
    if sag.value > RESOLVED_SIGMAS * sag.sigma {
        Found::Identified(sag)
    } else {
        Found::NotIdentifiable(format!(
            "the supply sag came out {:.3e} ± {:.2e} Pa/(m³/s), not resolved from zero (5 σ)",
            sag.value, sag.sigma
        ))
    }
}

/// The line resistance between manifold transducers and the chambers,
/// Pa/(m³/s): identified when resolved from zero (5 σ).
fn line_resistance(fit: &Fitted) -> Found {
    let r = estimate(fit, LINE);
    if r.value > RESOLVED_SIGMAS * r.sigma {
        Found::Identified(r)
    } else {
        Found::NotIdentifiable(format!(
            "the line resistance came out {:.2e} ± {:.1e} Pa/(m³/s), not resolved from zero (5 σ): \
             the flow balance is fitted without it",
            r.value, r.sigma
        ))
    }
}

/// The spool's natural frequency, rad/s: the fitted multiple of the model's, judged.
fn spool_natural_freq(p: &ActuatorParams, fit: &Fitted) -> Found {
    match judge(
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
    }
}
