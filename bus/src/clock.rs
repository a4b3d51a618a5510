//! Time on the host's `CLOCK_MONOTONIC`: reading it, sleeping until an
//! absolute instant, and the fixed-rate [`Pacer`] of the acquisition loop.

/// `CLOCK_MONOTONIC` now, ns.
#[inline]
pub fn monotonic_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec; CLOCK_MONOTONIC always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// Sleeps until `CLOCK_MONOTONIC` reaches `deadline_ns` (absolute; returns at
/// once if it is past). Interrupted sleeps resume unless `interruptible`, in
/// which case a signal ends the sleep early (the caller re-checks its stop flag).
pub fn sleep_until_ns(deadline_ns: u64, interruptible: bool) {
    let ts = libc::timespec {
        tv_sec: (deadline_ns / 1_000_000_000) as libc::time_t,
        tv_nsec: (deadline_ns % 1_000_000_000) as libc::c_long,
    };
    loop {
        // SAFETY: valid timespec, null remainder (unused with TIMER_ABSTIME).
        let rc = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                std::ptr::null_mut(),
            )
        };
        if rc != libc::EINTR || interruptible {
            return;
        }
    }
}

/// Sets the calling thread's timer slack, ns (`PR_SET_TIMERSLACK`; the Linux
/// default of 50 µs makes a 1 kHz sleep wake 80-100 µs late, 1 ns about 40 µs).
/// Returns false if the kernel refused.
pub fn set_timer_slack_ns(ns: u64) -> bool {
    // SAFETY: prctl with PR_SET_TIMERSLACK takes one unsigned long argument.
    unsafe { libc::prctl(libc::PR_SET_TIMERSLACK, ns as libc::c_ulong, 0, 0, 0) == 0 }
}

/// One tick of a [`Pacer`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// The scheduled instant, `CLOCK_MONOTONIC` ns.
    pub scheduled_ns: u64,
    /// The instant the pacer returned, ns.
    pub now_ns: u64,
    /// How late `now_ns` is against the schedule, ns (0 if on time or early).
    pub late_ns: u64,
    /// True if the tick is more than one period late (a deadline miss).
    pub missed: bool,
}

/// Fixed-rate pacing on absolute deadlines (`clock_nanosleep(TIMER_ABSTIME)`):
/// no drift, a late tick does not shift the following ones (the pacer catches
/// up, as a DAQ board with a FIFO would deliver late samples in a burst).
///
/// With `spin_ns > 0` the pacer sleeps until `spin_ns` before each deadline
/// and spins the rest of the way, trading a little CPU for less jitter.
#[derive(Debug, Clone)]
pub struct Pacer {
    period_ns: u64,
    spin_ns: u64,
    next_ns: Option<u64>,
}

impl Pacer {
    /// A pacer with period `period_ns` (0 = no pacing, every tick at once)
    /// and a spin finish of `spin_ns`. Sets the calling thread's timer slack
    /// to 1 ns: create it on the thread that will call [`Pacer::wait`].
    pub fn new(period_ns: u64, spin_ns: u64) -> Pacer {
        if period_ns > 0 {
            set_timer_slack_ns(1);
        }
        Pacer {
            period_ns,
            spin_ns,
            next_ns: None,
        }
    }

    /// The period, ns (0 = unpaced).
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// Waits for the next deadline (the first tick is immediate and anchors
    /// the schedule) and reports how late it returned.
    pub fn wait(&mut self) -> Tick {
        let now = monotonic_ns();
        let scheduled = *self.next_ns.get_or_insert(now);
        if self.period_ns == 0 {
            return Tick {
                scheduled_ns: now,
                now_ns: now,
                late_ns: 0,
                missed: false,
            };
        }
        if now < scheduled {
            let wake = scheduled.saturating_sub(self.spin_ns);
            if now < wake {
                sleep_until_ns(wake, false);
            }
            while monotonic_ns() < scheduled {
                std::hint::spin_loop();
            }
        }
        let now = monotonic_ns();
        let late = now.saturating_sub(scheduled);
        self.next_ns = Some(scheduled + self.period_ns);
        Tick {
            scheduled_ns: scheduled,
            now_ns: now,
            late_ns: late,
            missed: late > self.period_ns,
        }
    }
}
