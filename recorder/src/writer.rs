//! The MCAP log writer: a thread that owns the file, fed through a bounded
//! crossbeam channel, so a slow disk never stalls the subscribing loop.

use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, TrySendError};
use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame};
use mcap::records::MessageHeader;
use serde_json::json;

use crate::msg::Message;
use crate::record::Record;
use crate::{Entry, GapRecord, RecorderError, CONFIG_KEY, CONFIG_METADATA, GAPS_CHANNEL, GAP_SCHEMA_NAME};

/// How the messages of a log are encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Encoding {
    /// ROS 2 messages in CDR with ros2msg schemas (see [`crate::msg`]): what
    /// the recorder writes.
    #[default]
    Cdr,
    /// JSON objects with JSON Schemas: the encoding of logs before the CDR one,
    /// still written on request so that tests can make such logs.
    Json,
}

/// Settings of a [`LogWriter`].
#[derive(Debug, Clone)]
pub struct WriterOptions {
    /// Target uncompressed chunk size, bytes: a killed recorder loses at most
    /// the chunk being filled.
    pub chunk_size: u64,
    /// Longest time a chunk stays open, ns: slow streams are flushed this often too.
    pub max_chunk_age_ns: u64,
    /// Entries the channel to the writer thread holds; when it is full (the
    /// disk stalled this long) entries are dropped and counted. The channel
    /// allocates and touches every slot up front (about 540 bytes each, an
    /// event frame by value): the default 8192 is 4 s of the two 1 kHz
    /// streams in about 4.4 MB resident.
    pub queue_len: usize,
    /// Compression of the chunks.
    pub compression: Option<mcap::Compression>,
    /// zstd level of the chunks (1-22; 0: zstd's default, 3). Level 9 takes
    /// about 1 % of a core for the 1 kHz streams and writes ~2 % less than 3.
    pub compression_level: u32,
    /// The encoding of the messages.
    pub encoding: Encoding,
    /// Metadata written into the file (`leakwatch` record): rig id, command line, ...
    pub metadata: BTreeMap<String, String>,
    /// The configuration the run used (TOML), written as the metadata record
    /// [`CONFIG_METADATA`] with the key [`CONFIG_KEY`].
    pub config_toml: Option<String>,
    /// Replace an existing log file (`--force`); a symbolic link is never followed.
    pub overwrite: bool,
    /// The rig whose topics are logged: the channels are `/leakwatch/<rig>/<topic>`
    /// (see [`channel_topic`]), the live view's topic names.
    pub rig: String,
    /// Wall clock minus `CLOCK_MONOTONIC`, ns, that turns each record's
    /// monotonic stamp into its `log_time` (Unix time, ns); `None`: this
    /// process's [`bus::epoch_offset_ns`] (from `LEAKWATCH_EPOCH_OFFSET_NS` in a
    /// stage of `leakwatch run`, so the log and the live view agree).
    pub epoch_offset_ns: Option<i64>,
}

impl Default for WriterOptions {
    fn default() -> Self {
        WriterOptions {
            chunk_size: 256 * 1024,
            max_chunk_age_ns: 1_000_000_000,
            queue_len: 8_192,
            compression: Some(mcap::Compression::Zstd),
            compression_level: 9,
            encoding: Encoding::Cdr,
            metadata: BTreeMap::new(),
            config_toml: None,
            overwrite: false,
            rig: "rig1".into(),
            epoch_offset_ns: None,
        }
    }
}

/// What a finished [`LogWriter`] wrote.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct WriterSummary {
    /// The file.
    pub path: PathBuf,
    /// Messages written, per channel topic.
    pub messages: BTreeMap<String, u64>,
    /// Entries dropped because the queue was full.
    pub dropped: u64,
    /// Bytes of the finished file.
    pub bytes: u64,
}

/// Writes one MCAP log: a channel per topic plus `gaps`, ROS 2 messages in CDR
/// with their ros2msg schemas (see [`crate::msg`]; JSON with
/// [`Encoding::Json`]), zstd-compressed chunks of about [`WriterOptions::chunk_size`].
///
/// A rosbag2 file: MCAP profile `ros2`, channels `/leakwatch/<rig>/<topic>`
/// ([`channel_topic`]) with the metadata `offered_qos_profiles`
/// ([`OFFERED_QOS_PROFILES`]), so rosbag2 readers (`ros2 bag`, Python's
/// `rosbags`) open it as it is.
///
/// One time base: each message's `log_time` and `publish_time` are both the
/// record's own `CLOCK_MONOTONIC` stamp turned into Unix time, ns (stamp +
/// [`WriterOptions::epoch_offset_ns`], the wall clock minus the monotonic
/// clock fixed once at the start of the run): `acq_mono_ns` for frames,
/// estimates and events (the acquisition of the sample), `mono_ns` for health
/// and stats, `recv_mono_ns` for gaps (the recorder's receive time where a
/// stamp is 0). The times never go back when NTP steps the wall clock, and the
/// live view puts the same time on the same message; the messages keep their
/// monotonic stamps (latency). The `leakwatch` metadata record holds the offset
/// (`epoch_offset_ns`) and the wall clock and the monotonic clock read together
/// when the file was created (`wall_clock_ns_at_start`, `monotonic_ns_at_start`).
/// `sequence` is the frame's `seq` (truncated to 32 bits) where it has one,
/// else a count per channel.
pub struct LogWriter {
    tx: Option<Sender<Entry>>,
    thread: Option<JoinHandle<Result<WriterSummary, RecorderError>>>,
    dropped: u64,
}

