//! `leakwatch commission HEALTHY.csv --out rig.toml`: identifies the rig (valve
//! flow gains, null leakage, oil stiffness: the `identify` crate), then the
//! spool's null bias, and learns the healthy state of the leak filter's
//! estimates on a rig (offsets, spreads, crossing rates), and writes a config
//! that carries all of them.
//!
//! Why the bias is identified here and then held: at chamber pressures near
//! p_s/2 a spool null bias b and a pair of opposite external leaks (flow into
//! chamber 1, out of chamber 2) are the same flow. A filter that estimates both
//! cannot tell them apart; the start of a run sets them (seen on plant_dev/double:
//! b −3 µm against a pair of ∓0.5 L/min) and the detector reads the pair as
//! leaks. On a healthy recording the leaks are known to be zero, so b is
//! observable there: the leak filter runs with its leak sizes held at zero and
//! its mean b after convergence is the valve's null bias (leaks_dev's healthy
//! runs: −8.90, 3.76, 7.34, −4.54 µm against −8.90, 3.76, 7.34, −4.53 true).

use std::path::Path;

use detect::CommissioningLearner;
use model::process::I_BIAS;

use config::Config;

pub use crate::commission_report::{CommissionRecord, FitTrace, Identified, Learned, Param};

mod balances;
mod delay;
mod healthy;
mod misreading;
mod reach;
mod recording;
mod theta;
#[cfg(test)]
use balances::lag_against_datasheet;
use balances::{flow_balance, force_balance};
use delay::lag_bound_s;
pub use delay::{DelayFit, DelayTaken};
use misreading::transducer_tolerance;
pub use misreading::{Misreading, MisreadingFit, MisreadingTaken, MISREADING_LEAST_SHARE};
pub use reach::{ResponseTrace, SensorReach};
use recording::{read_rows, replay_estimates};
pub use theta::{laminar_pull, PROBE as LAMINAR_PROBE};
use theta::{nothing_read_from_theta, oil_reading_line, ThetaMean};

/// What `identify` finds on one healthy recording: the flow balance's
/// parameters, and the rod's mass and friction (or why not).
pub struct Found {
    /// Valve, oil and supply ([`identify::identify`]).
    pub rig: identify::Identification,
    /// Mass and friction ([`identify::identify_mechanics`]), or why they were not identified.
    pub mechanics: Result<identify::Mechanics, String>,
    /// How far the transducers' zero offsets and span errors the datasheet
    /// allows move the null leakage ([`identify::null_leakage_tolerance`]):
    /// `None` without them in `[datasheet.pressure_transducers]`, or without a null leakage.
    pub null_leakage_tolerance: Option<identify::NullLeakageTolerance>,
}

/// The identification of the rig on the healthy recording `input` against
/// `cfg`'s model, both balances on the rows read once.
pub fn identify_on(input: &Path, cfg: &Config) -> Result<Found, String> {
    let rows = read_rows(input, cfg)?;
    let dt = cfg.leak_filter.sample_period_s;
    let noise = identify::SensorNoise {
        position_m: cfg.sensors.position_sigma_m(),
        pressure_pa: cfg.sensors.pressure_sigma_pa(),
        position_step_m: cfg.sensors.encoder_resolution_m,
    };
    let rig = identify::identify(&cfg.model, dt, &rows, noise)
        .map_err(|e| format!("{}: cannot identify the rig: {e}", input.display()))?;
    let mechanics = identify::identify_mechanics(&cfg.model, dt, &rows)
        .map_err(|e| format!("{}: cannot identify the rod's mechanics: {e}", input.display()));
    let null_leakage_tolerance = transducer_tolerance(cfg)
        .and_then(|tol| identify::null_leakage_tolerance(&cfg.model, dt, &rows, noise, &rig, tol));
    Ok(Found {
        rig,
        mechanics,
        null_leakage_tolerance,
    })
}

/// Identifies the valve's flow gains, null leakage and the oil's stiffness on
/// `input` and puts them into the model (printing what was found).
pub fn identify_rig(input: &Path, cfg: &Config) -> Result<Config, String> {
    identify_rig_said(input, cfg).map(|(cfg, _)| cfg)
}

