//! What a log holds, in the manner of `ros2 bag info`: the file, its time span,
//! every channel with its message count, mean rate and encoding, the gaps, the
//! events raised, damage, and the configuration of the run.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use frames::{code_name, event_kind, event_phase, LeakEventFrame};

use crate::{Log, LEAKWATCH_METADATA};

/// The channels in the order [`Info`] lists them (others follow by name).
pub const CHANNEL_ORDER: [&str; 7] = [
    "frames",
    "frame_batches",
    "estimates",
    "events",
    "health",
    "stats",
    "gaps",
];

/// One channel of [`Info`].
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSummary {
    /// The channel's name (`frames`, ..., the last part of its topic).
    pub topic: String,
    /// The channel's topic in the file (`/leakwatch/<rig>/frames`; `frames` in
    /// logs of earlier versions): what rosbag2 tools call it.
    pub mcap_topic: String,
    /// Messages read.
    pub messages: u64,
    /// Mean rate over the channel's own span, Hz ((messages − 1) / span; `None`
    /// with fewer than two messages or a zero span).
    pub rate_hz: Option<f64>,
    /// The channel's message encoding (`cdr`, `json`).
    pub message_encoding: String,
    /// Its schema name and encoding (`leakwatch_msgs/msg/SensorFrame (ros2msg)`).
    pub schema: String,
}

/// Missing frames in one topic's sequence.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GapCount {
    /// Gaps (places where frames are missing).
    pub gaps: u64,
    /// Frames missing in all of them.
    pub missing: u64,
}

/// A summary of a log (see [`Info::from_log`]); [`Info::render`] prints it.
#[derive(Debug, Clone)]
pub struct Info {
    /// The file.
    pub path: PathBuf,
    /// The later parts read with it (a restarted recorder's `run-1.mcap`, ...;
    /// empty for a log of one file).
    pub later_parts: Vec<PathBuf>,
    /// Its size, bytes (all parts).
    pub bytes: u64,
    /// The first and last `log_time` of any message, ns (`None`: no message).
    pub span_ns: Option<(u64, u64)>,
    /// Wall clock minus the log-time clock, ns, where the log says (this
    /// version logs Unix time: 0; the versions before logged `CLOCK_MONOTONIC`,
    /// the offset from their `leakwatch` metadata record; JSON logs, older
    /// still, the wall clock: 0).
    pub wall_offset_ns: Option<i128>,
    /// The first and last sample time of the sensor frames, s.
    pub sample_span_s: Option<(f64, f64)>,
    /// The channels, in [`CHANNEL_ORDER`] then by name.
    pub channels: Vec<ChannelSummary>,
    /// Gap records of the `gaps` channel (what the recorder saw missing), per topic.
    pub gap_records: Vec<(String, GapCount)>,
    /// Jumps in the sensor frames' sequence numbers in the log itself (the gaps
    /// above, frames lost with damaged chunks, frames the recorder dropped).
    pub frame_seq_jumps: GapCount,
    /// The events raised (phase `raised`), in file order.
    pub events: Vec<LeakEventFrame>,
    /// Why the file ends early, if it does.
    pub truncated: Option<String>,
    /// Damaged chunks skipped, with where and why.
    pub chunks_skipped: Vec<String>,
    /// Sensor frames lost with them.
    pub frames_lost: u64,
    /// The `leakwatch` metadata record (rig, command, format, clocks).
    pub recorder: Vec<(String, String)>,
    /// The configuration the run used (TOML), if the log holds it.
    pub config_toml: Option<String>,
}

