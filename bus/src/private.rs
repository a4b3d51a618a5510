//! The per-user private directory of a run's lock files and iceoryx2 files:
//! only its user can write there, so another local user can neither hold a
//! run's lock nor plant files in its iceoryx2 root (docs/security.md).

use std::os::unix::fs::{DirBuilderExt, MetadataExt};
use std::path::{Path, PathBuf};

use crate::BusError;

/// The environment variable that names the private directory outright
/// (instead of `$XDG_RUNTIME_DIR/leakwatch` or `/tmp/leakwatch-<uid>`).
pub const RUNTIME_DIR_ENV: &str = "LEAKWATCH_RUNTIME_DIR";

/// This process's effective user id.
pub fn current_uid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// The private directory of this user's runs, created `0700` if it is missing
/// and checked: a real directory (not a symbolic link), owned by this user,
/// with no access for group or others. It is `$LEAKWATCH_RUNTIME_DIR` if set,
/// else `$XDG_RUNTIME_DIR/leakwatch` if `XDG_RUNTIME_DIR` is an absolute path
/// to a directory of this user that only it can enter, else
/// `/tmp/leakwatch-<uid>`. The error names the directory, what is wrong with
/// it and what to do.
pub fn private_dir() -> Result<PathBuf, BusError> {
    let dir = private_dir_path();
    ensure_private(&dir)?;
    Ok(dir)
}

/// Where [`private_dir`] is, without creating or checking it.
pub fn private_dir_path() -> PathBuf {
    let uid = current_uid();
    if let Some(d) = std::env::var_os(RUNTIME_DIR_ENV).filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    if let Some(x) = std::env::var_os("XDG_RUNTIME_DIR").filter(|d| !d.is_empty()) {
        let x = PathBuf::from(x);
        let usable = x.is_absolute()
            && std::fs::symlink_metadata(&x)
                .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.mode() & 0o077 == 0);
        if usable {
            return x.join("leakwatch");
        }
    }
    PathBuf::from(format!("/tmp/leakwatch-{uid}"))
}

/// Creates `dir` with mode `0700` if it is missing, then checks that it is a
/// directory (not a link) of this user that nobody else can enter.
pub fn ensure_private(dir: &Path) -> Result<(), BusError> {
    match std::fs::DirBuilder::new().mode(0o700).create(dir) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => {
            return Err(BusError(format!(
                "cannot create leakwatch's private directory {}: {e} (set {RUNTIME_DIR_ENV} to a directory \
                 only you can write)",
                dir.display()
            )))
        }
    }
    let meta = std::fs::symlink_metadata(dir).map_err(|e| {
        BusError(format!(
            "cannot read leakwatch's private directory {}: {e}",
            dir.display()
        ))
    })?;
    let uid = current_uid();
    let mode = meta.mode() & 0o7777;
    let problem = if meta.file_type().is_symlink() {
        Some("is a symbolic link".to_string())
    } else if !meta.is_dir() {
        Some("is not a directory".to_string())
    } else if meta.uid() != uid {
        Some(format!("belongs to another user (uid {}, not {uid})", meta.uid()))
    } else if mode & 0o077 != 0 {
        Some(format!("is open to other users (mode {mode:o}, not 700)"))
    } else {
        None
    };
    match problem {
        None => Ok(()),
        Some(p) => Err(BusError(format!(
            "leakwatch's private directory {} {p}: a run keeps its lock and iceoryx2 files there and needs a \
             directory only its user can write; remove it if it is yours and left over (a new one is made \
             0700), have its owner remove it, or set {RUNTIME_DIR_ENV} to a directory of yours with mode 700; \
             see docs/security.md",
            dir.display()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn a_missing_directory_is_made_0700_and_an_open_or_linked_one_is_refused() {
        let base = std::env::temp_dir().join(format!("lw-private-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        std::fs::create_dir_all(&base).unwrap();
        let made = base.join("made");
        ensure_private(&made).expect("made");
        let m = std::fs::symlink_metadata(&made).unwrap();
        assert_eq!(m.mode() & 0o7777, 0o700);
        ensure_private(&made).expect("an existing private one is fine");

        let open = base.join("open");
        std::fs::create_dir(&open).unwrap();
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o755)).unwrap();
        let e = ensure_private(&open).expect_err("group/other access").0;
        assert!(
            e.contains(&format!(
                "{} is open to other users (mode 755, not 700)",
                open.display()
            )),
            "{e}"
        );
        assert!(e.contains(RUNTIME_DIR_ENV), "{e}");

        let link = base.join("link");
        std::os::unix::fs::symlink(&made, &link).unwrap();
        let e = ensure_private(&link).expect_err("a link").0;
        assert!(e.contains("is a symbolic link"), "{e}");

        let file = base.join("file");
        std::fs::write(&file, "").unwrap();
        let e = ensure_private(&file).expect_err("a file").0;
        assert!(e.contains("is not a directory"), "{e}");

        if current_uid() == 0 {
            // root can make a directory of another user: it is refused, naming the owner
            let theirs = base.join("theirs");
            std::fs::DirBuilder::new().mode(0o700).create(&theirs).unwrap();
            std::os::unix::fs::chown(&theirs, Some(4242), None).unwrap();
            let e = ensure_private(&theirs).expect_err("another user's").0;
            assert!(e.contains("belongs to another user (uid 4242, not 0)"), "{e}");
        }
        std::fs::remove_dir_all(&base).unwrap();
    }
}
