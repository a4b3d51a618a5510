//! The MCAP log writer: a thread that owns the file, fed through a bounded
//! crossbeam channel, so a slow disk never stalls the subscribing loop.

use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, TrySendError};
use mcap::records::MessageHeader;
use serde_json::json;

use crate::msg::{Message, SensorFrameBatch};
#[allow(unused_imports)] // (named in the docs)
use crate::parts::rotated_part;
use crate::record::Record;
use crate::{Entry, GapRecord, RecorderError, FRAME_BATCHES_CHANNEL, GAPS_CHANNEL, GAP_SCHEMA_NAME};
#[allow(unused_imports)] // (named in the docs)
use crate::{CONFIG_KEY, CONFIG_METADATA};

mod rotation;

use rotation::open_part;

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
    /// Longest time a chunk stays open, ns, by the entries' receive times (the
    /// span from the chunk's first entry to the newest) or by the clock since
    /// its first entry came (a quiet stream): a killed recorder loses at most
    /// this much.
    pub max_chunk_age_ns: u64,
    /// Sensor frames per [`SensorFrameBatch`] message on the channel
    /// [`FRAME_BATCHES_CHANNEL`] (100: 100 ms at 1 kHz), the lossless record of
    /// every frame; a batch also ends at a jump in the sequence numbers, at
    /// the end of a stream and before a chunk is closed. 0: no batches, every
    /// frame a message on the `frames` channel (the layout of earlier versions).
    /// Batches are CDR only ([`Encoding::Json`] writes every frame).
    pub frame_batch_len: usize,
    /// The time after which the file is closed (summary and footer) and the
    /// log continues in the next part, [`rotated_part`] (`run.1.mcap`, ...),
    /// ns, by the entries' receive times: the MCAP writer keeps an index entry
    /// per chunk in memory until its file is closed, so a part of an hour
    /// (the default; 1800 chunks of 2 s) keeps the recorder's memory flat over
    /// days. The readers join the parts as one log. Tests make it small.
    pub part_span_ns: u64,
    /// With batches: the `frames` channel (for plotting, e.g. in Foxglove)
    /// holds every `frames_every`-th frame by sequence number (40: 25 Hz at
    /// 1 kHz) and every frame with a flag (after a gap, end of stream).
    pub frames_every: u64,
    /// Entries the channel to the writer thread holds; when it is full (the
    /// disk stalled this long) entries are dropped and counted. The channel
    /// allocates and touches every slot up front (about 540 bytes each, an
    /// event frame by value): the default 8192 is 4 s of the two 1 kHz
    /// streams in about 4.4 MB resident.
    pub queue_len: usize,
    /// Compression of the chunks.
    pub compression: Option<mcap::Compression>,
    /// zstd level of the chunks (1-22; 0: zstd's default, 3). 9 takes well
    /// under 1 % of a core for a rig's streams; 18 writes about 10 % less but
    /// takes ten times the CPU and tens of MB per chunk, and recorders beside
    /// a loaded pipeline then lose frames (recorder/tests/size.rs measures).
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
            chunk_size: 1024 * 1024,
            max_chunk_age_ns: 2_000_000_000,
            frame_batch_len: 100,
            frames_every: 40,
            part_span_ns: 3_600_000_000_000,
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
    /// Records written, per channel (`frames`, ..., `gaps`, the last part of
    /// its topic): `frames` counts every sensor frame logged, in a batch or
    /// alone; `frame_batches` (with batches) the batch messages.
    pub messages: BTreeMap<String, u64>,
    /// Entries dropped because the queue was full.
    pub dropped: u64,
    /// Bytes of the finished files.
    pub bytes: u64,
    /// Every file written: `path`, then its continuations ([`rotated_part`]).
    pub parts: Vec<PathBuf>,
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
    /// The channel of the frame batches (`None`: every frame on `frames`).
    frame_batches: Option<u16>,
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

