//! iceoryx2 plumbing shared by the leakwatch process shells.
//!
//! ```text
//! let stop = bus::stop_on_signals();
//! let bus = Bus::open("rig1", BusConfig::from_env()?)?;
//! let mut tx = bus.publisher::<SensorFrame>()?;            // leakwatch/rig1/frames
//! let mut rx = bus.subscriber::<SensorFrame>(WaitMode::Event)?;
//! tx.send(&frame)?;                                         // send + notify the wake event
//! if let Some(r) = rx.wait(Duration::from_millis(100), stop)? { r.seq; r.recv_mono_ns; }
//! ```
//!
//! Every topic is a publish-subscribe service `leakwatch/<rig>/<topic>` paired
//! with an event service `leakwatch/<rig>/<topic>/wake` that the publisher
//! notifies after each send (publish-subscribe has no wake-up of its own).
//! A [`Subscriber`] waits in one of three [`WaitMode`]s, counts sequence gaps,
//! and hands out copies of the frames (at most 264 bytes), so it never holds
//! shared memory across calls. [`run_stage`] is the whole receive-process-
//! publish loop of a 1-input, 1-output stage (estimator, classifier).
//!
//! Nodes are created with iceoryx2's signal handling disabled: the process
//! calls [`stop_on_signals`] and checks the flag. Setting
//! `LEAKWATCH_IOX_PREFIX` (see [`BusConfig::from_env`]) isolates a set of
//! processes from all others on the host (tests run in parallel that way);
//! processes see each other only if they use the same prefix.

use std::fmt;

use frames::{Frame, RigId, Topic};
use iceoryx2::prelude::*;

pub mod clock;
mod config;
mod private;
mod publisher;
mod schedule;
pub mod signals;
pub mod stage;
mod stage_args;
pub mod stats;
mod subscriber;

/// `eprintln!` that never panics: a standard error that cannot be written (a
/// stage's log file on a full disk, a closed descriptor) loses the line instead
/// of taking the process down with it.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use ::std::io::Write as _;
        let _ = ::std::writeln!(::std::io::stderr(), $($arg)*);
    }};
}

pub use clock::{
    epoch_ns, epoch_ns_with, epoch_offset_ns, init_epoch_offset, measure_epoch_offset_ns, monotonic_ns,
    set_timer_slack_ns, sleep_until_ns, wall_clock_ns, Pacer, Tick, EPOCH_OFFSET_ENV,
};
pub use config::{
    max_prefix_len_under, prefixes_with_files, prefixes_with_files_in, validate_prefix, BusConfig, Leftover,
    PrefixLock, MAX_PREFIX_LEN, PREFIX_ENV,
};
pub use frames;
pub use private::{current_uid, ensure_private, private_dir, private_dir_path, RUNTIME_DIR_ENV};
pub use publisher::{Publisher, PublisherWatch, TopicHold, TopicWatch};
pub use schedule::ArrivalSchedule;
pub use signals::stop_on_signals;
pub use stage::{run_stage, run_stage_with, StageOptions, StageReport, StopReason};
pub use stage_args::StageArgs;
pub use stats::{Percentiles, StageStats};
pub use subscriber::{Received, Subscriber};

/// An error of the bus, naming what was being done and the iceoryx2 cause.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusError(pub String);

impl BusError {
    pub(crate) fn new(what: impl fmt::Display, cause: impl fmt::Debug) -> BusError {
        BusError(format!("{what}: {cause:?}"))
    }
}

impl fmt::Display for BusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BusError {}

/// How a [`Subscriber`] waits for its next frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WaitMode {
    /// Sleep on the wake event (`Listener::timed_wait`): no CPU while idle,
    /// about 20 µs wake-up latency.
    Event,
    /// Learn the stream's schedule from arrivals, sleep until `lead_us`
    /// before the next frame is due, then poll; falls back to the wake event
    /// when a frame is late or the schedule is unknown. Polling latency at a
    /// few percent of a core on a periodic stream.
    LowLatency {
        /// How long before the predicted arrival to wake and start polling, µs.
        lead_us: u32,
    },
    /// Poll without sleeping: about 1 µs latency, a whole core.
    BusyPoll,
}

impl WaitMode {
    /// The default low-latency mode (wakes 80 µs before the frame is due).
    pub const LOW_LATENCY: WaitMode = WaitMode::LowLatency { lead_us: 80 };

    /// Parses `event`, `low-latency[:LEAD_US]` or `busy-poll`.
    pub fn parse(s: &str) -> Result<WaitMode, String> {
        match s {
            "event" => Ok(WaitMode::Event),
            "busy-poll" | "poll" => Ok(WaitMode::BusyPoll),
            "low-latency" => Ok(WaitMode::LOW_LATENCY),
            _ => match s.strip_prefix("low-latency:").map(str::parse::<u32>) {
                Some(Ok(lead_us)) => Ok(WaitMode::LowLatency { lead_us }),
                _ => Err(format!(
                    "unknown wait mode {s:?}: use event, low-latency[:LEAD_US] or busy-poll"
                )),
            },
        }
    }
}

/// The iceoryx2 node of one process and the rig it serves. Single-threaded
/// (iceoryx2's `ipc::Service`): a thread that needs the bus opens its own.
pub struct Bus {
    node: Node<ipc::Service>,
    rig: RigId,
    config: BusConfig,
}

