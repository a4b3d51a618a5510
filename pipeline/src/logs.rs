//! The recorded-log commands: `export` (a log as CSVs, also what `replay`,
//! `calibrate` and `plot` read a log through), `repair` and `info`.
//!
//! A run whose recorder was restarted has its log in parts: `run.mcap`, then
//! `run-1.mcap`, `run-2.mcap`, ... beside it. `export`, `replay`, `calibrate`,
//! `plot` and `info` given the first part read them all as one log
//! ([`log_parts`]); given a later part, that part alone (with its
//! continuations: a recorder continues its file after an hour in
//! `run.1.mcap`, `run.2.mcap`, ..., see `recorder::parts`).

use std::path::{Path, PathBuf};

use crate::replay;

/// `leakwatch export`: writes the log's CSVs into `csv` and names them.
pub fn export(log: &Path, csv: &Path, force: bool) -> Result<(), String> {
    let (files, _) = export_log(log, csv, force, false)?;
    for f in files {
        eprintln!("wrote {}", f.display());
    }
    Ok(())
}

/// `leakwatch repair`: writes every intact message of `log` into `out` and says what was lost.
pub fn repair(log: &Path, out: &Path, force: bool) -> Result<(), String> {
    let r = recorder::repair(log, out, force).map_err(|e| e.to_string())?;
    if let Some(why) = &r.truncated {
        eprintln!("{}: ends early ({why}); kept everything before", log.display());
    }
    for c in &r.chunks_skipped {
        eprintln!("{}: damaged {c}; skipped", log.display());
    }
    if r.messages_without_channel > 0 {
        eprintln!(
            "{}: {} messages dropped: their channel record was lost",
            log.display(),
            r.messages_without_channel
        );
    }
    let total: u64 = r.messages.values().sum();
    let per: Vec<String> = r.messages.iter().map(|(t, n)| format!("{t} {n}")).collect();
    eprintln!(
        "wrote {} ({} bytes): {total} messages ({})",
        out.display(),
        r.bytes,
        per.join(", ")
    );
    Ok(())
}

/// The file name of part `n` of the log whose first part is `<stem>.mcap`:
/// `<stem>.mcap` for 0, then `<stem>-1.mcap`, `<stem>-2.mcap`, ... (what a
/// restarted recorder writes, and what [`log_parts`] looks for).
pub fn part_name(stem: &str, n: u32) -> String {
    if n == 0 {
        format!("{stem}.mcap")
    } else {
        format!("{stem}-{n}.mcap")
    }
}

/// The parts of the run's log that `first` starts: `first`, then the
/// `<stem>-1.mcap`, `<stem>-2.mcap`, ... beside it that restarted recorders
/// wrote, as many as follow one another without a missing number; each
/// followed by the continuations its recorder wrote after an hour
/// (`<stem>.1.mcap`, ..., [`recorder::with_continuations`]).
pub fn log_parts(first: &Path) -> Vec<PathBuf> {
    let mut parts = recorder::with_continuations(first);
    let (Some(stem), Some("mcap")) = (
        first.file_stem().and_then(|s| s.to_str()),
        first.extension().and_then(|e| e.to_str()),
    ) else {
        return parts;
    };
    for n in 1.. {
        let p = first.with_file_name(part_name(stem, n));
        if !p.is_file() {
            break;
        }
        parts.extend(recorder::with_continuations(&p));
    }
    parts
}

/// Reads the run's log that `log` starts, every part of it ([`log_parts`]) in
/// order, as one; returns it, the parts and their total size in bytes. A part
/// that cannot be read is an error naming it.
pub fn read_log(log: &Path) -> Result<(recorder::Log, Vec<PathBuf>, u64), String> {
    read_log_with(log, false)
}

/// [`read_log`] with every part read for its sensor frames only
/// ([`recorder::LogReader::read_frames`]).
fn read_log_with(log: &Path, frames_only: bool) -> Result<(recorder::Log, Vec<PathBuf>, u64), String> {
    let parts = log_parts(log);
    let mut whole: Option<recorder::Log> = None;
    let mut bytes = 0;
    for p in &parts {
        bytes += std::fs::metadata(p)
            .map_err(|e| format!("{}: {e}", p.display()))?
            .len();
        let l = recorder::LogReader::open(p)
            .and_then(|r| if frames_only { r.read_frames() } else { r.read() })
            .map_err(|e| format!("{}: {e}", p.display()))?;
        match whole.as_mut() {
            None => whole = Some(l),
            Some(w) => w.append(l, &p.display().to_string()),
        }
    }
    if parts.len() > 1 {
        let names: Vec<String> = parts.iter().map(|p| p.display().to_string()).collect();
        eprintln!("reading the log in {} parts: {}", parts.len(), names.join(", "));
    }
    Ok((whole.unwrap_or_default(), parts, bytes))
}