/// [`identify_rig`], and what it found and printed.
pub fn identify_rig_said(input: &Path, cfg: &Config) -> Result<(Config, Identified), String> {
    let Found {
        rig: id,
        mechanics: found_mechanics,
        null_leakage_tolerance,
    } = identify_on(input, cfg)?;
    let mut said = Identified::default();
    flow_balance(&id, null_leakage_tolerance, cfg, &mut said);
    let mut out = cfg.clone();
    out.model = id.apply(&cfg.model);
    out.model.oil_temperature.null_leakage_sigma_share =
        balances::null_leakage_sigma_share(null_leakage_tolerance, out.model.valve_null_leakage_m3_s_pa);
    // the leak filter's measurement noise counts the DAQ's jitter read here
    if let Some(j) = id.sample_jitter_s.estimate() {
        out.leak_filter.sample_jitter_s = j.value;
    }
    // and its NIS each transducer's lag, up to the longest the
    // datasheet's response time allows
    let lag_bound_s = lag_bound_s(cfg);
    for (lag, found) in out.leak_filter.pressure_lag_s.iter_mut().zip(&id.pressure_lag_s) {
        *lag = found.estimate().map_or(0.0, |e| e.value.clamp(0.0, lag_bound_s));
    }
    match found_mechanics {
        Ok(mech) => {
            force_balance(&mech, cfg, &mut said);
            out.model = mech.apply(&out.model);
        }
        Err(e) => said.mechanics_error = Some(e),
    }
    for line in said.lines() {
        eprintln!("{line}");
    }
    Ok((out, said))
}

/// Least healthy, converged data a commissioning needs, s.
pub const MIN_HEALTHY_S: f64 = 10.0;

/// The smallest initial variance the leak filter takes, m² (or m⁶/s²): what
/// "held" means for a state (σ 1e-15 in SI; the state stays where it starts).
const HELD_VARIANCE: f64 = 1e-30;

/// The spool's null bias found on a healthy recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NullBias {
    /// Mean of the filter's bias estimate after convergence, m (to add to the model's).
    pub bias_m: f64,
    /// Its standard deviation over the recording, m.
    pub spread_m: f64,
    /// Converged time it was taken over, s.
    pub over_s: f64,
}

/// Identifies the spool's null bias on the healthy recording `input`: the leak
/// filter with its leak sizes held at zero, its bias estimate averaged once the
/// filter has converged and `settle_s` more have passed.
pub fn identify_null_bias(input: &Path, cfg: &Config) -> Result<NullBias, String> {
    let mut tuning = cfg.leak_filter.clone();
    tuning.q_leak_m6_s2 = 0.0;
    tuning.p0_leak_m6_s2 = HELD_VARIANCE;
    let settle_s = cfg.classifier.settle_s;
    let (mut n, mut sum, mut sum2) = (0u64, 0.0, 0.0);
    let mut converged_at = None;
    replay_estimates(input, cfg, tuning, |e| {
        if e.flags & filter::FLAG_CONVERGING != 0 || e.flags & filter::FLAG_RESET != 0 {
            converged_at = None;
            return;
        }
        let t0 = *converged_at.get_or_insert(e.t_s);
        let b = e.state[I_BIAS];
        if e.t_s - t0 >= settle_s && b.is_finite() {
            n += 1;
            sum += b;
            sum2 += b * b;
        }
    })?;
    let over_s = n as f64 * cfg.leak_filter.sample_period_s;
    if over_s < MIN_HEALTHY_S {
        return Err(format!(
            "{}: cannot identify the spool's null bias: {over_s:.1} s of converged data, {MIN_HEALTHY_S} s needed",
            input.display()
        ));
    }
    let mean = sum / n as f64;
    Ok(NullBias {
        bias_m: mean,
        spread_m: (sum2 / n as f64 - mean * mean).max(0.0).sqrt(),
        over_s,
    })
}

/// `cfg` with the identified bias put into the model and held in the leak filter.
pub fn with_null_bias(cfg: &Config, bias: &NullBias) -> Config {
    let mut out = cfg.clone();
    out.model.spool_null_bias_m += bias.bias_m;
    out.leak_filter.q_bias_m2 = 0.0;
    out.leak_filter.p0_bias_m2 = HELD_VARIANCE;
    out
}

