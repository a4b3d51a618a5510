//! The files of one recorder's log. A recorder closes its file and continues
//! in a new one after [`crate::WriterOptions::part_span_ns`] of the stream
//! (an hour by default), so that the MCAP writer's summary (a chunk index per
//! chunk, held in memory until the file is closed) stays bounded over a day:
//! `run.mcap`, then `run.1.mcap`, `run.2.mcap`, ... (and a restarted
//! recorder's `run-1.mcap`, then `run-1.1.mcap`, ...: the restart parts are
//! numbered with `-N`, the continuations with `.k`, so they never collide).
//! The readers join them as one log, in this order.

use std::path::{Path, PathBuf};

/// The `k`-th continuation (k ≥ 1) of the log file `path`: `<stem>.<k>.mcap`
/// for `<stem>.mcap`, else `<name>.<k>`.
pub fn rotated_part(path: &Path, k: u32) -> PathBuf {
    let name = match (
        path.file_stem().and_then(|s| s.to_str()),
        path.extension().and_then(|e| e.to_str()),
    ) {
        (Some(stem), Some("mcap")) => format!("{stem}.{k}.mcap"),
        _ => format!(
            "{}.{k}",
            path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default()
        ),
    };
    path.with_file_name(name)
}

/// The log file `path` and the continuations of it that exist
/// ([`rotated_part`] 1, 2, ... as long as they follow one another), in order.
pub fn with_continuations(path: &Path) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    for k in 1.. {
        let next = rotated_part(path, k);
        if !next.is_file() {
            break;
        }
        files.push(next);
    }
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn continuations_are_numbered_after_the_stem_and_never_name_a_restart_part() {
        let p = |s: &str| PathBuf::from(s);
        assert_eq!(rotated_part(&p("out/run.mcap"), 1), p("out/run.1.mcap"));
        assert_eq!(rotated_part(&p("out/run-2.mcap"), 3), p("out/run-2.3.mcap"));
        assert_eq!(rotated_part(&p("log"), 2), p("log.2"));
        // a restart part is `<stem>-N.mcap`: no continuation is named so
        assert!(!rotated_part(&p("run.mcap"), 1).to_string_lossy().contains('-'));
    }
}
