//! Batch replay throughput (`leakwatch bench replay`): samples per second in
//! total and per core when whole files are replayed side by side on worker
//! threads, one pass per number of threads. The replays themselves run in
//! `leakwatch` (its batch replay); this module turns their times into figures.

use serde::Serialize;

use crate::stats::quantile;

/// One file replayed in a pass.
#[derive(Debug, Clone, Serialize)]
pub struct FileTime {
    /// The file's name in the batch (`run_000/measured`).
    pub file: String,
    /// Samples replayed (0 if it failed).
    pub samples: u64,
    /// Wall time of this file on its worker thread, s.
    pub wall_s: f64,
    /// Its error, if it failed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// One pass: every file replayed on `threads` worker threads.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayPass {
    /// Worker threads.
    pub threads: usize,
    /// Files replayed.
    pub files: usize,
    /// Files that failed.
    pub failed: usize,
    /// Samples replayed in all.
    pub samples: u64,
    /// Wall time of the whole pass, s.
    pub wall_s: f64,
    /// Samples per second of wall time, all threads together.
    pub samples_per_s: f64,
    /// [`Self::samples_per_s`] divided by the threads (a core each).
    pub samples_per_s_per_core: f64,
    /// Median over the files of one file's samples per second on its thread.
    pub file_samples_per_s_median: f64,
    /// [`Self::samples_per_s`] over the first pass's (1 for the first pass).
    pub speedup: f64,
    /// Each file's figures.
    pub per_file: Vec<FileTime>,
}

impl ReplayPass {
    /// The figures of a pass of `threads` worker threads that replayed
    /// `per_file` in `wall_s` seconds; `first_samples_per_s` is the first
    /// pass's total rate (None: this is the first pass).
    pub fn new(
        threads: usize,
        per_file: Vec<FileTime>,
        wall_s: f64,
        first_samples_per_s: Option<f64>,
    ) -> Self {
        let samples: u64 = per_file.iter().map(|f| f.samples).sum();
        let samples_per_s = samples as f64 / wall_s.max(1e-9);
        let mut rates: Vec<f64> = per_file
            .iter()
            .filter(|f| f.error.is_none() && f.wall_s > 0.0)
            .map(|f| f.samples as f64 / f.wall_s)
            .collect();
        ReplayPass {
            threads,
            files: per_file.len(),
            failed: per_file.iter().filter(|f| f.error.is_some()).count(),
            samples,
            wall_s,
            samples_per_s,
            samples_per_s_per_core: samples_per_s / threads.max(1) as f64,
            file_samples_per_s_median: quantile(&mut rates, 0.5),
            speedup: first_samples_per_s.map_or(1.0, |r| samples_per_s / r.max(1e-9)),
            per_file,
        }
    }
}

/// What replay.json holds.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayBench {
    /// The directory replayed (or where the generated files were).
    pub data: String,
    /// Whether the files were generated for the benchmark (simulated, then removed).
    pub generated: bool,
    /// Cores of this host (`available_parallelism`).
    pub cores: usize,
    /// Format of the estimates files written.
    pub estimates: String,
    /// One pass per number of worker threads.
    pub passes: Vec<ReplayPass>,
}

/// The passes as a Markdown table.
pub fn table(b: &ReplayBench) -> String {
    let mut t = String::from(
        "| threads | files | failed | samples | wall s | samples/s | samples/s per core | \
         median file samples/s | speed-up |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for p in &b.passes {
        t.push_str(&format!(
            "| {} | {} | {} | {} | {:.2} | {:.0} | {:.0} | {:.0} | {:.2} |\n",
            p.threads,
            p.files,
            p.failed,
            p.samples,
            p.wall_s,
            p.samples_per_s,
            p.samples_per_s_per_core,
            p.file_samples_per_s_median,
            p.speedup
        ));
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pass_divides_its_rate_among_its_threads() {
        let f = |samples, wall_s| FileTime {
            file: "a".into(),
            samples,
            wall_s,
            error: None,
        };
        let p1 = ReplayPass::new(1, vec![f(100, 1.0), f(300, 1.0)], 2.0, None);
        assert_eq!((p1.samples, p1.samples_per_s, p1.speedup), (400, 200.0, 1.0));
        let p2 = ReplayPass::new(2, vec![f(100, 1.0), f(300, 1.5)], 1.0, Some(p1.samples_per_s));
        assert_eq!(
            (p2.samples_per_s, p2.samples_per_s_per_core, p2.speedup),
            (400.0, 200.0, 2.0)
        );
        assert_eq!(p2.file_samples_per_s_median, 150.0);
        assert!(table(&ReplayBench {
            data: "d".into(),
            generated: true,
            cores: 2,
            estimates: "csv".into(),
            passes: vec![p1, p2],
        })
        .contains("| 2 | 2 | 0 | 400 | 1.00 | 400 | 200 | 150 | 2.00 |"));
    }
}
