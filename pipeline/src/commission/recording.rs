//! Reading the healthy recording: into the rows identification takes, and
//! through the leak filter alone.

use std::path::Path;

use dataset::{CsvReader, Limits, PressureReach, Row};
use filter::Tuning;

use config::Config;

/// Reads `input` into the rows [`identify::identify`] takes: an error when
/// no row is usable (naming the first reason) or when its pressures are not
/// in Pa ([`dataset::PressureReach`]).
pub(super) fn read_rows(input: &Path, cfg: &Config) -> Result<Vec<identify::Row>, String> {
    let limits = Limits::for_model(&cfg.model, cfg.leak_filter.sample_period_s);
    let mut reader = CsvReader::open(input, limits).map_err(|e| e.to_string())?;
    let mut rows = Vec::new();
    let mut gap = false;
    let mut reach = PressureReach::default();
    let mut skipped = 0u64;
    let mut first_skipped = None;
    while let Some(row) = reader.next_row() {
        let (sample, after_gap) = match row {
            Row::Sample(sample) => (sample, std::mem::take(&mut gap)),
            Row::AfterGap(sample, _) => {
                gap = false;
                (sample, true)
            }
            Row::Skipped(issue) => {
                skipped += 1;
                first_skipped.get_or_insert(issue);
                gap = true;
                continue;
            }
        };
        reach.add(&sample);
        rows.push(identify::Row { sample, after_gap });
    }
    if rows.is_empty() {
        let first = first_skipped.map(|i| format!("; first: {i}")).unwrap_or_default();
        return Err(format!(
            "{}: no usable samples ({skipped} rows skipped{first})",
            input.display()
        ));
    }
    reach
        .check(cfg.model.supply_pressure_pa)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    Ok(rows)
}

/// Runs the leak filter of `cfg` with `tuning` over `input`, calling `each` with
/// every estimate; checks the recording's share of bad rows.
pub(super) fn replay_estimates(
    input: &Path,
    cfg: &Config,
    tuning: Tuning,
    mut each: impl FnMut(&filter::Estimate),
) -> Result<(), String> {
    let limits = Limits::for_model(&cfg.model, tuning.sample_period_s);
    let mut reader = CsvReader::open(input, limits).map_err(|e| e.to_string())?;
    let mut stage = crate::ChainSettings {
        leak_filter: tuning,
        ..crate::ChainSettings::from(cfg)
    }
    .leak_stage()?;
    while let Some(row) = reader.next_row() {
        match row {
            Row::Sample(s) | Row::AfterGap(s, _) => each(&stage.on_sample(&s).leak),
            Row::Skipped(_) => {}
        }
    }
    dataset::check_bad_fraction(reader.rows, reader.skipped, dataset::DEFAULT_MAX_BAD_FRACTION)
        .map_err(|e| format!("{}: cannot commission from it: {e}", input.display()))
}