/// Learns the commissioning of `input` under the config `cfg` as it is, and the
/// leak filter's mean oil stiffness θ over it (1; `None` without that state):
/// the θ at the recording's oil temperature, which the filter reads the
/// temperature against when no `temp_c` comes ([`filter::oil`]).
pub fn learn(input: &Path, cfg: &Config) -> Result<(detect::Commissioning, Option<f64>), String> {
    learn_traced(input, cfg).map(|t| (t.commissioning, t.theta))
}

/// [`learn`], the leak filter's fit to the recording ([`FitTrace`]) and, per
/// kind, the stretch of the recording that sets its threshold, with the
/// threshold the rest gives ([`detect::CommissioningLearner::thresholds_set_by_stretches`]).
pub fn learn_traced(input: &Path, cfg: &Config) -> Result<LearnedTrace, String> {
    if cfg.leak_filter.states < 10 {
        return Err(format!(
            "[leak_filter] states = {}: commissioning needs the leak filter (10, 11 or 12 states)",
            cfg.leak_filter.states
        ));
    }
    let mut learner = CommissioningLearner::new(cfg.classifier.settle_s);
    let at_reference = nothing_read_from_theta(cfg);
    let mut theta = ThetaMean::default();
    let mut fit = FitTrace::default();
    let mut responses = ResponseTrace::default();
    let mut misreading = MisreadingFit::default();
    let mut delay = DelayFit::default();
    replay_estimates(input, &at_reference, cfg.leak_filter.clone(), |e| {
        learner.on_estimate(e);
        fit.push(e);
        responses.push(e);
        misreading.push(e);
        delay.push(e);
        theta.push(e);
    })?;
    let c = learner
        .finish(&cfg.classifier, MIN_HEALTHY_S, &input.display().to_string())
        .map_err(|e| format!("{}: cannot commission: {e}", input.display()))?;
    let set_by = learner.thresholds_set_by_stretches(&cfg.classifier, &c);
    Ok(LearnedTrace {
        left_out_s: learner.left_out_s(&cfg.classifier),
        commissioning: c,
        theta: theta.mean(),
        theta_spread_share: theta.block_spread_share(),
        fit,
        set_by,
        responses,
        misreading,
        delay,
    })
}

/// What [`learn_traced`] gives.
pub struct LearnedTrace {
    /// The commissioning learned.
    pub commissioning: detect::Commissioning,
    /// θ's mean on the recording (1).
    pub theta: Option<f64>,
    /// θ's spread over its means of `filter::oil::OIL_STIFFNESS_TAU_S`, as a share of its mean (1).
    pub theta_spread_share: Option<f64>,
    /// The leak filter's fit to the recording.
    pub fit: FitTrace,
    /// Per kind, the stretch that sets its threshold and the rest's threshold (L/min at p_s/2).
    pub set_by: [Option<(detect::Stretch, f64)>; 3],
    /// The time left out, s: where the leak estimates made a pattern no leak can make
    /// ([`detect::CommissioningLearner::left_out_s`]).
    pub left_out_s: f64,
    /// The leak filter's responses to a misreading of each transducer on the recording.
    pub responses: ResponseTrace,
    /// The sums that fit the transducers' misreading to the recording.
    pub misreading: MisreadingFit,
    /// The sums that fit the transducers' delay to the leak sizes' swings.
    pub delay: DelayFit,
}

/// The smallest misreading of each transducer the detector names with
/// commissioning `c` and config `cfg`, on the duty cycle of the recording the
/// leak filter's `responses` come from.
pub fn sensor_reach(responses: &ResponseTrace, c: &detect::Commissioning, cfg: &Config) -> SensorReach {
    let (_, thr) = detect::thresholds(&cfg.classifier, c.spreads_lpm, c.crossings_per_s);
    SensorReach::new(
        responses.typical_rms(c.internal_factors, cfg.classifier.baseline_tau_s),
        thr,
        cfg.classifier.pressure_full_scale_pa,
    )
    .with_sound_transducer(
        responses.mean_reading_pa(),
        cfg.sensors.pressure_zero_offset_max_pa,
        cfg.sensors.pressure_span_error_max,
    )
}

/// Identifies the rig ([`identify_rig`]), the null bias (layouts with a bias state, 11 and 12), then
/// learns the commissioning with the bias held: the config to write.
pub fn commission(input: &Path, cfg: &Config) -> Result<Config, String> {
    commission_recorded(input, cfg).map(|(cfg, _)| cfg)
}

