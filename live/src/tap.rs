//! The live outputs' side of the bus: subscriptions to a rig's frames,
//! estimates, events and health, drained in batches; frames and estimates
//! decimated by their sample time; each message kept encoded as JSON once
//! and handed to a [`Sink`] (the Foxglove server, the Zenoh publishers).
//!
//! A message is encoded only if it survives decimation and the sink wants its
//! topic (a live view with no client subscribed encodes nothing). The
//! subscriptions are iceoryx2's with safe overflow: a tap that falls behind
//! loses its own oldest frames, never slows a publisher.

use bus::{Bus, Subscriber, WaitMode};
use frames::Frame;
use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame};
use serde::Serialize;

use crate::json::{EstimateMsg, EventMsg, FrameMsg, HealthMsg};

/// The topics a live output carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LiveTopic {
    /// Sensor frames (decimated).
    Frames,
    /// Estimates (decimated).
    Estimates,
    /// Leak and fault events (every one).
    Events,
    /// The classifier's health (every one, 10 Hz).
    Health,
}

impl LiveTopic {
    /// Every topic, in [`LiveTopic::index`] order.
    pub const ALL: [LiveTopic; 4] = [
        LiveTopic::Frames,
        LiveTopic::Estimates,
        LiveTopic::Events,
        LiveTopic::Health,
    ];

    /// The topic's name: the last part of the Foxglove topic and of the Zenoh key.
    pub fn name(self) -> &'static str {
        match self {
            LiveTopic::Frames => "frames",
            LiveTopic::Estimates => "estimates",
            LiveTopic::Events => "events",
            LiveTopic::Health => "health",
        }
    }

    /// Position in [`LiveTopic::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The topic of a name ([`LiveTopic::name`]).
    pub fn of_name(name: &str) -> Option<LiveTopic> {
        LiveTopic::ALL.into_iter().find(|t| t.name() == name)
    }
}

/// Keeps at most one sample per period of sample time: the first, then the
/// first at or after the previous kept one plus the period (a stream that
/// starts again, its time going back, starts again here too).
#[derive(Debug, Clone)]
pub struct Decimator {
    period_s: f64,
    next_t_s: f64,
}

impl Decimator {
    /// A decimator to `rate_hz` (≥ the sample rate: every sample).
    pub fn new(rate_hz: f64) -> Self {
        Decimator {
            period_s: 1.0 / rate_hz,
            next_t_s: f64::NEG_INFINITY,
        }
    }

    /// Whether the sample at `t_s` is kept (a non-finite time never is).
    pub fn keep(&mut self, t_s: f64) -> bool {
        if !t_s.is_finite() {
            return false;
        }
        // a tolerance of a microsecond for sample times summed in floating point
        let due = t_s + 1e-6 >= self.next_t_s;
        let restarted = t_s < self.next_t_s - 2.0 * self.period_s;
        if !(due || restarted) {
            return false;
        }
        // on schedule, or after a gap / restart anew from this sample
        self.next_t_s = if due && t_s - self.next_t_s < self.period_s {
            self.next_t_s + self.period_s
        } else {
            t_s + self.period_s
        };
        true
    }
}

/// Where the tap's messages go.
pub trait Sink {
    /// Whether anyone takes `topic` now (if not, nothing is encoded for it).
    fn wants(&self, topic: LiveTopic) -> bool;
    /// One message of `topic`, JSON text, with its time: the record's own
    /// `CLOCK_MONOTONIC` stamp (`acq_mono_ns` of frames, estimates and events,
    /// `mono_ns` of health) as Unix time, ns ([`bus::epoch_ns`]), the
    /// `log_time` the recorder gives the same message.
    fn send(&mut self, topic: LiveTopic, json: &[u8], log_time_ns: u64);
}

/// What a tap has seen and passed on, per topic in [`LiveTopic::ALL`] order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TapCounts {
    /// Messages received from the bus.
    pub received: [u64; 4],
    /// Messages handed to the sink.
    pub sent: [u64; 4],
    /// Messages missing from a topic's sequence (dropped by the bus while the tap was behind).
    pub missing: [u64; 4],
}

/// The subscriptions of a live output, with its decimation.
pub struct Tap {
    frames: Subscriber<SensorFrame>,
    estimates: Subscriber<EstimateFrame>,
    events: Subscriber<LeakEventFrame>,
    health: Subscriber<HealthFrame>,
    frames_dec: Decimator,
    estimates_dec: Decimator,
    buf: Vec<u8>,
    /// What was received and sent so far.
    pub counts: TapCounts,
}

