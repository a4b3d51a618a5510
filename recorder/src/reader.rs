//! Reading a leakwatch MCAP log back into frames: CDR messages (this
//! version) and JSON ones (earlier versions), by each channel's `message_encoding`.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame};

use crate::msg::SensorFrameBatch;
use crate::{GapRecord, RecorderError, FRAME_BATCHES_CHANNEL};

mod decode;

use decode::decode_as;

/// One channel of a log as read: how it is encoded and what it held.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChannelInfo {
    /// The channel's topic in the file (`/leakwatch/<rig>/frames`; `frames`,
    /// ... in logs of earlier versions). [`Log::channels`] is keyed by its last
    /// part ([`channel_name`]).
    pub topic: String,
    /// The channel's `message_encoding` (`cdr`, or `json` in logs of earlier versions).
    pub message_encoding: String,
    /// The name of its schema (`leakwatch_msgs/msg/SensorFrame`, ...; empty if its record was lost).
    pub schema_name: String,
    /// The encoding of its schema (`ros2msg`, or `jsonschema`).
    pub schema_encoding: String,
    /// The channel's metadata (`leakwatch_topic`, `leakwatch_type`).
    pub metadata: BTreeMap<String, String>,
    /// Messages read.
    pub messages: u64,
    /// The smallest `log_time` of its messages, ns (0 if none).
    pub first_log_time: u64,
    /// The largest `log_time` of its messages, ns (0 if none).
    pub last_log_time: u64,
}

/// Everything in a log, per channel, in file order.
#[derive(Debug, Clone, Default)]
pub struct Log {
    /// Every sensor frame: those of the `frame_batches` channel in a log that
    /// has one (the `frames` channel then holds a thinned copy for plotting,
    /// not read into this), else those of the `frames` channel (logs of
    /// earlier versions).
    pub frames: Vec<SensorFrame>,
    /// The `estimates` channel.
    pub estimates: Vec<EstimateFrame>,
    /// The `events` channel.
    pub events: Vec<LeakEventFrame>,
    /// The `health` channel.
    pub health: Vec<HealthFrame>,
    /// The `stats` channel.
    pub stats: Vec<StatsFrame>,
    /// The `gaps` channel.
    pub gaps: Vec<GapRecord>,
    /// Messages on channels this version does not know (or whose channel
    /// record was in a skipped chunk), skipped.
    pub unknown_messages: u64,
    /// `Some(reason)` if the file ended early (a killed recorder): everything
    /// up to the last complete chunk was read.
    pub truncated: Option<String>,
    /// Damaged chunks that were skipped (declared size above [`MAX_CHUNK_BYTES`]
    /// or different from the data, bad CRC, unknown compression, bad records),
    /// each with its byte offset in the file and the reason.
    pub chunks_skipped: Vec<String>,
    /// Sensor frames lost in the skipped chunks (from the gap in the frames'
    /// sequence numbers around each; before the first frame read, from sequence 0,
    /// where a run starts; a chunk skipped after the last frame is not counted).
    pub frames_lost: u64,
    /// Every channel by name (`frames`, `estimates`, `events`, `health`,
    /// `stats`, `gaps`: the last part of its topic, [`channel_name`]), with its
    /// topic, encoding and message count and times.
    pub channels: BTreeMap<String, ChannelInfo>,
    /// The metadata records by name (`leakwatch`: rig, command, clocks;
    /// [`crate::CONFIG_METADATA`]: the run's configuration), in file order
    /// (a name seen twice: the last record).
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
}