/// [`commission`], and the commissioning record: what it printed, for the report.
pub fn commission_recorded(input: &Path, cfg: &Config) -> Result<(Config, CommissionRecord), String> {
    let datasheet_model = cfg.model.clone();
    let tolerance = transducer_tolerance(cfg);
    let (mut identified_cfg, identified) = identify_rig_said(input, cfg)?;
    // the identified model is now the rig's; the datasheet it started from is not written again
    identified_cfg.datasheet = None;
    let mut pass = bias_then_learn(input, &identified_cfg)?;
    let delay = delay::fit_delay(input, &mut identified_cfg, lag_bound_s(cfg), &mut pass)?;
    delay.iter().for_each(|d| eprintln!("{}", d.line()));
    let misreading = match tolerance {
        Some(t) => fit_misreading(input, &identified_cfg, t, &mut pass)?,
        None => None,
    };
    if let Some(d) = delay.as_ref().filter(|d| d.taken && !d.sure()) {
        delay::hold_over_unsure_fit(input, &identified_cfg, d, tolerance, &mut pass)?;
    }
    let Pass { mut cfg, bias, trace } = pass;
    misreading.iter().for_each(|m| eprintln!("{}", m.line()));
    if let Some(bias) = &bias {
        eprintln!(
            "spool null bias: {:+.2} µm (spread {:.2} µm over {:.0} s, leaks held at zero); the model's is now {:+.2} µm, held by the leak filter",
            bias.bias_m * 1e6,
            bias.spread_m * 1e6,
            bias.over_s,
            cfg.model.spool_null_bias_m * 1e6
        );
    }
    let null_bias = bias.map(|b| (b, datasheet_model.spool_null_bias_m));
    let LearnedTrace {
        commissioning: mut c,
        theta,
        theta_spread_share,
        fit,
        set_by,
        left_out_s,
        responses,
        delay: delay_fit,
        ..
    } = trace;
    cfg.model.oil_temperature.reference_stiffness = theta;
    cfg.model.oil_temperature.reference_stiffness_sigma_share = theta.and(theta_spread_share);
    cfg.model.oil_temperature.stiffness_per_laminar_factor = match theta {
        Some(t) => laminar_pull(input, &cfg, t)?,
        None => None,
    };
    if let Some(line) = oil_reading_line(&cfg.model.oil_temperature) {
        eprintln!("{line}");
    }
    let (_, thr) = detect::thresholds(&cfg.classifier, c.spreads_lpm, c.crossings_per_s);
    let (_, naming) = detect::thresholds(&cfg.classifier, c.naming_spreads_lpm(), c.crossings_per_s);
    let mut learned = Learned {
        theta,
        reference_c: cfg.model.oil_temperature.reference_c,
        healthy_s: c.healthy_s,
        left_out_s,
        offsets_lpm: c.offsets_lpm,
        spreads_lpm: c.spreads_lpm,
        internal_factors: (c.internal_factors != detect::NOMINAL_INTERNAL_FACTORS)
            .then_some(c.internal_factors),
        thresholds_lpm: thr,
        naming_thresholds_lpm: naming,
        false_alarms_per_hour: cfg.classifier.false_alarms_per_hour,
        detectable: detectable_at(&cfg.model, naming, c.offsets_lpm),
        detectable_line: detectable_over_temperature(&cfg.model, naming, c.offsets_lpm),
        nis_mean: c.nis_mean,
        set_by,
        sensor_reach: sensor_reach(&responses, &c, &cfg),
        healthy_misreading: None,
        delay_uncertainty: None,
    };
    c.least_offsets_named = learned.sensor_reach.least_named();
    c.delay_uncertainty_s =
        delay::uncertainty_s(cfg.leak_filter.lag_correction_s, cfg.leak_filter.pressure_lag_s);
    c.delay_response_reach_lpm_per_ms = delay::response_seen_lpm_per_ms(
        delay.as_ref().is_some_and(|d| d.sure()),
        delay_fit.reach_lpm_per_ms(c.internal_factors),
    );
    learned.delay_uncertainty =
        delay::uncertainty_line(c.delay_uncertainty_s, cfg.leak_filter.pressure_lag_s);
    learned.lines().iter().for_each(|line| eprintln!("{line}"));
    cfg.classifier.commissioning = Some(c.clone());
    if let Some(m) = healthy::healthy_misreading(input, &cfg)? {
        let line = healthy::line(&m);
        eprintln!("{line}");
        learned.healthy_misreading = Some(line);
        healthy::keep(&mut c, &m);
    }
    cfg.classifier.commissioning = Some(c);
    let record = CommissionRecord {
        input: input.display().to_string(),
        identified,
        null_bias,
        misreading,
        delay,
        learned,
        fit,
    };
    Ok((cfg, record))
}