impl Tap {
    /// Subscribes to a rig's topics; frames and estimates are decimated to
    /// `frames_hz` and `estimates_hz` (of sample time).
    pub fn open(bus: &Bus, frames_hz: f64, estimates_hz: f64) -> Result<Tap, String> {
        // the tap drains in batches: it never waits on a topic
        let e = |e: bus::BusError| e.to_string();
        Ok(Tap {
            frames: bus.subscriber(WaitMode::Event).map_err(e)?,
            estimates: bus.subscriber(WaitMode::Event).map_err(e)?,
            events: bus.subscriber(WaitMode::Event).map_err(e)?,
            health: bus.subscriber(WaitMode::Event).map_err(e)?,
            frames_dec: Decimator::new(frames_hz),
            estimates_dec: Decimator::new(estimates_hz),
            buf: Vec::with_capacity(2048),
            counts: TapCounts::default(),
        })
    }

    /// Takes everything buffered on every topic and hands the kept messages to
    /// `sink`; returns the number of messages received.
    pub fn drain(&mut self, sink: &mut impl Sink) -> Result<u64, String> {
        let mut n = 0;
        while let Some(r) = self.frames.try_receive().map_err(|e| e.to_string())? {
            n += 1;
            self.counts.missing[0] += r.missing_before;
            let keep = self.frames_dec.keep(r.t_s) || r.is_end_of_stream();
            pass(
                &mut self.counts,
                &mut self.buf,
                sink,
                LiveTopic::Frames,
                keep,
                r.frame.acq_mono_ns,
                || FrameMsg::from(&r.frame),
            )?;
        }
        while let Some(r) = self.estimates.try_receive().map_err(|e| e.to_string())? {
            n += 1;
            self.counts.missing[1] += r.missing_before;
            let keep = self.estimates_dec.keep(r.t_s);
            pass(
                &mut self.counts,
                &mut self.buf,
                sink,
                LiveTopic::Estimates,
                keep,
                r.frame.acq_mono_ns,
                || EstimateMsg::from(&r.frame),
            )?;
        }
        while let Some(r) = self.events.try_receive().map_err(|e| e.to_string())? {
            n += 1;
            pass(
                &mut self.counts,
                &mut self.buf,
                sink,
                LiveTopic::Events,
                true,
                r.frame.acq_mono_ns,
                || EventMsg::from(&r.frame),
            )?;
        }
        while let Some(r) = self.health.try_receive().map_err(|e| e.to_string())? {
            n += 1;
            self.counts.missing[3] += r.missing_before;
            pass(
                &mut self.counts,
                &mut self.buf,
                sink,
                LiveTopic::Health,
                true,
                r.frame.mono_ns,
                || HealthMsg::from(&r.frame),
            )?;
        }
        Ok(n)
    }
}

fn pass<M: Serialize>(
    counts: &mut TapCounts,
    buf: &mut Vec<u8>,
    sink: &mut impl Sink,
    topic: LiveTopic,
    keep: bool,
    stamp_mono_ns: u64,
    msg: impl FnOnce() -> M,
) -> Result<(), String> {
    let i = topic.index();
    counts.received[i] += 1;
    if !keep || !sink.wants(topic) {
        return Ok(());
    }
    buf.clear();
    serde_json::to_writer(&mut *buf, &msg()).map_err(|e| format!("{} message: {e}", topic.name()))?;
    sink.send(topic, buf, bus::epoch_ns(stamp_mono_ns));
    counts.sent[i] += 1;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_1_khz_stream_decimated_to_50_hz_keeps_every_20th_sample() {
        let mut d = Decimator::new(50.0);
        let kept: Vec<u64> = (0..10_000u64).filter(|i| d.keep(*i as f64 * 0.001)).collect();
        assert_eq!(kept.len(), 500);
        assert!(kept.windows(2).all(|w| w[1] - w[0] == 20), "{:?}", &kept[..5]);
        // a new stream (time back to 0) is followed at once
        assert!(d.keep(0.0));
        assert!(!d.keep(0.001));
        assert!(d.keep(0.02));
        // after a gap, on from the next sample
        assert!(d.keep(5.0003));
        assert!(!d.keep(5.0103));
        assert!(d.keep(5.0203));
        assert!(!d.keep(f64::NAN));
        // faster than the samples: every one
        let mut all = Decimator::new(1000.0);
        assert_eq!((0..1000).filter(|i| all.keep(*i as f64 * 0.001)).count(), 1000);
    }
}
