//! The exit status of a command that ran but could not do all it should:
//! `leakwatch run` or `replay` whose leak detector never armed exits with
//! [`NOT_WATCHED`], not 0, so a script cannot take "no leak detected" from a run
//! that saw nothing; a `run` that watched to the end while an output failed (the
//! log could not be written, events.json had to go elsewhere, the live view or
//! the gateway stopped for good) exits with [`OUTPUT_FAILED`].

use std::sync::atomic::{AtomicBool, Ordering};

/// Exit status of a run or replay whose leak detector never armed. It wins over
/// [`OUTPUT_FAILED`] when both hold (the summary names both).
pub const NOT_WATCHED: u8 = 3;

/// Exit status of a run that monitored to its end (its events printed and
/// written) while an output failed: the recorder could not write the log (a full
/// disk; the summary names the file and the reason), events.json or latency.json
/// were written elsewhere than the output directory, or the live view or the
/// gateway kept failing and was given up.
pub const OUTPUT_FAILED: u8 = 4;

static FLAG: AtomicBool = AtomicBool::new(false);
static OUTPUT: AtomicBool = AtomicBool::new(false);

/// Records that this command's detector never armed.
pub fn set_not_watched() {
    FLAG.store(true, Ordering::Relaxed);
}

/// Whether this command's detector never armed.
pub fn not_watched() -> bool {
    FLAG.load(Ordering::Relaxed)
}

/// Records that this run monitored to its end while an output failed.
pub fn set_output_failed() {
    OUTPUT.store(true, Ordering::Relaxed);
}

/// Whether an output of this run failed (see [`OUTPUT_FAILED`]).
pub fn output_failed() -> bool {
    OUTPUT.load(Ordering::Relaxed)
}