/// What one pass over the healthy recording gives: the config with the null
/// bias held, the bias, and what the learning traced.
struct Pass {
    cfg: Config,
    bias: Option<NullBias>,
    trace: LearnedTrace,
}

/// The null bias identified on `input` under `cfg` (layouts with a bias
/// state, 11 and 12) and held, then the commissioning learned with it.
fn bias_then_learn(input: &Path, cfg: &Config) -> Result<Pass, String> {
    let mut cfg = cfg.clone();
    let mut bias = None;
    if cfg.leak_filter.states >= 11 {
        let b = identify_null_bias(input, &cfg)?;
        cfg = with_null_bias(&cfg, &b);
        bias = Some(b);
    }
    let trace = learn_traced(input, &cfg)?;
    Ok(Pass { cfg, bias, trace })
}

/// Rounds of the misreading's fit at most: each refits on the recording
/// read less the misreading taken so far.
const MISREADING_ROUNDS: usize = 3;

/// Fits the transducers' misreading to the commissioning of `pass` (learned
/// from `identified` on `input`) and takes it while each round takes
/// [`MISREADING_LEAST_SHARE`] of the healthy spreads' energy away, replacing
/// `pass` each time ([`MisreadingFit`]); `None` when the recording cannot tell it.
fn fit_misreading(
    input: &Path,
    identified: &Config,
    tol: identify::TransducerTolerance,
    pass: &mut Pass,
) -> Result<Option<MisreadingTaken>, String> {
    let before = pass.trace.commissioning.spreads_lpm;
    let mut outcome: Option<MisreadingTaken> = None;
    for _ in 0..MISREADING_ROUNDS {
        let taken_pa = pass.cfg.model.pressure_misreading_pa;
        let Some(m) =
            pass.trace
                .misreading
                .solve(tol.zero_offset_max_pa, tol.span_error_max_fraction, taken_pa)
        else {
            break;
        };
        let mut trial = identified.clone();
        trial.model.pressure_misreading_pa = m.pa;
        let trial = bias_then_learn(input, &trial)?;
        let after = trial.trace.commissioning.spreads_lpm;
        let taken =
            energy(after) <= (1.0 - MISREADING_LEAST_SHARE) * energy(pass.trace.commissioning.spreads_lpm);
        if !taken {
            outcome.get_or_insert(MisreadingTaken {
                found: m,
                taken,
                spreads_lpm: [before, after],
            });
            break;
        }
        *pass = trial;
        outcome = Some(MisreadingTaken {
            found: m,
            taken,
            spreads_lpm: [before, after],
        });
    }
    Ok(outcome)
}

/// Σ of `spreads`² (L/min²): what a misreading must lower to be taken ([`MISREADING_LEAST_SHARE`]).
fn energy(spreads: [f64; 3]) -> f64 {
    spreads.iter().map(|s| s * s).sum()
}

/// The oil temperatures at which commissioning states the smallest detectable
/// leaks, °C: the ends and the middle of the model's operating range.
fn stated_temperatures_c(oil: &model::params::OilTemperature) -> [f64; 3] {
    let (lo, hi) = (oil.operating_min_c, oil.operating_max_c);
    [lo, 0.5 * (lo + hi), hi]
}

/// How far a tank thermometer's reading may be from the oil in the
/// cylinder, K: a commissioning this close outside the operating range is
/// not said to be outside it.
const TANK_THERMOMETER_K: f64 = 2.0;

