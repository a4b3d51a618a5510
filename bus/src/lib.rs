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
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use frames::{Frame, RigId, Topic};
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use iceoryx2::service::header::payload_header::PayloadHeader;

pub mod clock;
mod schedule;
pub mod signals;
pub mod stage;
pub mod stats;

pub use clock::{monotonic_ns, set_timer_slack_ns, sleep_until_ns, Pacer, Tick};
pub use frames;
pub use schedule::ArrivalSchedule;
pub use signals::stop_on_signals;
pub use stage::{run_stage, StageOptions, StageReport, StopReason};
pub use stats::{Percentiles, StageStats};

/// The environment variable that isolates a set of processes (see [`BusConfig::from_env`]).
pub const PREFIX_ENV: &str = "LEAKWATCH_IOX_PREFIX";

/// An error of the bus, naming what was being done and the iceoryx2 cause.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusError(pub String);

impl BusError {
    fn new(what: impl fmt::Display, cause: impl fmt::Debug) -> BusError {
        BusError(format!("{what}: {cause:?}"))
    }
}

impl fmt::Display for BusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BusError {}

/// Sizes of the services and the isolation prefix. Every process of a rig
/// must use the same values: the first process creates the services and the
/// others open them only if their requirements fit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BusConfig {
    /// Isolation prefix (`[A-Za-z0-9_-]{1,32}`): iceoryx2 files get the
    /// prefix `lw_<prefix>_` and live under `/tmp/iceoryx2/lw_<prefix>/`.
    /// `None`: iceoryx2's defaults (what other iceoryx2 programs, like the
    /// Python bindings with a default config, see).
    pub iox_prefix: Option<String>,
    /// Frames a subscriber buffers before the oldest is overwritten (a 1 kHz
    /// stream survives a stall of this many ms).
    pub subscriber_buffer: usize,
    /// Frames a late subscriber receives on connecting.
    pub history: usize,
    /// Publishers per service (a restarted publisher needs a free slot while
    /// its dead predecessor is being cleaned up).
    pub max_publishers: usize,
    /// Subscribers per service (the next stage, the recorder, a Python
    /// viewer, restarts).
    pub max_subscribers: usize,
    /// Nodes (processes) per service.
    pub max_nodes: usize,
}

impl Default for BusConfig {
    fn default() -> Self {
        BusConfig {
            iox_prefix: None,
            subscriber_buffer: 256,
            history: 0,
            max_publishers: 8,
            max_subscribers: 16,
            max_nodes: 32,
        }
    }
}

impl BusConfig {
    /// The defaults, with [`BusConfig::iox_prefix`] from `LEAKWATCH_IOX_PREFIX`
    /// if it is set and not empty.
    pub fn from_env() -> Result<BusConfig, BusError> {
        let mut c = BusConfig::default();
        match std::env::var(PREFIX_ENV) {
            Ok(p) if !p.is_empty() => {
                validate_prefix(&p)?;
                c.iox_prefix = Some(p);
            }
            Ok(_) | Err(std::env::VarError::NotPresent) => {}
            Err(e) => return Err(BusError(format!("{PREFIX_ENV}: {e}"))),
        }
        Ok(c)
    }

    /// The iceoryx2 configuration for these settings.
    pub fn iceoryx2_config(&self) -> Result<iceoryx2::config::Config, BusError> {
        let mut c = iceoryx2::config::Config::global_config().clone();
        if let Some(p) = &self.iox_prefix {
            validate_prefix(p)?;
            c.global.prefix = FileName::new(format!("lw_{p}_").as_bytes())
                .map_err(|e| BusError::new(format!("iceoryx2 prefix from {p:?}"), e))?;
            let root = format!("/tmp/iceoryx2/lw_{p}/");
            c.global
                .set_root_path(&Path::new(root.as_bytes()).map_err(|e| BusError::new(&root, e))?);
        }
        Ok(c)
    }
}

impl BusConfig {
    /// Removes the files an isolated run leaves behind (`/tmp/iceoryx2/lw_<prefix>/`
    /// and `/dev/shm/lw_<prefix>_*`); for tests, once every process of the
    /// prefix has ended. Does nothing without a prefix. Returns the entries removed.
    pub fn remove_isolated_files(&self) -> std::io::Result<usize> {
        let Some(p) = &self.iox_prefix else {
            return Ok(0);
        };
        validate_prefix(p).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e.0))?;
        let mut removed = 0;
        let root = std::path::PathBuf::from(format!("/tmp/iceoryx2/lw_{p}"));
        if root.exists() {
            std::fs::remove_dir_all(&root)?;
            removed += 1;
        }
        let start = format!("lw_{p}_");
        for entry in std::fs::read_dir("/dev/shm")?.flatten() {
            if entry.file_name().to_string_lossy().starts_with(&start) {
                std::fs::remove_file(entry.path())?;
                removed += 1;
            }
        }
        Ok(removed)
    }
}

impl BusConfig {
    /// The iceoryx2 file prefix in `/dev/shm` (`lw_<prefix>_`, or iceoryx2's `iox2_`)
    /// and the root directory of its other files.
    fn file_prefix_and_root(&self) -> (String, String) {
        match &self.iox_prefix {
            Some(p) => (format!("lw_{p}_"), format!("/tmp/iceoryx2/lw_{p}")),
            None => ("iox2_".to_string(), "/tmp/iceoryx2".to_string()),
        }
    }

