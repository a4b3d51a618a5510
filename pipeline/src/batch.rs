//! `leakwatch replay DIR` (or several files): a batch of replays spread over
//! worker threads. Each file is replayed whole on one thread by the single
//! replay's path ([`crate::replay_cmd::replay_file`], its one-thread wiring), so its
//! outputs, in `OUT/<relative name without extension>/`, are the bytes a
//! replay of that file alone writes. A file that fails is reported and the
//! others go on; the command then ends with an error (a non-zero exit).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use detect::{EventKind, LeakEvent, Phase};

use crate::out::outln;
use crate::replay::{Summary, Wiring};
use crate::replay_cmd::{replay_file, Settings};

/// One file of a batch.
#[derive(Debug, Clone)]
pub struct Job {
    /// The input file.
    pub input: PathBuf,
    /// Its name relative to the directory given (or its file name), without the
    /// extension (`run_000/measured`): the folder of its outputs under OUT.
    pub name: String,
    /// Its size, bytes (the largest files start first).
    pub bytes: u64,
}

/// What replaying one file of a batch gave.
#[derive(Debug)]
pub struct Done {
    /// The replay's summary, or its error (naming the file).
    pub result: Result<Summary, String>,
    /// Wall time of this file, s.
    pub wall_s: f64,
}

/// A whole batch: one [`Done`] per job, in the jobs' order.
#[derive(Debug)]
pub struct BatchResult {
    /// The outcome of each job.
    pub done: Vec<Done>,
    /// Wall time of the batch, s.
    pub wall_s: f64,
    /// Worker threads used.
    pub threads: usize,
    /// Samples processed, failed files' included as far as they got.
    pub samples: u64,
}

/// The name of a replayable file without its extension (`.csv`, `.csv.gz`,
/// `.mcap`, any case); `None` for other files and hidden ones.
pub fn stem(file_name: &str) -> Option<&str> {
    if file_name.starts_with('.') {
        return None;
    }
    let lower = file_name.to_ascii_lowercase();
    [".csv.gz", ".csv", ".mcap"]
        .into_iter()
        .find(|ext| lower.ends_with(ext) && lower.len() > ext.len())
        .map(|ext| &file_name[..file_name.len() - ext.len()])
}

/// Sorted entries of `dir`, each with whether it is a directory (symbolic links followed).
fn entries(dir: &Path) -> Result<Vec<(PathBuf, String, bool)>, String> {
    let rd = std::fs::read_dir(dir).map_err(|e| format!("cannot read directory {}: {e}", dir.display()))?;
    let mut v = Vec::new();
    for entry in rd {
        let entry = entry.map_err(|e| format!("cannot read directory {}: {e}", dir.display()))?;
        let path = entry.path();
        let Some(name) = entry.file_name().to_str().map(str::to_string) else {
            eprintln!("warning: {}: a name that is not UTF-8, skipped", path.display());
            continue;
        };
        let is_dir = std::fs::metadata(&path).map(|m| m.is_dir()).unwrap_or(false);
        v.push((path, name, is_dir));
    }
    v.sort_by(|a, b| a.1.cmp(&b.1));
    Ok(v)
}

fn file_job(input: PathBuf, name: String) -> Result<Job, String> {
    let bytes = std::fs::metadata(&input)
        .map_err(|e| format!("{}: {e}", input.display()))?
        .len();
    Ok(Job { input, name, bytes })
}

