//! Repairing a log whose recorder was killed (no summary, no footer, maybe a
//! cut last chunk) or that has damaged chunks: every intact schema, channel,
//! message and metadata record is copied, in file order, into a new, complete
//! MCAP file with a summary section, which any MCAP reader opens.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::path::{Path, PathBuf};

use crate::reader::{summary, walk, Item};
use crate::RecorderError;

/// What [`repair`] wrote.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RepairSummary {
    /// The repaired file.
    pub path: PathBuf,
    /// Messages copied, per channel name (`frames`, ..., the last part of its
    /// topic, [`crate::channel_name`]).
    pub messages: BTreeMap<String, u64>,
    /// Messages dropped because their channel (or its schema) record was lost
    /// with a damaged chunk and the file has no summary that names it.
    pub messages_without_channel: u64,
    /// Damaged chunks skipped (byte offset and reason), as in [`crate::Log::chunks_skipped`].
    pub chunks_skipped: Vec<String>,
    /// Why the input ended early, if it did (a killed recorder): everything
    /// before that point was copied.
    pub truncated: Option<String>,
    /// Bytes of the repaired file.
    pub bytes: u64,
}

/// A schema as found in the input.
struct SchemaContent {
    name: String,
    encoding: String,
    data: Vec<u8>,
}

/// A channel as found in the input (its schema by input id).
struct ChannelContent {
    schema_id: u16,
    topic: String,
    encoding: String,
    metadata: BTreeMap<String, String>,
}

/// Copies records into the new file, mapping the input's schema and channel
/// ids onto the writer's.
struct Copier {
    w: mcap::Writer<File>,
    schemas: HashMap<u16, SchemaContent>,
    channels: HashMap<u16, ChannelContent>,
    new_schema: HashMap<u16, u16>,
    new_channel: HashMap<u16, u16>,
    topics: HashMap<u16, String>,
    summary: RepairSummary,
}

impl Copier {
    /// The output id of input schema `id` (0: no schema); `None` if its record was lost.
    fn schema(&mut self, id: u16) -> Result<Option<u16>, mcap::McapError> {
        if id == 0 {
            return Ok(Some(0));
        }
        if let Some(&n) = self.new_schema.get(&id) {
            return Ok(Some(n));
        }
        let Some(s) = self.schemas.get(&id) else {
            return Ok(None);
        };
        let n = self.w.add_schema(&s.name, &s.encoding, &s.data)?;
        self.new_schema.insert(id, n);
        Ok(Some(n))
    }

    /// The output id of input channel `id`; `None` if its record (or its schema's) was lost.
    fn channel(&mut self, id: u16) -> Result<Option<u16>, mcap::McapError> {
        if let Some(&n) = self.new_channel.get(&id) {
            return Ok(Some(n));
        }
        let Some(schema_id) = self.channels.get(&id).map(|c| c.schema_id) else {
            return Ok(None);
        };
        let Some(schema) = self.schema(schema_id)? else {
            return Ok(None);
        };
        let Some(c) = self.channels.get(&id) else {
            return Ok(None);
        };
        let n = self.w.add_channel(schema, &c.topic, &c.encoding, &c.metadata)?;
        self.new_channel.insert(id, n);
        self.topics.insert(id, crate::channel_name(&c.topic).to_string());
        Ok(Some(n))
    }

    fn visit(&mut self, item: Item<'_>) -> Result<(), mcap::McapError> {
        match item {
            Item::Schema(h, data) => {
                // a schema record seen again (or changed) replaces the one known
                self.new_schema.remove(&h.id);
                self.schemas.insert(
                    h.id,
                    SchemaContent {
                        name: h.name,
                        encoding: h.encoding,
                        data: data.to_vec(),
                    },
                );
            }
            Item::Channel(c) => {
                self.new_channel.remove(&c.id);
                self.channels.insert(
                    c.id,
                    ChannelContent {
                        schema_id: c.schema_id,
                        topic: c.topic,
                        encoding: c.message_encoding,
                        metadata: c.metadata,
                    },
                );
                // channels without messages are kept too
                self.channel(c.id)?;
            }
            Item::Message(header, data) => match self.channel(header.channel_id)? {
                Some(channel_id) => {
                    let topic = self.topics.get(&header.channel_id).cloned().unwrap_or_default();
                    self.w.write_to_known_channel(
                        &mcap::records::MessageHeader { channel_id, ..header },
                        data,
                    )?;
                    *self.summary.messages.entry(topic).or_default() += 1;
                }
                None => self.summary.messages_without_channel += 1,
            },
            Item::Metadata(m) => self.w.write_metadata(&m)?,
            Item::ChunkSkipped(why) => self.summary.chunks_skipped.push(why),
        }
        Ok(())
    }
}

