//! The MCAP log writer: a thread that owns the file, fed through a bounded
//! crossbeam channel, so a slow disk never stalls the subscribing loop.

use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, Sender, TrySendError};
use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};
use mcap::records::MessageHeader;
use serde_json::json;

use crate::record::Record;
use crate::{Entry, GapRecord, RecorderError, GAPS_CHANNEL, GAP_SCHEMA_NAME};

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
    /// allocates and touches every slot up front (about 512 bytes each, an
    /// estimate frame by value): the default 8192 is 4 s of the two 1 kHz
    /// streams in about 4 MB resident.
    pub queue_len: usize,
    /// Compression of the chunks.
    pub compression: Option<mcap::Compression>,
    /// Metadata written into the file (`leakwatch` record): rig id, command line, ...
    pub metadata: BTreeMap<String, String>,
    /// Replace an existing log file (`--force`); a symbolic link is never followed.
    pub overwrite: bool,
}

impl Default for WriterOptions {
    fn default() -> Self {
        WriterOptions {
            chunk_size: 256 * 1024,
            max_chunk_age_ns: 1_000_000_000,
            queue_len: 8_192,
            compression: Some(mcap::Compression::Zstd),
            metadata: BTreeMap::new(),
            overwrite: false,
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

/// Writes one MCAP log: a channel per topic plus `gaps`, JSON messages with
/// JSON Schemas, zstd-compressed chunks of about [`WriterOptions::chunk_size`].
///
/// Each message's `log_time` is the receive time mapped onto the wall clock
/// (ns since the Unix epoch, so viewers show real dates), its `publish_time`
/// the frame's own monotonic stamp (`acq_mono_ns` or `mono_ns`), and its
/// `sequence` the frame's `seq` (truncated to 32 bits) where it has one.
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
}

fn add_channel<R: Record>(
    w: &mut mcap::Writer<File>,
    metadata: &BTreeMap<String, String>,
) -> Result<u16, mcap::McapError> {
    let schema = serde_json::to_vec(&R::schema()).unwrap_or_default();
    let sid = w.add_schema(R::SCHEMA_NAME, "jsonschema", &schema)?;
    w.add_channel(sid, R::TOPIC.as_str(), "json", metadata)
}

impl LogWriter {
    /// Creates `path` (an existing file only with `options.overwrite`; never
    /// through a symbolic link), writes the header, schemas and channels, and
    /// starts the writer thread.
    pub fn create(path: &Path, options: WriterOptions) -> Result<LogWriter, RecorderError> {
        let mcap_err = |e: mcap::McapError| RecorderError::Mcap(path.to_path_buf(), e.to_string());
        let file = dataset::output::create_file(path, options.overwrite, &[])
            .map_err(|e| RecorderError::Io(path.to_path_buf(), e))?;
        let mut w = mcap::WriteOptions::new()
            .compression(options.compression)
            .chunk_size(Some(options.chunk_size))
            .profile("leakwatch")
            .create(file)
            .map_err(mcap_err)?;
        let mut meta = options.metadata.clone();
        meta.insert(
            "format".into(),
            "leakwatch frames as JSON, see frames/README.md".into(),
        );
        w.write_metadata(&mcap::records::Metadata {
            name: "leakwatch".into(),
            metadata: meta,
        })
        .map_err(mcap_err)?;
        let m = |t: Topic| BTreeMap::from([("leakwatch_topic".to_string(), t.as_str().to_string())]);
        let channels = Channels {
            frames: add_channel::<SensorFrame>(&mut w, &m(Topic::Frames)).map_err(mcap_err)?,
            estimates: add_channel::<EstimateFrame>(&mut w, &m(Topic::Estimates)).map_err(mcap_err)?,
            events: add_channel::<LeakEventFrame>(&mut w, &m(Topic::Events)).map_err(mcap_err)?,
            health: add_channel::<HealthFrame>(&mut w, &m(Topic::Health)).map_err(mcap_err)?,
            stats: add_channel::<StatsFrame>(&mut w, &m(Topic::Stats)).map_err(mcap_err)?,
            gaps: {
                let schema = serde_json::to_vec(&GapRecord::schema()).unwrap_or_default();
                let sid = w
                    .add_schema(GAP_SCHEMA_NAME, "jsonschema", &schema)
                    .map_err(mcap_err)?;
                w.add_channel(sid, GAPS_CHANNEL, "json", &BTreeMap::new())
                    .map_err(mcap_err)?
            },
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
    /// (the entry is dropped and counted); an error if the writer thread
    /// has stopped (its error is returned by [`LogWriter::finish`]).
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
            Err(TrySendError::Disconnected(_)) => Err(RecorderError::WriterStopped),
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

fn realtime_minus_monotonic_ns() -> i128 {
    let wall = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as i128)
        .unwrap_or(0);
    wall - bus::monotonic_ns() as i128
}

fn write_loop(
    mut w: mcap::Writer<File>,
    ch: Channels,
    rx: Receiver<Entry>,
    path: PathBuf,
    options: WriterOptions,
) -> Result<WriterSummary, RecorderError> {
    let mcap_err = |e: mcap::McapError| RecorderError::Mcap(path.clone(), e.to_string());
    let offset = realtime_minus_monotonic_ns();
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
            let log_time = (entry.recv_mono_ns() as i128 + offset).max(0) as u64;
            buf.clear();
            let (channel_id, idx, sequence, publish_time) = match &entry {
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
            let json = match &entry {
                Entry::Frame(f, _) => f.to_json(),
                Entry::Estimate(f, _) => f.to_json(),
                Entry::Event(f, _) => f.to_json(),
                Entry::Health(f, _) => f.to_json(),
                Entry::Stats(f, _) => f.to_json(),
                Entry::Gap(g) => g.to_json(),
            };
            serde_json::to_writer(&mut buf, &json).map_err(|e| RecorderError::Thread(e.to_string()))?;
            w.write_to_known_channel(
                &MessageHeader {
                    channel_id,
                    sequence,
                    log_time,
                    publish_time,
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

impl GapRecord {
    /// The JSON object.
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
