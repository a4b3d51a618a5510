//! The `[live_view]` and `[zenoh]` sections of the configuration file (both
//! read by `leakwatch` into its one config, and by the stage processes from the
//! run's config.toml).

use std::net::IpAddr;
use std::path::{Path, PathBuf};

use schema::{int, num, Range};
use serde::{Deserialize, Serialize};

/// Foxglove's default WebSocket port, the live view's default.
pub const DEFAULT_PORT: u16 = 8765;

/// Where `leakwatch watch` listens by default and a gateway connects by
/// default: Zenoh's usual port on this machine.
pub const DEFAULT_WATCH_ENDPOINT: &str = "tcp/127.0.0.1:7447";

schema::config_struct! {
    /// `[live_view]`: the Foxglove WebSocket live view.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct LiveViewConfig {
        /// Serve the live view in `leakwatch run` (also `run --live-view [PORT]`).
        pub enabled: bool = false,
        /// Address to listen on: `127.0.0.1` (this machine only, the default) or
        /// `0.0.0.0` (every interface: anyone who reaches the port sees the rig).
        pub bind: String = "127.0.0.1".into() => [
            "",
            Range::Stated("an IP address (127.0.0.1: this machine; 0.0.0.0: every interface)")
        ],
        /// TCP port, 1 to 65535 (8765 is Foxglove's default).
        pub port: u16 = DEFAULT_PORT => ["", int!(1, 65535, "(a TCP port)")],
        /// Sensor frames sent at most this often, Hz (of the rig's sample time).
        pub frames_hz: f64 = 50.0 => ["Hz", num!("a number", 0.1, 1000.0)],
        /// Estimates sent at most this often, Hz (events and health: every one).
        pub estimates_hz: f64 = 50.0 => ["Hz", num!("a number", 0.1, 1000.0)],
        /// Messages queued per client before the oldest are dropped (a slow
        /// client loses messages; the pipeline never waits for it), 1 to 65536.
        pub backlog: usize = 256 => ["messages", int!(1, 65536)],
        /// A token every client must send (`ws://HOST:PORT/?token=TOKEN`, or an
        /// `Authorization: Bearer TOKEN` header); a client without it is refused
        /// with HTTP 401. None by default. 16 to 256 characters of
        /// `A-Z a-z 0-9 - _ . ~` (nothing to escape in a URL). It is copied into
        /// the run's config.toml and its log's metadata: prefer `token_file`.
        pub token: Option<String> = None,
        /// A file holding the token (its first line), instead of `token`: a
        /// regular file of this user that nobody else can read (mode 0600 or 0400).
        pub token_file: Option<PathBuf> = None,
    }
}

schema::config_struct! {
    /// `[zenoh]`: the fleet gateway and `leakwatch watch`.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct ZenohConfig {
        /// Run the gateway in `leakwatch run` (also `run --zenoh`).
        pub enabled: bool = false,
        /// Zenoh endpoints the gateway listens on, e.g. `["tcp/0.0.0.0:7447"]` (none by default).
        pub listen: Vec<String> = Vec::new(),
        /// Zenoh endpoints the gateway connects to: a `leakwatch watch --listen`,
        /// a Zenoh router or another peer, e.g. `["tcp/10.0.0.5:7447"]` (default
        /// `tcp/127.0.0.1:7447`, a `leakwatch watch` on this machine).
        pub connect: Vec<String> = vec![DEFAULT_WATCH_ENDPOINT.to_string()],
        /// Zenoh's multicast scouting (finds peers on the local network by itself);
        /// off by default: only the endpoints given are used.
        pub multicast_scouting: bool = false,
        /// Estimates published at most this often, Hz (events and health: every one).
        pub estimates_hz: f64 = 10.0 => ["Hz", num!("a number", 0.1, 1000.0)],
        /// A file holding the key shared by the gateways and `watch` (its first
        /// line, at least 32 bytes; a file of this user with mode 0600): the
        /// gateway signs every message with it (HMAC-SHA256) and `watch` marks
        /// what it cannot verify `UNVERIFIED` and leaves out replays. None by
        /// default: unsigned, unverified.
        pub key_file: Option<PathBuf> = None,
        /// The oldest signed message `watch` accepts, s (and as far ahead: the
        /// clocks of the gateway's and the watch's machines must agree this well).
        pub max_age_s: f64 = 30.0 => ["s", num!("a number", 1, 3600)],
    }
}

/// Checks a Zenoh endpoint: `PROTOCOL/ADDRESS`, e.g. `tcp/127.0.0.1:7447`.
pub fn check_endpoint(e: &str) -> Result<(), String> {
    match e.split_once('/') {
        Some((proto, addr)) if !proto.is_empty() && !addr.is_empty() && e.len() <= 256 => Ok(()),
        _ => Err(format!(
            "zenoh endpoint {e:?}: expected PROTOCOL/ADDRESS, e.g. tcp/127.0.0.1:7447"
        )),
    }
}

