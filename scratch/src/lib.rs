//! Scratch folders for the tests.
//!
//! A [`ScratchDir`] is a fresh, empty folder under the system's temporary
//! directory. It is removed when it goes out of scope, unless the thread is
//! panicking: a failing test keeps its files, and the folder is named on
//! stderr. The end-to-end tests copy binaries and write logs of hundreds of
//! MB, so a test suite that left its folders behind would fill the disk of
//! the machine it runs on.

#![forbid(unsafe_code)]

use std::ffi::OsStr;
use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh folder, removed on drop unless a test is failing.
#[derive(Debug)]
pub struct ScratchDir {
    path: PathBuf,
}

impl ScratchDir {
    /// A fresh, empty folder named `leakwatch-{label}-{pid}-{n}` in the
    /// system's temporary directory (`n` counts the folders of this process,
    /// so tests running in parallel never share one).
    ///
    /// Panics if the folder cannot be made: this is test support.
    pub fn new(label: &str) -> ScratchDir {
        static MADE: AtomicUsize = AtomicUsize::new(0);
        let n = MADE.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("leakwatch-{label}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        if let Err(e) = std::fs::create_dir_all(&path) {
            panic!("cannot make the scratch folder {}: {e}", path.display());
        }
        ScratchDir { path }
    }

    /// The folder's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Deref for ScratchDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<OsStr> for ScratchDir {
    fn as_ref(&self) -> &OsStr {
        self.path.as_os_str()
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept the failed test's files in {}", self.path.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ScratchDir;

    #[test]
    fn a_scratch_folder_is_fresh_and_removed_on_drop() {
        let a = ScratchDir::new("scratch-test");
        let b = ScratchDir::new("scratch-test");
        assert_ne!(a.path(), b.path());
        assert!(a.is_dir() && std::fs::read_dir(&*a).unwrap().next().is_none());
        std::fs::create_dir_all(a.join("deep/er")).unwrap();
        std::fs::write(a.join("deep/er/file"), b"x").unwrap();
        let path = a.path().to_path_buf();
        drop(a);
        assert!(!path.exists(), "{} is still there", path.display());
    }

    #[test]
    fn a_failing_tests_folder_is_kept() {
        let path = std::thread::spawn(|| {
            let d = ScratchDir::new("scratch-kept");
            let path = d.path().to_path_buf();
            std::panic::set_hook(Box::new(|_| {}));
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || {
                let _d = d;
                panic!("the test fails");
            }));
            let _ = std::panic::take_hook();
            assert!(r.is_err());
            path
        })
        .join()
        .unwrap();
        assert!(path.is_dir(), "{} was removed", path.display());
        std::fs::remove_dir_all(&path).unwrap();
    }
}
