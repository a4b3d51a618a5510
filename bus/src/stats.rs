//! Per-stage counters and latency histograms, turned into a [`StatsFrame`]
//! once a second; CPU and memory of the process.

use frames::StatsFrame;
use hdrhistogram::Histogram;

use crate::clock::monotonic_ns;

/// Largest value a histogram records, ns (larger values saturate): 60 s.
const HIST_MAX_NS: u64 = 60_000_000_000;

/// Percentiles of one histogram, ns.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Percentiles {
    /// Number of values recorded.
    pub count: u64,
    /// Median, ns.
    pub p50_ns: u64,
    /// 99th percentile, ns.
    pub p99_ns: u64,
    /// 99.9th percentile, ns.
    pub p999_ns: u64,
    /// Maximum, ns.
    pub max_ns: u64,
}

impl Percentiles {
    /// The percentiles of `h`.
    pub fn of(h: &Histogram<u64>) -> Percentiles {
        if h.is_empty() {
            return Percentiles::default();
        }
        Percentiles {
            count: h.len(),
            p50_ns: h.value_at_quantile(0.5),
            p99_ns: h.value_at_quantile(0.99),
            p999_ns: h.value_at_quantile(0.999),
            max_ns: h.max(),
        }
    }
}

impl std::fmt::Display for Percentiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let us = |ns: u64| ns as f64 / 1e3;
        write!(
            f,
            "n={} p50={:.1}µs p99={:.1}µs p99.9={:.1}µs max={:.1}µs",
            self.count,
            us(self.p50_ns),
            us(self.p99_ns),
            us(self.p999_ns),
            us(self.max_ns)
        )
    }
}

fn histogram() -> Histogram<u64> {
    // 3 significant digits from 1 ns to 60 s: about 30 kB; never resized, so
    // recording never allocates.
    Histogram::new_with_bounds(1, HIST_MAX_NS, 3).expect("constant histogram bounds are valid")
}

/// CPU time of this process (user + system), ns, from `getrusage`.
pub fn process_cpu_ns() -> u64 {
    // SAFETY: a zeroed rusage is a valid out-parameter.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: RUSAGE_SELF with a valid pointer.
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) } != 0 {
        return 0;
    }
    let tv = |t: libc::timeval| t.tv_sec as u64 * 1_000_000_000 + t.tv_usec as u64 * 1_000;
    tv(ru.ru_utime) + tv(ru.ru_stime)
}

/// User + system CPU time of this process's waited-for descendants, s (NaN if
/// `getrusage` fails).
pub fn children_cpu_s() -> f64 {
    // SAFETY: a zeroed rusage is a valid out-parameter.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: RUSAGE_CHILDREN with a valid pointer.
    if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru) } != 0 {
        return f64::NAN;
    }
    let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
    t(ru.ru_utime) + t(ru.ru_stime)
}

/// Resident set size of this process, bytes (`/proc/self/statm`; 0 if unreadable).
pub fn rss_bytes() -> u64 {
    let Ok(text) = std::fs::read_to_string("/proc/self/statm") else {
        return 0;
    };
    let pages: u64 = text
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    // SAFETY: sysconf has no preconditions.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    pages * page.max(0) as u64
}

/// Counters and histograms of one pipeline stage.
///
/// Two sets of histograms are kept: one for the current stats interval
/// (reported in each [`StatsFrame`], then cleared) and one since the start
/// (for the final report). Recording never allocates.
pub struct StageStats {
    stage: u32,
    /// Frames received.
    pub frames_in: u64,
    /// Frames published.
    pub frames_out: u64,
    /// Input frames missing from the sequence.
    pub seq_gaps: u64,
    /// Deadlines missed.
    pub deadline_misses: u64,
    proc_window: Histogram<u64>,
    lat_window: Histogram<u64>,
    proc_total: Histogram<u64>,
    lat_total: Histogram<u64>,
    last_fill_mono_ns: u64,
    last_fill_cpu_ns: u64,
}

impl StageStats {
    /// Empty statistics for `stage` (one of [`frames::stage`]).
    pub fn new(stage: u32) -> StageStats {
        StageStats {
            stage,
            frames_in: 0,
            frames_out: 0,
            seq_gaps: 0,
            deadline_misses: 0,
            proc_window: histogram(),
            lat_window: histogram(),
            proc_total: histogram(),
            lat_total: histogram(),
            last_fill_mono_ns: monotonic_ns(),
            last_fill_cpu_ns: process_cpu_ns(),
        }
    }

    /// Records the processing time of one frame, ns.
    #[inline]
    pub fn record_proc_ns(&mut self, ns: u64) {
        self.proc_window.saturating_record(ns.max(1));
        self.proc_total.saturating_record(ns.max(1));
    }

    /// Records one latency, ns (since `acq_mono_ns`; for the acquisition the
    /// lateness against its schedule).
    #[inline]
    pub fn record_latency_ns(&mut self, ns: u64) {
        self.lat_window.saturating_record(ns.max(1));
        self.lat_total.saturating_record(ns.max(1));
    }

    /// Processing-time percentiles since the start.
    pub fn proc_total(&self) -> Percentiles {
        Percentiles::of(&self.proc_total)
    }

    /// Latency percentiles since the start.
    pub fn latency_total(&self) -> Percentiles {
        Percentiles::of(&self.lat_total)
    }

    /// The stats frame for the interval since the previous call (percentiles
    /// and CPU fraction of the interval; counters since the start), then
    /// starts a new interval. Reads `/proc/self/statm`: call it at 1 Hz, not per frame.
    pub fn take_frame(&mut self) -> StatsFrame {
        let now = monotonic_ns();
        let cpu = process_cpu_ns();
        let wall = now.saturating_sub(self.last_fill_mono_ns);
        let cpu_fraction = if wall > 0 {
            cpu.saturating_sub(self.last_fill_cpu_ns) as f64 / wall as f64
        } else {
            f64::NAN
        };
        let proc = Percentiles::of(&self.proc_window);
        let lat = Percentiles::of(&self.lat_window);
        self.proc_window.reset();
        self.lat_window.reset();
        self.last_fill_mono_ns = now;
        self.last_fill_cpu_ns = cpu;
        StatsFrame {
            mono_ns: now,
            pid: std::process::id(),
            stage: self.stage,
            frames_in: self.frames_in,
            frames_out: self.frames_out,
            seq_gaps: self.seq_gaps,
            deadline_misses: self.deadline_misses,
            proc_ns_p50: proc.p50_ns,
            proc_ns_p99: proc.p99_ns,
            proc_ns_max: proc.max_ns,
            lat_ns_p50: lat.p50_ns,
            lat_ns_p99: lat.p99_ns,
            lat_ns_max: lat.max_ns,
            cpu_fraction,
            rss_bytes: rss_bytes(),
        }
    }
}
