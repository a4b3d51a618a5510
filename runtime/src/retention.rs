//! What a service keeps of its runs: `run --runs-dir DIR` puts each run in
//! a new `DIR/leakwatch-run-YYYYMMDD-HHMMSS` folder and, at its start and
//! every 10 minutes, removes the oldest earlier run folders until those left
//! are younger than `--keep-days` and, with the current run, within
//! `--keep-gib`. Only folders named as runs are touched; the current run's
//! folder never is.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// The prefix of every run folder's name.
pub const RUN_FOLDER_PREFIX: &str = "leakwatch-run-";

/// How often a running service prunes, s.
pub const PRUNE_EVERY_S: u64 = 600;

/// What to keep of the earlier runs in a runs directory.
#[derive(Debug, Clone, PartialEq)]
pub struct Retention {
    /// The directory holding the run folders.
    pub dir: PathBuf,
    /// Runs whose newest file is older than this are removed (`--keep-days`).
    pub max_age: Option<Duration>,
    /// The run folders' total size is kept within this, bytes (`--keep-gib`).
    pub max_bytes: Option<u64>,
}

/// One earlier run folder: its path, its size in bytes and when it was last written.
#[derive(Debug)]
struct RunFolder {
    /// The folder.
    path: PathBuf,
    /// The size of its files, bytes.
    bytes: u64,
    /// Its newest file's modification time.
    modified: SystemTime,
}

impl Retention {
    /// The run folders removed (oldest first) so that what is left of `dir`'s
    /// runs, `current` included, keeps the age and size limits. A folder
    /// that cannot be removed is said in the error after the others are tried.
    pub fn prune(&self, current: &Path, now: SystemTime) -> Result<Vec<PathBuf>, String> {
        let mut runs = self.earlier_runs(current)?;
        runs.sort_by_key(|r| r.modified);
        let mut total: u64 = runs.iter().map(|r| r.bytes).sum::<u64>() + folder_size(current).0;
        let mut removed = Vec::new();
        let mut failed = Vec::new();
        for run in runs {
            let too_old = self
                .max_age
                .is_some_and(|a| now.duration_since(run.modified).is_ok_and(|age| age > a));
            let too_big = self.max_bytes.is_some_and(|b| total > b);
            if !(too_old || too_big) {
                continue;
            }
            match std::fs::remove_dir_all(&run.path) {
                Ok(()) => {
                    total = total.saturating_sub(run.bytes);
                    removed.push(run.path);
                }
                Err(e) => failed.push(format!("{}: {e}", run.path.display())),
            }
        }
        if failed.is_empty() {
            Ok(removed)
        } else {
            Err(format!("could not remove old runs: {}", failed.join("; ")))
        }
    }

    /// The run folders in `dir` other than `current`.
    fn earlier_runs(&self, current: &Path) -> Result<Vec<RunFolder>, String> {
        let entries =
            std::fs::read_dir(&self.dir).map_err(|e| format!("--runs-dir {}: {e}", self.dir.display()))?;
        let current = current.canonicalize().ok();
        let mut runs = Vec::new();
        for entry in entries.flatten() {
            let path = entry.path();
            let is_run = entry.file_name().to_string_lossy().starts_with(RUN_FOLDER_PREFIX)
                && entry.file_type().is_ok_and(|t| t.is_dir());
            if !is_run || path.canonicalize().ok() == current {
                continue;
            }
            let (bytes, modified) = folder_size(&path);
            runs.push(RunFolder {
                path,
                bytes,
                modified: modified.unwrap_or(SystemTime::UNIX_EPOCH),
            });
        }
        Ok(runs)
    }
}

