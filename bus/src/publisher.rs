//! The sending side of a topic: [`Publisher`] (send + wake), and the
//! counting of a topic's publishers ([`TopicWatch`], [`PublisherWatch`]), and
//! a topic's services kept created ([`TopicHold`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use frames::{Frame, Topic};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;

use crate::{monotonic_ns, BusError};

/// Keeps one topic's services (its frames and its wake-ups) created for as long
/// as it lives (see [`Bus::hold`](crate::Bus::hold)). A process killed while it
/// creates a service leaves it half made, and every later open of it fails
/// with "hangs in creation"; a service that already exists is only opened.
pub struct TopicHold<T: Frame> {
    _service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
    _wake: iceoryx2::service::port_factory::event::PortFactory<ipc::Service>,
}

impl<T: Frame> TopicHold<T> {
    pub(crate) fn new(
        service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
        wake: iceoryx2::service::port_factory::event::PortFactory<ipc::Service>,
    ) -> TopicHold<T> {
        TopicHold {
            _service: service,
            _wake: wake,
        }
    }
}

/// Counts the publishers of one topic without subscribing to it (see
/// [`Bus::topic_watch`](crate::Bus::topic_watch)): a publisher more than the pipeline's own is another
/// process of this user publishing on the topic (docs/security.md).
pub struct TopicWatch<T: Frame> {
    pub(crate) service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
}

impl<T: Frame> TopicWatch<T> {
    /// Publishers currently connected to the topic (iceoryx2's dynamic service state).
    pub fn publisher_count(&self) -> usize {
        self.service.dynamic_config().number_of_publishers()
    }
}

/// Decides when a topic has more publishers than it should and says so once:
/// an excess must be seen on two checks in a row (a restarted stage's dead
/// publisher is removed by iceoryx2 when the new one starts), and is reported
/// again only if it grows, or after the count went back to normal.
#[derive(Debug, Clone)]
pub struct PublisherWatch {
    topic: Topic,
    expected: usize,
    last: usize,
    warned_at: usize,
}

impl PublisherWatch {
    /// A watch of `topic`, which should have at most `expected` publishers.
    pub fn new(topic: Topic, expected: usize) -> Self {
        PublisherWatch {
            topic,
            expected,
            last: 0,
            warned_at: 0,
        }
    }

    /// Takes one count of the topic's publishers; returns the warning to show, if any.
    pub fn observe(&mut self, count: usize) -> Option<String> {
        let previous = std::mem::replace(&mut self.last, count);
        if count <= self.expected {
            self.warned_at = 0;
            return None;
        }
        if previous <= self.expected || count <= self.warned_at {
            return None;
        }
        self.warned_at = count;
        Some(format!(
            "{count} publishers on topic {} (expected {}): another process of this user is publishing \
             on it; its frames are mixed with the pipeline's (see docs/security.md)",
            self.topic, self.expected
        ))
    }
}

/// Publishes frames of one topic and wakes its subscribers.
pub struct Publisher<T: Frame> {
    pub(crate) service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
    pub(crate) publisher: iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>,
    pub(crate) notifier: Notifier<ipc::Service>,
    pub(crate) sent: u64,
}

impl<T: Frame> Publisher<T> {
    /// Sends a copy of `frame` and notifies the wake event. No allocation.
    pub fn send(&mut self, frame: &T) -> Result<(), BusError> {
        let sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| BusError::new(format!("cannot loan a {} sample", T::TOPIC), e))?;
        sample
            .write_payload(*frame)
            .send()
            .map_err(|e| BusError::new(format!("cannot send on {}", T::TOPIC), e))?;
        self.sent += 1;
        self.notify()
    }

    /// Loans a sample initialised with `T::default()`, lets `fill` write it in
    /// shared memory, and sends it (then notifies) if `fill` returns true;
    /// otherwise the sample is returned unsent. Returns whether it was sent.
    pub fn send_with(&mut self, fill: impl FnOnce(&mut T) -> bool) -> Result<bool, BusError> {
        let mut sample = self
            .publisher
            .loan_uninit()
            .map_err(|e| BusError::new(format!("cannot loan a {} sample", T::TOPIC), e))?
            .write_payload(T::default());
        if !fill(sample.payload_mut()) {
            return Ok(false);
        }
        sample
            .send()
            .map_err(|e| BusError::new(format!("cannot send on {}", T::TOPIC), e))?;
        self.sent += 1;
        self.notify()?;
        Ok(true)
    }

    fn notify(&self) -> Result<(), BusError> {
        self.notifier
            .notify()
            .map(|_| ())
            .map_err(|e| BusError::new(format!("cannot notify {}/wake", T::TOPIC), e))
    }

    /// Frames sent by this publisher.
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// Subscribers currently connected to the topic.
    pub fn subscriber_count(&self) -> usize {
        self.service.dynamic_config().number_of_subscribers()
    }

    /// Waits until at least `n` subscribers are connected (false on timeout or stop).
    pub fn wait_for_subscribers(&self, n: usize, timeout: Duration, stop: &AtomicBool) -> bool {
        let deadline = monotonic_ns() + timeout.as_nanos() as u64;
        while self.subscriber_count() < n {
            if stop.load(Ordering::Relaxed) || monotonic_ns() >= deadline {
                return false;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        true
    }
}
