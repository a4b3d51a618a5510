//! Where a run writes: its folder (`--out`, or a new one in `--runs-dir`)
//! and the rosbag2 metadata beside its log.

use std::path::{Path, PathBuf};

use crate::args::RunArgs;
use crate::retention::{Retention, RUN_FOLDER_PREFIX};

/// The run's folder: `--out`, or a new one in `--runs-dir` (with what to keep
/// of the earlier runs there), or a new one here.
pub(crate) fn out_dir_of(args: &RunArgs) -> Result<(PathBuf, Option<Retention>), String> {
    let (max_age, max_bytes) = crate::retention::limits(args.keep_days, args.keep_gib)?;
    match (&args.out, &args.runs_dir) {
        (Some(_), Some(_)) => {
            Err("--out and --runs-dir: give one (--runs-dir makes a new folder in it per run)".into())
        }
        (_, None) if max_age.is_some() || max_bytes.is_some() => {
            Err("--keep-days and --keep-gib are for --runs-dir".into())
        }
        (Some(dir), None) => Ok((dir.clone(), None)),
        (None, None) => Ok((default_out_dir(Path::new("")), None)),
        (None, Some(runs)) => {
            pipeline::out::dir(runs)?;
            let keep = Retention {
                dir: runs.clone(),
                max_age,
                max_bytes,
            };
            Ok((default_out_dir(runs), Some(keep)))
        }
    }
}

/// Where a run without `--out` writes: `leakwatch-run-YYYYMMDD-HHMMSS` (its
/// UTC start time, as rosbag2 names a recording by its start), so a second run
/// never collides with the first; `-2`, `-3`, ... within one second.
fn default_out_dir(parent: &Path) -> PathBuf {
    let ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i128);
    // "YYYY-MM-DD hh:mm:ss.mmm UTC" -> "YYYYMMDD-hhmmss"
    let digits: String = recorder::info::utc(ns)
        .chars()
        .take(19)
        .filter(char::is_ascii_digit)
        .collect();
    let stamp = format!("{RUN_FOLDER_PREFIX}{}-{}", &digits[..8], &digits[8..]);
    let mut dir = parent.join(&stamp);
    let mut n = 2;
    while dir.exists() {
        dir = parent.join(format!("{stamp}-{n}"));
        n += 1;
    }
    dir
}

/// Writes the rosbag2 `metadata.yaml` beside the run's log, so that rosbag2
/// readers open the run's folder as a bag (`ros2 bag info DIR`, `rosbags`).
/// A log that cannot be read or a file that cannot be written is said on
/// stderr; the run's other outputs stand.
pub(crate) fn write_bag_metadata(out_dir: &Path, force: bool, inputs: &[&Path]) {
    let log = out_dir.join("run.mcap");
    if !log.is_file() {
        return;
    }
    let written = pipeline::logs::read_log(&log).and_then(|(l, parts, bytes)| {
        let mut info = recorder::Info::from_log(&log, bytes, &l);
        info.later_parts = parts.into_iter().skip(1).collect();
        let text = recorder::rosbag2::metadata_yaml(&info);
        pipeline::out::write(&out_dir.join("metadata.yaml"), text.as_bytes(), force, inputs)
    });
    if let Err(e) = written {
        eprintln!("leakwatch run: no rosbag2 metadata.yaml beside the log: {e}");
    }
}