impl Bus {
    /// Validates `rig_id` and creates this process's iceoryx2 node (signal
    /// handling left to [`stop_on_signals`]). Dead nodes of killed processes
    /// are cleaned up on the way.
    /// iceoryx2's own log is limited to errors unless `IOX2_LOG_LEVEL` says otherwise.
    pub fn open(rig_id: &str, config: BusConfig) -> Result<Bus, BusError> {
        set_log_level_from_env_or(LogLevel::Error);
        let rig = RigId::new(rig_id).map_err(|e| BusError(e.to_string()))?;
        let iox = config.iceoryx2_config()?;
        let node = NodeBuilder::new()
            .config(&iox)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| {
                let mut m = BusError::new("cannot create the iceoryx2 node", e);
                if let Some(why) = config.diagnose_blocked_start() {
                    m.0.push_str(&format!("; {why}"));
                }
                m
            })?;
        node.try_cleanup_dead_nodes();
        Ok(Bus { node, rig, config })
    }

    /// The rig id.
    pub fn rig(&self) -> &RigId {
        &self.rig
    }

    /// The service sizes in use.
    pub fn config(&self) -> &BusConfig {
        &self.config
    }

    /// The iceoryx2 node (for anything this crate does not wrap).
    pub fn node(&self) -> &Node<ipc::Service> {
        &self.node
    }

    fn pubsub<T: Frame>(
        &self,
    ) -> Result<iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>, BusError>
    {
        let name = frames::service_name(&self.rig, T::TOPIC);
        let sname = ServiceName::new(&name).map_err(|e| BusError::new(format!("service name {name}"), e))?;
        let c = &self.config;
        self.node
            .service_builder(&sname)
            .publish_subscribe::<T>()
            .history_size(c.history)
            .subscriber_max_buffer_size(c.subscriber_buffer)
            .max_publishers(c.max_publishers)
            .max_subscribers(c.max_subscribers)
            .max_nodes(c.max_nodes)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| {
                BusError::new(
                    format!(
                        "cannot open or create service {name} (another process with other sizes or another \
                         frame layout may have created it)"
                    ),
                    e,
                )
            })
    }

    fn wake(
        &self,
        topic: Topic,
    ) -> Result<iceoryx2::service::port_factory::event::PortFactory<ipc::Service>, BusError> {
        let name = frames::wake_service_name(&self.rig, topic);
        let sname = ServiceName::new(&name).map_err(|e| BusError::new(format!("service name {name}"), e))?;
        let c = &self.config;
        self.node
            .service_builder(&sname)
            .event()
            .max_notifiers(c.max_publishers)
            .max_listeners(c.max_subscribers)
            .max_nodes(c.max_nodes)
            .open_or_create()
            .map_err(|e| BusError::new(format!("cannot open or create event service {name}"), e))
    }

    /// A publisher of `T` on its topic (`T::TOPIC`), with the topic's wake notifier.
    pub fn publisher<T: Frame>(&self) -> Result<Publisher<T>, BusError> {
        let service = self.pubsub::<T>()?;
        let publisher = service
            .publisher_builder()
            .create()
            .map_err(|e| BusError::new(format!("cannot create a publisher on {}", T::TOPIC), e))?;
        let notifier = self
            .wake(T::TOPIC)?
            .notifier_builder()
            .create()
            .map_err(|e| BusError::new(format!("cannot create a notifier on {}/wake", T::TOPIC), e))?;
        Ok(Publisher {
            service,
            publisher,
            notifier,
            sent: 0,
        })
    }

    /// A [`TopicWatch`] of topic `T`: its publishers counted without subscribing.
    pub fn topic_watch<T: Frame>(&self) -> Result<TopicWatch<T>, BusError> {
        Ok(TopicWatch {
            service: self.pubsub::<T>()?,
        })
    }

    /// Topic `T`'s services (frames and wake-ups), opened or created now and
    /// kept while the [`TopicHold`] lives. A supervisor holds every topic
    /// before it starts the stages, so that a stage killed at its start cannot
    /// leave a service half created.
    pub fn hold<T: Frame>(&self) -> Result<TopicHold<T>, BusError> {
        Ok(TopicHold::new(self.pubsub::<T>()?, self.wake(T::TOPIC)?))
    }

    /// A subscriber of `T` on its topic, waiting in `mode`.
    pub fn subscriber<T: Frame>(&self, mode: WaitMode) -> Result<Subscriber<T>, BusError> {
        let service = self.pubsub::<T>()?;
        let subscriber = service
            .subscriber_builder()
            .buffer_size(self.config.subscriber_buffer)
            .create()
            .map_err(|e| BusError::new(format!("cannot create a subscriber on {}", T::TOPIC), e))?;
        let listener = self
            .wake(T::TOPIC)?
            .listener_builder()
            .create()
            .map_err(|e| BusError::new(format!("cannot create a listener on {}/wake", T::TOPIC), e))?;
        if matches!(mode, WaitMode::LowLatency { .. }) {
            set_timer_slack_ns(1);
        }
        Ok(Subscriber {
            subscriber,
            listener,
            mode,
            next_seq: None,
            received: 0,
            seq_gaps: 0,
            restarts: 0,
            schedule: ArrivalSchedule::default(),
        })
    }
}