impl Log {
    /// Appends `later`, the next part of the same run's log (the `run-N.mcap` a
    /// restarted recorder writes, continuing after the frames this part holds):
    /// every channel's messages after this part's, sensor frames this part already
    /// holds (sequence number not above its last) left out; the damage of both
    /// (`truncated` names the part it comes from); channel counts summed (the
    /// frames left out not counted again) and their time spans joined; metadata
    /// records of both (this part's where both have one).
    pub fn append(&mut self, later: Log, later_name: &str) {
        let last_seq = self.frames.last().map(|f| f.seq);
        let held_before = self.frames.len();
        let offered = later.frames.len();
        self.frames.extend(
            later
                .frames
                .into_iter()
                .filter(|f| last_seq.is_none_or(|l| f.seq > l)),
        );
        // (the frames left out are not counted twice on their channel)
        let repeated = offered - (self.frames.len() - held_before);
        self.estimates.extend(later.estimates);
        self.events.extend(later.events);
        self.health.extend(later.health);
        self.stats.extend(later.stats);
        self.gaps.extend(later.gaps);
        self.unknown_messages += later.unknown_messages;
        if let Some(t) = later.truncated {
            let t = format!("{later_name}: {t}");
            self.truncated = Some(match self.truncated.take() {
                Some(mine) => format!("{mine}; {t}"),
                None => t,
            });
        }
        self.chunks_skipped.extend(
            later
                .chunks_skipped
                .into_iter()
                .map(|c| format!("{later_name}: {c}")),
        );
        self.frames_lost += later.frames_lost;
        let batched = later.channels.contains_key(FRAME_BATCHES_CHANNEL);
        for (topic, c) in later.channels {
            match self.channels.get_mut(&topic) {
                Some(mine) => {
                    if c.messages > 0 {
                        mine.first_log_time = if mine.messages > 0 {
                            mine.first_log_time.min(c.first_log_time)
                        } else {
                            c.first_log_time
                        };
                        mine.last_log_time = mine.last_log_time.max(c.last_log_time);
                    }
                    // (with batches, the frames channel holds a thinned copy: its messages are counted as they are)
                    mine.messages += if topic == frames::Topic::Frames.as_str() && !batched {
                        c.messages.saturating_sub(repeated as u64)
                    } else {
                        c.messages
                    };
                }
                None => {
                    self.channels.insert(topic, c);
                }
            }
        }
        for (name, record) in later.metadata {
            self.metadata.entry(name).or_insert(record);
        }
    }

    /// The configuration the run used (TOML), if the log holds it.
    pub fn config_toml(&self) -> Option<&str> {
        self.metadata
            .get(crate::CONFIG_METADATA)
            .and_then(|m| m.get(crate::CONFIG_KEY))
            .map(String::as_str)
    }
}

/// The name of a channel of topic `topic`: its last part (`frames` of
/// `/leakwatch/rig1/frames`; logs of earlier versions named the channel `frames`).
pub fn channel_name(topic: &str) -> &str {
    topic.rsplit('/').next().unwrap_or(topic)
}

/// A channel of the file by id: its name ([`channel_name`]), topic, encoding and schema id.
#[derive(Debug, Clone)]
struct ChannelDef {
    name: String,
    topic: String,
    encoding: String,
    schema_id: u16,
    metadata: BTreeMap<String, String>,
}

/// Largest uncompressed chunk accepted, bytes (64 MiB; the recorder writes chunks of up to 1 MiB).
/// A chunk declaring more is skipped before anything is decompressed.
pub const MAX_CHUNK_BYTES: u64 = 64 << 20;

/// The records of one chunk, decompressed with its declared size as a hard bound:
/// a chunk that declares more than [`MAX_CHUNK_BYTES`], decompresses to more or
/// less than it declares, or fails its CRC is refused with the reason.
fn decompress_chunk(header: &mcap::records::ChunkHeader, data: &[u8]) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let size = header.uncompressed_size;
    if size > MAX_CHUNK_BYTES {
        return Err(format!(
            "declares {size} bytes uncompressed, more than the {MAX_CHUNK_BYTES} accepted"
        ));
    }
    let out = match header.compression.as_str() {
        "" => data.to_vec(),
        "zstd" => {
            let mut out = Vec::with_capacity(size as usize);
            zstd::stream::read::Decoder::new(data)
                .and_then(|d| d.take(size + 1).read_to_end(&mut out))
                .map_err(|e| format!("zstd: {e}"))?;
            out
        }
        other => return Err(format!("compression {other:?} is not supported")),
    };
    if out.len() as u64 > size {
        return Err(format!(
            "declares {size} bytes uncompressed, but the data holds more"
        ));
    }
    if (out.len() as u64) < size {
        return Err(format!(
            "declares {size} bytes uncompressed, but the data holds {}",
            out.len()
        ));
    }
    if header.uncompressed_crc != 0 && crc32fast::hash(&out) != header.uncompressed_crc {
        return Err("CRC of the uncompressed data does not match".into());
    }
    Ok(out)
}