impl Info {
    /// The summary of `log`, read from the file `path` of `bytes` bytes.
    pub fn from_log(path: &Path, bytes: u64, log: &Log) -> Info {
        let mut topics: Vec<&String> = log.channels.keys().collect();
        let rank = |t: &str| {
            CHANNEL_ORDER
                .iter()
                .position(|c| *c == t)
                .unwrap_or(CHANNEL_ORDER.len())
        };
        topics.sort_by(|a, b| rank(a).cmp(&rank(b)).then(a.cmp(b)));
        let mut span: Option<(u64, u64)> = None;
        let channels = topics
            .into_iter()
            .map(|topic| {
                let c = &log.channels[topic];
                if c.messages > 0 {
                    span = Some(match span {
                        Some((a, b)) => (a.min(c.first_log_time), b.max(c.last_log_time)),
                        None => (c.first_log_time, c.last_log_time),
                    });
                }
                let dt = c.last_log_time.saturating_sub(c.first_log_time) as f64 * 1e-9;
                ChannelSummary {
                    topic: topic.clone(),
                    mcap_topic: if c.topic.is_empty() {
                        topic.clone()
                    } else {
                        c.topic.clone()
                    },
                    messages: c.messages,
                    rate_hz: (c.messages > 1 && dt > 0.0).then(|| (c.messages - 1) as f64 / dt),
                    message_encoding: c.message_encoding.clone(),
                    schema: if c.schema_name.is_empty() {
                        "(schema lost)".into()
                    } else {
                        format!("{} ({})", c.schema_name, c.schema_encoding)
                    },
                }
            })
            .collect();
        let meta = log.metadata.get(LEAKWATCH_METADATA);
        let num = |k: &str| meta.and_then(|m| m.get(k)).and_then(|v| v.parse::<i128>().ok());
        let wall_offset_ns = match (num("wall_clock_ns_at_start"), num("monotonic_ns_at_start")) {
            // this version: log_time is Unix time (the stamp + epoch_offset_ns)
            _ if num("epoch_offset_ns").is_some() => Some(0),
            // the versions before: log_time was CLOCK_MONOTONIC
            (Some(w), Some(m)) => Some(w - m),
            // earlier versions: log_time was the wall clock
            _ if log.channels.values().any(|c| c.message_encoding == "json") => Some(0),
            _ => None,
        };
        let mut gap_records: Vec<(String, GapCount)> = Vec::new();
        for g in &log.gaps {
            let name = g.topic.as_str().to_string();
            let i = match gap_records.iter().position(|(t, _)| *t == name) {
                Some(i) => i,
                None => {
                    gap_records.push((name, GapCount::default()));
                    gap_records.len() - 1
                }
            };
            gap_records[i].1.gaps += 1;
            gap_records[i].1.missing += g.missing;
        }
        let mut frame_seq_jumps = GapCount::default();
        for w in log.frames.windows(2) {
            // a new stream starts again at 0 (`recorder --keep-running`): no gap
            if w[1].seq > w[0].seq + 1 {
                frame_seq_jumps.gaps += 1;
                frame_seq_jumps.missing += w[1].seq - w[0].seq - 1;
            }
        }
        Info {
            path: path.to_path_buf(),
            later_parts: Vec::new(),
            bytes,
            span_ns: span,
            wall_offset_ns,
            sample_span_s: match (log.frames.first(), log.frames.last()) {
                (Some(a), Some(b)) => Some((a.t_s, b.t_s)),
                _ => None,
            },
            channels,
            gap_records,
            frame_seq_jumps,
            events: log
                .events
                .iter()
                .filter(|e| e.phase == event_phase::RAISED)
                .copied()
                .collect(),
            truncated: log.truncated.clone(),
            chunks_skipped: log.chunks_skipped.clone(),
            frames_lost: log.frames_lost,
            recorder: meta
                .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
                .unwrap_or_default(),
            config_toml: log.config_toml().map(str::to_string),
        }
    }

    /// The duration from the first to the last message, s.
    pub fn duration_s(&self) -> f64 {
        self.span_ns
            .map(|(a, b)| b.saturating_sub(a) as f64 * 1e-9)
            .unwrap_or(0.0)
    }

