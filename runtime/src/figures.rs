//! The figures of a run: per-stage counts and latency gathered from the stats
//! frames, and latency.json.

use crate::stages::Stage;
use std::collections::BTreeMap;

use frames::StatsFrame;
use serde::Serialize;

/// Latency and counts of one stage, from its stats frames.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StageFigures {
    /// Frames received.
    pub frames_in: u64,
    /// Frames published.
    pub frames_out: u64,
    /// Frames missing from the input sequence.
    pub seq_gaps: u64,
    /// Missed 1 kHz deadlines (acquisition).
    pub deadline_misses: u64,
    /// Latency since acquisition at this stage's input, µs: median of the 1 s p50s
    /// (to 3 significant digits).
    pub latency_p50_us: f64,
    /// The worst one-second p99 of that latency (the largest of the 1 s p99s the
    /// stage reported; not the whole run's p99), µs.
    pub latency_worst_1s_p99_us: f64,
    /// Largest latency, µs.
    pub latency_max_us: f64,
    /// Processing time per frame: median of the 1 s p50s (to 3 significant digits), µs.
    pub proc_p50_us: f64,
    /// Largest 1 s p99 of the processing time, µs.
    pub proc_p99_us: f64,
    /// Mean CPU use, fraction of a core.
    pub cpu_fraction: f64,
    /// Largest resident set size, MB.
    pub rss_mb: f64,
    /// Stats frames seen.
    pub intervals: u64,
}

/// The 1-s p50s of a run, ns: a histogram of fixed size (3 significant
/// digits), so a day-long run's supervisor does not grow with it.
struct SecondP50s(hdrhistogram::Histogram<u64>);

impl Default for SecondP50s {
    fn default() -> Self {
        // 1 ns to 1 h: any latency a stage reports
        let h = hdrhistogram::Histogram::new_with_bounds(1, 3_600_000_000_000, 3)
            .expect("constant bounds are valid");
        SecondP50s(h)
    }
}

impl SecondP50s {
    fn record(&mut self, ns: u64) {
        self.0.saturating_record(ns.max(1));
    }
    /// The median, µs (NaN without a value; within 0.1 % of the exact one).
    fn median_us(&self) -> f64 {
        if self.0.is_empty() {
            f64::NAN
        } else {
            self.0.value_at_quantile(0.5) as f64 / 1e3
        }
    }
}

#[derive(Default)]
pub(super) struct StageAcc {
    last: Option<StatsFrame>,
    p50s: SecondP50s,
    proc_p50s: SecondP50s,
    fig: StageFigures,
    cpu_sum: f64,
}

impl StageAcc {
    pub(super) fn push(&mut self, s: &StatsFrame) {
        let f = &mut self.fig;
        f.intervals += 1;
        // counters run from the process start: keep the latest (a restart starts again: add up)
        if let Some(prev) = self.last {
            if s.pid != prev.pid {
                f.frames_in += prev.frames_in;
                f.frames_out += prev.frames_out;
                f.seq_gaps += prev.seq_gaps;
                f.deadline_misses += prev.deadline_misses;
            }
        }
        self.last = Some(*s);
        if s.lat_ns_p50 > 0 {
            self.p50s.record(s.lat_ns_p50);
            f.latency_worst_1s_p99_us = f.latency_worst_1s_p99_us.max(s.lat_ns_p99 as f64 / 1e3);
            f.latency_max_us = f.latency_max_us.max(s.lat_ns_max as f64 / 1e3);
        }
        if s.proc_ns_p50 > 0 {
            self.proc_p50s.record(s.proc_ns_p50);
            f.proc_p99_us = f.proc_p99_us.max(s.proc_ns_p99 as f64 / 1e3);
        }
        self.cpu_sum += s.cpu_fraction;
        f.rss_mb = f.rss_mb.max(s.rss_bytes as f64 / 1e6);
    }
    /// Frames the stage published so far, over all its processes.
    pub(super) fn frames_out_total(&self) -> u64 {
        self.fig.frames_out + self.last.map_or(0, |l| l.frames_out)
    }
    pub(super) fn finish(mut self) -> StageFigures {
        if let Some(l) = self.last {
            self.fig.frames_in += l.frames_in;
            self.fig.frames_out += l.frames_out;
            self.fig.seq_gaps += l.seq_gaps;
            self.fig.deadline_misses += l.deadline_misses;
        }
        self.fig.latency_p50_us = self.p50s.median_us();
        self.fig.proc_p50_us = self.proc_p50s.median_us();
        self.fig.cpu_fraction = self.cpu_sum / self.fig.intervals.max(1) as f64;
        self.fig
    }
}

/// What latency.json holds.
#[derive(Debug, Clone, Serialize)]
pub struct LatencyReport {
    /// Wait mode of the stages.
    pub mode: String,
    /// Per stage (acquisition, estimator, classifier, recorder).
    pub stages: BTreeMap<String, StageFigures>,
    /// Restarts of stages that exited or were killed, per stage.
    pub restarts: BTreeMap<String, u32>,
    /// Times each stage made no progress for more than 1.5 s (stopped, hung),
    /// the longest such time, and kills after 5 s (see `run::watchdog`).
    pub stalls: BTreeMap<String, crate::watchdog::StallFigures>,
}

/// The stage of each stats frame's code (`StatsFrame::stage`).
pub(super) const STAGE_CODES: [Stage; 4] = [
    Stage::Acquisition,
    Stage::Estimator,
    Stage::Classifier,
    Stage::Recorder,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_days_one_second_p50s_give_their_median_from_the_fixed_histogram() {
        let mut acc = StageAcc::default();
        let frame = |k: u64| StatsFrame {
            // a p50 that wanders from 20 to 220 µs, and a processing time of 1-3 µs
            lat_ns_p50: 20_000 + (k * 7919) % 200_000,
            lat_ns_p99: 500_000,
            proc_ns_p50: 1_000 + (k * 104_729) % 2_000,
            ..StatsFrame::default()
        };
        for k in 0..86_400 {
            acc.push(&frame(k));
        }
        let exact = |f: fn(&StatsFrame) -> u64| {
            let mut v: Vec<u64> = (0..86_400).map(|k| f(&frame(k))).collect();
            v.sort_unstable();
            v[v.len() / 2] as f64 / 1e3
        };
        let (lat, proc) = (exact(|s| s.lat_ns_p50), exact(|s| s.proc_ns_p50));
        let fig = acc.finish();
        assert!(
            (fig.latency_p50_us / lat - 1.0).abs() < 1e-3,
            "{} against {lat}",
            fig.latency_p50_us
        );
        assert!(
            (fig.proc_p50_us / proc - 1.0).abs() < 1e-3,
            "{} against {proc}",
            fig.proc_p50_us
        );
        assert_eq!(fig.intervals, 86_400);
    }
}