/// Reads a whole log file (into memory).
pub struct LogReader {
    path: PathBuf,
    data: Vec<u8>,
}

impl LogReader {
    /// Reads `path`.
    pub fn open(path: &Path) -> Result<LogReader, RecorderError> {
        let data = std::fs::read(path).map_err(|e| RecorderError::Io(path.to_path_buf(), e))?;
        Ok(LogReader {
            path: path.to_path_buf(),
            data,
        })
    }

    /// Decodes every message. A file that ends early (no footer, a partial
    /// chunk) is read up to its last complete chunk and marked
    /// [`Log::truncated`]; a damaged chunk (see [`MAX_CHUNK_BYTES`]) is skipped
    /// and listed in [`Log::chunks_skipped`], never handed to the decompressor
    /// unbounded; a file that is not MCAP, or a message that does not decode, is
    /// an error naming the channel and message.
    pub fn read(&self) -> Result<Log, RecorderError> {
        self.read_with(false)
    }

    /// What [`Self::read`] gives with the sensor frames only ([`Log::frames`],
    /// their damage and their channels' counts): the other channels' messages
    /// are not decoded (a replay's input, read at several times the speed).
    pub fn read_frames(&self) -> Result<Log, RecorderError> {
        self.read_with(true)
    }

    fn read_with(&self, frames_only: bool) -> Result<Log, RecorderError> {
        let mut log = Log::default();
        // The channels and schemas, from the summary at the end when there is one
        // (a damaged first chunk then loses its messages, not the channels of all others).
        let mut channels: HashMap<u16, ChannelDef> = HashMap::new();
        let mut schemas: HashMap<u16, (String, String)> = HashMap::new();
        if let Some(summary) = summary(&self.data) {
            for (id, c) in &summary.channels {
                channels.insert(
                    *id,
                    ChannelDef {
                        name: channel_name(&c.topic).to_string(),
                        topic: c.topic.clone(),
                        encoding: c.message_encoding.clone(),
                        schema_id: c.schema.as_ref().map(|s| s.id).unwrap_or(0),
                        metadata: c.metadata.clone(),
                    },
                );
            }
            for (id, sc) in &summary.schemas {
                schemas.insert(*id, (sc.name.clone(), sc.encoding.clone()));
            }
        }
        // the frames of the `frames` channel, apart from the batches' (in `log.frames`)
        let mut single: Vec<SensorFrame> = Vec::new();
        // where in the batches' and the frames channel's frames each skipped chunk was
        let mut skipped_at: Vec<(usize, usize)> = Vec::new();
        log.truncated = walk(&self.path, &self.data, |item| {
            match item {
                Item::Channel(c) => {
                    let def = ChannelDef {
                        name: channel_name(&c.topic).to_string(),
                        topic: c.topic,
                        encoding: c.message_encoding,
                        schema_id: c.schema_id,
                        metadata: c.metadata,
                    };
                    channels.insert(c.id, def);
                }
                Item::Schema(h, _) => {
                    schemas.insert(h.id, (h.name, h.encoding));
                }
                Item::Message(header, data) => {
                    let wanted = !frames_only
                        || channels
                            .get(&header.channel_id)
                            .is_some_and(|c| c.name == "frames" || c.name == FRAME_BATCHES_CHANNEL);
                    if wanted {
                        self.decode(&mut log, &mut single, &channels, &header, data)?
                    }
                }
                Item::ChunkSkipped(why) => {
                    log.chunks_skipped.push(why);
                    skipped_at.push((log.frames.len(), single.len()));
                }
                Item::Metadata(m) => {
                    log.metadata.insert(m.name, m.metadata);
                }
            }
            Ok(())
        })?;
        // every channel known, with or without messages
        for def in channels.values() {
            let info = log.channels.entry(def.name.clone()).or_default();
            info.topic.clone_from(&def.topic);
            info.message_encoding.clone_from(&def.encoding);
            info.metadata.clone_from(&def.metadata);
            if let Some((name, encoding)) = schemas.get(&def.schema_id) {
                info.schema_name.clone_from(name);
                info.schema_encoding.clone_from(encoding);
            }
        }
        // the batches hold every frame; a log without them, its frames channel
        let batched = channels.values().any(|c| c.name == FRAME_BATCHES_CHANNEL);
        let mut skipped_at: Vec<usize> = if batched {
            skipped_at.into_iter().map(|(b, _)| b).collect()
        } else {
            log.frames = single;
            skipped_at.into_iter().map(|(_, s)| s).collect()
        };
        // (chunks skipped side by side share one gap in the frames)
        skipped_at.dedup();
        for p in skipped_at {
            if p > 0 && p < log.frames.len() {
                let gap = log.frames[p].seq.saturating_sub(log.frames[p - 1].seq);
                log.frames_lost += gap.saturating_sub(1);
            } else if p == 0 && !log.frames.is_empty() {
                // before the first frame read: counted from sequence 0, where a run starts
                log.frames_lost += log.frames[0].seq;
            }
        }
        Ok(log)
    }

