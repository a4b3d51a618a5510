//! The leakwatch log: one MCAP file per run, a rosbag2 file (profile `ros2`),
//! with a channel per topic (`/leakwatch/<rig>/frames`, `estimates`, `events`,
//! `health`, `stats`) plus `gaps` and `frame_batches` (every sensor frame, in
//! columns; `frames` then holds every 40th, for plotting): ROS 2 messages in CDR described by their
//! ros2msg schemas ([`msg`], the `.msg` files in `leakwatch_msgs/msg/`), log times
//! in Unix time (ns), so Foxglove, rosbag2 readers (`rosbags`) and Python's
//! `mcap` with `mcap-ros2-support` open it without leakwatch. Logs of earlier
//! versions (channels `frames`, ..., profile `leakwatch`, monotonic log times;
//! JSON messages with JSON Schemas before that) still read: the reader names
//! a channel by the last part of its topic and follows its `message_encoding`.
//!
//! - [`LogWriter`]: a writer thread fed through a bounded channel; chunked,
//!   zstd-compressed, flushed at least every 2 s, so a killed recorder
//!   leaves a file readable up to its last complete chunk; a new file every
//!   hour ([`parts`]).
//! - [`LogReader`]: every channel back into the frame types, bit for bit;
//!   a truncated file yields everything up to its last complete chunk.
//! - [`repair`]: a killed recorder's file (no summary, a cut last chunk) or a
//!   damaged one rewritten as a complete MCAP file with what is intact.
//! - [`resume`]: a restarted recorder continues the log in a numbered part,
//!   the frames in no part recorded as a gap.
//! - [`export_csv`]: one CSV per channel, and the frames again in the
//!   dataset format (`t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c`) that
//!   `leakwatch replay` reads.

use std::fmt;
use std::path::PathBuf;

use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};

mod export;
pub mod info;
pub mod msg;
pub mod parts;
mod reader;
pub mod record;
mod repair;
pub mod resume;
pub mod rosbag2;
pub mod shell;
mod writer;

pub use export::export_csv;
pub use info::{Info, CHANNEL_ORDER};
pub use msg::{Message, SensorFrameBatch};
pub use parts::{rotated_part, with_continuations};
pub use reader::{channel_name, ChannelInfo, Log, LogReader};
pub use record::Record;
pub use repair::{repair, RepairSummary};
pub use writer::{channel_topic, Encoding, LogWriter, WriterOptions, WriterSummary, OFFERED_QOS_PROFILES};

/// The name of the metadata record that holds the configuration of the run.
pub const CONFIG_METADATA: &str = "leakwatch.config";
/// The key of the configuration (TOML text) in the [`CONFIG_METADATA`] record.
pub const CONFIG_KEY: &str = "toml";
/// The name of the metadata record of the recorder (rig, command, clocks, format).
pub const LEAKWATCH_METADATA: &str = "leakwatch";

/// The MCAP channel of the [`msg::SensorFrameBatch`]es: every sensor frame,
/// in columns (the `frames` channel then holds every
/// [`WriterOptions::frames_every`]-th frame, for plotting).
pub const FRAME_BATCHES_CHANNEL: &str = "frame_batches";

/// The MCAP channel of [`GapRecord`]s.
pub const GAPS_CHANNEL: &str = "gaps";
/// The type name of [`GapRecord`]s: their JSON Schema's name in JSON logs, and the
/// `leakwatch_type` of the `gaps` channel (the CDR schema is `leakwatch_msgs/msg/Gap`).
pub const GAP_SCHEMA_NAME: &str = "leakwatch.Gap.v1";

