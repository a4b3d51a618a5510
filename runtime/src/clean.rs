//! What a run does when its own outputs or an earlier run's leftovers are in
//! the way: the iceoryx2 files a killed run left on its prefix (removed at the
//! next start on that prefix, or by `leakwatch clean`), a recorder that cannot
//! write its log (its file and reason found for the summary), and an output
//! file that cannot be written into the output directory (written to the
//! temporary directory instead).

use std::path::{Path, PathBuf};

use bus::{BusConfig, Leftover};

use bus::say as errln;
use pipeline::out::outln;

/// Bytes as MB with one decimal (10^6 bytes).
fn mb(bytes: u64) -> f64 {
    bytes as f64 / 1e6
}

/// One line per file removed: path and size.
fn listing(removed: &[Leftover]) -> String {
    removed
        .iter()
        .map(|f| format!("  {} ({:.3} MB)", f.path.display(), mb(f.bytes)))
        .collect::<Vec<_>>()
        .join("\n")
}

/// At the start of a run that holds the prefix's lock: removes what a dead run
/// on the same prefix left (its iceoryx2 segments and directory) and says so on
/// stderr; leaves them, with a warning, while a process of the prefix still runs
/// (a stage started by hand).
pub(super) fn remove_at_start(cfg: &BusConfig) {
    let prefix = cfg.iox_prefix.as_deref().unwrap_or("");
    match cfg.remove_leftovers() {
        Ok(removed) if removed.is_empty() => {}
        Ok(removed) => errln!(
            "leakwatch run: removed what a dead run left on the iceoryx2 prefix {prefix:?} ({} files or directories, \
             {:.1} MB):\n{}",
            removed.len(),
            mb(removed.iter().map(|f| f.bytes).sum()),
            listing(&removed)
        ),
        Err(e) => errln!("leakwatch run: warning: {e}"),
    }
}

/// What a run's start makes on its prefix (its own services, the stages'
/// files), removed again when the start fails: dropped before
/// [`StartCleanup::started`], it removes the prefix's iceoryx2 files and says so
/// on stderr. Declared after the prefix's lock and before the bus, so that it
/// runs once the run's own services are closed and while the lock is held.
pub(super) struct StartCleanup {
    cfg: BusConfig,
    started: bool,
}

impl StartCleanup {
    /// Watches the start of a run on `cfg`'s prefix.
    pub(super) fn new(cfg: &BusConfig) -> StartCleanup {
        StartCleanup {
            cfg: cfg.clone(),
            started: false,
        }
    }

    /// Every stage started: what the start made stays for the run.
    pub(super) fn started(&mut self) {
        self.started = true;
    }
}

impl Drop for StartCleanup {
    fn drop(&mut self) {
        if self.started {
            return;
        }
        let prefix = self.cfg.iox_prefix.as_deref().unwrap_or("");
        match self.cfg.remove_leftovers() {
            Ok(removed) if removed.is_empty() => {}
            Ok(removed) => errln!(
                "leakwatch run: the start failed: removed what it had made on the iceoryx2 prefix {prefix:?} \
                 ({} files or directories, {:.1} MB)",
                removed.len(),
                mb(removed.iter().map(|f| f.bytes).sum())
            ),
            Err(e) => errln!(
                "leakwatch run: the start failed and its iceoryx2 files stay: {e} \
                 (`leakwatch clean --prefix {prefix}` removes them)"
            ),
        }
    }
}

/// `leakwatch clean --all`: what [`clean`] does, on every prefix that has
/// iceoryx2 files of leakwatch's naming, one line per prefix; a prefix a live
/// run holds is named and left, and does not make the command fail.
pub fn clean_all() -> Result<(), String> {
    let prefixes = bus::prefixes_with_files();
    if prefixes.is_empty() {
        outln!("leakwatch clean: no leakwatch iceoryx2 files on this machine");
        return Ok(());
    }
    let mut in_use = Vec::new();
    for p in &prefixes {
        match clean_prefix(p) {
            Ok(removed) => outln!(
                "  {p}: removed {} files or directories ({:.1} MB)",
                removed.len(),
                mb(removed.iter().map(|f| f.bytes).sum())
            ),
            Err(e) => {
                errln!("  {p}: left: {e}");
                in_use.push(p.as_str());
            }
        }
    }
    outln!(
        "leakwatch clean: {} of {} prefixes cleaned{}",
        prefixes.len() - in_use.len(),
        prefixes.len(),
        if in_use.is_empty() {
            String::new()
        } else {
            format!("; in use, left: {}", in_use.join(", "))
        }
    );
    Ok(())
}