    /// The highest sequence number of the frames the file holds (up to the last
    /// complete chunk of a killed recorder's file), without keeping any message:
    /// the chunks are decompressed one at a time and only the frames' sequence
    /// numbers decoded. `None` if it holds no frame.
    pub fn last_frame_seq(&self) -> Result<Option<u64>, RecorderError> {
        let mut frames_channels: Vec<(u16, String)> = Vec::new();
        let mut batch_channels: Vec<u16> = Vec::new();
        // the last frame of the frames channel and of the batches: with batches,
        // the frames channel's copy can run ahead of the batch being filled
        let mut last: Option<u64> = None;
        let mut last_batched: Option<u64> = None;
        walk(&self.path, &self.data, |item| {
            match item {
                Item::Channel(c) if channel_name(&c.topic) == "frames" => {
                    frames_channels.push((c.id, c.message_encoding))
                }
                Item::Channel(c) if channel_name(&c.topic) == FRAME_BATCHES_CHANNEL => {
                    batch_channels.push(c.id)
                }
                Item::Message(header, data) if batch_channels.contains(&header.channel_id) => {
                    let seq = SensorFrameBatch::last_seq_from_cdr(data).map_err(|problem| {
                        RecorderError::Decode {
                            path: self.path.clone(),
                            channel: FRAME_BATCHES_CHANNEL.into(),
                            sequence: header.sequence,
                            problem,
                        }
                    })?;
                    last_batched = last_batched.max(seq);
                }
                Item::Message(header, data) => {
                    if let Some((_, encoding)) =
                        frames_channels.iter().find(|(id, _)| *id == header.channel_id)
                    {
                        let f: SensorFrame =
                            decode_as(encoding, data).map_err(|problem| RecorderError::Decode {
                                path: self.path.clone(),
                                channel: "frames".into(),
                                sequence: header.sequence,
                                problem,
                            })?;
                        last = last.max(Some(f.seq));
                    }
                }
                _ => {}
            }
            Ok(())
        })?;
        Ok(if batch_channels.is_empty() {
            last
        } else {
            last_batched
        })
    }
}

/// The length of the top-level record at byte `at` of `data` (opcode, length
/// field and body), for reporting where a chunk is; 0 past the end.
fn record_len(data: &[u8], at: usize) -> usize {
    data.get(at + 1..at + 9)
        .and_then(|b| <[u8; 8]>::try_from(b).ok())
        .map(|b| 9usize.saturating_add(u64::from_le_bytes(b) as usize))
        .unwrap_or(0)
}

/// The summary section of an MCAP file, if it has one that reads.
pub(crate) fn summary(data: &[u8]) -> Option<mcap::read::Summary> {
    mcap::read::Summary::read(data).ok().flatten()
}