/// The profile of the file's header record ("" if it has none that reads).
fn profile(data: &[u8]) -> String {
    let reader = mcap::read::LinearReader::new_with_options(data, mcap::read::Options::IgnoreEndMagic.into());
    match reader.ok().and_then(|mut r| r.next()) {
        Some(Ok(mcap::records::Record::Header(h))) => h.profile,
        _ => String::new(),
    }
}

/// Writes `output`, a complete MCAP file (zstd chunks, summary, footer) with
/// every intact record of the log `input`: what [`crate::LogReader`] reads
/// from `input` (a killed recorder's file up to its last complete chunk,
/// damaged chunks skipped), with the same schemas, channels, metadata and
/// messages (time stamps and sequence numbers kept). `output` is created by
/// `dataset::output::create_file`: never through a symbolic link, never over
/// `input`, an existing file only with `overwrite`. A file that is not MCAP is
/// an error and writes nothing; on a write error the partial output is removed.
pub fn repair(input: &Path, output: &Path, overwrite: bool) -> Result<RepairSummary, RecorderError> {
    let data = std::fs::read(input).map_err(|e| RecorderError::Io(input.to_path_buf(), e))?;
    if !data.starts_with(b"\x89MCAP0\r\n") {
        return Err(RecorderError::Mcap(
            input.to_path_buf(),
            "not an MCAP file (no MCAP magic at the start)".into(),
        ));
    }
    let file = dataset::output::create_file(output, overwrite, &[input])
        .map_err(|e| RecorderError::Io(output.to_path_buf(), e))?;
    let result = copy(input, output, &data, file);
    if result.is_err() {
        let _ = std::fs::remove_file(output);
    }
    result
}

fn copy(input: &Path, output: &Path, data: &[u8], file: File) -> Result<RepairSummary, RecorderError> {
    let out_err = |e: mcap::McapError| RecorderError::from_mcap(output, e);
    let w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .chunk_size(Some(256 * 1024))
        .profile(profile(data))
        .create(file)
        .map_err(out_err)?;
    let mut c = Copier {
        w,
        schemas: HashMap::new(),
        channels: HashMap::new(),
        new_schema: HashMap::new(),
        new_channel: HashMap::new(),
        topics: HashMap::new(),
        summary: RepairSummary {
            path: output.to_path_buf(),
            ..RepairSummary::default()
        },
    };
    // a damaged file with a summary still names the channels of a lost first chunk
    if let Some(s) = summary(data) {
        for (id, ch) in &s.channels {
            let schema_id = ch.schema.as_ref().map(|s| s.id).unwrap_or(0);
            c.channels.insert(
                *id,
                ChannelContent {
                    schema_id,
                    topic: ch.topic.clone(),
                    encoding: ch.message_encoding.clone(),
                    metadata: ch.metadata.clone(),
                },
            );
        }
        for (id, sc) in &s.schemas {
            c.schemas.insert(
                *id,
                SchemaContent {
                    name: sc.name.clone(),
                    encoding: sc.encoding.clone(),
                    data: sc.data.to_vec(),
                },
            );
        }
    }
    let truncated = walk(input, data, |item| c.visit(item).map_err(out_err))?;
    c.summary.truncated = truncated;
    c.w.finish().map_err(out_err)?;
    let Copier { w, mut summary, .. } = c;
    drop(w);
    summary.bytes = std::fs::metadata(output).map(|m| m.len()).unwrap_or(0);
    Ok(summary)
}
