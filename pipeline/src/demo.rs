//! `leakwatch demo`: the whole chain in one process on the simulated rig.

use detect::Phase;
use model::{Fault, FaultSchedule, Scenario, Simulator};

use crate::out::outln;
use config::Config;

/// A rig that differs from the model the way real ones do: friction 15 % higher
/// extending and 10 % lower retracting, bulk modulus 15 % lower (air), a spool
/// null bias of 3 % of the spool amplitude.
pub fn off_nominal_rig(model: &model::ActuatorParams) -> model::ActuatorParams {
    model.off_nominal(0.85, 0.03)
}

/// Runs the demonstration and prints what happens: on the thesis rig, or with
/// `lift` on the vertical single-rod lift (`ActuatorParams::vertical_lift`),
/// `scenario` defaulting to each rig's own (loaded-sine, lift).
pub fn run(
    scenario: Option<&str>,
    seconds: f64,
    seed: u64,
    faults: &[String],
    lift: bool,
) -> Result<(), String> {
    let mut cfg = Config::default();
    if lift {
        cfg.model = model::ActuatorParams::vertical_lift();
    }
    let scenario = scenario.unwrap_or(if lift { "lift" } else { "loaded-sine" });
    if lift {
        let c = commission_lift(&cfg, seed)?;
        outln!(
            "  commissioned on {:.0} s of the healthy lift: the internal leak's pressure factors {:.3}/{:.3} (docs/plant.md)",
            c.healthy_s,
            c.internal_factors[0],
            c.internal_factors[1]
        );
        cfg.classifier.commissioning = Some(c);
    }
    crate::simulate::check_seconds(seconds, cfg.sim.sample_period_s)?;
    let rig = off_nominal_rig(&cfg.model);
    let specs: Vec<String> = if faults.is_empty() {
        vec!["ext1:0.5lpm@20s".into()]
    } else {
        faults.to_vec()
    };
    let mut schedule = FaultSchedule::default();
    for s in &specs {
        schedule
            .faults
            .push(Fault::parse(s, &rig).map_err(|e| e.to_string())?);
    }
    let sc = Scenario::by_name(scenario, seed, seconds).map_err(|e| e.to_string())?;
    outln!(
        "leakwatch demo: {} rig, scenario {scenario}, {seconds} s, rig off-nominal (friction ±, air, spool bias)",
        if lift { "lift (single-rod, vertical)" } else { "thesis (double-rod)" }
    );
    for f in &schedule.faults {
        outln!(
            "  injected: {} leak ({} law) at t = {} s{}",
            f.path.name(),
            f.law.name(),
            f.onset_s,
            f.nominal_lpm
                .map(|q| format!(", {q} L/min at nominal pressure"))
                .unwrap_or_default()
        );
    }
    outln!(
        "  estimator: 12-state leak filter; classifier warm-up {} s",
        cfg.classifier.warmup_s
    );
    let mut sim = Simulator::new(rig, cfg.sensors, cfg.sim, sc, schedule, seed).map_err(|e| e.to_string())?;
    // (the thesis filter runs for its baseline only, which the demonstration does not report)
    let mut chain = crate::Chain::new(&crate::ChainSettings::from(&cfg))?;
    let n = (seconds / sim.sample_period_s()).round() as u64;
    let t0 = std::time::Instant::now();
    let mut leak_found = false;
    let mut last_t = 0.0;
    let mut out_err: Option<String> = None;
    for _ in 0..n {
        let s = sim.step();
        last_t = s.t_s;
        chain.step(&s, |ev| {
            if ev.phase == Phase::Raised && ev.kind.is_leak_alarm() && ev.detector == "leak-size" {
                leak_found = true;
            }
            let size = if ev.size_lpm.is_finite() {
                format!(" size {:.3} ± {:.3} L/min", ev.size_lpm, ev.size_lpm_sigma)
            } else {
                String::new()
            };
            let line = format!(
                "  t = {:6.3} s  {:<10} {:<8} {:<16} onset {:.2} s{size}  confidence {:.2}{}\n",
                ev.t_detect_s,
                ev.detector,
                format!("{:?}", ev.phase).to_lowercase(),
                ev.kind.name(),
                ev.t_onset_s,
                ev.confidence,
                if ev.detail.is_empty() {
                    String::new()
                } else {
                    format!("  ({})", ev.detail)
                }
            );
            if let Err(e) = crate::out::stdout(&line) {
                out_err.get_or_insert(e);
            }
        });
        if let Some(e) = out_err.take() {
            return Err(e);
        }
    }
    chain.finish(last_t, |ev| {
        if let Err(e) = crate::out::stdout(&format!("  {} {}\n", ev.kind.name(), ev.detail)) {
            out_err.get_or_insert(e);
        }
    });
    if let Some(e) = out_err {
        return Err(e);
    }
    let wall = t0.elapsed().as_secs_f64();
    outln!(
        "done: {seconds} s simulated and watched in {wall:.2} s ({:.0}x real time); leak {}",
        seconds / wall,
        if leak_found { "detected" } else { "not detected" }
    );
    Ok(())
}

/// Seconds of healthy lift the lift demonstration commissions on.
const LIFT_COMMISSIONING_S: f64 = 60.0;

/// The lift's commissioning, as `leakwatch commission` would learn it: a minute
/// of the healthy off-nominal rig (another seed) through the leak filter.
fn commission_lift(cfg: &Config, seed: u64) -> Result<detect::Commissioning, String> {
    let rig = off_nominal_rig(&cfg.model);
    let sc =
        Scenario::by_name("lift", seed.wrapping_add(1), LIFT_COMMISSIONING_S).map_err(|e| e.to_string())?;
    let mut sim = Simulator::new(
        rig,
        cfg.sensors,
        cfg.sim,
        sc,
        FaultSchedule::default(),
        seed.wrapping_add(1),
    )
    .map_err(|e| e.to_string())?;
    let mut stage = crate::ChainSettings::from(cfg).leak_stage()?;
    let mut learner = detect::CommissioningLearner::new(cfg.classifier.settle_s);
    let n = (LIFT_COMMISSIONING_S / sim.sample_period_s()).round() as u64;
    for _ in 0..n {
        let s = sim.step();
        learner.on_estimate(&stage.on_sample(&s).leak);
    }
    learner.finish(&cfg.classifier, 10.0, "the simulated healthy lift")
}