    /// Why a node of this prefix may fail to start, read off the files: a global
    /// management segment (`/dev/shm/<prefix>*.global_mgmt`) of another user or of a
    /// size other than iceoryx2's own, or a root directory of another user; with
    /// the way out. `None` when nothing looks wrong (or nothing can be read).
    pub fn diagnose_blocked_start(&self) -> Option<String> {
        use std::os::unix::fs::MetadataExt;
        let (start, root) = self.file_prefix_and_root();
        // SAFETY: geteuid has no preconditions and cannot fail.
        let me = unsafe { libc::geteuid() };
        let env = match &self.iox_prefix {
            Some(p) => format!("prefix {p:?}"),
            None => "iceoryx2's default prefix".to_string(),
        };
        let way_out = format!(
            "once no process of this prefix runs, remove its files (rm -rf {root} /dev/shm/{start}*) or start \
             with another prefix (LEAKWATCH_IOX_PREFIX=...); see docs/security.md"
        );
        let mut found = Vec::new();
        for entry in std::fs::read_dir("/dev/shm").ok()?.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if !(name.starts_with(&start) && name.ends_with(".global_mgmt")) {
                continue;
            }
            let Ok(meta) = entry.metadata() else { continue };
            if meta.uid() != me {
                found.push(format!(
                    "the management segment /dev/shm/{name} of {env} belongs to another user (uid {}, mode {:o})",
                    meta.uid(),
                    meta.mode() & 0o7777
                ));
            } else if meta.len() < GLOBAL_MGMT_MIN_BYTES {
                found.push(format!(
                    "the management segment /dev/shm/{name} of {env} is damaged ({} bytes, iceoryx2 writes {GLOBAL_MGMT_MIN_BYTES})",
                    meta.len()
                ));
            }
        }
        if let Ok(meta) = std::fs::metadata(&root) {
            if meta.uid() != me {
                found.push(format!(
                    "{root} belongs to another user (uid {}, mode {:o})",
                    meta.uid(),
                    meta.mode() & 0o7777
                ));
            }
        }
        if found.is_empty() {
            None
        } else {
            Some(format!("{}: {way_out}", found.join("; ")))
        }
    }
}

/// A prefix owned by one run: an exclusive lock (`flock`) on
/// `$TMPDIR/leakwatch-prefix-<prefix>.lock`, released when it is dropped or the
/// process ends (however it ends). The file holds the owner's process id.
#[derive(Debug)]
pub struct PrefixLock {
    _file: std::fs::File,
    /// The lock file.
    pub path: std::path::PathBuf,
}

impl BusConfig {
    /// Takes the ownership of this config's prefix for one run: a second run with
    /// the same prefix is refused (naming the owner's process id) instead of sharing,
    /// and later deleting, the first one's shared memory. Without a prefix there is
    /// nothing to own (an error: a run always has one).
    pub fn lock_prefix(&self) -> Result<PrefixLock, BusError> {
        use std::io::{Read, Seek, Write};
        use std::os::unix::fs::OpenOptionsExt;
        use std::os::unix::io::AsRawFd;
        let Some(p) = &self.iox_prefix else {
            return Err(BusError("a run needs an isolation prefix to own".into()));
        };
        validate_prefix(p)?;
        let path = std::env::temp_dir().join(format!("leakwatch-prefix-{p}.lock"));
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .mode(0o600)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
            .open(&path)
            .map_err(|e| BusError(format!("cannot open the prefix lock {}: {e}", path.display())))?;
        // SAFETY: flock on an open descriptor we own; no memory is passed.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let mut owner = String::new();
            let _ = file.read_to_string(&mut owner);
            return Err(BusError(format!(
                "the iceoryx2 prefix {p:?} is in use by another leakwatch run (process {}, lock {}): \
                 two runs on one prefix would share and then delete each other's shared memory; \
                 use another LEAKWATCH_IOX_PREFIX, or leave it unset for a private one",
                owner.trim(),
                path.display()
            )));
        }
        let pid = std::process::id();
        let write = |f: &mut std::fs::File| -> std::io::Result<()> {
            f.set_len(0)?;
            f.rewind()?;
            writeln!(f, "{pid}")
        };
        write(&mut file)
            .map_err(|e| BusError(format!("cannot write the prefix lock {}: {e}", path.display())))?;
        Ok(PrefixLock { _file: file, path })
    }
}

/// Size of the global management segment iceoryx2 0.10 writes, bytes (the node id
/// counter); a smaller file of that name is damaged.
const GLOBAL_MGMT_MIN_BYTES: u64 = 16;

fn validate_prefix(p: &str) -> Result<(), BusError> {
    if p.is_empty()
        || p.len() > 32
        || !p
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
    {
        return Err(BusError(format!(
            "invalid iceoryx2 isolation prefix {p:?} (from {PREFIX_ENV}?): use 1 to 32 characters of A-Z a-z 0-9 _ -"
        )));
    }
    Ok(())
}

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

/// Counts the publishers of one topic without subscribing to it (see
/// [`Bus::topic_watch`]): a publisher more than the pipeline's own is another
/// process of this user publishing on the topic (docs/security.md).
pub struct TopicWatch<T: Frame> {
    service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
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
    service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, ()>,
    publisher: iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    sent: u64,
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
    subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>,
    listener: Listener<ipc::Service>,
    mode: WaitMode,
    next_seq: Option<u64>,
    received: u64,
    seq_gaps: u64,
    restarts: u64,
    schedule: ArrivalSchedule,
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
                        schedule::Window::SleepUntil(t) => sleep_until_ns(t.min(deadline), true),
                        schedule::Window::Poll => {
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