/// The files of a batch: every `*.csv`, `*.csv.gz` and `*.mcap` of each
/// directory in `inputs` and of its subfolders one level down (named
/// `sub/stem`; the output directory `out` and folders with a replay's
/// summary.json are skipped), and each file in
/// `inputs` (named by its stem), sorted by name. Two files with the same name
/// (`a.csv` beside `a.mcap`) are refused, as is a batch with no file.
pub fn jobs(inputs: &[PathBuf], out: &Path) -> Result<Vec<Job>, String> {
    let out_canon = std::fs::canonicalize(out).ok();
    let mut jobs: Vec<Job> = Vec::new();
    for input in inputs {
        let meta = std::fs::metadata(input).map_err(|e| format!("{}: {e}", input.display()))?;
        if !meta.is_dir() {
            let file_name = input.file_name().and_then(|n| n.to_str()).unwrap_or_default();
            let name = stem(file_name)
                .or_else(|| Path::new(file_name).file_stem().and_then(|s| s.to_str()))
                .filter(|s| !s.is_empty())
                .ok_or_else(|| format!("{}: no file name to name its outputs by", input.display()))?;
            jobs.push(file_job(input.clone(), name.to_string())?);
            continue;
        }
        let before = jobs.len();
        for (path, name, is_dir) in entries(input)? {
            if !is_dir {
                if let Some(s) = stem(&name) {
                    jobs.push(file_job(path, s.to_string())?);
                }
                continue;
            }
            // the output directory, and a replay's output folder (its summary.json
            // beside an estimates.csv that is no recording) are not inputs
            if name.starts_with('.')
                || out_canon.is_some() && std::fs::canonicalize(&path).ok() == out_canon
                || path.join("summary.json").exists()
            {
                continue;
            }
            for (sub_path, sub_name, sub_is_dir) in entries(&path)? {
                if let (false, Some(s)) = (sub_is_dir, stem(&sub_name)) {
                    jobs.push(file_job(sub_path, format!("{name}/{s}"))?);
                }
            }
        }
        if jobs.len() == before {
            return Err(format!(
                "{}: no *.csv, *.csv.gz or *.mcap file in it or in its subfolders",
                input.display()
            ));
        }
    }
    jobs.sort_by(|a, b| a.name.cmp(&b.name));
    for w in jobs.windows(2) {
        if w[0].name == w[1].name {
            return Err(format!(
                "{} and {} would both write to {}: replay them separately",
                w[0].input.display(),
                w[1].input.display(),
                out.join(&w[0].name).display()
            ));
        }
    }
    Ok(jobs)
}

/// Worker threads for `threads` (default: all cores) and `files` files.
pub fn threads_for(threads: Option<usize>, files: usize) -> Result<usize, String> {
    let n = match threads {
        Some(0) => return Err("--threads 0: at least one worker thread".into()),
        Some(n) => n,
        None => cores(),
    };
    Ok(n.min(files.max(1)))
}

/// The cores this process may run on (1 when the system cannot say): the
/// default number of worker threads of every batch and benchmark.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Replays `jobs` into `out` on `threads` worker threads, each taking the next
/// file (the largest first) until none is left. With `progress`, one bar on
/// stderr (files done / total, samples, samples/s) on a terminal, else a line
/// for every file done and every 10 s.
pub fn replay_all(
    jobs: &[Job],
    out: &Path,
    settings: &Settings,
    threads: usize,
    progress: bool,
) -> BatchResult {
    let settings = &Settings {
        batch: true,
        ..settings.clone()
    };
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by(|&a, &b| jobs[b].bytes.cmp(&jobs[a].bytes).then(a.cmp(&b)));
    let next = AtomicUsize::new(0);
    let samples = Arc::new(AtomicU64::new(0));
    let (tx, rx) = crossbeam_channel::unbounded::<(usize, Done)>();
    let mut done: Vec<Option<Done>> = jobs.iter().map(|_| None).collect();
    let threads = threads.max(1);
    let started = Instant::now();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let tx = tx.clone();
            let (next, order, samples) = (&next, &order, &samples);
            scope.spawn(move || loop {
                let Some(&i) = order.get(next.fetch_add(1, Ordering::Relaxed)) else {
                    return;
                };
                let job = &jobs[i];
                let t0 = Instant::now();
                let dir = out.join(&job.name);
                let run = || {
                    replay_file(
                        &job.input,
                        &dir,
                        settings,
                        Wiring::SingleThread,
                        false,
                        Some(samples.clone()),
                        &[],
                    )
                };
                let result =
                    std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)).unwrap_or_else(|p| {
                        let why = p
                            .downcast_ref::<&str>()
                            .map(|s| s.to_string())
                            .or_else(|| p.downcast_ref::<String>().cloned())
                            .unwrap_or_else(|| "unknown".into());
                        Err(format!("{}: the replay panicked: {why}", job.input.display()))
                    });
                let wall_s = t0.elapsed().as_secs_f64();
                if tx.send((i, Done { result, wall_s })).is_err() {
                    return;
                }
            });
        }
        drop(tx);
        let bar = BatchProgress::new(progress, jobs.len());
        let mut finished = 0usize;
        loop {
            match rx.recv_timeout(bar.tick()) {
                Ok((i, d)) => {
                    finished += 1;
                    bar.file_done(finished, &jobs[i].name, &d, &samples, started);
                    done[i] = Some(d);
                }
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => bar.waiting(finished, &samples, started),
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
            }
        }
        bar.finish();
    });
    let done = done
        .into_iter()
        .zip(jobs)
        .map(|(d, job)| {
            d.unwrap_or_else(|| Done {
                result: Err(format!(
                    "{}: not replayed (its worker thread ended)",
                    job.input.display()
                )),
                wall_s: 0.0,
            })
        })
        .collect();
    BatchResult {
        done,
        wall_s: started.elapsed().as_secs_f64(),
        threads,
        samples: samples.load(Ordering::Relaxed),
    }
}