struct Channels {
    frames: u16,
    estimates: u16,
    events: u16,
    health: u16,
    stats: u16,
    gaps: u16,
    /// Wall clock minus `CLOCK_MONOTONIC`, ns: stamp + this = `log_time`.
    epoch_offset_ns: i64,
}

/// The QoS a rosbag2 recording of the topics would have offered (the MCAP
/// `ros2` profile requires `offered_qos_profiles` on every channel): reliable,
/// keep last 1000, volatile, the defaults of `ros2 bag record`, in its YAML.
pub const OFFERED_QOS_PROFILES: &str = "- history: keep_last
  depth: 1000
  reliability: reliable
  durability: volatile
  deadline:
    sec: 9223372036
    nsec: 854775807
  lifespan:
    sec: 9223372036
    nsec: 854775807
  liveliness: automatic
  liveliness_lease_duration:
    sec: 9223372036
    nsec: 854775807
  avoid_ros_namespace_conventions: false
";

/// The MCAP channel (ROS 2 topic) of `topic` (`frames`, ..., `gaps`) of `rig`:
/// `/leakwatch/<rig>/<topic>`, the live view's topic name. The reader takes the
/// last part of a channel's topic, so logs of earlier versions (channels
/// `frames`, ...) still read.
pub fn channel_topic(rig: &str, topic: &str) -> String {
    format!("/leakwatch/{rig}/{topic}")
}

/// Adds the schema and channel of topic `topic` (`frames`, ...) of `rig`, type
/// `R` (iceoryx2 type name `type_name`, in the channel's metadata), in `encoding`.
fn add_channel<R: Message>(
    w: &mut mcap::Writer<File>,
    encoding: Encoding,
    rig: &str,
    topic: &str,
    type_name: &str,
    json_schema: impl FnOnce() -> (String, serde_json::Value),
) -> Result<u16, mcap::McapError> {
    let metadata = BTreeMap::from([
        ("leakwatch_topic".to_string(), topic.to_string()),
        ("leakwatch_type".to_string(), type_name.to_string()),
        (
            "offered_qos_profiles".to_string(),
            OFFERED_QOS_PROFILES.to_string(),
        ),
    ]);
    let sid = match encoding {
        Encoding::Cdr => w.add_schema(R::MSG_TYPE, "ros2msg", R::DEFINITION.as_bytes())?,
        Encoding::Json => {
            let (name, schema) = json_schema();
            let schema = serde_json::to_vec(&schema).unwrap_or_default();
            w.add_schema(&name, "jsonschema", &schema)?
        }
    };
    let message_encoding = match encoding {
        Encoding::Cdr => "cdr",
        Encoding::Json => "json",
    };
    w.add_channel(sid, &channel_topic(rig, topic), message_encoding, &metadata)
}

fn add_frame_channel<R: Record + Message>(
    w: &mut mcap::Writer<File>,
    encoding: Encoding,
    rig: &str,
) -> Result<u16, mcap::McapError> {
    add_channel::<R>(w, encoding, rig, R::TOPIC.as_str(), R::SCHEMA_NAME, || {
        (R::SCHEMA_NAME.to_string(), R::schema())
    })
}

