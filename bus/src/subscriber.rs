//! The receiving side of a topic: [`Subscriber`] (the three wait modes,
//! sequence-gap counting) and the [`Received`] frame.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use frames::Frame;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::prelude::*;
use iceoryx2::service::header::payload_header::PayloadHeader;

use crate::schedule::{self, ArrivalSchedule};
use crate::{monotonic_ns, sleep_until_ns, BusError, WaitMode};

/// A frame as received: a copy of the payload with receive bookkeeping.
/// Derefs to the frame.
#[derive(Debug, Clone, Copy)]
pub struct Received<T> {
    /// The frame.
    pub frame: T,
    /// `CLOCK_MONOTONIC` when it was taken from the buffer, ns.
    pub recv_mono_ns: u64,
    /// Frames missing from the sequence just before this one (0 if none or
    /// if the type has no sequence).
    pub missing_before: u64,
    /// True if the sequence went backwards: a new publisher (restart).
    pub restarted: bool,
    /// Process id of the node that published the frame, from the sample header
    /// iceoryx2 writes (not from the payload, which any publisher fills as it
    /// likes); 0 if unknown.
    pub publisher_pid: u32,
}

impl<T> std::ops::Deref for Received<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.frame
    }
}

/// Receives frames of one topic, counting sequence gaps.
pub struct Subscriber<T: Frame> {
    pub(crate) subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>,
    pub(crate) listener: Listener<ipc::Service>,
    pub(crate) mode: WaitMode,
    pub(crate) next_seq: Option<u64>,
    pub(crate) received: u64,
    pub(crate) seq_gaps: u64,
    pub(crate) restarts: u64,
    pub(crate) schedule: ArrivalSchedule,
}

/// How often a polling loop checks its stop flag and timeout, iterations (a power of 2).
const POLL_CHECK_EVERY: u32 = 256;
/// Longest single sleep on the wake event, so a stop flag is seen promptly.
const MAX_EVENT_SLICE: Duration = Duration::from_millis(50);

impl<T: Frame> Subscriber<T> {
    /// Frames received.
    pub fn received(&self) -> u64 {
        self.received
    }

    /// Frames missing from the sequence (summed over gaps).
    pub fn seq_gaps(&self) -> u64 {
        self.seq_gaps
    }

    /// Times the sequence went backwards (a publisher restarted).
    pub fn restarts(&self) -> u64 {
        self.restarts
    }

    /// Continues a stream another process (this stage's previous process) was
    /// reading: the next frame expected is `seq + 1`, so the frames missing before
    /// the first one received are counted as a gap (in [`Self::seq_gaps`] and
    /// that frame's [`Received::missing_before`]) instead of going unnoticed.
    pub fn resume_after(&mut self, seq: u64) {
        self.next_seq = Some(seq.wrapping_add(1));
    }

    /// The wait mode.
    pub fn mode(&self) -> WaitMode {
        self.mode
    }

    /// The learned arrival schedule (used by [`WaitMode::LowLatency`]).
    pub fn schedule(&self) -> &ArrivalSchedule {
        &self.schedule
    }

    /// Takes the oldest buffered frame, if any, without waiting.
    #[inline]
    pub fn try_receive(&mut self) -> Result<Option<Received<T>>, BusError> {
        let sample = self
            .subscriber
            .receive()
            .map_err(|e| BusError::new(format!("cannot receive on {}", T::TOPIC), e))?;
        let Some(sample) = sample else {
            return Ok(None);
        };
        let frame = *sample.payload();
        let publisher_pid = sample
            .header()
            .node_id()
            .pid::<ipc::Service>()
            .map(|p| u32::try_from(p.value()).unwrap_or(0))
            .unwrap_or(0);
        drop(sample);
        let now = monotonic_ns();
        self.received += 1;
        let mut missing = 0;
        let mut restarted = false;
        if let Some(seq) = frame.seq() {
            match self.next_seq {
                Some(expected) if seq > expected => missing = seq - expected,
                Some(expected) if seq < expected => restarted = true,
                _ => {}
            }
            self.seq_gaps += missing;
            self.restarts += restarted as u64;
            self.next_seq = Some(seq.wrapping_add(1));
            if restarted {
                self.schedule = ArrivalSchedule::default();
            }
            self.schedule.observe(seq, now);
        }
        Ok(Some(Received {
            frame,
            recv_mono_ns: now,
            missing_before: missing,
            restarted,
            publisher_pid,
        }))
    }

