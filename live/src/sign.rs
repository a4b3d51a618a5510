//! Signed Zenoh messages: the gateway signs each message with an HMAC-SHA256
//! under a key shared with `leakwatch watch` (`[zenoh] key_file`), and `watch`
//! verifies it. The payload stays the plain JSON message (any Zenoh client
//! reads it); the signature travels in the sample's attachment, as ASCII:
//!
//! ```text
//! lw1 <boot> <seq> <time> <mac>
//! ```
//!
//! `boot`: when the gateway process started (Unix ns), `seq`: its message
//! count (from 1), `time`: when the message was signed (Unix ns), `mac`: 64 hex
//! digits of HMAC-SHA256 over [`signed_bytes`] (the key expression, the three
//! numbers and the payload). So a signed message cannot be moved to another
//! rig's key or changed; a replayed one is refused by [`Verifier`] when it is
//! older than `max_age_s` or not newer than the last one of its key (`boot`,
//! then `seq`).

use std::collections::BTreeMap;

use hmac::{Hmac, Mac};
use sha2::Sha256;

type HmacSha256 = Hmac<Sha256>;

/// The first word of a signature attachment (the format's version).
pub const SIGNATURE_TAG: &str = "lw1";

/// The bytes a signature covers: a domain tag, the key expression, `boot`,
/// `seq`, `time` and the payload, separated by newlines.
pub fn signed_bytes(key_expr: &str, boot: u64, seq: u64, time_ns: u64, payload: &[u8]) -> Vec<u8> {
    let mut b =
        format!("leakwatch-zenoh-{SIGNATURE_TAG}\n{key_expr}\n{boot}\n{seq}\n{time_ns}\n").into_bytes();
    b.extend_from_slice(payload);
    b
}

/// The current Unix time, ns (0 if the clock is before 1970).
pub fn unix_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}

fn mac_of(key: &[u8], bytes: &[u8]) -> HmacSha256 {
    // HMAC takes a key of any length: new_from_slice cannot fail
    let mut m = <HmacSha256 as Mac>::new_from_slice(key)
        .unwrap_or_else(|_| unreachable!("HMAC takes any key length"));
    m.update(bytes);
    m
}

/// The gateway's signer: one `boot` per process, `seq` counting its messages.
#[derive(Clone)]
pub struct Signer {
    key: Vec<u8>,
    boot: u64,
    seq: u64,
}

impl Signer {
    /// A signer with the shared `key`, its `boot` now.
    pub fn new(key: Vec<u8>) -> Signer {
        Signer {
            key,
            boot: unix_ns(),
            seq: 0,
        }
    }

    /// The attachment that signs `payload` on `key_expr`, at `time_ns` (Unix ns).
    pub fn sign_at(&mut self, key_expr: &str, payload: &[u8], time_ns: u64) -> String {
        self.seq += 1;
        let mac = mac_of(
            &self.key,
            &signed_bytes(key_expr, self.boot, self.seq, time_ns, payload),
        );
        let hex: String = mac
            .finalize()
            .into_bytes()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        format!("{SIGNATURE_TAG} {} {} {time_ns} {hex}", self.boot, self.seq)
    }

    /// [`Signer::sign_at`] now.
    pub fn sign(&mut self, key_expr: &str, payload: &[u8]) -> String {
        self.sign_at(key_expr, payload, unix_ns())
    }
}

/// What [`Verifier::check`] found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Signed with the shared key, fresh and newer than the last of its key.
    Verified,
    /// Not verified: no signature, a malformed one, or one the key did not make
    /// (the reason).
    Unverified(String),
    /// Signed with the shared key but a replay: too old or not newer than the
    /// last message of its key (the reason).
    Replayed(String),
}

/// `watch`'s verifier: the shared key, the longest age accepted, and per key
/// expression the newest (`boot`, `seq`) verified.
pub struct Verifier {
    key: Vec<u8>,
    max_age_ns: u64,
    last: BTreeMap<String, (u64, u64)>,
}

impl Verifier {
    /// A verifier with the shared `key` accepting messages up to `max_age_s` old
    /// (and as far ahead: the clocks of two machines differ).
    pub fn new(key: Vec<u8>, max_age_s: f64) -> Verifier {
        Verifier {
            key,
            max_age_ns: (max_age_s.max(0.0) * 1e9) as u64,
            last: BTreeMap::new(),
        }
    }