/// The smallest detectable leak of each kind (L/min at p_s/2) at each of
/// [`stated_temperatures_c`] (°C): the thresholds `thr` widened by what the oil's
/// temperature leaves uncertain for `model` with healthy offsets `offsets_lpm`.
pub fn detectable_at(
    model: &model::ActuatorParams,
    thr: [f64; 3],
    offsets_lpm: [f64; 3],
) -> [(f64, [f64; 3]); 3] {
    let oil = &model.oil_temperature;
    // (where θ does not tell the temperature the model stays at the reference,
    // as uncertain as the operating range, whatever the oil's temperature)
    let unreadable = oil
        .reference_stiffness
        .and_then(|theta| filter::oil::OilFromStiffness::new(oil, theta))
        .filter(|o| !o.readable());
    stated_temperatures_c(oil).map(|t| {
        let (model_c, sigma_k) = match &unreadable {
            Some(o) => (oil.reference_c, o.sigma_k(0.0)),
            None => (t, filter::oil::settled_sigma_k(oil, t)),
        };
        let (sigma, band) = filter::oil::null_leakage_band(model, model_c, sigma_k);
        let widen = detect::oil_band_lpm(sigma, band, offsets_lpm);
        (t, std::array::from_fn(|k| thr[k] + widen[k]))
    })
}

/// The line that states the smallest detectable leak of each kind over the
/// operating range ([`stated_temperatures_c`]): the thresholds `thr` (L/min at
/// p_s/2) widened by what the oil's temperature leaves uncertain for the model
/// `model` with healthy offsets `offsets_lpm` (L/min), the temperature read
/// from θ once it settled (no thermometer: the widest band; docs/plant.md).
fn detectable_over_temperature(
    model: &model::ActuatorParams,
    thr: [f64; 3],
    offsets_lpm: [f64; 3],
) -> String {
    let oil = &model.oil_temperature;
    let at = detectable_at(model, thr, offsets_lpm)
        .map(|(t, d)| format!("{t:.0} °C {:.3}/{:.3}/{:.3}", d[0], d[1], d[2]));
    let range = oil.operating_min_c - TANK_THERMOMETER_K..=oil.operating_max_c + TANK_THERMOMETER_K;
    let outside = if range.contains(&oil.reference_c) {
        String::new()
    } else {
        format!(
            " (the commissioning's temperature is outside the operating range {:.0}-{:.0} °C: \
             commission on a recording inside it)",
            oil.operating_min_c, oil.operating_max_c
        )
    };
    format!(
        "smallest detectable leak (ext1/ext2/int, L/min at p_s/2) over the operating range, as the oil \
         moves from the commissioning's {:.1} °C: {}{outside}",
        oil.reference_c,
        at.join(", ")
    )
}

/// The command: learn, then write the config with its commissioning.
pub fn run(input: &Path, config: Option<&Path>, out: &Path, force: bool) -> Result<(), String> {
    let mut inputs = vec![input];
    inputs.extend(config);
    let report = report_path(out);
    // refused before the learning, not after
    crate::out::check(out, force, &inputs)?;
    crate::out::check(&report, force, &inputs)?;
    if config.is_none() {
        Config::note_builtin_rig("./leakwatch.toml");
    }
    let (cfg, record) = commission_recorded(input, &Config::load_or_default(config)?)?;
    let body = toml::to_string(&cfg).map_err(|e| e.to_string())?;
    let text = format!(
        "# leakwatch configuration with the rig's commissioning (the healthy state of the leak\n\
         # filter's estimates, learned from {}; the spool's null bias identified there and\n\
         # held by the leak filter). [model] is the rig as identified there (from the\n\
         # datasheet's values where the recording could not tell).\n\
         # Use it with: leakwatch replay RUN.csv --config {name} --out DIR\n\
         #              leakwatch run --config {name} ...\n\
         # A leak present when monitoring starts is then seen once the filter has converged.\n\
         # Commission again after a change to the rig or to [model] / [leak_filter].\n\n{body}",
        input.display(),
        name = out.display()
    );
    crate::out::write(out, text.as_bytes(), force, &inputs)?;
    eprintln!("wrote {}", out.display());
    crate::out::write(&report, record.html()?.as_bytes(), force, &inputs)?;
    eprintln!("wrote {} (the commissioning record)", report.display());
    Ok(())
}

/// The report beside the config `out`: its name with `.html` for `.toml`.
pub fn report_path(out: &Path) -> std::path::PathBuf {
    out.with_extension("html")
}

#[cfg(test)]
mod tests;