/// Removes what a dead run left on `prefix` and its lock file: refused while
/// a run holds the prefix's lock or a process of it still runs.
fn clean_prefix(prefix: &str) -> Result<Vec<Leftover>, String> {
    let cfg = BusConfig {
        iox_prefix: Some(prefix.to_string()),
        ..BusConfig::default()
    };
    // a live run holds it: refused (naming the run), nothing touched
    let lock = cfg.lock_prefix().map_err(|e| format!("not cleaned: {e}"))?;
    let removed = cfg.remove_leftovers().map_err(|e| format!("not cleaned: {e}"))?;
    let lock_path = lock.path.clone();
    // the lock's file goes with the lock (a killed run left it)
    drop(lock);
    if lock_path.exists() {
        errln!(
            "leakwatch clean: warning: the lock file {} is still there",
            lock_path.display()
        );
    }
    Ok(removed)
}

/// `leakwatch clean [--prefix P]`: removes what a killed run left on prefix `P`
/// (default `LEAKWATCH_IOX_PREFIX`): its iceoryx2 files and its lock file.
/// Refused while a run holds the prefix's lock or a process of it still runs.
pub fn clean(prefix: Option<&str>) -> Result<(), String> {
    let prefix = match prefix {
        Some(p) => p.to_string(),
        None => match std::env::var(bus::PREFIX_ENV) {
            Ok(p) if !p.is_empty() => p,
            _ => {
                return Err(format!(
                    "which prefix? give --prefix P (a run's prefix is run<its process id>, or the {} it was \
                     started with)",
                    bus::PREFIX_ENV
                ))
            }
        },
    };
    let removed = clean_prefix(&prefix)?;
    if removed.is_empty() {
        outln!("leakwatch clean: nothing left on the iceoryx2 prefix {prefix:?}");
    } else {
        outln!(
            "leakwatch clean: removed {} files or directories of the iceoryx2 prefix {prefix:?} ({:.1} MB):\n{}",
            removed.len(),
            mb(removed.iter().map(|f| f.bytes).sum()),
            listing(&removed)
        );
    }
    Ok(())
}

/// Free bytes for an unprivileged user on the file system of `dir`.
fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    // SAFETY: statvfs reads the NUL-terminated path and fills the zeroed struct we own.
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statvfs(c.as_ptr(), &mut st) } != 0 {
        return None;
    }
    Some((st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
}

/// What a recorder that exited with [`recorder::shell::EXIT_LOG_UNWRITABLE`]
/// could not write, from its log `stage_log` (its line names the file and the
/// reason); if that line is not there (the stage's log is on the same full
/// disk), the log part `part` it was writing and the free space there.
pub(super) fn log_write_error(stage_log: &Path, part: &Path) -> String {
    let text = std::fs::read(stage_log).unwrap_or_default();
    let text = String::from_utf8_lossy(&text);
    let line = text
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix(recorder::shell::LOG_UNWRITABLE_LINE));
    match line {
        // " DIR/run.mcap: File too large (os error 27); stopping (...)"
        Some(rest) => format!(
            "the recorder cannot write the log{}",
            rest.split("; stopping").next().unwrap_or(rest)
        ),
        None => {
            let dir = part.parent().unwrap_or(Path::new("."));
            format!(
                "the recorder cannot write the log {} (its message did not reach {} either; the file system \
                 there has {})",
                part.display(),
                stage_log.display(),
                match free_bytes(dir) {
                    Some(b) => format!("{b} bytes free"),
                    None => "an unknown amount of free space".into(),
                }
            )
        }
    }
}

/// Where `name` goes when the output directory cannot take it: the temporary
/// directory, named after the rig and this process.
fn fallback_path(name: &str, rig: &str) -> PathBuf {
    std::env::temp_dir().join(format!("leakwatch-{rig}-{}-{name}", std::process::id()))
}