/// The size of the files in `dir` and below, bytes, and the newest file's
/// modification time (symbolic links are not followed).
fn folder_size(dir: &Path) -> (u64, Option<SystemTime>) {
    let mut bytes = 0;
    let mut newest: Option<SystemTime> = None;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for entry in entries.flatten() {
            let Ok(meta) = std::fs::symlink_metadata(entry.path()) else {
                continue;
            };
            if meta.is_dir() {
                stack.push(entry.path());
            } else {
                bytes += meta.len();
                if let Ok(m) = meta.modified() {
                    newest = Some(newest.map_or(m, |n| n.max(m)));
                }
            }
        }
    }
    (bytes, newest)
}

/// `--keep-days` and `--keep-gib` checked: positive and finite.
pub fn limits(
    keep_days: Option<f64>,
    keep_gib: Option<f64>,
) -> Result<(Option<Duration>, Option<u64>), String> {
    let check = |flag: &str, v: f64| {
        if v.is_finite() && v > 0.0 && v <= 1e6 {
            Ok(v)
        } else {
            Err(format!("{flag} {v}: must be a positive number up to 1e6"))
        }
    };
    let age = keep_days
        .map(|d| check("--keep-days", d).map(|d| Duration::from_secs_f64(d * 86_400.0)))
        .transpose()?;
    let bytes = keep_gib
        .map(|g| check("--keep-gib", g).map(|g| (g * (1u64 << 30) as f64) as u64))
        .transpose()?;
    Ok((age, bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run folder `name` in `dir` with one file of `bytes` bytes written `age_days` ago.
    fn run_folder(dir: &Path, name: &str, bytes: usize, age_days: f64) -> PathBuf {
        let p = dir.join(name);
        std::fs::create_dir_all(&p).expect("mkdir");
        let f = p.join("run.mcap");
        std::fs::write(&f, vec![0u8; bytes]).expect("write");
        let t = SystemTime::now() - Duration::from_secs_f64(age_days * 86_400.0);
        let file = std::fs::File::options().write(true).open(&f).expect("open");
        file.set_modified(t).expect("set mtime");
        p
    }

    #[test]
    fn the_oldest_runs_go_first_until_age_and_size_hold_and_nothing_else_is_touched() {
        let scratch = scratch::ScratchDir::new("retention");
        let dir = scratch.path();
        let old = run_folder(dir, "leakwatch-run-20260101-000000", 1000, 40.0);
        let mid = run_folder(dir, "leakwatch-run-20261101-000000", 3000, 10.0);
        let new = run_folder(dir, "leakwatch-run-20261120-000000", 3000, 2.0);
        let cur = run_folder(dir, "leakwatch-run-20261128-000000", 3000, 0.0);
        let other = run_folder(dir, "my-notes", 100_000, 400.0);
        let keep = Retention {
            dir: dir.to_path_buf(),
            max_age: Some(Duration::from_secs(30 * 86_400)),
            max_bytes: Some(7000),
        };
        let removed = keep.prune(&cur, SystemTime::now()).expect("prune");
        // 40 days old: by age; then 3000 + 3000 + 3000 > 7000: the oldest left, by size
        assert_eq!(removed, vec![old.clone(), mid.clone()]);
        assert!(!old.exists() && !mid.exists());
        assert!(new.exists() && cur.exists() && other.exists());
        // within the limits now: nothing more goes
        assert!(keep.prune(&cur, SystemTime::now()).expect("prune").is_empty());
        // the current run is never removed, even alone over the limit
        let tight = Retention {
            max_bytes: Some(10),
            ..keep
        };
        assert_eq!(tight.prune(&cur, SystemTime::now()).expect("prune"), vec![new]);
        assert!(cur.exists());
    }

    #[test]
    fn limits_refuse_what_is_not_a_positive_number() {
        assert_eq!(limits(None, None), Ok((None, None)));
        assert_eq!(
            limits(Some(1.0), Some(0.5)),
            Ok((Some(Duration::from_secs(86_400)), Some(1 << 29)))
        );
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(limits(Some(bad), None).unwrap_err().contains("--keep-days"));
            assert!(limits(None, Some(bad)).unwrap_err().contains("--keep-gib"));
        }
    }
}
