//! Reading a leakwatch MCAP log back into frames.

use std::path::{Path, PathBuf};

use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};
use serde_json::Value;

use crate::record::Record;
use crate::{GapRecord, RecorderError, GAPS_CHANNEL};

/// Everything in a log, per channel, in file order.
#[derive(Debug, Clone, Default)]
pub struct Log {
    /// The `frames` channel.
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
    /// Messages on channels this version does not know, skipped.
    pub unknown_messages: u64,
    /// `Some(reason)` if the file ended early (a killed recorder): everything
    /// up to the last complete chunk was read.
    pub truncated: Option<String>,
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
    /// [`Log::truncated`]; a file that is not MCAP, or a message that does not
    /// decode, is an error naming the channel and message.
    pub fn read(&self) -> Result<Log, RecorderError> {
        let mut log = Log::default();
        let stream =
            mcap::MessageStream::new_with_options(&self.data, mcap::read::Options::IgnoreEndMagic.into())
                .map_err(|e| RecorderError::Mcap(self.path.clone(), e.to_string()))?;
        let mut any = false;
        for item in stream {
            let msg = match item {
                Ok(m) => m,
                Err(e) if any || self.data.len() > 8 && self.data.starts_with(b"\x89MCAP0\r\n") => {
                    log.truncated = Some(e.to_string());
                    break;
                }
                Err(e) => return Err(RecorderError::Mcap(self.path.clone(), e.to_string())),
            };
            any = true;
            let topic = msg.channel.topic.as_str();
            let decode_err = |problem: String| RecorderError::Decode {
                path: self.path.clone(),
                channel: topic.to_string(),
                sequence: msg.sequence,
                problem,
            };
            let v: Value = serde_json::from_slice(&msg.data).map_err(|e| decode_err(e.to_string()))?;
            match topic {
                "frames" => log.frames.push(SensorFrame::from_json(&v).map_err(decode_err)?),
                "estimates" => log
                    .estimates
                    .push(EstimateFrame::from_json(&v).map_err(decode_err)?),
                "events" => log
                    .events
                    .push(LeakEventFrame::from_json(&v).map_err(decode_err)?),
                "health" => log.health.push(HealthFrame::from_json(&v).map_err(decode_err)?),
                "stats" => log.stats.push(StatsFrame::from_json(&v).map_err(decode_err)?),
                GAPS_CHANNEL => log.gaps.push(GapRecord::from_json(&v).map_err(decode_err)?),
                _ => log.unknown_messages += 1,
            }
        }
        if !any && log.truncated.is_none() && !self.data.ends_with(b"\x89MCAP0\r\n") {
            log.truncated = Some("no complete chunk".into());
        }
        Ok(log)
    }
}

impl GapRecord {
    /// From its JSON object; the error names the field.
    pub fn from_json(v: &Value) -> Result<GapRecord, String> {
        let int = |k: &str| {
            v.get(k)
                .and_then(Value::as_u64)
                .ok_or_else(|| format!("gap.{k}: expected an unsigned integer"))
        };
        let name = v
            .get("topic")
            .and_then(Value::as_str)
            .ok_or("gap.topic: expected a string")?;
        let topic = Topic::ALL
            .into_iter()
            .find(|t| t.as_str() == name)
            .ok_or_else(|| format!("gap.topic: unknown topic {name:?}"))?;
        Ok(GapRecord {
            topic,
            expected_seq: int("expected_seq")?,
            got_seq: int("got_seq")?,
            missing: int("missing")?,
            recv_mono_ns: int("recv_mono_ns")?,
        })
    }
}