/// Checks that `bind`, the `bind` field of the section `section` declared by
/// `schema`, is an IP address; the error says what it must be.
pub(crate) fn check_bind(section: &str, bind: &str, schema: &schema::Section) -> Result<(), String> {
    bind.parse::<IpAddr>().map(|_| ()).map_err(|_| {
        format!(
            "{section} bind = {bind:?}: must be {}",
            schema
                .find(&["bind"])
                .map(schema::Field::expected)
                .unwrap_or_default()
        )
    })
}

/// The shortest token of the live view, characters.
pub const MIN_TOKEN_LEN: usize = 16;

/// Checks a live view token: [`MIN_TOKEN_LEN`] to 256 characters of
/// `A-Z a-z 0-9 - _ . ~`; `what` names where it came from.
fn check_token(what: &str, t: &str) -> Result<(), String> {
    let ok_chars = t
        .bytes()
        .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'-' | b'_' | b'.' | b'~'));
    if (MIN_TOKEN_LEN..=256).contains(&t.len()) && ok_chars {
        Ok(())
    } else {
        Err(format!(
            "{what}: a token must be {MIN_TOKEN_LEN} to 256 characters of A-Z a-z 0-9 - _ . ~ (it has {} \
             characters{}); e.g. `head -c 24 /dev/urandom | base64 | tr +/ -_`",
            t.len(),
            if ok_chars { "" } else { ", some of them others" }
        ))
    }
}

/// Reads a secret from `path` (`what`: the setting that names it): a regular
/// file (not a link) of this user that nobody else can read or write (no group
/// or other permission bits), holding the secret on its first line. The
/// error names the file and what is wrong with it.
pub fn read_secret_file(what: &str, path: &Path) -> Result<String, String> {
    use std::io::Read;
    use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
    let shown = path.display();
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
        .open(path)
        .map_err(|e| format!("{what} {shown}: cannot open it: {e} (a symbolic link is not followed)"))?;
    let meta = f.metadata().map_err(|e| format!("{what} {shown}: {e}"))?;
    let me = current_uid();
    let mode = meta.mode() & 0o7777;
    if !meta.is_file() {
        return Err(format!("{what} {shown}: not a regular file"));
    }
    if meta.uid() != me {
        return Err(format!(
            "{what} {shown}: belongs to another user (uid {}, not {me}); it must be this user's",
            meta.uid()
        ));
    }
    if mode & 0o077 != 0 {
        return Err(format!(
            "{what} {shown}: mode {mode:o} lets other users read or write it; it must be 600 (chmod 600 {shown})"
        ));
    }
    let mut text = String::new();
    f.take(64 * 1024)
        .read_to_string(&mut text)
        .map_err(|e| format!("{what} {shown}: cannot read it: {e}"))?;
    let line = text.lines().next().unwrap_or("").trim().to_string();
    if line.is_empty() {
        return Err(format!(
            "{what} {shown}: empty (the secret goes on its first line)"
        ));
    }
    Ok(line)
}

impl LiveViewConfig {
    /// The token clients must send: `token`, or the first line of
    /// `token_file` (checked: this user's, mode 0600); `None` when neither is set.
    pub fn resolve_token(&self) -> Result<Option<String>, String> {
        match (&self.token, &self.token_file) {
            (Some(_), Some(_)) => Err("[live_view] token and token_file: give one of them, not both".into()),
            (Some(t), None) => check_token("[live_view] token", t).map(|()| Some(t.clone())),
            (None, Some(path)) => {
                let what = "[live_view] token_file";
                let t = read_secret_file(what, path)?;
                check_token(&format!("{what} {}", path.display()), &t)?;
                Ok(Some(t))
            }
            (None, None) => Ok(None),
        }
    }

    /// The warning for a live view that every host that reaches it can watch:
    /// bound to an address other than a loopback one, with no token.
    pub fn exposure_warning(&self) -> Option<String> {
        let open = self.bind.parse::<IpAddr>().is_ok_and(|a| !a.is_loopback());
        (open && self.token.is_none() && self.token_file.is_none()).then(|| {
            format!(
                "the live view listens on {}:{} with no token: anyone who reaches that port sees the rig live; \
                 set [live_view] token_file (clients then connect to ws://HOST:{}/?token=TOKEN) or bind 127.0.0.1 \
                 (see docs/security.md)",
                self.bind, self.port, self.port
            )
        })
    }

    /// Checks every field; the error names the field, its range and unit.
    pub fn validate(&self) -> Result<(), String> {
        self.check_ranges("").map_err(|e| format!("[live_view] {e}"))?;
        self.resolve_token()?;
        check_bind("[live_view]", &self.bind, &Self::SCHEMA)?;
        Ok(())
    }
}

