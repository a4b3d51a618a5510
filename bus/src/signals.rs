//! SIGINT/SIGTERM as a stop flag. The bus creates its iceoryx2 nodes with
//! signal handling disabled, so these handlers are the only ones: a signal
//! sets the flag (and interrupts a blocking wait), every loop checks it and
//! ends cleanly.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Once;

static STOP: AtomicBool = AtomicBool::new(false);
static INSTALL: Once = Once::new();

extern "C" fn on_signal(_sig: libc::c_int) {
    STOP.store(true, Ordering::SeqCst);
}

/// Installs SIGINT and SIGTERM handlers (once per process) and returns the
/// flag they set. Pass it as the `stop` argument of the bus's loops.
pub fn stop_on_signals() -> &'static AtomicBool {
    INSTALL.call_once(|| {
        for sig in [libc::SIGINT, libc::SIGTERM] {
            // SAFETY: a zeroed sigaction with a plain handler that only stores to an
            // atomic (async-signal-safe); no SA_RESTART so blocking waits return EINTR.
            unsafe {
                let mut sa: libc::sigaction = std::mem::zeroed();
                sa.sa_sigaction = on_signal as *const () as libc::sighandler_t;
                libc::sigemptyset(&mut sa.sa_mask);
                sa.sa_flags = 0;
                libc::sigaction(sig, &sa, std::ptr::null_mut());
            }
        }
    });
    &STOP
}
