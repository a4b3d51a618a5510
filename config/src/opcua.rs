//! `[opcua]`: the OPC UA server a plant's SCADA reads a rig's state and leak
//! alarms from (`leakwatch stage opcua`, `run --opcua`). Read-only: no node
//! of its address space can be written, no method called.

use std::net::IpAddr;
use std::path::PathBuf;

use schema::{int, num, Range};
use serde::{Deserialize, Serialize};

use crate::live::read_secret_file;

/// The OPC UA port of the standard (IANA's `opc-ua-tcp`).
pub const DEFAULT_PORT: u16 = 4840;

/// The security policies the server offers, by their names in `[opcua]
/// security_policies`: `None` (no signing, no encryption) and two that sign
/// and encrypt every message (mode SignAndEncrypt).
pub const POLICIES: [&str; 3] = ["None", "Basic256Sha256", "Aes128Sha256RsaOaep"];

schema::config_struct! {
    /// `[opcua]`: the OPC UA server output.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct OpcuaConfig {
        /// Serve the rig over OPC UA in `leakwatch run` (also `run --opcua`).
        pub enabled: bool = false,
        /// Address to listen on: `127.0.0.1` (this machine only, the default) or
        /// `0.0.0.0` (every interface).
        pub bind: String = "127.0.0.1".into() => [
            "",
            Range::Stated("an IP address (127.0.0.1: this machine; 0.0.0.0: every interface)")
        ],
        /// TCP port, 1 to 65535 (4840 is OPC UA's); the endpoint is `opc.tcp://HOST:PORT/`.
        pub port: u16 = DEFAULT_PORT => ["", int!(1, 65535, "(a TCP port)")],
        /// The state variables are updated at most this often, Hz (10 to 50).
        pub update_hz: f64 = 20.0 => ["Hz", num!("a number", 10, 50)],
        /// The security policies offered, of `None`, `Basic256Sha256` and
        /// `Aes128Sha256RsaOaep` (the last two sign and encrypt; they need
        /// `pki_dir`); default `["None"]`.
        pub security_policies: Vec<String> = vec!["None".into()],
        /// The one user a client must log in as (with `password_file`); anonymous
        /// clients are then refused. None by default: anonymous, read-only.
        pub user: Option<String> = None,
        /// A file holding the user's password (its first line): a regular file of
        /// this user that nobody else can read (mode 0600 or 0400).
        pub password_file: Option<PathBuf> = None,
        /// The server's certificate store: `own/cert.der` and `private/private.pem`
        /// (made, self-signed, when absent), `trusted/` and `rejected/` client
        /// certificates; needed by a signing policy or a user (the password is
        /// sent encrypted with the server's certificate).
        pub pki_dir: Option<PathBuf> = None,
        /// Accept any client certificate on a signing policy (by default only those
        /// copied into `pki_dir/trusted/`).
        pub trust_client_certs: bool = false,
    }
}

impl OpcuaConfig {
    /// Whether a policy other than `None` is offered.
    pub fn secure(&self) -> bool {
        self.security_policies.iter().any(|p| p != "None")
    }

    /// The user and the password clients must log in with (the password read
    /// from `password_file`, checked: this user's, mode 0600); `None` when no
    /// user is configured (anonymous).
    pub fn credentials(&self) -> Result<Option<(String, String)>, String> {
        match (&self.user, &self.password_file) {
            (None, None) => Ok(None),
            (Some(u), Some(f)) => {
                let ok = !u.is_empty() && u.len() <= 64 && u.bytes().all(|b| b.is_ascii_graphic());
                if !ok {
                    return Err(format!(
                        "[opcua] user = {u:?}: must be 1 to 64 printable ASCII characters, no spaces"
                    ));
                }
                let pass = read_secret_file("[opcua] password_file", f)?;
                if pass.len() < 8 {
                    return Err(format!(
                        "[opcua] password_file {}: the password has {} characters; at least 8 are needed",
                        f.display(),
                        pass.len()
                    ));
                }
                Ok(Some((u.clone(), pass)))
            }
            (Some(_), None) => {
                Err("[opcua] user: give password_file too (the password is not written inline)".into())
            }
            (None, Some(_)) => Err("[opcua] password_file: give user too".into()),
        }
    }