    /// The summary as text, one item per line, `ros2 bag info` style.
    pub fn render(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(o, "File:        {}", self.path.display());
        if !self.later_parts.is_empty() {
            let names: Vec<String> = self.later_parts.iter().map(|p| p.display().to_string()).collect();
            let _ = writeln!(o, "Later parts: {}", names.join(", "));
        }
        let _ = writeln!(
            o,
            "Size:        {} ({} bytes){}",
            human_bytes(self.bytes),
            self.bytes,
            match self.duration_s() {
                d if d > 0.0 => format!(", {:.1} MB/h", self.bytes as f64 / d * 3600.0 / 1e6),
                _ => String::new(),
            }
        );
        let _ = writeln!(o, "Duration:    {:.3} s", self.duration_s());
        if let Some((a, b)) = self.span_ns {
            let _ = writeln!(o, "Start:       {}", self.time(a));
            let _ = writeln!(o, "End:         {}", self.time(b));
        }
        if let Some((a, b)) = self.sample_span_s {
            let _ = writeln!(o, "Sample time: {a:.3} s to {b:.3} s (the frames' t_s)");
        }
        for key in ["rig", "format", "clock"] {
            if let Some((_, v)) = self.recorder.iter().find(|(k, _)| k == key) {
                let _ = writeln!(o, "{:<13}{v}", format!("{}:", capitalise(key)));
            }
        }
        let total: u64 = self.channels.iter().map(|c| c.messages).sum();
        let _ = writeln!(o, "Messages:    {total}");
        let _ = writeln!(o, "Channels:");
        let width = self
            .channels
            .iter()
            .map(|c| c.mcap_topic.len())
            .max()
            .unwrap_or(0);
        for c in &self.channels {
            let rate = match c.rate_hz {
                Some(r) if r >= 10.0 => format!("{r:>8.1} Hz"),
                Some(r) => format!("{r:>8.3} Hz"),
                None => format!("{:>11}", "-"),
            };
            let _ = writeln!(
                o,
                "  {:<width$}  {:>9} msgs  {rate}  {} {}",
                c.mcap_topic, c.messages, c.message_encoding, c.schema
            );
        }
        let recorded: u64 = self.gap_records.iter().map(|(_, g)| g.gaps).sum();
        if recorded == 0 {
            let _ = writeln!(o, "Gaps:        none recorded");
        } else {
            let parts: Vec<String> = self
                .gap_records
                .iter()
                .map(|(t, g)| format!("{t} {} ({} missing)", g.gaps, g.missing))
                .collect();
            let _ = writeln!(o, "Gaps:        {}", parts.join(", "));
        }
        let j = self.frame_seq_jumps;
        let _ = writeln!(
            o,
            "Frame seq:   {} jumps, {} frames missing from the log's frames",
            j.gaps, j.missing
        );
        if self.events.is_empty() {
            let _ = writeln!(o, "Events:      none raised");
        } else {
            let _ = writeln!(o, "Events:      {} raised", self.events.len());
            for e in &self.events {
                let size = if e.size_lpm.is_nan() {
                    String::new()
                } else {
                    format!(
                        "  size {:.3} ± {:.3} L/min",
                        e.size_lpm,
                        if e.size_lpm_sigma.is_nan() {
                            0.0
                        } else {
                            e.size_lpm_sigma
                        }
                    )
                };
                let onset = if e.t_onset_s.is_nan() {
                    String::new()
                } else {
                    format!("  onset {:.2} s", e.t_onset_s)
                };
                let _ = writeln!(
                    o,
                    "  t = {:>9.3} s  {:<16} {:<10} id {}{onset}{size}",
                    e.t_detect_s,
                    code_name(&event_kind::NAMES, e.kind),
                    frames::detector_name(&e.detector),
                    e.event_id
                );
            }
        }
        match &self.truncated {
            Some(why) => {
                let _ = writeln!(o, "Truncated:   yes: {why}");
            }
            None => {
                let _ = writeln!(o, "Truncated:   no");
            }
        }
        if self.chunks_skipped.is_empty() {
            let _ = writeln!(o, "Damaged:     none");
        } else {
            let _ = writeln!(
                o,
                "Damaged:     {} chunks skipped, {} frames lost with them",
                self.chunks_skipped.len(),
                self.frames_lost
            );
            for c in &self.chunks_skipped {
                let _ = writeln!(o, "  {c}");
            }
        }
        match &self.config_toml {
            Some(toml) => {
                let sections: Vec<&str> = toml
                    .lines()
                    .filter(|l| l.starts_with('[') && !l.starts_with("[["))
                    .collect();
                let _ = writeln!(
                    o,
                    "Config:      stored ({} lines): {}",
                    toml.lines().count(),
                    sections.join(" ")
                );
            }
            None => {
                let _ = writeln!(o, "Config:      not stored in the log");
            }
        }
        o
    }

    /// A log time as a UTC date where the wall clock is known, and as seconds of its clock.
    fn time(&self, t: u64) -> String {
        match self.wall_offset_ns {
            Some(off) => {
                let wall = t as i128 + off;
                if off == 0 {
                    utc(wall)
                } else {
                    format!("{} (monotonic {:.3} s)", utc(wall), t as f64 * 1e-9)
                }
            }
            None => format!("monotonic {:.3} s", t as f64 * 1e-9),
        }
    }
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

/// `bytes` in B, KiB, MiB or GiB.
fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1024.0 * 1024.0 * 1024.0 {
        format!("{:.2} GiB", b / (1024.0 * 1024.0 * 1024.0))
    } else if b >= 1024.0 * 1024.0 {
        format!("{:.2} MiB", b / (1024.0 * 1024.0))
    } else if b >= 1024.0 {
        format!("{:.1} KiB", b / 1024.0)
    } else {
        format!("{bytes} B")
    }
}

/// Nanoseconds since the Unix epoch as `YYYY-MM-DD hh:mm:ss.mmm UTC`.
pub fn utc(ns: i128) -> String {
    let ms = ns.div_euclid(1_000_000);
    let (days, ms_of_day) = (ms.div_euclid(86_400_000), ms.rem_euclid(86_400_000));
    // civil date of a day count (H. Hinnant's algorithm)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i128::from(m <= 2);
    let s = ms_of_day / 1000;
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02}.{:03} UTC",
        s / 3600,
        s / 60 % 60,
        s % 60,
        ms_of_day % 1000
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn utc_dates() {
        assert_eq!(super::utc(0), "1970-01-01 00:00:00.000 UTC");
        // 2024-02-29 12:34:56.789 UTC
        assert_eq!(
            super::utc(1_709_210_096_789_000_000),
            "2024-02-29 12:34:56.789 UTC"
        );
    }
}
