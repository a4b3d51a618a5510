//! The exit status of a command that ran but could not watch: `leakwatch run`
//! or `replay` whose leak detector never armed exits with [`NOT_WATCHED`], not
//! 0, so a script cannot take "no leak detected" from a run that saw nothing.

use std::sync::atomic::{AtomicBool, Ordering};

/// Exit status of a run or replay whose leak detector never armed.
pub const NOT_WATCHED: u8 = 3;

static FLAG: AtomicBool = AtomicBool::new(false);

/// Records that this command's detector never armed.
pub fn set_not_watched() {
    FLAG.store(true, Ordering::Relaxed);
}

/// Whether this command's detector never armed.
pub fn not_watched() -> bool {
    FLAG.load(Ordering::Relaxed)
}