/// One intact item of an MCAP file, in file order, as [`walk`] finds it.
pub(crate) enum Item<'a> {
    /// A schema record and its data.
    Schema(mcap::records::SchemaHeader, &'a [u8]),
    /// A channel record.
    Channel(mcap::records::Channel),
    /// A message and its data.
    Message(mcap::records::MessageHeader, &'a [u8]),
    /// A metadata record.
    Metadata(mcap::records::Metadata),
    /// A damaged chunk was skipped: where and why.
    ChunkSkipped(String),
}

/// Walks the records of an MCAP file (`data`, read from `path`), handing every
/// intact schema, channel, message and metadata record to `visit`, in file
/// order, chunks decompressed with their declared size as a hard bound (see
/// [`MAX_CHUNK_BYTES`]); a damaged chunk is skipped and reported as
/// [`Item::ChunkSkipped`]. Returns `Some(reason)` if the file ends early (no
/// footer, a partial record: everything before it was visited); a file that is
/// not MCAP is an error, and so is an error of `visit`.
pub(crate) fn walk<F>(path: &Path, data: &[u8], mut visit: F) -> Result<Option<String>, RecorderError>
where
    F: FnMut(Item<'_>) -> Result<(), RecorderError>,
{
    const MAGIC: &[u8] = b"\x89MCAP0\r\n";
    let records =
        mcap::read::LinearReader::new_with_options(data, mcap::read::Options::IgnoreEndMagic.into())
            .map_err(|e| RecorderError::Mcap(path.to_path_buf(), e.to_string()))?;
    let mut truncated = None;
    let mut offset = 8usize; // after the magic
    let mut any = false;
    let mut footer = false;
    for item in records {
        let record = match item {
            Ok(r) => r,
            Err(e) if any || data.len() > 8 && data.starts_with(MAGIC) => {
                truncated = Some(e.to_string());
                break;
            }
            Err(e) => return Err(RecorderError::Mcap(path.to_path_buf(), e.to_string())),
        };
        let at = offset;
        offset = offset.saturating_add(record_len(data, at));
        match record {
            mcap::records::Record::Chunk { header, data } => {
                let bytes = match decompress_chunk(&header, &data) {
                    Ok(b) => b,
                    Err(why) => {
                        visit(Item::ChunkSkipped(format!("chunk at byte {at}: {why}")))?;
                        continue;
                    }
                };
                for inner in mcap::read::LinearReader::sans_magic(&bytes) {
                    match inner {
                        Ok(mcap::records::Record::Unknown { opcode, .. }) => {
                            // leakwatch writes no private records: a damaged opcode
                            visit(Item::ChunkSkipped(format!(
                                "chunk at byte {at}: a record with unknown opcode 0x{opcode:02x} (damaged: \
                                 leakwatch writes none); the rest of the chunk is skipped"
                            )))?;
                            break;
                        }
                        Ok(r) => any |= visit_record(r, &mut visit)?,
                        Err(e) => {
                            visit(Item::ChunkSkipped(format!("chunk at byte {at}: record: {e}")))?;
                            break;
                        }
                    }
                }
            }
            mcap::records::Record::Footer(_) => footer = true,
            mcap::records::Record::Unknown { opcode, .. } => {
                // leakwatch writes no private records: a chunk (or other record)
                // whose opcode byte was damaged; what it held is lost
                visit(Item::ChunkSkipped(format!(
                    "record at byte {at}: unknown opcode 0x{opcode:02x} (a damaged chunk or record: \
                     leakwatch writes none)"
                )))?;
            }
            r => any |= visit_record(r, &mut visit)?,
        }
    }
    if !any && truncated.is_none() && !data.ends_with(MAGIC) {
        truncated = Some("no complete chunk".into());
    }
    if truncated.is_none() && !footer {
        // cut at a record boundary (a recorder killed right after a flush)
        truncated = Some(format!(
            "no summary or footer: the file ends after byte {} (was its recorder killed?)",
            data.len()
        ));
    }
    Ok(truncated)
}

/// Hands one record to `visit`; true if it was a message.
fn visit_record<F>(record: mcap::records::Record<'_>, visit: &mut F) -> Result<bool, RecorderError>
where
    F: FnMut(Item<'_>) -> Result<(), RecorderError>,
{
    use mcap::records::Record;
    match record {
        Record::Schema { header, data } => visit(Item::Schema(header, &data))?,
        Record::Channel(c) => visit(Item::Channel(c))?,
        Record::Message { header, data } => {
            visit(Item::Message(header, &data))?;
            return Ok(true);
        }
        Record::Metadata(m) => visit(Item::Metadata(m))?,
        _ => {}
    }
    Ok(false)
}