impl LogWriter {
    /// Creates `path` (an existing file only with `options.overwrite`; never
    /// through a symbolic link), writes the header, schemas and channels, and
    /// starts the writer thread.
    pub fn create(path: &Path, options: WriterOptions) -> Result<LogWriter, RecorderError> {
        let mcap_err = |e: mcap::McapError| RecorderError::from_mcap(path, e);
        let file = dataset::output::create_file(path, options.overwrite, &[])
            .map_err(|e| RecorderError::Io(path.to_path_buf(), e))?;
        let mut w = mcap::WriteOptions::new()
            .compression(options.compression)
            .compression_level(options.compression_level)
            .chunk_size(Some(options.chunk_size))
            .profile("ros2")
            .create(file)
            .map_err(mcap_err)?;
        let mut meta = options.metadata.clone();
        let format = match options.encoding {
            Encoding::Cdr => {
                "leakwatch frames as ROS 2 messages (CDR, ros2msg schemas in the file), see leakwatch_msgs/msg"
            }
            Encoding::Json => "leakwatch frames as JSON, see frames/README.md",
        };
        meta.insert("format".into(), format.into());
        let offset = options.epoch_offset_ns.unwrap_or_else(bus::epoch_offset_ns);
        let mono = bus::monotonic_ns();
        meta.insert("wall_clock_ns_at_start".into(), bus::wall_clock_ns().to_string());
        meta.insert("monotonic_ns_at_start".into(), mono.to_string());
        meta.insert("epoch_offset_ns".into(), offset.to_string());
        meta.insert(
            "clock".into(),
            "log_time = publish_time = Unix time ns: the record's own CLOCK_MONOTONIC stamp \
             (acq_mono_ns, mono_ns or recv_mono_ns) + epoch_offset_ns (wall clock minus \
             CLOCK_MONOTONIC, fixed at the start of the run)"
                .into(),
        );
        w.write_metadata(&mcap::records::Metadata {
            name: "leakwatch".into(),
            metadata: meta,
        })
        .map_err(mcap_err)?;
        if let Some(toml) = &options.config_toml {
            w.write_metadata(&mcap::records::Metadata {
                name: CONFIG_METADATA.into(),
                metadata: BTreeMap::from([(CONFIG_KEY.to_string(), toml.clone())]),
            })
            .map_err(mcap_err)?;
        }
        let enc = options.encoding;
        let rig = options.rig.as_str();
        let channels = Channels {
            frames: add_frame_channel::<SensorFrame>(&mut w, enc, rig).map_err(mcap_err)?,
            estimates: add_frame_channel::<EstimateFrame>(&mut w, enc, rig).map_err(mcap_err)?,
            events: add_frame_channel::<LeakEventFrame>(&mut w, enc, rig).map_err(mcap_err)?,
            health: add_frame_channel::<HealthFrame>(&mut w, enc, rig).map_err(mcap_err)?,
            stats: add_frame_channel::<StatsFrame>(&mut w, enc, rig).map_err(mcap_err)?,
            epoch_offset_ns: offset,
            gaps: add_channel::<GapRecord>(&mut w, enc, rig, GAPS_CHANNEL, GAP_SCHEMA_NAME, || {
                (GAP_SCHEMA_NAME.to_string(), GapRecord::schema())
            })
            .map_err(mcap_err)?,
        };
        // the header, schemas and channels are on disk before any data
        w.flush().map_err(mcap_err)?;
        let (tx, rx) = crossbeam_channel::bounded(options.queue_len.max(1));
        let path = path.to_path_buf();
        let thread = std::thread::Builder::new()
            .name("mcap-writer".into())
            .spawn(move || write_loop(w, channels, rx, path, options))
            .map_err(|e| RecorderError::Thread(e.to_string()))?;
        Ok(LogWriter {
            tx: Some(tx),
            thread: Some(thread),
            dropped: 0,
        })
    }

    /// Queues an entry without blocking. Returns false if the queue was full
    /// (the entry is dropped and counted). If the writer thread has stopped on an
    /// error (a full disk, an I/O error), returns that error, which names the
    /// file and the reason; later calls return [`RecorderError::WriterStopped`].
    pub fn write(&mut self, entry: Entry) -> Result<bool, RecorderError> {
        let Some(tx) = &self.tx else {
            return Err(RecorderError::WriterStopped);
        };
        match tx.try_send(entry) {
            Ok(()) => Ok(true),
            Err(TrySendError::Full(_)) => {
                self.dropped += 1;
                Ok(false)
            }
            Err(TrySendError::Disconnected(_)) => {
                self.tx = None;
                Err(self.stopped_error())
            }
        }
    }

    /// The error the writer thread stopped on (it has stopped).
    fn stopped_error(&mut self) -> RecorderError {
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Err(e))) => e,
            Some(Err(_)) => RecorderError::Thread("the writer thread panicked".into()),
            Some(Ok(Ok(_))) | None => RecorderError::WriterStopped,
        }
    }

    /// Entries dropped so far because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Writes everything queued, the summary and the footer, and closes the file.
    pub fn finish(mut self) -> Result<WriterSummary, RecorderError> {
        self.tx = None;
        let thread = self.thread.take().ok_or(RecorderError::WriterStopped)?;
        let mut summary = thread
            .join()
            .map_err(|_| RecorderError::Thread("the writer thread panicked".into()))??;
        summary.dropped = self.dropped;
        Ok(summary)
    }
}

