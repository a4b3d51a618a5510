//! CSV export of a log.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use model::Sample;

use crate::record::Record;
use crate::{GapRecord, Log, RecorderError};

fn create(path: &Path, overwrite: bool) -> Result<File, RecorderError> {
    dataset::output::create_file(path, overwrite, &[]).map_err(|e| RecorderError::Io(path.to_path_buf(), e))
}

fn write_channel<R: Record>(
    dir: &Path,
    name: &str,
    items: &[R],
    overwrite: bool,
) -> Result<PathBuf, RecorderError> {
    let path = dir.join(format!("{name}.csv"));
    let io = |e| RecorderError::Io(path.clone(), e);
    let mut w = BufWriter::new(create(&path, overwrite)?);
    writeln!(w, "{}", R::csv_header().join(",")).map_err(io)?;
    let mut line = String::with_capacity(1024);
    for item in items {
        line.clear();
        item.csv_row(&mut line);
        line.push('\n');
        w.write_all(line.as_bytes()).map_err(io)?;
    }
    w.flush().map_err(io)?;
    Ok(path)
}

fn write_gaps(dir: &Path, gaps: &[GapRecord], overwrite: bool) -> Result<PathBuf, RecorderError> {
    let path = dir.join("gaps.csv");
    let io = |e| RecorderError::Io(path.clone(), e);
    let mut w = BufWriter::new(create(&path, overwrite)?);
    writeln!(w, "topic,expected_seq,got_seq,missing,recv_mono_ns").map_err(io)?;
    for g in gaps {
        writeln!(
            w,
            "{},{},{},{},{}",
            g.topic, g.expected_seq, g.got_seq, g.missing, g.recv_mono_ns
        )
        .map_err(io)?;
    }
    w.flush().map_err(io)?;
    Ok(path)
}

/// Writes `frames.csv`, `estimates.csv`, `events.csv`, `health.csv`,
/// `stats.csv` and `gaps.csv` (every field; arrays as `name_0..name_N`;
/// floats in shortest round-trip form, NaN as `NaN`) into `dir` (created if
/// needed), and `dataset.csv`: the frames in the dataset format
/// `t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c` that `leakwatch replay` reads.
/// Returns the files written. The directory must not be a symbolic link; an
/// existing file in it is replaced only if `overwrite` (`--force`), and none is
/// touched if one would be refused.
pub fn export_csv(log: &Log, dir: &Path, overwrite: bool) -> Result<Vec<PathBuf>, RecorderError> {
    dataset::output::create_dir(dir).map_err(|e| RecorderError::Io(dir.to_path_buf(), e))?;
    for name in [
        "frames",
        "estimates",
        "events",
        "health",
        "stats",
        "gaps",
        "dataset",
    ] {
        let p = dir.join(format!("{name}.csv"));
        dataset::output::check_replaceable(&p, overwrite, &[])
            .map_err(|e| RecorderError::Io(p.clone(), e))?;
    }
    let mut out = vec![
        write_channel(dir, "frames", &log.frames, overwrite)?,
        write_channel(dir, "estimates", &log.estimates, overwrite)?,
        write_channel(dir, "events", &log.events, overwrite)?,
        write_channel(dir, "health", &log.health, overwrite)?,
        write_channel(dir, "stats", &log.stats, overwrite)?,
        write_gaps(dir, &log.gaps, overwrite)?,
    ];
    let path = dir.join("dataset.csv");
    let io = |e| RecorderError::Io(path.clone(), e);
    let mut w = BufWriter::new(create(&path, overwrite)?);
    dataset::write_header(&mut w).map_err(io)?;
    for f in &log.frames {
        let s = Sample::from(f);
        dataset::write_row(&mut w, &s).map_err(io)?;
    }
    w.flush().map_err(io)?;
    out.push(path);
    Ok(out)
}
