//! Creating output files safely: the one place every leakwatch writer opens
//! a file or a directory for writing.
//!
//! - a symbolic link is never followed, for a file (`O_NOFOLLOW`) or for an
//!   output directory (its last component);
//! - an existing file is not replaced unless `overwrite` is set (`--force`);
//! - a file that is one of the command's inputs (same device and inode, so a
//!   hard link or another spelling of the path counts too) is never replaced,
//!   even with `--force`.
//!
//! Errors are `std::io::Error`s whose message says what was refused and why;
//! callers add the path.

use std::fs::{File, OpenOptions};
use std::io::{Error, ErrorKind, Write};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::Path;

/// `O_NOFOLLOW` (Linux): `open` fails with `ELOOP` on a symbolic link.
const O_NOFOLLOW: i32 = 0o400000;
/// `ELOOP`: what `open` with `O_NOFOLLOW` returns for a symbolic link.
const ELOOP: i32 = 40;

fn symlink_error() -> Error {
    Error::new(
        ErrorKind::InvalidInput,
        "is a symbolic link: refusing to write through it (give the real path)",
    )
}

fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    a.dev() == b.dev() && a.ino() == b.ino()
}

/// Fails if `meta` (an existing output) is the same file as one of `inputs`.
fn check_not_input(meta: &std::fs::Metadata, inputs: &[&Path]) -> std::io::Result<()> {
    for input in inputs {
        if let Ok(m) = std::fs::metadata(input) {
            if same_file(meta, &m) {
                return Err(Error::new(
                    ErrorKind::InvalidInput,
                    format!("is the input {}: refusing to overwrite it", input.display()),
                ));
            }
        }
    }
    Ok(())
}

/// Checks, without opening anything, that [`create_file`] may write `path`: it is
/// absent in an existing directory, or (with `overwrite`) an existing file that
/// is neither a symbolic link nor one of `inputs`.
pub fn check_replaceable(path: &Path, overwrite: bool, inputs: &[&Path]) -> std::io::Result<()> {
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if meta.file_type().is_symlink() {
            return Err(symlink_error());
        }
        check_not_input(&meta, inputs)?;
        if !overwrite {
            return Err(Error::new(
                ErrorKind::AlreadyExists,
                "exists: not overwritten (use --force to replace it)",
            ));
        }
        return Ok(());
    }
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => {
            let what = if dir.exists() {
                "is not a directory"
            } else {
                "does not exist"
            };
            Err(Error::new(
                ErrorKind::NotFound,
                format!("its folder {} {what} (create it first)", dir.display()),
            ))
        }
        _ => Ok(()),
    }
}

/// Opens `path` for writing, created or emptied, without following a symbolic
/// link; an existing file is refused unless `overwrite`, and one of `inputs`
/// always. With `overwrite`, an existing device or FIFO (e.g. /dev/null) is
/// opened as it is.
pub fn create_file(path: &Path, overwrite: bool, inputs: &[&Path]) -> std::io::Result<File> {
    check_replaceable(path, overwrite, inputs)?;
    let mut opts = OpenOptions::new();
    opts.write(true).custom_flags(O_NOFOLLOW);
    if overwrite {
        opts.create(true);
    } else {
        opts.create_new(true);
    }
    let file = opts.open(path).map_err(|e| {
        if e.raw_os_error() == Some(ELOOP) {
            symlink_error()
        } else {
            e
        }
    })?;
    // The file opened is the one checked: compare again, then empty it.
    let meta = file.metadata()?;
    check_not_input(&meta, inputs)?;
    if meta.is_file() {
        file.set_len(0)?;
    }
    Ok(file)
}

/// Writes `bytes` to `path` as [`create_file`] opens it.
pub fn write_file(path: &Path, bytes: &[u8], overwrite: bool, inputs: &[&Path]) -> std::io::Result<()> {
    let mut f = create_file(path, overwrite, inputs)?;
    f.write_all(bytes)?;
    f.flush()
}

/// Creates the output directory `dir` (and its parents); a `dir` that is a
/// symbolic link, or exists and is not a directory, is refused.
pub fn create_dir(dir: &Path) -> std::io::Result<()> {
    if let Ok(meta) = std::fs::symlink_metadata(dir) {
        if meta.file_type().is_symlink() {
            return Err(symlink_error());
        }
        if !meta.is_dir() {
            return Err(Error::new(
                ErrorKind::AlreadyExists,
                "exists and is not a directory",
            ));
        }
        return Ok(());
    }
    std::fs::create_dir_all(dir)?;
    match std::fs::symlink_metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(symlink_error()),
        Err(e) => Err(e),
    }
}

/// A message for a refused or failed output: `cannot write PATH: why`.
pub fn message(path: &Path, e: &Error) -> String {
    format!("cannot write {}: {e}", path.display())
}