/// Writes the output `name` into `out_dir` with `write(path, force)`; if that
/// fails (a full disk), says so on stderr and writes it to the temporary
/// directory instead. Each failure is added to `failures`. Returns where it was
/// written, if anywhere.
pub(super) fn write_somewhere(
    out_dir: &Path,
    name: &str,
    rig: &str,
    failures: &mut Vec<String>,
    write: impl Fn(&Path, bool) -> Result<(), String>,
    force: bool,
) -> Option<PathBuf> {
    let path = out_dir.join(name);
    let existed = std::fs::symlink_metadata(&path).is_ok();
    let err = match write(&path, force) {
        Ok(()) => return Some(path),
        Err(e) => e,
    };
    if !existed {
        // the empty or cut file this attempt made is no output: not left to be read
        let _ = std::fs::remove_file(&path);
    }
    let alt = fallback_path(name, rig);
    match write(&alt, false) {
        Ok(()) => {
            errln!(
                "leakwatch run: error: {err}; {name} written to {} instead",
                alt.display()
            );
            failures.push(format!(
                "{name} could not be written ({err}); it is in {}",
                alt.display()
            ));
            Some(alt)
        }
        Err(e2) => {
            errln!("leakwatch run: error: {err}; nor to {}: {e2}", alt.display());
            failures.push(format!(
                "{name} could not be written ({err}), nor to {} ({e2})",
                alt.display()
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An output directory that cannot take the file (here: a path through a
    /// regular file) sends it to the temporary directory, and both failures are
    /// kept apart from each other.
    #[test]
    fn an_output_the_directory_cannot_take_goes_to_the_temporary_directory() {
        let d = scratch::ScratchDir::new("run-fallback");
        let blocker = d.join("not-a-dir");
        std::fs::write(&blocker, "x").unwrap();
        let mut failures = vec!["the recorder cannot write the log".to_string()];
        let rig = format!("fallback{}", std::process::id());
        let at = write_somewhere(
            &blocker,
            "events.json",
            &rig,
            &mut failures,
            |p, force| pipeline::out::write(p, b"[]\n", force, &[]),
            false,
        )
        .expect("written somewhere");
        assert_eq!(at, fallback_path("events.json", &rig));
        assert_eq!(std::fs::read_to_string(&at).unwrap(), "[]\n");
        std::fs::remove_file(&at).unwrap();
        assert_eq!(failures.len(), 2, "{failures:?}");
        assert_eq!(failures[0], "the recorder cannot write the log");
        assert!(
            failures[1].starts_with("events.json could not be written (")
                && failures[1].contains(&blocker.join("events.json").display().to_string())
                && failures[1].ends_with(&format!("it is in {}", at.display())),
            "{}",
            failures[1]
        );
    }

    /// A write that made the file and then failed (a disk that filled
    /// meanwhile) leaves no empty events.json behind; one that was there before
    /// (`--force`) is not removed.
    #[test]
    fn a_file_cut_by_a_failed_write_is_not_left_in_the_output_directory() {
        let d = scratch::ScratchDir::new("run-cut");
        let rig = format!("cut{}", std::process::id());
        let cut = |p: &Path, force: bool| {
            if p.starts_with(d.path()) {
                std::fs::write(p, "").map_err(|e| e.to_string())?;
                Err(format!(
                    "cannot write {}: No space left on device (os error 28)",
                    p.display()
                ))
            } else {
                pipeline::out::write(p, b"[]\n", force, &[])
            }
        };
        let mut failures = Vec::new();
        let at = write_somewhere(d.path(), "events.json", &rig, &mut failures, cut, false).unwrap();
        assert!(!d.join("events.json").exists());
        assert_eq!(std::fs::read_to_string(&at).unwrap(), "[]\n");
        std::fs::remove_file(&at).unwrap();
        std::fs::write(d.join("latency.json"), "{}").unwrap();
        let at = write_somewhere(d.path(), "latency.json", &rig, &mut failures, cut, true).unwrap();
        assert!(d.join("latency.json").exists());
        std::fs::remove_file(&at).unwrap();
        assert_eq!(failures.len(), 2, "{failures:?}");
    }

    #[test]
    fn the_recorders_line_gives_the_file_and_the_reason() {
        let d = scratch::ScratchDir::new("run-logerror");
        let log = d.join("recorder.log");
        std::fs::write(
            &log,
            "recorder: rig r -> /x/run.mcap\nrecorder: error: cannot write the log /x/run.mcap: File too large \
             (os error 27); stopping (a restart cannot help until the disk has room)\n",
        )
        .unwrap();
        assert_eq!(
            log_write_error(&log, Path::new("/x/run.mcap")),
            "the recorder cannot write the log /x/run.mcap: File too large (os error 27)"
        );
        // no line (the stage's log on the same full disk): the part and the free space
        let empty = d.join("empty.log");
        std::fs::write(&empty, "").unwrap();
        let part = d.join("run-1.mcap");
        let why = log_write_error(&empty, &part);
        assert!(
            why.starts_with(&format!("the recorder cannot write the log {} (", part.display()))
                && why.contains("bytes free)"),
            "{why}"
        );
    }
}