/// One item for the log, with the recorder's receive time
/// (`CLOCK_MONOTONIC`, ns) where it has one.
/// (Frames travel by value through a bounded channel to the writer thread; the
/// size difference between variants is the frames', boxing would allocate per frame.)
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub enum Entry {
    /// A sensor frame and its receive time, ns.
    Frame(SensorFrame, u64),
    /// An estimate and its receive time, ns.
    Estimate(EstimateFrame, u64),
    /// A leak event and its receive time, ns.
    Event(LeakEventFrame, u64),
    /// A health frame and its receive time, ns.
    Health(HealthFrame, u64),
    /// A stats frame and its receive time, ns.
    Stats(StatsFrame, u64),
    /// Frames missing from a sequence.
    Gap(GapRecord),
}

impl Entry {
    /// When the recorder received it, `CLOCK_MONOTONIC` ns.
    pub fn recv_mono_ns(&self) -> u64 {
        match self {
            Entry::Frame(_, t)
            | Entry::Estimate(_, t)
            | Entry::Event(_, t)
            | Entry::Health(_, t)
            | Entry::Stats(_, t) => *t,
            Entry::Gap(g) => g.recv_mono_ns,
        }
    }
}

/// Frames missing from one topic's sequence, as the recorder saw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GapRecord {
    /// The topic.
    pub topic: Topic,
    /// The sequence number that was expected.
    pub expected_seq: u64,
    /// The sequence number that came.
    pub got_seq: u64,
    /// Frames missing (`got_seq − expected_seq`).
    pub missing: u64,
    /// When the frame after the gap was received, `CLOCK_MONOTONIC` ns.
    pub recv_mono_ns: u64,
}

/// An error of the log, naming the file.
#[derive(Debug)]
pub enum RecorderError {
    /// An I/O error on this file.
    Io(PathBuf, std::io::Error),
    /// The MCAP library refused this file.
    Mcap(PathBuf, String),
    /// A message in this file, on this channel, could not be decoded.
    Decode {
        /// The file.
        path: PathBuf,
        /// The channel topic.
        channel: String,
        /// The MCAP message sequence number.
        sequence: u32,
        /// What was wrong.
        problem: String,
    },
    /// The writer thread had stopped before (its error was returned then).
    WriterStopped,
    /// The writer thread could not start or failed.
    Thread(String),
}

impl fmt::Display for RecorderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RecorderError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            RecorderError::Mcap(p, e) => write!(f, "{}: MCAP: {e}", p.display()),
            RecorderError::Decode {
                path,
                channel,
                sequence,
                problem,
            } => write!(
                f,
                "{}: channel {channel}, message {sequence}: {problem}",
                path.display()
            ),
            RecorderError::WriterStopped => write!(f, "the log writer had stopped on an earlier error"),
            RecorderError::Thread(e) => write!(f, "log writer thread: {e}"),
        }
    }
}

impl std::error::Error for RecorderError {}

impl RecorderError {
    /// The error of the MCAP library on `path` as a [`RecorderError`]: an I/O
    /// error (a full disk, a file too large) keeps its reason and becomes
    /// [`RecorderError::Io`] (the library's own message names no reason).
    pub fn from_mcap(path: &std::path::Path, e: mcap::McapError) -> RecorderError {
        if let mcap::McapError::Io(io) = e {
            return RecorderError::Io(path.to_path_buf(), io);
        }
        // an I/O error wrapped deeper (a record the binary writer could not write)
        let mut source: Option<&(dyn std::error::Error + 'static)> = std::error::Error::source(&e);
        while let Some(s) = source {
            if let Some(io) = s.downcast_ref::<std::io::Error>() {
                let copy = match io.raw_os_error() {
                    Some(code) => std::io::Error::from_raw_os_error(code),
                    None => std::io::Error::new(io.kind(), io.to_string()),
                };
                return RecorderError::Io(path.to_path_buf(), copy);
            }
            source = s.source();
        }
        RecorderError::Mcap(path.to_path_buf(), e.to_string())
    }

    /// Whether this is an error of writing the log file (I/O, or the MCAP
    /// library refusing to write): a recorder restarted on the same disk would
    /// fail the same way.
    pub fn is_write_error(&self) -> bool {
        matches!(self, RecorderError::Io(..) | RecorderError::Mcap(..))
    }
}
