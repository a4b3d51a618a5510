//! `leakwatch commission HEALTHY.csv --out rig.toml`: learns the healthy state of
//! the leak filter's estimates on a rig (offsets, spreads, crossing rates) and
//! writes a config that carries it in `[classifier.commissioning]`.

use std::path::Path;

use classifier::CommissioningLearner;
use dataset::{CsvReader, Limits, Row};
use estimator::EstimatorStage;

use crate::config::Config;

/// Least healthy, converged data a commissioning needs, s.
pub const MIN_HEALTHY_S: f64 = 10.0;

/// Learns the commissioning of `input` under the config at `config` (or the defaults).
pub fn learn(input: &Path, cfg: &Config) -> Result<classifier::Commissioning, String> {
    let limits = Limits::for_model(&cfg.model, cfg.leak_filter.sample_period_s);
    let mut reader = CsvReader::open(input, limits).map_err(|e| e.to_string())?;
    let mut stage = EstimatorStage::new(cfg.model.clone(), cfg.leak_filter.clone(), cfg.estimator.clone())?;
    if cfg.leak_filter.states < 10 {
        return Err(format!(
            "[leak_filter] states = {}: commissioning needs the leak filter (10, 11 or 12 states)",
            cfg.leak_filter.states
        ));
    }
    let mut learner = CommissioningLearner::new(cfg.classifier.settle_s);
    while let Some(row) = reader.next_row() {
        match row {
            Row::Sample(s) | Row::AfterGap(s, _) => learner.on_estimate(&stage.on_sample(&s).leak),
            Row::Skipped(_) => {}
        }
    }
    dataset::check_bad_fraction(reader.rows, reader.skipped, dataset::DEFAULT_MAX_BAD_FRACTION)
        .map_err(|e| format!("{}: cannot commission from it: {e}", input.display()))?;
    learner
        .finish(MIN_HEALTHY_S, &input.display().to_string())
        .map_err(|e| format!("{}: cannot commission: {e}", input.display()))
}

/// The command: learn, then write the config with its commissioning.
pub fn run(input: &Path, config: Option<&Path>, out: &Path, force: bool) -> Result<(), String> {
    let mut inputs = vec![input];
    inputs.extend(config);
    // refused before the learning, not after
    crate::out::check(out, force, &inputs)?;
    let mut cfg = Config::load_or_default(config)?;
    let c = learn(input, &cfg)?;
    eprintln!(
        "learned {:.0} s of healthy data: offsets ext1/ext2/int {:.3}/{:.3}/{:.3} L/min, spreads {:.3}/{:.3}/{:.3} L/min (at p_s/2)",
        c.healthy_s, c.offsets_lpm[0], c.offsets_lpm[1], c.offsets_lpm[2], c.spreads_lpm[0], c.spreads_lpm[1], c.spreads_lpm[2]
    );
    cfg.classifier.commissioning = Some(c);
    let body = toml::to_string(&cfg).map_err(|e| e.to_string())?;
    let text = format!(
        "# leakwatch configuration with the rig's commissioning (the healthy state of the leak\n\
         # filter's estimates, learned from {}).\n\
         # Use it with: leakwatch replay RUN.csv --config {name} --out DIR\n\
         #              leakwatch run --config {name} ...\n\
         # A leak present when monitoring starts is then seen once the filter has converged.\n\
         # Commission again after a change to the rig or to [model] / [leak_filter].\n\n{body}",
        input.display(),
        name = out.display()
    );
    crate::out::write(out, text.as_bytes(), force, &inputs)?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
