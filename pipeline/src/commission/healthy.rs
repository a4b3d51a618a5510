//! The healthy rises' own misreading: the recording replayed through the
//! commissioned detector, its offset watch fitting every rise it reads
//! ([`detect::offset::HealthyMisreading`]). A rig's model error can swing
//! with the flow as a transducer's misreading does; taken off the rises, a
//! transducer that goes on to read off is fitted from where the healthy rig
//! stood.

use std::path::Path;

use config::Config;
use detect::offset::HealthyMisreading;

/// The misreading the healthy rises of `input` fit, replayed with `cfg`
/// (its `[classifier.commissioning]` learned, nothing taken off yet), where
/// it explains at least [`detect::offset::HEALTHY_MISREADING_LEAST_SHARE`]
/// of their energy.
pub(super) fn healthy_misreading(input: &Path, cfg: &Config) -> Result<Option<HealthyMisreading>, String> {
    let mut detector = detect::LeakSizeDetector::new(cfg.classifier.clone()).learning_healthy_misreading();
    let mut event = None;
    super::replay_estimates(input, cfg, cfg.leak_filter.clone(), |e| {
        detector.on_estimate(e, &mut event);
    })?;
    Ok(detector.healthy_misreading())
}

/// Keeps `m` in `c` (`healthy_offsets_kpa` or `healthy_span_errors`).
pub(super) fn keep(c: &mut detect::Commissioning, m: &HealthyMisreading) {
    if m.span_error.is_nan() {
        c.healthy_offsets_kpa[m.channel] = m.offset_mpa * 1e3;
    } else {
        c.healthy_span_errors[m.channel] = m.span_error;
    }
}

/// What `commission` prints of `m`.
pub(super) fn line(m: &HealthyMisreading) -> String {
    let channel = ["p1", "p2"][m.channel];
    let what = if m.span_error.is_nan() {
        format!("an offset of {:+.0} kPa", m.offset_mpa * 1e3)
    } else {
        format!("a span error of {:+.2} %", m.span_error * 100.0)
    };
    format!(
        "the healthy rises swing as {channel} reading off would: {what} explains {:.0} % of their energy; the offset watch takes it off before it fits a misreading (a transducer that reads off is fitted from there)",
        m.share * 100.0
    )
}