/// A batch's progress on stderr: one bar (files done of all, samples, samples/s)
/// on a terminal; elsewhere a line for every file done and every 10 s.
struct BatchProgress {
    /// The bar, on a terminal (none: lines, or nothing without `progress`).
    bar: Option<indicatif::ProgressBar>,
    /// Lines are printed (asked for, not on a terminal).
    lines: bool,
    files: usize,
}

impl BatchProgress {
    /// The progress of `files` files, shown if `progress`.
    fn new(progress: bool, files: usize) -> BatchProgress {
        use std::io::IsTerminal;
        let terminal = progress && std::io::stderr().is_terminal();
        let bar = terminal.then(|| {
            let bar = indicatif::ProgressBar::new(files as u64);
            bar.set_style(
                indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} files  {msg}  {elapsed}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        BatchProgress {
            bar,
            lines: progress && !terminal,
            files,
        }
    }

    /// How long to wait for a file before showing the progress again.
    fn tick(&self) -> Duration {
        if self.bar.is_some() {
            Duration::from_millis(250)
        } else {
            Duration::from_secs(10)
        }
    }

    /// Shows file `name` done (`finished` so far).
    fn file_done(&self, finished: usize, name: &str, d: &Done, samples: &AtomicU64, started: Instant) {
        let what = match &d.result {
            Ok(s) => format!("{} samples in {:.1} s", s.samples, d.wall_s),
            Err(e) => format!("FAILED: {e}"),
        };
        if let Some(bar) = &self.bar {
            if d.result.is_err() {
                bar.suspend(|| eprintln!("{name}: {what}"));
            }
            bar.set_position(finished as u64);
            bar.set_message(rate(samples, started));
        } else if self.lines {
            eprintln!(
                "[{finished}/{}] {name}: {what} | {}",
                self.files,
                rate(samples, started)
            );
        }
    }

    /// Shows the progress while no file ended.
    fn waiting(&self, finished: usize, samples: &AtomicU64, started: Instant) {
        if let Some(bar) = &self.bar {
            bar.set_message(rate(samples, started));
        } else if self.lines {
            eprintln!("[{finished}/{}] ... | {}", self.files, rate(samples, started));
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn rate(samples: &AtomicU64, started: Instant) -> String {
    let n = samples.load(Ordering::Relaxed);
    format!(
        "batch: {n} samples, {:.0} samples/s",
        n as f64 / started.elapsed().as_secs_f64().max(1e-9)
    )
}

/// The leak kinds raised by the leak-size detector (`ext1, int`; `leak` for
/// one whose kind was not named yet) and its first alarm (the earliest raised
/// leak event: its kind, size in L/min and time in s).
pub fn leaks_raised(s: &Summary) -> (Vec<&'static str>, Option<&LeakEvent>) {
    let mut kinds: Vec<&'static str> = Vec::new();
    let mut first: Option<&LeakEvent> = None;
    for e in s.event_log.iter().filter(|e| {
        e.phase == Phase::Raised
            && e.detector == "leak-size"
            && (EventKind::LEAKS.contains(&e.kind) || e.kind == EventKind::Leak)
    }) {
        if !kinds.contains(&e.kind.name()) {
            kinds.push(e.kind.name());
        }
        if first.is_none_or(|f| e.t_detect_s < f.t_detect_s) {
            first = Some(e);
        }
    }
    (kinds, first)
}

/// The first alarm's table cell: `ext1 0.312 L/min at 10.512 s` (`leak` while
/// its kind is pending); `–` without one.
fn first_alarm_cell(first: Option<&LeakEvent>) -> String {
    first.map_or("–".into(), |e| {
        format!(
            "{} {:.3} L/min at {:.3} s",
            e.kind.name(),
            e.size_lpm,
            e.t_detect_s
        )
    })
}

/// One table cell: no `|` nor line break.
fn cell(text: &str) -> String {
    text.replace('|', "/").replace(['\n', '\r'], " ")
}

/// What the files replayed without error add up to: read, found and written.
#[derive(Debug, Default)]
struct Totals {
    /// Input bytes.
    input_bytes: u64,
    /// Samples processed and rows skipped.
    samples: u64,
    rows_skipped: u64,
    /// Events raised (distinct, any kind).
    events_raised: usize,
    /// Estimates rows and bytes written, and their formats.
    estimates_rows: u64,
    estimates_bytes: u64,
    formats: Vec<String>,
}

impl Totals {
    /// Adds the replay `s` of `job`, whose outputs are in `dir`.
    fn add(&mut self, job: &Job, s: &Summary, dir: &Path) {
        self.input_bytes += job.bytes;
        self.samples += s.samples;
        self.rows_skipped += s.rows_skipped;
        self.estimates_rows += s.estimates.rows;
        if let Some(file) = &s.estimates.file {
            self.estimates_bytes += std::fs::metadata(dir.join(file)).map_or(0, |m| m.len());
        }
        if !self.formats.contains(&s.estimates.format) {
            self.formats.push(s.estimates.format.clone());
        }
    }

    /// The totals' line for `files` files.
    fn line(&self, files: usize) -> String {
        let mib = |b: u64| b as f64 / f64::from(1 << 20);
        format!(
            "totals of {files} files: {:.1} MiB read, {} samples, {} rows skipped, {} events raised; \
             estimates ({}): {} rows, {:.1} MiB",
            mib(self.input_bytes),
            self.samples,
            self.rows_skipped,
            self.events_raised,
            if self.formats.is_empty() {
                "none".to_string()
            } else {
                self.formats.join(", ")
            },
            self.estimates_rows,
            mib(self.estimates_bytes)
        )
    }
}

/// `leakwatch replay DIR|FILE...`: the batch, its progress on stderr, its table
/// on stdout (per file: samples, events raised (distinct events of any kind),
/// the leak kinds the leak-size detector raised, its first alarm's kind, size
/// and sample time, the seconds watched of the run, the error); an error (a non-zero
/// exit) if any file failed.
pub fn run(
    inputs: &[PathBuf],
    out: &Path,
    settings: &Settings,
    threads: Option<usize>,
) -> Result<(), String> {
    let jobs = jobs(inputs, out)?;
    let threads = threads_for(threads, jobs.len())?;
    crate::out::dir(out)?;
    eprintln!(
        "replaying {} files on {threads} threads into {}",
        jobs.len(),
        out.display()
    );
    let b = replay_all(&jobs, out, settings, threads, true);
    outln!("| file | samples | events raised | leaks raised | first alarm | watched s | error |");
    outln!("|---|---|---|---|---|---|---|");
    let mut failed = 0usize;
    let mut totals = Totals::default();
    for (job, d) in jobs.iter().zip(&b.done) {
        match &d.result {
            Ok(s) => {
                totals.add(job, s, &out.join(&job.name));
                // events, not reports: a leak raised first with its kind pending
                // and again, same id, with its kind is one event
                let mut raised: Vec<(&str, u64)> = s
                    .event_log
                    .iter()
                    .filter(|e| e.phase == Phase::Raised)
                    .map(|e| (e.detector.as_str(), e.event_id))
                    .collect();
                raised.sort_unstable();
                raised.dedup();
                let raised = raised.len();
                totals.events_raised += raised;
                let (kinds, first) = leaks_raised(s);
                let watched = match s.watch.armed_at_s {
                    Some(_) => format!("{:.1} of {:.1}", s.watch.watched_s, s.watch.run_s),
                    None => {
                        crate::status::set_not_watched();
                        "NOT WATCHED (never armed)".into()
                    }
                };
                outln!(
                    "| {} | {} | {raised} | {} | {} | {watched} | |",
                    cell(&job.name),
                    s.samples,
                    if kinds.is_empty() {
                        "none".into()
                    } else {
                        kinds.join(", ")
                    },
                    first_alarm_cell(first),
                )
            }
            Err(e) => {
                failed += 1;
                outln!("| {} | – | – | – | – | – | {} |", cell(&job.name), cell(e))
            }
        }
    }
    eprintln!(
        "replayed {} files ({failed} failed) in {:.1} s on {} threads: {} samples, {:.0} samples/s; wrote {}",
        jobs.len(),
        b.wall_s,
        b.threads,
        b.samples,
        b.samples as f64 / b.wall_s.max(1e-9),
        out.display()
    );
    eprintln!("{}", totals.line(jobs.len() - failed));
    if failed > 0 {
        return Err(format!("{failed} of {} files failed (see the table)", jobs.len()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replayable_names_lose_their_extension() {
        assert_eq!(stem("measured.csv.gz"), Some("measured"));
        assert_eq!(stem("RUN.CSV"), Some("RUN"));
        assert_eq!(stem("a.b.mcap"), Some("a.b"));
        assert_eq!(stem("truth.json"), None);
        assert_eq!(stem(".hidden.csv"), None);
        assert_eq!(stem(".csv"), None);
    }
}
