//! `leakwatch watch`: subscribes to `leakwatch/**` on Zenoh and prints every
//! rig's events as they happen (and each rig's health status when it
//! changes), until a signal or `--seconds`.
//!
//! With `[zenoh] key_file` each message's signature is checked
//! ([`crate::sign::Verifier`]): an event that cannot be verified (no
//! signature, or one the shared key did not make) is printed marked
//! `UNVERIFIED (why)`, its health and estimates are left out; a signed message
//! that is a replay (too old, or not newer than the last of its key) is left
//! out. Both are counted per rig in the summary.

use std::collections::BTreeMap;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use serde_json::Value;
use zenoh::Wait;

use crate::gateway::{open_session, parse_key, KEY_ROOT};
use crate::sign::{unix_ns, Verdict, Verifier};
use config::live::ZenohConfig;

/// What one rig sent, as `watch` counts it.
#[derive(Debug, Clone, Default)]
pub struct RigSeen {
    /// Messages per topic name.
    pub messages: BTreeMap<String, u64>,
    /// The last health status (`healthy`, `leak`, ...).
    pub status: String,
    /// Messages that could not be verified (with a key only).
    pub unverified: u64,
    /// Signed messages left out as replays (with a key only).
    pub replayed: u64,
}

/// The rigs seen by a watch, by rig id.
pub type Seen = BTreeMap<String, RigSeen>;

fn num(v: &Value, k: &str) -> f64 {
    v.get(k).and_then(Value::as_f64).unwrap_or(f64::NAN)
}

fn text<'a>(v: &'a Value, k: &str) -> &'a str {
    v.get(k).and_then(Value::as_str).unwrap_or("?")
}

/// One event as `watch` prints it: rig, time, phase, kind, size, onset, confidence, detector and id.
pub fn event_line(rig: &str, e: &Value) -> String {
    let size = num(e, "size_lpm");
    let size = if size.is_finite() {
        format!("  size {size:.3} ± {:.3} L/min", num(e, "size_lpm_sigma"))
    } else {
        String::new()
    };
    format!(
        "{rig:<12} t = {:8.3} s  {:<8} {:<16}{size}  onset {:.2} s  confidence {:.2}  ({}, event {})",
        num(e, "t_detect_s"),
        text(e, "phase"),
        text(e, "kind"),
        num(e, "t_onset_s"),
        num(e, "confidence"),
        text(e, "detector"),
        e.get("event_id").and_then(Value::as_u64).unwrap_or(0)
    )
}

/// Watches until `stop` is set or `seconds` have passed, printing to `out`;
/// returns what each rig sent.
pub fn watch(
    cfg: &ZenohConfig,
    seconds: Option<f64>,
    stop: &AtomicBool,
    out: &mut impl Write,
) -> Result<Seen, String> {
    let mut verifier = cfg.key()?.map(|k| Verifier::new(k, cfg.max_age_s));
    let session = open_session(cfg)?;
    let sub = session
        .declare_subscriber(format!("{KEY_ROOT}/**"))
        .wait()
        .map_err(|e| format!("cannot subscribe to {KEY_ROOT}/**: {e}"))?;
    let w = |e: std::io::Error| format!("standard output: {e}");
    writeln!(
        out,
        "leakwatch watch: subscribed to {KEY_ROOT}/** (listening on [{}], connecting to [{}]); events as they happen:",
        cfg.listen.join(", "),
        cfg.connect.join(", ")
    )
    .map_err(w)?;
    if verifier.is_none() {
        writeln!(
            out,
            "leakwatch watch: no [zenoh] key_file: messages are not authenticated (anyone who reaches this \
             Zenoh network can publish an event; see docs/security.md)"
        )
        .map_err(w)?;
    }
    let start = Instant::now();
    let mut left_out = 0u64;
    let mut seen = Seen::new();
    let mut malformed = 0u64;
    while !stop.load(Ordering::Relaxed) && seconds.is_none_or(|s| start.elapsed().as_secs_f64() < s) {
        let sample = match sub.recv_timeout(Duration::from_millis(100)) {
            Ok(Some(s)) => s,
            Ok(None) => continue,
            Err(e) => return Err(format!("zenoh subscriber: {e}")),
        };
        let key = sample.key_expr().as_str().to_string();
        let Some((rig, topic)) = parse_key(&key) else {
            continue;
        };
        let bytes = sample.payload().to_bytes();
        let msg: Value = match serde_json::from_slice(&bytes) {
            Ok(v @ Value::Object(_)) => v,
            _ => {
                malformed += 1;
                if malformed <= 10 {
                    eprintln!("leakwatch watch: a message on {key} is not a JSON object; left out");
                }
                continue;
            }
        };
        let verdict = match &mut verifier {
            Some(v) => {
                let att = sample.attachment().map(|a| a.to_bytes());
                v.check(&key, &bytes, att.as_deref(), unix_ns())
            }
            None => Verdict::Verified,
        };
        let first = !seen.contains_key(rig);
        let r = seen.entry(rig.to_string()).or_default();
        let mark = match verdict {
            Verdict::Verified => String::new(),
            Verdict::Unverified(why) => {
                r.unverified += 1;
                if topic != "events" {
                    continue;
                }
                format!("UNVERIFIED ({why}): ")
            }
            Verdict::Replayed(why) => {
                r.replayed += 1;
                left_out += 1;
                if left_out <= 10 {
                    eprintln!("leakwatch watch: a replayed message on {key} left out: {why}");
                }
                continue;
            }
        };
        *r.messages.entry(topic.to_string()).or_default() += 1;
        if first {
            writeln!(out, "{rig:<12} seen ({topic})").map_err(w)?;
        }
        match topic {
            "events" => writeln!(out, "{mark}{}", event_line(rig, &msg)).map_err(w)?,
            "health" => {
                let status = text(&msg, "status");
                if status != r.status {
                    writeln!(out, "{rig:<12} t = {:8.3} s  status {}", num(&msg, "t_s"), status)
                        .map_err(w)?;
                    r.status = status.to_string();
                }
            }
            _ => {}
        }
    }
    writeln!(out, "leakwatch watch: {} rig(s) seen", seen.len()).map_err(w)?;
    for (rig, r) in &seen {
        let counts: Vec<String> = r.messages.iter().map(|(t, n)| format!("{t} {n}")).collect();
        let doubtful = if r.unverified + r.replayed > 0 {
            format!("; UNVERIFIED {}, replays left out {}", r.unverified, r.replayed)
        } else {
            String::new()
        };
        writeln!(
            out,
            "  {rig:<12} {}; status {}{doubtful}",
            counts.join(", "),
            r.status
        )
        .map_err(w)?;
    }
    Ok(seen)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_event_line_gives_kind_size_and_confidence() {
        let e = serde_json::json!({"t_detect_s": 21.5, "phase": "raised", "kind": "ext1", "size_lpm": 0.5123,
            "size_lpm_sigma": 0.02, "t_onset_s": 20.0, "confidence": 0.9, "detector": "leak-size", "event_id": 3});
        let l = event_line("rig2", &e);
        assert!(l.starts_with("rig2         t =   21.500 s  raised   ext1"), "{l}");
        assert!(
            l.contains("size 0.512 ± 0.020 L/min  onset 20.00 s  confidence 0.90  (leak-size, event 3)"),
            "{l}"
        );
        // absent fields print as such, without a panic
        let l = event_line("r", &serde_json::json!({"kind": 5}));
        assert!(l.contains("?"), "{l}");
    }
}
