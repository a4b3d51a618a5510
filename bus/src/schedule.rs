//! The arrival schedule of a periodic stream, learned from arrivals, for
//! [`crate::WaitMode::LowLatency`]: sleep until shortly before the next frame
//! is due, poll for a short window, and fall back to the wake event if the
//! frame does not come.
//!
//! A frame with sequence number `s` arrives at `T(s) + delay`, where `T` is
//! the stream's schedule and `delay ≥ 0` (the publisher's own lateness,
//! transport, upstream processing). Among the last [`WINDOW`] arrivals the
//! one with the smallest delay (the earliest against the current period) is
//! the reference point `B`; the prediction for the next frame is
//! `t_B + (s_next − s_B)·period`. The period is the slope from such an early
//! point `A`, taken when the number of frames seen was last a power of two,
//! to `B`: both carry near-minimal delays and lie far apart, so the slope is
//! accurate, a disturbed start is forgotten, and an error in the slope only
//! acts over at most [`WINDOW`] frames (it never accumulates).

/// Arrivals the reference point is chosen from.
const WINDOW: usize = 16;
/// Frames observed before the schedule is trusted.
const MIN_OBSERVATIONS: u64 = 2 * WINDOW as u64;
/// Shortest period the schedule predicts, ns (faster streams are just polled).
const MIN_PERIOD_NS: f64 = 20_000.0;
/// Longest period the schedule predicts, ns (slower streams sleep on the event).
const MAX_PERIOD_NS: f64 = 200_000_000.0;

/// What a low-latency wait should do now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Window {
    /// Sleep until this instant (`CLOCK_MONOTONIC` ns), then poll.
    SleepUntil(u64),
    /// The frame is due: poll.
    Poll,
    /// No usable prediction (not learned yet, or the frame is overdue): sleep on the event.
    Unknown,
}

/// The learned schedule of one stream. Fixed size; observing never allocates.
#[derive(Debug, Clone, Default)]
pub struct ArrivalSchedule {
    /// The last arrivals (seq, t ns), a ring.
    ring: [(u64, u64); WINDOW],
    observations: u64,
    last_seq: u64,
    first: Option<(u64, u64)>,
    anchor: Option<(u64, u64)>,
    pending_anchor: Option<(u64, u64)>,
    period_ns: f64,
    due_ns: Option<f64>,
}

impl ArrivalSchedule {
    /// Records that frame `seq` arrived (was received) at `t_ns`.
    pub fn observe(&mut self, seq: u64, t_ns: u64) {
        if self.observations > 0 {
            let steps = seq.wrapping_sub(self.last_seq);
            if steps == 0 || steps > 1_000_000 {
                // repeated or absurd sequence: learn again
                *self = ArrivalSchedule::default();
            }
        }
        let (s0, t0) = *self.first.get_or_insert((seq, t_ns));
        self.ring[(self.observations % WINDOW as u64) as usize] = (seq, t_ns);
        self.observations += 1;
        self.last_seq = seq;
        let n = (self.observations as usize).min(WINDOW);
        if self.anchor.is_none() {
            // first frames: a rough slope, then the earliest of them as the anchor
            if seq > s0 {
                self.period_ns = t_ns.saturating_sub(t0) as f64 / (seq - s0) as f64;
            }
            if self.observations >= WINDOW as u64 {
                self.anchor = Some(self.earliest(n));
            }
            return;
        }
        let b = self.earliest(n);
        // at every power of two the anchor moves to the reference point of the
        // previous power of two: the baseline spans the later half of the
        // history, so a disturbed start is forgotten
        if self.observations.is_power_of_two() {
            if let Some(p) = self.pending_anchor.replace(b) {
                self.anchor = Some(p);
            }
        }
        if let Some((sa, ta)) = self.anchor {
            if b.0 > sa + WINDOW as u64 {
                self.period_ns = b.1.saturating_sub(ta) as f64 / (b.0 - sa) as f64;
            }
        }
        let ds = seq.wrapping_add(1).wrapping_sub(b.0) as f64;
        self.due_ns = Some(b.1 as f64 + ds * self.period_ns);
    }

