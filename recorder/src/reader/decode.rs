//! Decoding the log's messages into frames by their channel's
//! `message_encoding`: CDR (this version) or JSON (earlier versions).

use std::collections::HashMap;

use frames::SensorFrame;
use serde_json::Value;

use super::{ChannelDef, Log, LogReader};
use crate::msg::{topic_of, Message, SensorFrameBatch};
use crate::record::Record;
use crate::{GapRecord, RecorderError, FRAME_BATCHES_CHANNEL, GAPS_CHANNEL};

impl LogReader {
    pub(super) fn decode(
        &self,
        log: &mut Log,
        single: &mut Vec<SensorFrame>,
        channels: &HashMap<u16, ChannelDef>,
        header: &mcap::records::MessageHeader,
        data: &[u8],
    ) -> Result<(), RecorderError> {
        let Some(def) = channels.get(&header.channel_id) else {
            // its channel record was in a skipped chunk
            log.unknown_messages += 1;
            return Ok(());
        };
        let decode_err = |problem: String| RecorderError::Decode {
            path: self.path.clone(),
            channel: def.topic.clone(),
            sequence: header.sequence,
            problem,
        };
        match def.name.as_str() {
            "frames" => single.push(decode_as(&def.encoding, data).map_err(decode_err)?),
            FRAME_BATCHES_CHANNEL => {
                if def.encoding != "cdr" {
                    return Err(decode_err(format!(
                        "message encoding `{}` is not supported (cdr)",
                        def.encoding
                    )));
                }
                SensorFrameBatch::append_frames_from_cdr(data, &mut log.frames).map_err(decode_err)?;
            }
            "estimates" => log
                .estimates
                .push(decode_as(&def.encoding, data).map_err(decode_err)?),
            "events" => log
                .events
                .push(decode_as(&def.encoding, data).map_err(decode_err)?),
            "health" => log
                .health
                .push(decode_as(&def.encoding, data).map_err(decode_err)?),
            "stats" => log
                .stats
                .push(decode_as(&def.encoding, data).map_err(decode_err)?),
            GAPS_CHANNEL => log
                .gaps
                .push(decode_gap(&def.encoding, data).map_err(decode_err)?),
            _ => {
                log.unknown_messages += 1;
                return Ok(());
            }
        }
        let info = log.channels.entry(def.name.clone()).or_default();
        if info.messages == 0 || header.log_time < info.first_log_time {
            info.first_log_time = header.log_time;
        }
        info.last_log_time = info.last_log_time.max(header.log_time);
        info.messages += 1;
        Ok(())
    }
}

/// A frame from a message in `encoding` (`cdr` or `json`).
pub(super) fn decode_as<R: Record + Message>(encoding: &str, data: &[u8]) -> Result<R, String> {
    match encoding {
        "cdr" => R::from_cdr(data),
        "json" => {
            let v: Value = serde_json::from_slice(data).map_err(|e| e.to_string())?;
            R::from_json(&v)
        }
        other => Err(format!(
            "message encoding `{other}` is not supported (cdr or json)"
        )),
    }
}

/// A gap record from a message in `encoding` (`cdr` or `json`).
fn decode_gap(encoding: &str, data: &[u8]) -> Result<GapRecord, String> {
    match encoding {
        "cdr" => GapRecord::from_cdr(data),
        "json" => {
            let v: Value = serde_json::from_slice(data).map_err(|e| e.to_string())?;
            GapRecord::from_json(&v)
        }
        other => Err(format!(
            "message encoding `{other}` is not supported (cdr or json)"
        )),
    }
}

impl GapRecord {
    /// From its JSON object (the JSON encoding); the error names the field.
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
        let topic = topic_of(name).ok_or_else(|| format!("gap.topic: unknown topic {name:?}"))?;
        Ok(GapRecord {
            topic,
            expected_seq: int("expected_seq")?,
            got_seq: int("got_seq")?,
            missing: int("missing")?,
            recv_mono_ns: int("recv_mono_ns")?,
        })
    }
}