/// `leakwatch info`: prints what `log` holds ([`recorder::Info`]); with
/// `config_out`, writes the configuration stored in it there (`-`: standard output).
pub fn info(log: &Path, config_out: Option<&Path>, force: bool) -> Result<(), String> {
    let (l, parts, bytes) = read_log(log)?;
    let mut info = recorder::Info::from_log(log, bytes, &l);
    info.later_parts = parts.into_iter().skip(1).collect();
    match config_out {
        Some(out) => {
            let toml = info.config_toml.as_deref().ok_or_else(|| {
                format!(
                    "{}: the log holds no configuration (logs of `leakwatch run` from this version on do)",
                    log.display()
                )
            })?;
            if out == Path::new("-") {
                crate::out::stdout(toml)
            } else {
                crate::out::write(out, toml.as_bytes(), force, &[log])?;
                eprintln!("wrote {}", out.display());
                Ok(())
            }
        }
        None => crate::out::stdout(&info.render()),
    }
}

/// Writes every channel of a recorded log as CSV into `dir` (plus dataset.csv);
/// returns the files and what reading the log skipped (damaged chunks).
/// Exports the log `log` as CSVs into `dir`; with `need_frames`, a log without a
/// readable sensor frame is an error naming the log (what replay and calibrate read),
/// and any log without a single readable message is one.
pub fn export_log(
    log: &std::path::Path,
    dir: &std::path::Path,
    force: bool,
    need_frames: bool,
) -> Result<(Vec<PathBuf>, replay::LogDamage), String> {
    let (l, _, _) = read_log(log)?;
    let damage = check_log(&l, log, need_frames)?;
    let files = recorder::export_csv(&l, dir, force).map_err(|e| e.to_string())?;
    Ok((files, damage))
}

/// The samples of the sensor frames of the log `log` (every part, [`log_parts`]), read for a
/// replay (the other channels not decoded), and what reading skipped; a log
/// without a readable frame is an error naming it; a truncated or damaged one
/// is warned about on stderr.
pub fn log_samples(
    log: &Path,
) -> Result<(impl Iterator<Item = model::Sample> + Send, replay::LogDamage), String> {
    let (l, _, _) = read_log_with(log, true)?;
    let damage = check_log(&l, log, true)?;
    Ok((l.frames.into_iter().map(|f| model::Sample::from(&f)), damage))
}

/// What reading `l` (from `log`) skipped, with a warning on stderr for each
/// damage; an error if it holds no message (or no sensor frame, with
/// `need_frames`).
fn check_log(l: &recorder::Log, log: &Path, need_frames: bool) -> Result<replay::LogDamage, String> {
    let messages = l.frames.len() + l.estimates.len() + l.events.len() + l.health.len() + l.stats.len();
    if messages == 0 || need_frames && l.frames.is_empty() {
        let why = match (&l.truncated, l.chunks_skipped.first()) {
            (_, Some(c)) => format!(" ({} damaged chunks skipped; first: {c})", l.chunks_skipped.len()),
            (Some(t), None) => format!(" ({t})"),
            (None, None) => String::new(),
        };
        return Err(format!(
            "{}: no {} could be read from the log{why}",
            log.display(),
            if messages == 0 { "message" } else { "sensor frame" }
        ));
    }
    if let Some(why) = &l.truncated {
        eprintln!("warning: {}: {why}; reading what is complete", log.display());
    }
    for c in &l.chunks_skipped {
        eprintln!("warning: {}: damaged {c}; skipped", log.display());
    }
    if !l.chunks_skipped.is_empty() {
        eprintln!(
            "warning: {}: {} damaged chunks skipped, {} samples lost with them",
            log.display(),
            l.chunks_skipped.len(),
            l.frames_lost
        );
    }
    Ok(replay::LogDamage {
        chunks_skipped: l.chunks_skipped.clone(),
        frames_lost: l.frames_lost,
    })
}

#[cfg(test)]
mod tests {
    use super::log_parts;

    #[test]
    fn the_parts_of_a_log_follow_one_another_without_a_hole() {
        let d = scratch::ScratchDir::new("parts");
        for name in [
            "run.mcap",
            "run.1.mcap",
            "run.2.mcap",
            "run-1.mcap",
            "run-2.mcap",
            "run-2.1.mcap",
            "run-2.3.mcap",
            "run-4.mcap",
            "other-1.mcap",
        ] {
            std::fs::write(d.join(name), b"").unwrap();
        }
        let names = |first: &str| -> Vec<String> {
            log_parts(&d.join(first))
                .iter()
                .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
                .collect()
        };
        // each part followed by its recorder's continuations (run.1.mcap, ...)
        assert_eq!(
            names("run.mcap"),
            [
                "run.mcap",
                "run.1.mcap",
                "run.2.mcap",
                "run-1.mcap",
                "run-2.mcap",
                "run-2.1.mcap"
            ]
        );
        assert_eq!(names("run-1.mcap"), ["run-1.mcap"], "a later part alone");
        assert_eq!(names("run-2.mcap"), ["run-2.mcap", "run-2.1.mcap"]);
        assert_eq!(names("other.mcap"), ["other.mcap", "other-1.mcap"]);
        assert_eq!(names("data.csv"), ["data.csv"]);
    }
}