    /// Waits up to `timeout` for the next frame in this subscriber's mode.
    /// `Ok(None)` on timeout or when `stop` is set.
    pub fn wait(&mut self, timeout: Duration, stop: &AtomicBool) -> Result<Option<Received<T>>, BusError> {
        self.wait_then(timeout, stop, &mut || {})
    }

    /// [`Self::wait`], and in low-latency mode calls `before_frame` once when it
    /// wakes from its sleep, the lead before the next frame is due, while no frame
    /// is there yet: the place for a throw-away step that brings the caches back
    /// after the sleep (the other modes never call it).
    pub fn wait_then(
        &mut self,
        timeout: Duration,
        stop: &AtomicBool,
        before_frame: &mut dyn FnMut(),
    ) -> Result<Option<Received<T>>, BusError> {
        let mut slept = false;
        let deadline = monotonic_ns().saturating_add(timeout.as_nanos().min(u64::MAX as u128) as u64);
        let mut spins = 0u32;
        loop {
            if let Some(r) = self.try_receive()? {
                return Ok(Some(r));
            }
            match self.mode {
                WaitMode::BusyPoll => {
                    spins = spins.wrapping_add(1);
                    if spins & (POLL_CHECK_EVERY - 1) == 0 && self.should_return(deadline, stop) {
                        return Ok(None);
                    }
                    std::hint::spin_loop();
                }
                WaitMode::Event => {
                    if self.should_return(deadline, stop) {
                        return Ok(None);
                    }
                    self.event_wait(deadline, stop)?;
                }
                WaitMode::LowLatency { lead_us } => {
                    let now = monotonic_ns();
                    if stop.load(Ordering::Relaxed) || now >= deadline {
                        return Ok(None);
                    }
                    match self.schedule.poll_window(now, lead_us as u64 * 1000) {
                        schedule::Window::SleepUntil(t) => {
                            sleep_until_ns(t.min(deadline), true);
                            slept = true;
                        }
                        schedule::Window::Poll => {
                            if std::mem::take(&mut slept) && !self.subscriber.has_samples().unwrap_or(true) {
                                before_frame();
                                continue;
                            }
                            // poll a bounded number of times, then re-evaluate the window
                            for _ in 0..POLL_CHECK_EVERY {
                                if self.subscriber.has_samples().unwrap_or(true) {
                                    break;
                                }
                                std::hint::spin_loop();
                            }
                        }
                        schedule::Window::Unknown => self.event_wait(deadline, stop)?,
                    }
                }
            }
        }
    }

    fn should_return(&self, deadline: u64, stop: &AtomicBool) -> bool {
        stop.load(Ordering::Relaxed) || monotonic_ns() >= deadline
    }

    /// Sleeps on the wake event until notified, the deadline, or at most
    /// [`MAX_EVENT_SLICE`]. A signal ends the sleep early.
    fn event_wait(&mut self, deadline: u64, stop: &AtomicBool) -> Result<(), BusError> {
        let left = deadline.saturating_sub(monotonic_ns());
        let slice = Duration::from_nanos(left).min(MAX_EVENT_SLICE);
        match self.listener.timed_wait(|_| {}, slice) {
            Ok(_) => Ok(()),
            Err(_) if stop.load(Ordering::Relaxed) => Ok(()),
            Err(ListenerWaitError::InterruptSignal) => Ok(()),
            Err(e) => Err(BusError::new(format!("waiting on {}/wake failed", T::TOPIC), e)),
        }
    }
}
