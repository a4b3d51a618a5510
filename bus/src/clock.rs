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
    /// True if the tick is more than one period late, or deadlines were
    /// skipped before it (a deadline miss).
    pub missed: bool,
    /// Deadlines skipped just before this tick (see [`Pacer::skip_after`]):
    /// the samples due then are lost, so the caller drops as many. 0 normally.
    pub skipped: u64,
}

/// Fixed-rate pacing on absolute deadlines (`clock_nanosleep(TIMER_ABSTIME)`):
/// no drift, a late tick does not shift the following ones (the pacer catches
/// up, as a DAQ board with a FIFO would deliver late samples in a burst).
/// With [`Pacer::skip_after`], a pacer further behind than that (the process
/// was stopped or starved of CPU: a FIFO would have overflowed) skips the
/// missed deadlines instead and reports how many ([`Tick::skipped`]).
///
/// With `spin_ns > 0` the pacer sleeps until `spin_ns` before each deadline
/// and spins the rest of the way, trading a little CPU for less jitter.
#[derive(Debug, Clone)]
pub struct Pacer {
    period_ns: u64,
    spin_ns: u64,
    next_ns: Option<u64>,
    /// Lateness beyond which missed deadlines are skipped, ns (`None`: never).
    max_late_ns: Option<u64>,
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
            max_late_ns: None,
        }
    }

    /// Skips the missed deadlines when a tick is more than `max_late_ns` late:
    /// the tick moves to the latest deadline already past (so it is less than a
    /// period late) and [`Tick::skipped`] says how many deadlines were passed
    /// over. Lateness up to `max_late_ns` is still caught up in a burst (the
    /// depth of a DAQ's FIFO, in time). No effect on an unpaced pacer.
    pub fn skip_after(mut self, max_late_ns: u64) -> Pacer {
        self.max_late_ns = Some(max_late_ns);
        self
    }

    /// Continues the schedule of an earlier pacer whose last tick was at
    /// `last_tick_ns` (`CLOCK_MONOTONIC`, ns; e.g. a restarted process taking
    /// over a stream): the first deadline is `last_tick_ns` + one period
    /// instead of the first call. No effect on an unpaced pacer.
    pub fn resume_after(mut self, last_tick_ns: u64) -> Pacer {
        if self.period_ns > 0 {
            self.next_ns = Some(last_tick_ns.saturating_add(self.period_ns));
        }
        self
    }

    /// The period, ns (0 = unpaced).
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// Waits for the next deadline (the first tick is immediate and anchors
    /// the schedule, unless [`Pacer::resume_after`] set it) and reports how
    /// late it returned and how many deadlines it skipped.
    pub fn wait(&mut self) -> Tick {
        let now = monotonic_ns();
        let mut scheduled = *self.next_ns.get_or_insert(now);
        if self.period_ns == 0 {
            return Tick {
                scheduled_ns: now,
                now_ns: now,
                late_ns: 0,
                missed: false,
                skipped: 0,
            };
        }
        let mut skipped = 0;
        if let Some(max_late) = self.max_late_ns {
            let late = now.saturating_sub(scheduled);
            if late > max_late {
                skipped = late / self.period_ns;
                scheduled += skipped * self.period_ns;
            }
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
            missed: late > self.period_ns || skipped > 0,
            skipped,
        }
    }
}

/// The environment variable by which `leakwatch run` hands every stage one
/// [`epoch_offset_ns`] (decimal ns), so that the log, the live view and a
/// restarted stage put the same Unix time on the same message.
pub const EPOCH_OFFSET_ENV: &str = "LEAKWATCH_EPOCH_OFFSET_NS";

static EPOCH_OFFSET: std::sync::OnceLock<i64> = std::sync::OnceLock::new();

/// `CLOCK_REALTIME` now, ns since the Unix epoch (0 before 1970).
pub fn wall_clock_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
        .unwrap_or(0)
}