    /// The ring entry with the smallest delay against the current period.
    fn earliest(&self, n: usize) -> (u64, u64) {
        let p = self.period_ns;
        let (s_ref, t_ref) = self.ring[0];
        let offset = |(s, t): (u64, u64)| (t as f64 - t_ref as f64) - (s as f64 - s_ref as f64) * p;
        let mut best = self.ring[0];
        for &e in &self.ring[1..n] {
            if offset(e) < offset(best) {
                best = e;
            }
        }
        best
    }

    /// The learned period, ns (None until trusted).
    pub fn period_ns(&self) -> Option<f64> {
        (self.observations >= MIN_OBSERVATIONS && (MIN_PERIOD_NS..=MAX_PERIOD_NS).contains(&self.period_ns))
            .then_some(self.period_ns)
    }

    /// When the next frame is due, `CLOCK_MONOTONIC` ns (None until trusted).
    pub fn next_due_ns(&self) -> Option<u64> {
        self.period_ns()?;
        self.due_ns.map(|d| d.max(0.0) as u64)
    }

    /// What to do at `now_ns` when polling should start `lead_ns` before the
    /// frame is due.
    pub(crate) fn poll_window(&self, now_ns: u64, lead_ns: u64) -> Window {
        let (Some(due), Some(period)) = (self.next_due_ns(), self.period_ns()) else {
            return Window::Unknown;
        };
        let wake = due.saturating_sub(lead_ns);
        // poll until the frame is half a period overdue (at least 300 µs)
        let give_up = due + (period as u64 / 2).max(300_000);
        if now_ns < wake {
            Window::SleepUntil(wake)
        } else if now_ns < give_up {
            Window::Poll
        } else {
            Window::Unknown
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 kHz stream whose frames arrive 5..105 µs after their grid instant.
    #[test]
    fn predicts_the_earliest_arrival_of_a_jittery_periodic_stream() {
        let mut s = ArrivalSchedule::default();
        let t0 = 5_000_000_000u64;
        let mut rng = 12345u64;
        let mut errors = Vec::new();
        for k in 0..3000u64 {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let delay = 5_000 + (rng >> 33) % 100_000;
            let t = t0 + k * 1_000_000 + delay;
            if let Some(due) = s.next_due_ns() {
                errors.push(t as i64 - due as i64);
            }
            s.observe(k, t);
        }
        errors.sort_unstable();
        let late = errors.len() - 2000..;
        let tail = &errors[late];
        // after learning, the prediction sits at the early edge of the arrivals
        let median = tail[tail.len() / 2];
        assert!((0..80_000).contains(&median), "median error {median} ns");
        assert!(tail[0] > -20_000, "earliest error {} ns", tail[0]);
        assert!(matches!(
            s.poll_window(t0 + 3000 * 1_000_000 - 200_000, 80_000),
            Window::SleepUntil(_)
        ));
    }

    /// The first frames come late in a burst (a subscriber that joined a
    /// backlog); the prediction must not drift early afterwards.
    #[test]
    fn a_late_burst_at_the_start_does_not_bias_the_period() {
        let mut s = ArrivalSchedule::default();
        let t0 = 1_000_000_000u64;
        for k in 0..5000u64 {
            let delay = if k < 20 {
                3_000_000 - k * 150_000
            } else {
                10_000 + (k * 7919 % 40) * 1000
            };
            let t = t0 + k * 1_000_000 + delay;
            if k > 4000 {
                let due = s.next_due_ns().unwrap() as i64;
                let err = t as i64 - due;
                assert!((-15_000..60_000).contains(&err), "frame {k}: error {err} ns");
            }
            s.observe(k, t);
        }
        assert!((s.period_ns().unwrap() - 1e6).abs() < 50.0, "{:?}", s.period_ns());
    }
}