    /// Checks a message: its key expression, payload and attachment, at `now_ns`
    /// (Unix ns). A verified message becomes the newest of its key.
    pub fn check(
        &mut self,
        key_expr: &str,
        payload: &[u8],
        attachment: Option<&[u8]>,
        now_ns: u64,
    ) -> Verdict {
        let Some(att) = attachment else {
            return Verdict::Unverified("no signature".into());
        };
        let Ok(att) = std::str::from_utf8(att) else {
            return Verdict::Unverified("a signature that is not text".into());
        };
        let parts: Vec<&str> = att.split(' ').collect();
        let [tag, boot, seq, time, hex] = parts[..] else {
            return Verdict::Unverified("a malformed signature".into());
        };
        let (Ok(boot), Ok(seq), Ok(time)) = (boot.parse::<u64>(), seq.parse::<u64>(), time.parse::<u64>())
        else {
            return Verdict::Unverified("a malformed signature".into());
        };
        if tag != SIGNATURE_TAG || hex.len() != 64 {
            return Verdict::Unverified(format!("a signature of another format ({tag})"));
        }
        let Some(mac_bytes) = (0..32)
            .map(|i| {
                hex.get(2 * i..2 * i + 2)
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
            })
            .collect::<Option<Vec<u8>>>()
        else {
            return Verdict::Unverified("a malformed signature".into());
        };
        // constant-time comparison (hmac's verify_slice)
        if mac_of(&self.key, &signed_bytes(key_expr, boot, seq, time, payload))
            .verify_slice(&mac_bytes)
            .is_err()
        {
            return Verdict::Unverified("a signature the shared key did not make".into());
        }
        let age_ns = now_ns.abs_diff(time);
        if age_ns > self.max_age_ns {
            return Verdict::Replayed(format!(
                "signed {:.1} s {} (at most {:.1} s accepted)",
                age_ns as f64 * 1e-9,
                if time <= now_ns {
                    "ago"
                } else {
                    "ahead of this clock"
                },
                self.max_age_ns as f64 * 1e-9
            ));
        }
        if let Some(&(last_boot, last_seq)) = self.last.get(key_expr) {
            if (boot, seq) <= (last_boot, last_seq) {
                return Verdict::Replayed(format!(
                    "message {seq} of gateway start {boot}, not newer than the last one ({last_seq} of {last_boot})"
                ));
            }
        }
        self.last.insert(key_expr.to_string(), (boot, seq));
        Verdict::Verified
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEY: &[u8] = b"0123456789abcdef0123456789abcdef";

    #[test]
    fn a_signed_message_verifies_once_and_a_changed_or_moved_one_does_not() {
        let mut s = Signer::new(KEY.to_vec());
        let mut v = Verifier::new(KEY.to_vec(), 30.0);
        let now = unix_ns();
        let key = "leakwatch/r1/events";
        let msg = br#"{"kind":"ext1"}"#;
        let att = s.sign_at(key, msg, now);
        assert_eq!(
            v.check(key, msg, Some(att.as_bytes()), now + 1),
            Verdict::Verified
        );
        // the same message again: a replay
        assert!(matches!(
            v.check(key, msg, Some(att.as_bytes()), now + 2),
            Verdict::Replayed(_)
        ));
        // changed, moved to another rig, unsigned, signed with another key
        let att2 = s.sign_at(key, msg, now);
        assert!(
            matches!(v.check(key, br#"{"kind":"ext2"}"#, Some(att2.as_bytes()), now), Verdict::Unverified(r) if r.contains("did not make"))
        );
        assert!(matches!(
            v.check("leakwatch/r2/events", msg, Some(att2.as_bytes()), now),
            Verdict::Unverified(_)
        ));
        assert_eq!(
            v.check(key, msg, None, now),
            Verdict::Unverified("no signature".into())
        );
        let forged = Signer::new(b"another key of thirty-two bytes!".to_vec()).sign_at(key, msg, now);
        assert!(matches!(
            v.check(key, msg, Some(forged.as_bytes()), now),
            Verdict::Unverified(_)
        ));
        assert!(
            matches!(v.check(key, msg, Some(b"lw1 1 2 x"), now), Verdict::Unverified(r) if r == "a malformed signature")
        );
        // the next one of the signer still verifies (the failed checks changed nothing)
        assert_eq!(v.check(key, msg, Some(att2.as_bytes()), now), Verdict::Verified);
        // too old
        let old = s.sign_at(key, msg, now - 31_000_000_000);
        assert!(
            matches!(v.check(key, msg, Some(old.as_bytes()), now), Verdict::Replayed(r) if r.contains("31.0 s ago"))
        );
        // a restarted gateway (a later boot) starts its count again
        let mut again = Signer::new(KEY.to_vec());
        again.boot = s.boot + 1;
        let first = again.sign_at(key, msg, now);
        assert_eq!(v.check(key, msg, Some(first.as_bytes()), now), Verdict::Verified);
    }
}
