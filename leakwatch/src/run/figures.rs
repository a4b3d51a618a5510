//! The figures of a run: per-stage counts and latency gathered from the stats
//! frames, and latency.json.

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
    /// Latency since acquisition at this stage's input, µs: median of the 1 s p50s.
    pub latency_p50_us: f64,
    /// The worst one-second p99 of that latency (the largest of the 1 s p99s the
    /// stage reported; not the whole run's p99), µs.
    pub latency_worst_1s_p99_us: f64,
    /// Largest latency, µs.
    pub latency_max_us: f64,
    /// Processing time per frame: median of the 1 s p50s, µs.
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

#[derive(Default)]
pub(super) struct StageAcc {
    last: Option<StatsFrame>,
    p50s: Vec<f64>,
    proc_p50s: Vec<f64>,
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
            self.p50s.push(s.lat_ns_p50 as f64 / 1e3);
            f.latency_worst_1s_p99_us = f.latency_worst_1s_p99_us.max(s.lat_ns_p99 as f64 / 1e3);
            f.latency_max_us = f.latency_max_us.max(s.lat_ns_max as f64 / 1e3);
        }
        if s.proc_ns_p50 > 0 {
            self.proc_p50s.push(s.proc_ns_p50 as f64 / 1e3);
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
        let med = |v: &mut Vec<f64>| {
            if v.is_empty() {
                return f64::NAN;
            }
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        if let Some(l) = self.last {
            self.fig.frames_in += l.frames_in;
            self.fig.frames_out += l.frames_out;
            self.fig.seq_gaps += l.seq_gaps;
            self.fig.deadline_misses += l.deadline_misses;
        }
        self.fig.latency_p50_us = med(&mut self.p50s);
        self.fig.proc_p50_us = med(&mut self.proc_p50s);
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
    pub stalls: BTreeMap<String, super::watchdog::StallFigures>,
}

pub(super) const STAGE_NAMES: [&str; 4] = ["acquisition", "estimator", "classifier", "recorder"];