impl Drop for LogWriter {
    fn drop(&mut self) {
        self.tx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn write_loop(
    mut w: mcap::Writer<File>,
    ch: Channels,
    rx: Receiver<Entry>,
    path: PathBuf,
    options: WriterOptions,
) -> Result<WriterSummary, RecorderError> {
    let mcap_err = |e: mcap::McapError| RecorderError::from_mcap(&path, e);
    let mut counters = [0u64; 6];
    let mut counter_gaps = 0u32;
    let mut last_flush = bus::monotonic_ns();
    let tick = std::time::Duration::from_nanos(options.max_chunk_age_ns.clamp(1_000_000, 10_000_000_000));
    let mut buf = Vec::with_capacity(4096);
    loop {
        let entry = match rx.recv_timeout(tick) {
            Ok(e) => Some(e),
            Err(crossbeam_channel::RecvTimeoutError::Timeout) => None,
            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
        };
        if let Some(entry) = entry {
            let (channel_id, idx, sequence, stamp) = match &entry {
                Entry::Frame(f, _) => (ch.frames, 0, f.seq as u32, f.acq_mono_ns),
                Entry::Estimate(f, _) => (ch.estimates, 1, f.seq as u32, f.acq_mono_ns),
                Entry::Event(f, _) => (ch.events, 2, f.seq as u32, f.acq_mono_ns),
                Entry::Health(f, _) => (ch.health, 3, f.seq as u32, f.mono_ns),
                Entry::Stats(f, _) => (ch.stats, 4, counters[4] as u32, f.mono_ns),
                Entry::Gap(g) => {
                    counter_gaps = counter_gaps.wrapping_add(1);
                    (ch.gaps, 5, counter_gaps, g.recv_mono_ns)
                }
            };
            // one clock for both: the record's own stamp (the receive time if it
            // has none) as Unix time
            let mono = if stamp > 0 { stamp } else { entry.recv_mono_ns() };
            let time = bus::epoch_ns_with(mono, ch.epoch_offset_ns);
            encode(&entry, options.encoding, &mut buf).map_err(RecorderError::Thread)?;
            w.write_to_known_channel(
                &MessageHeader {
                    channel_id,
                    sequence,
                    log_time: time,
                    publish_time: time,
                },
                &buf,
            )
            .map_err(mcap_err)?;
            counters[idx] += 1;
        }
        let now = bus::monotonic_ns();
        if now.saturating_sub(last_flush) >= options.max_chunk_age_ns {
            // close the open chunk and hand it to the kernel: a crash loses at most one chunk
            w.flush().map_err(mcap_err)?;
            last_flush = now;
        }
    }
    w.finish().map_err(mcap_err)?;
    drop(w);
    let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    let names = ["frames", "estimates", "events", "health", "stats", GAPS_CHANNEL];
    Ok(WriterSummary {
        path,
        messages: names.iter().map(|n| n.to_string()).zip(counters).collect(),
        dropped: 0,
        bytes,
    })
}

/// The message of `entry` in `encoding`, written into `buf` (cleared first).
fn encode(entry: &Entry, encoding: Encoding, buf: &mut Vec<u8>) -> Result<(), String> {
    match encoding {
        Encoding::Cdr => match entry {
            Entry::Frame(f, _) => f.to_cdr(buf),
            Entry::Estimate(f, _) => f.to_cdr(buf),
            Entry::Event(f, _) => f.to_cdr(buf),
            Entry::Health(f, _) => f.to_cdr(buf),
            Entry::Stats(f, _) => f.to_cdr(buf),
            Entry::Gap(g) => g.to_cdr(buf),
        },
        Encoding::Json => {
            let json = match entry {
                Entry::Frame(f, _) => f.to_json(),
                Entry::Estimate(f, _) => f.to_json(),
                Entry::Event(f, _) => f.to_json(),
                Entry::Health(f, _) => f.to_json(),
                Entry::Stats(f, _) => f.to_json(),
                Entry::Gap(g) => g.to_json(),
            };
            buf.clear();
            serde_json::to_writer(&mut *buf, &json).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

impl GapRecord {
    /// The JSON object (the JSON encoding).
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "topic": self.topic.as_str(),
            "expected_seq": self.expected_seq,
            "got_seq": self.got_seq,
            "missing": self.missing,
            "recv_mono_ns": self.recv_mono_ns,
        })
    }

    /// The JSON Schema of [`GapRecord::to_json`].
    pub fn schema() -> serde_json::Value {
        json!({
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": GAP_SCHEMA_NAME,
            "description": "frames missing from a topic's sequence as seen by the recorder",
            "type": "object",
            "properties": {
                "topic": {"type": "string"},
                "expected_seq": {"type": "integer", "minimum": 0},
                "got_seq": {"type": "integer", "minimum": 0},
                "missing": {"type": "integer", "minimum": 0},
                "recv_mono_ns": {"type": "integer", "minimum": 0},
            }
        })
    }
}