/// The wall clock minus `CLOCK_MONOTONIC`, ns, read now (the wall clock between
/// two monotonic readings, their midpoint taken).
pub fn measure_epoch_offset_ns() -> i64 {
    let m0 = monotonic_ns();
    let wall = wall_clock_ns();
    let m1 = monotonic_ns();
    let mono = m0 / 2 + m1 / 2 + (m0 % 2 + m1 % 2) / 2;
    (i128::from(wall) - i128::from(mono)).clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
}

/// Fixes this process's [`epoch_offset_ns`]: from [`EPOCH_OFFSET_ENV`] if it
/// is set (a stage of `leakwatch run`), else measured now. Call it once at
/// start; a value of the variable that is not a whole number of ns is an
/// error naming it. Later calls return the offset fixed first.
pub fn init_epoch_offset() -> Result<i64, crate::BusError> {
    if let Some(v) = EPOCH_OFFSET.get() {
        return Ok(*v);
    }
    let offset = match std::env::var(EPOCH_OFFSET_ENV) {
        Ok(s) => s.trim().parse::<i64>().map_err(|e| {
            crate::BusError(format!(
                "{EPOCH_OFFSET_ENV}={s:?}: expected the wall clock minus CLOCK_MONOTONIC in ns, a whole number ({e})"
            ))
        })?,
        Err(std::env::VarError::NotPresent) => measure_epoch_offset_ns(),
        Err(e) => return Err(crate::BusError(format!("{EPOCH_OFFSET_ENV}: {e}"))),
    };
    Ok(*EPOCH_OFFSET.get_or_init(|| offset))
}

/// The wall clock minus `CLOCK_MONOTONIC`, ns, fixed once per process (by
/// [`init_epoch_offset`], or measured at the first call): one monotonic clock
/// anchored once to the wall clock, so the times it gives never go back when
/// NTP steps the wall clock.
pub fn epoch_offset_ns() -> i64 {
    *EPOCH_OFFSET.get_or_init(measure_epoch_offset_ns)
}

/// A `CLOCK_MONOTONIC` stamp as Unix time, ns: `mono_ns` + `offset_ns`
/// (saturating at 0 and `u64::MAX`).
pub fn epoch_ns_with(mono_ns: u64, offset_ns: i64) -> u64 {
    mono_ns.saturating_add_signed(offset_ns)
}

/// A `CLOCK_MONOTONIC` stamp as Unix time, ns, with this process's [`epoch_offset_ns`].
pub fn epoch_ns(mono_ns: u64) -> u64 {
    epoch_ns_with(mono_ns, epoch_offset_ns())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    /// A pacer stalled for 30 ms skips the missed deadlines (at most 5 ms
    /// of them are caught up) and is on schedule right after.
    #[test]
    fn a_stalled_pacer_skips_the_missed_deadlines() {
        let mut p = Pacer::new(MS, 0).skip_after(5 * MS);
        let t0 = p.wait().scheduled_ns;
        p.wait();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let t = p.wait();
        assert!((28..=40).contains(&t.skipped), "{t:?}");
        assert!(t.missed && t.late_ns < MS, "{t:?}");
        assert_eq!(t.scheduled_ns, t0 + (2 + t.skipped) * MS);
        let next = p.wait();
        assert_eq!((next.skipped, next.scheduled_ns), (0, t.scheduled_ns + MS));
        // without skip_after the same stall is caught up tick by tick
        let mut q = Pacer::new(MS, 0);
        q.wait();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let t = q.wait();
        assert_eq!(t.skipped, 0);
        assert!(t.late_ns >= 29 * MS, "{t:?}");
    }

    /// A resumed pacer continues an earlier schedule: its first deadline is
    /// one period after the earlier last tick, and the time since is skipped.
    #[test]
    fn a_resumed_pacer_continues_the_schedule() {
        let last = monotonic_ns() - 50 * MS;
        let mut p = Pacer::new(MS, 0).skip_after(5 * MS).resume_after(last);
        let t = p.wait();
        assert!((48..=60).contains(&t.skipped), "{t:?}");
        assert_eq!(t.scheduled_ns, last + (1 + t.skipped) * MS);
        // unpaced: nothing to resume, nothing skipped
        let mut u = Pacer::new(0, 0).skip_after(0).resume_after(last);
        assert_eq!(u.wait().skipped, 0);
    }
}
