//! The log's parts: opening each part file (header, metadata, schemas and
//! channels) and rolling over from one part to the next ([`rotated_part`]).

use std::collections::BTreeMap;
use std::fs::File;
use std::path::Path;

use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame};

use super::{channel_topic, Channels, Encoding, Sink, WriterOptions, OFFERED_QOS_PROFILES};
use crate::msg::{Message, SensorFrameBatch};
use crate::parts::rotated_part;
use crate::record::Record;
use crate::{
    GapRecord, RecorderError, CONFIG_KEY, CONFIG_METADATA, FRAME_BATCHES_CHANNEL, GAPS_CHANNEL,
    GAP_SCHEMA_NAME,
};

/// The `leakwatch_type` of the [`FRAME_BATCHES_CHANNEL`] channel.
const BATCH_TYPE_NAME: &str = "leakwatch.SensorFrameBatch.v1";

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

/// Creates the log file `path` (an existing file only with `options.overwrite`;
/// never through a symbolic link) and writes the header, the metadata, the
/// schemas and the channels (log times: stamp + `offset`, ns), flushed to disk
/// before any data; `part`: 0 for the file the recorder was given, k for its
/// k-th continuation ([`rotated_part`]).
pub(super) fn open_part(
    path: &Path,
    options: &WriterOptions,
    offset: i64,
    part: u32,
) -> Result<(mcap::Writer<File>, Channels), RecorderError> {
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
    if part > 0 {
        meta.insert("part".into(), part.to_string());
    }
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
    let batches = enc == Encoding::Cdr && options.frame_batch_len > 0;
    let channels = Channels {
        frames: add_frame_channel::<SensorFrame>(&mut w, enc, rig).map_err(mcap_err)?,
        frame_batches: if batches {
            let ch = add_channel::<SensorFrameBatch>(
                &mut w,
                enc,
                rig,
                FRAME_BATCHES_CHANNEL,
                BATCH_TYPE_NAME,
                || (String::new(), serde_json::Value::Null),
            )
            .map_err(mcap_err)?;
            Some(ch)
        } else {
            None
        },
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
    Ok((w, channels))
}

impl Sink {
    /// Closes the open part (the batch being filled, the summary and the
    /// footer) and continues in the next ([`rotated_part`]) with the same
    /// header, metadata, schemas and channels.
    pub(super) fn rotate(&mut self) -> Result<(), RecorderError> {
        self.write_batch()?;
        self.w.finish().map_err(|e| self.mcap_err(e))?;
        self.closed_bytes += std::fs::metadata(&self.path).map(|m| m.len()).unwrap_or(0);
        let part = self.parts.len() as u32;
        let next = rotated_part(&self.parts[0], part);
        let (w, ch) = open_part(&next, &self.options, self.ch.epoch_offset_ns, part)?;
        // (the closed writer is dropped here)
        self.w = w;
        self.ch = ch;
        self.path = next.clone();
        self.parts.push(next);
        self.chunk_first = None;
        self.part_first = None;
        Ok(())
    }
}
