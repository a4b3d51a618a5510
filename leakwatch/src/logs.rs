//! The recorded-log commands: `export` (a log as CSVs, also what `replay`,
//! `calibrate` and `plot` read a log through), `repair` and `info`.

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

/// `leakwatch info`: prints what `log` holds ([`recorder::Info`]); with
/// `config_out`, writes the configuration stored in it there (`-`: standard output).
pub fn info(log: &Path, config_out: Option<&Path>, force: bool) -> Result<(), String> {
    let bytes = std::fs::metadata(log)
        .map_err(|e| format!("{}: {e}", log.display()))?
        .len();
    let l = recorder::LogReader::open(log)
        .and_then(|r| r.read())
        .map_err(|e| format!("{}: {e}", log.display()))?;
    let info = recorder::Info::from_log(log, bytes, &l);
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
    let l = recorder::LogReader::open(log)
        .and_then(|r| r.read())
        .map_err(|e| format!("{}: {e}", log.display()))?;
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
    let files = recorder::export_csv(&l, dir, force).map_err(|e| e.to_string())?;
    let damage = replay::LogDamage {
        chunks_skipped: l.chunks_skipped,
        frames_lost: l.frames_lost,
    };
    Ok((files, damage))
}