impl ZenohConfig {
    /// Checks every field; the error names the field, its range and unit.
    pub fn validate(&self) -> Result<(), String> {
        self.check_ranges("").map_err(|e| format!("[zenoh] {e}"))?;
        for e in self.listen.iter().chain(&self.connect) {
            check_endpoint(e).map_err(|m| format!("[zenoh] {m}"))?;
        }
        self.key().map(|_| ())
    }

    /// The shared key of `key_file` (checked: this user's, mode 0600, at least
    /// 32 bytes); `None` without one.
    pub fn key(&self) -> Result<Option<Vec<u8>>, String> {
        self.key_file.as_deref().map(read_key).transpose()
    }
}

/// The shortest shared key, bytes (its file's first line).
pub const MIN_KEY_LEN: usize = 32;

/// The shared key from `[zenoh] key_file` `path`: its first line, at least
/// [`MIN_KEY_LEN`] bytes, from a file of this user with mode 0600 (checked:
/// [`read_secret_file`]).
pub fn read_key(path: &Path) -> Result<Vec<u8>, String> {
    let what = "[zenoh] key_file";
    let key = read_secret_file(what, path)?;
    if key.len() < MIN_KEY_LEN {
        return Err(format!(
            "{what} {}: the key has {} bytes; at least {MIN_KEY_LEN} are needed (e.g. `head -c 32 /dev/urandom | \
             base64 > FILE; chmod 600 FILE`, the same file on the gateway's and the watch's machine)",
            path.display(),
            key.len()
        ));
    }
    Ok(key.into_bytes())
}

/// This process's effective user id.
fn current_uid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        LiveViewConfig::default().validate().unwrap();
        ZenohConfig::default().validate().unwrap();
        let v = LiveViewConfig {
            estimates_hz: 0.0,
            ..LiveViewConfig::default()
        };
        assert_eq!(
            v.validate().unwrap_err(),
            "[live_view] estimates_hz = 0.0: must be a number from 0.1 to 1000.0 Hz"
        );
        let v = LiveViewConfig {
            bind: "localhost:1".into(),
            ..LiveViewConfig::default()
        };
        assert!(v.validate().unwrap_err().contains("bind"));
        let z = ZenohConfig {
            connect: vec!["127.0.0.1:7447".into()],
            ..ZenohConfig::default()
        };
        assert!(z.validate().unwrap_err().contains("PROTOCOL/ADDRESS"));
    }

    #[test]
    fn a_token_is_checked_and_its_file_must_be_private() {
        use std::os::unix::fs::PermissionsExt;
        let inline = |t: &str| LiveViewConfig {
            token: Some(t.into()),
            ..LiveViewConfig::default()
        };
        assert_eq!(
            inline("abcdefghijklmnop").resolve_token(),
            Ok(Some("abcdefghijklmnop".into()))
        );
        assert!(inline("short")
            .validate()
            .unwrap_err()
            .contains("16 to 256 characters"));
        assert!(inline("abcdefghijklmnop q")
            .validate()
            .unwrap_err()
            .contains("some of them others"));
        let dir = std::env::temp_dir().join(format!("lw-token-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("token");
        std::fs::write(&file, "0123456789abcdefXYZ\n").unwrap();
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o644)).unwrap();
        let from_file = LiveViewConfig {
            token_file: Some(file.clone()),
            ..LiveViewConfig::default()
        };
        let e = from_file.validate().unwrap_err();
        assert!(
            e.contains(&format!(
                "[live_view] token_file {}: mode 644 lets other users read",
                file.display()
            )),
            "{e}"
        );
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o600)).unwrap();
        assert_eq!(from_file.resolve_token(), Ok(Some("0123456789abcdefXYZ".into())));
        let link = dir.join("link");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        let e = LiveViewConfig {
            token_file: Some(link),
            ..LiveViewConfig::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.contains("cannot open it"), "{e}");
        let both = LiveViewConfig {
            token: Some("abcdefghijklmnop".into()),
            ..from_file.clone()
        };
        assert!(both.validate().unwrap_err().contains("not both"));
        std::fs::remove_dir_all(&dir).unwrap();
        // the exposure warning: any address but a loopback one, without a token
        assert_eq!(LiveViewConfig::default().exposure_warning(), None);
        let open = LiveViewConfig {
            bind: "0.0.0.0".into(),
            ..LiveViewConfig::default()
        };
        assert!(open
            .exposure_warning()
            .is_some_and(|w| w.contains("0.0.0.0:8765 with no token")));
        assert_eq!(
            LiveViewConfig {
                token_file: Some(file),
                ..open
            }
            .exposure_warning(),
            None
        );
    }
}