impl LogWriter {
    /// Creates `path` (an existing file only with `options.overwrite`; never
    /// through a symbolic link), writes the header, schemas and channels, and
    /// starts the writer thread.
    pub fn create(path: &Path, options: WriterOptions) -> Result<LogWriter, RecorderError> {
        let offset = options.epoch_offset_ns.unwrap_or_else(bus::epoch_offset_ns);
        let (w, channels) = open_part(path, &options, offset, 0)?;
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

/// The open file of the writer thread: the MCAP writer, its channels, the
/// frame batch being filled and the counts.
struct Sink {
    w: mcap::Writer<File>,
    ch: Channels,
    path: PathBuf,
    options: WriterOptions,
    /// Records written per channel: frames (every frame logged), estimates,
    /// events, health, stats, gaps, frame batches.
    counters: [u64; 7],
    counter_gaps: u32,
    buf: Vec<u8>,
    /// The frames not yet written as a batch, and the `log_time` of its first, ns.
    batch: SensorFrameBatch,
    batch_time: u64,
    /// The receive time of the open chunk's first entry, and `CLOCK_MONOTONIC`
    /// when the writer took it, ns.
    chunk_first: Option<(u64, u64)>,
    /// The receive time of the open part's first entry, ns.
    part_first: Option<u64>,
    /// The files written, the open one last, and the bytes of those closed.
    parts: Vec<PathBuf>,
    closed_bytes: u64,
}

impl Sink {
    fn new(w: mcap::Writer<File>, ch: Channels, path: PathBuf, options: WriterOptions) -> Sink {
        let path_copy = path.clone();
        let batch = SensorFrameBatch::with_capacity(options.frame_batch_len);
        Sink {
            w,
            ch,
            path,
            options,
            counters: [0; 7],
            counter_gaps: 0,
            buf: Vec::with_capacity(4096),
            batch,
            batch_time: 0,
            chunk_first: None,
            part_first: None,
            parts: vec![path_copy],
            closed_bytes: 0,
        }
    }

    fn mcap_err(&self, e: mcap::McapError) -> RecorderError {
        RecorderError::from_mcap(&self.path, e)
    }

    /// Writes the message in `self.buf` on `channel_id`.
    fn put(&mut self, channel_id: u16, sequence: u32, time: u64) -> Result<(), RecorderError> {
        let header = MessageHeader {
            channel_id,
            sequence,
            log_time: time,
            publish_time: time,
        };
        self.w
            .write_to_known_channel(&header, &self.buf)
            .map_err(|e| RecorderError::from_mcap(&self.path, e))
    }

    /// Writes the frames batched so far as one message (none if there are none).
    fn write_batch(&mut self) -> Result<(), RecorderError> {
        let Some(channel_id) = self.ch.frame_batches else {
            return Ok(());
        };
        if self.batch.is_empty() {
            return Ok(());
        }
        self.batch.to_cdr(&mut self.buf);
        self.put(channel_id, self.batch.first_seq as u32, self.batch_time)?;
        self.counters[6] += 1;
        self.batch.clear();
        Ok(())
    }

    /// Logs one entry.
    fn entry(&mut self, entry: &Entry) -> Result<(), RecorderError> {
        let (channel_id, idx, sequence, stamp) = match entry {
            Entry::Frame(f, _) => (self.ch.frames, 0, f.seq as u32, f.acq_mono_ns),
            Entry::Estimate(f, _) => (self.ch.estimates, 1, f.seq as u32, f.acq_mono_ns),
            Entry::Event(f, _) => (self.ch.events, 2, f.seq as u32, f.acq_mono_ns),
            Entry::Health(f, _) => (self.ch.health, 3, f.seq as u32, f.mono_ns),
            Entry::Stats(f, _) => (self.ch.stats, 4, self.counters[4] as u32, f.mono_ns),
            Entry::Gap(g) => {
                self.counter_gaps = self.counter_gaps.wrapping_add(1);
                (self.ch.gaps, 5, self.counter_gaps, g.recv_mono_ns)
            }
        };
        // one clock for both: the record's own stamp (the receive time if it
        // has none) as Unix time
        let mono = if stamp > 0 { stamp } else { entry.recv_mono_ns() };
        let time = bus::epoch_ns_with(mono, self.ch.epoch_offset_ns);
        // by the recorder's receive times (its own clock, whatever the stamps
        // say): a part holds at most part_span_ns of them, a chunk at most
        // max_chunk_age_ns
        let recv = entry.recv_mono_ns();
        match self.part_first {
            Some(first) if recv.saturating_sub(first) >= self.options.part_span_ns => {
                self.rotate()?;
                self.part_first = Some(recv);
            }
            Some(_) => {}
            None => self.part_first = Some(recv),
        }
        match self.chunk_first {
            Some((first, _)) if recv.saturating_sub(first) >= self.options.max_chunk_age_ns => {
                self.flush()?;
                self.chunk_first = Some((recv, bus::monotonic_ns()));
            }
            Some(_) => {}
            None => self.chunk_first = Some((recv, bus::monotonic_ns())),
        }
        self.counters[idx] += 1;
        if let (Entry::Frame(f, _), Some(_)) = (entry, self.ch.frame_batches) {
            if !self.batch.continues_with(f) {
                self.write_batch()?;
            }
            if self.batch.is_empty() {
                self.batch_time = time;
            }
            self.batch.push(f);
            if self.batch.len() >= self.options.frame_batch_len
                || f.flags & frames::sensor_flags::END_OF_STREAM != 0
            {
                self.write_batch()?;
            }
            let every = self.options.frames_every.max(1);
            if !f.seq.is_multiple_of(every) && f.flags == 0 {
                // in its batch only
                return Ok(());
            }
        }
        encode(entry, self.options.encoding, &mut self.buf).map_err(RecorderError::Thread)?;
        self.put(channel_id, sequence, time)
    }

    /// Whether the open chunk's first message came `max_chunk_age_ns` ago by
    /// the clock, `now` (a stream that went quiet).
    fn due(&self, now: u64) -> bool {
        self.chunk_first
            .is_some_and(|(_, came)| now.saturating_sub(came) >= self.options.max_chunk_age_ns)
    }

    /// Writes the open batch, closes the open chunk and hands it to the
    /// kernel: a crash loses at most one chunk.
    fn flush(&mut self) -> Result<(), RecorderError> {
        self.write_batch()?;
        self.w.flush().map_err(|e| self.mcap_err(e))?;
        self.chunk_first = None;
        Ok(())
    }

    /// Writes the open batch, the summary and the footer; what was written.
    fn finish(mut self) -> Result<WriterSummary, RecorderError> {
        self.write_batch()?;
        self.w
            .finish()
            .map_err(|e| RecorderError::from_mcap(&self.path, e))?;
        drop(self.w);
        let bytes = self.closed_bytes + std::fs::metadata(&self.path).map(|m| m.len()).unwrap_or(0);
        let names = [
            "frames",
            "estimates",
            "events",
            "health",
            "stats",
            GAPS_CHANNEL,
            FRAME_BATCHES_CHANNEL,
        ];
        let n = if self.ch.frame_batches.is_some() { 7 } else { 6 };
        Ok(WriterSummary {
            path: self.parts[0].clone(),
            messages: names
                .iter()
                .map(|n| n.to_string())
                .zip(self.counters)
                .take(n)
                .collect(),
            dropped: 0,
            bytes,
            parts: self.parts,
        })
    }
}

fn write_loop(
    w: mcap::Writer<File>,
    ch: Channels,
    rx: Receiver<Entry>,
    path: PathBuf,
    options: WriterOptions,
) -> Result<WriterSummary, RecorderError> {
    // a quiet stream's open chunk is flushed within a quarter of its age bound
    let tick =
        std::time::Duration::from_nanos((options.max_chunk_age_ns / 4).clamp(1_000_000, 1_000_000_000));
    let mut sink = Sink::new(w, ch, path, options);
    loop {
        match rx.recv_timeout(tick) {
            Ok(e) => sink.entry(&e)?,
            Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
        }
        if sink.due(bus::monotonic_ns()) {
            sink.flush()?;
        }
    }
    sink.finish()
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