    /// Checks every field; the error names the field, its range and unit.
    pub fn validate(&self) -> Result<(), String> {
        self.check_ranges("").map_err(|e| format!("[opcua] {e}"))?;
        crate::live::check_bind("[opcua]", &self.bind, &Self::SCHEMA)?;
        if self.security_policies.is_empty() {
            return Err(format!(
                "[opcua] security_policies = []: give at least one of {}",
                POLICIES.join(", ")
            ));
        }
        for (i, p) in self.security_policies.iter().enumerate() {
            if !POLICIES.contains(&p.as_str()) {
                return Err(format!(
                    "[opcua] security_policies: {p:?} is not one of {}",
                    POLICIES.join(", ")
                ));
            }
            if self.security_policies[..i].contains(p) {
                return Err(format!("[opcua] security_policies: {p:?} is given twice"));
            }
        }
        let user = self.credentials()?;
        if (self.secure() || user.is_some()) && self.pki_dir.is_none() {
            return Err(
                "[opcua] pki_dir: needed by a security policy other than None or a user (the server's \
                 certificate and private key are kept there, made when absent)"
                    .into(),
            );
        }
        Ok(())
    }

    /// The warning for a server that every host that reaches it can read with
    /// no login: bound to an address other than a loopback one, with no user.
    pub fn exposure_warning(&self) -> Option<String> {
        let open = self.bind.parse::<IpAddr>().is_ok_and(|a| !a.is_loopback());
        (open && self.user.is_none()).then(|| {
            format!(
                "the OPC UA server listens on {}:{} with anonymous access: anyone who reaches that port reads the \
                 rig's state (read-only); set [opcua] user and password_file, or bind 127.0.0.1 (see docs/opcua.md)",
                self.bind, self.port
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_anonymous_read_only_on_the_loopback_and_bad_values_are_named() {
        let d = OpcuaConfig::default();
        d.validate().unwrap();
        assert_eq!((d.bind.as_str(), d.port, d.secure()), ("127.0.0.1", 4840, false));
        assert_eq!(d.credentials(), Ok(None));
        assert_eq!(d.exposure_warning(), None);
        let slow = OpcuaConfig {
            update_hz: 5.0,
            ..OpcuaConfig::default()
        };
        assert_eq!(
            slow.validate().unwrap_err(),
            "[opcua] update_hz = 5.0: must be a number from 10 to 50 Hz"
        );
        let bad = OpcuaConfig {
            security_policies: vec!["Basic128Rsa15".into()],
            ..OpcuaConfig::default()
        };
        assert!(bad.validate().unwrap_err().contains("is not one of None"));
        let secure = OpcuaConfig {
            security_policies: vec!["None".into(), "Basic256Sha256".into()],
            ..OpcuaConfig::default()
        };
        assert!(secure.validate().unwrap_err().contains("[opcua] pki_dir"));
        let inline = OpcuaConfig {
            user: Some("scada".into()),
            ..OpcuaConfig::default()
        };
        assert!(inline.validate().unwrap_err().contains("password_file"));
        let open = OpcuaConfig {
            bind: "0.0.0.0".into(),
            ..OpcuaConfig::default()
        };
        assert!(open.exposure_warning().is_some_and(|w| w.contains("anonymous")));
    }

    #[test]
    fn the_password_comes_from_a_private_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = std::env::temp_dir().join(format!("lw-opcua-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("password");
        std::fs::write(&file, "s3cret-pass\n").unwrap();
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o644)).unwrap();
        let cfg = OpcuaConfig {
            user: Some("scada".into()),
            password_file: Some(file.clone()),
            pki_dir: Some(dir.join("pki")),
            ..OpcuaConfig::default()
        };
        assert!(cfg.validate().unwrap_err().contains("mode 644"));
        std::fs::set_permissions(&file, std::fs::Permissions::from_mode(0o600)).unwrap();
        cfg.validate().unwrap();
        assert_eq!(
            cfg.credentials(),
            Ok(Some(("scada".into(), "s3cret-pass".into())))
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
