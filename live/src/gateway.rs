//! The fleet gateway: a rig's events, health and decimated estimates
//! published on Zenoh under `leakwatch/<rig>/<topic>` (JSON, the messages of
//! [`crate::json`]; encoding `application/json`), for `leakwatch watch`, a
//! Zenoh router or any Zenoh client (Python's `eclipse-zenoh`, ...).
//!
//! Zenoh runs in peer mode over TCP only, on the endpoints of the `[zenoh]`
//! section, with multicast scouting off unless asked for: what connects to
//! what is what the configuration says. Events are sent reliably and block
//! briefly under congestion; health and estimates are dropped under
//! congestion (the next ones follow at 10 Hz).

use zenoh::qos::CongestionControl;
use zenoh::{Session, Wait};

use crate::sign::Signer;
use crate::{LiveTopic, Sink};
use config::live::ZenohConfig;

/// The first part of every key leakwatch publishes.
pub const KEY_ROOT: &str = "leakwatch";

/// The Zenoh key of `topic` of rig `rig`: `leakwatch/<rig>/<topic>`.
pub fn key(rig: &str, topic: LiveTopic) -> String {
    format!("{KEY_ROOT}/{rig}/{}", topic.name())
}

/// The rig and topic of a key `leakwatch/<rig>/<topic>` (`None`: another key).
pub fn parse_key(key: &str) -> Option<(&str, &str)> {
    let mut parts = key.split('/');
    match (parts.next(), parts.next(), parts.next(), parts.next()) {
        (Some(KEY_ROOT), Some(rig), Some(topic), None) => Some((rig, topic)),
        _ => None,
    }
}

/// A Zenoh session configured from `cfg` (peer mode, TCP, the endpoints given,
/// multicast scouting as configured).
pub fn open_session(cfg: &ZenohConfig) -> Result<Session, String> {
    let mut c = zenoh::Config::default();
    let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
    let settings = [
        ("mode", "\"peer\"".to_string()),
        ("scouting/multicast/enabled", cfg.multicast_scouting.to_string()),
        ("listen/endpoints", list(&cfg.listen)),
        ("connect/endpoints", list(&cfg.connect)),
    ];
    for (key, value) in settings {
        c.insert_json5(key, &value)
            .map_err(|e| format!("zenoh configuration {key} = {value}: {e}"))?;
    }
    zenoh::open(c)
        .wait()
        .map_err(|e| format!("cannot open a zenoh session: {e}"))
}

/// The gateway's publishers (one per topic but the sensor frames), and its
/// signer with `[zenoh] key_file` ([`crate::sign`]).
pub struct Gateway {
    _session: Session,
    publishers: Vec<Option<zenoh::pubsub::Publisher<'static>>>,
    keys: Vec<String>,
    signer: Option<Signer>,
    /// Messages Zenoh refused to send (e.g. the session closing).
    pub errors: u64,
}

impl Gateway {
    /// Opens the session and declares the publishers of rig `rig`; with
    /// `[zenoh] key_file`, every message is signed.
    pub fn open(rig: &str, cfg: &ZenohConfig) -> Result<Gateway, String> {
        let signer = cfg.key()?.map(Signer::new);
        let session = open_session(cfg)?;
        let mut publishers = Vec::new();
        for topic in LiveTopic::ALL {
            if topic == LiveTopic::Frames {
                publishers.push(None);
                continue;
            }
            let congestion = if topic == LiveTopic::Events {
                CongestionControl::Block
            } else {
                CongestionControl::Drop
            };
            let p = session
                .declare_publisher(key(rig, topic))
                .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
                .congestion_control(congestion)
                .wait()
                .map_err(|e| format!("cannot declare the zenoh publisher {}: {e}", key(rig, topic)))?;
            publishers.push(Some(p));
        }
        Ok(Gateway {
            _session: session,
            publishers,
            keys: LiveTopic::ALL.iter().map(|t| key(rig, *t)).collect(),
            signer,
            errors: 0,
        })
    }
}

impl Sink for Gateway {
    fn wants(&self, topic: LiveTopic) -> bool {
        self.publishers[topic.index()].is_some()
    }

    fn send(&mut self, topic: LiveTopic, json: &[u8], _log_time_ns: u64) {
        if let Some(p) = &self.publishers[topic.index()] {
            let put = p.put(json.to_vec());
            let put = match &mut self.signer {
                Some(s) => put.attachment(s.sign(&self.keys[topic.index()], json)),
                None => put,
            };
            if put.wait().is_err() {
                self.errors += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_name_rig_and_topic() {
        assert_eq!(key("rig-7", LiveTopic::Events), "leakwatch/rig-7/events");
        assert_eq!(parse_key("leakwatch/rig-7/health"), Some(("rig-7", "health")));
        assert_eq!(parse_key("leakwatch/rig-7"), None);
        assert_eq!(parse_key("other/rig/events"), None);
    }
}
