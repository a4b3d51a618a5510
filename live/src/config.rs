//! The `[live_view]` and `[zenoh]` sections of the configuration file (both
//! read by `leakwatch` into its one config, and by the stage processes from the
//! run's config.toml).

use std::net::IpAddr;

use serde::{Deserialize, Serialize};

/// Foxglove's default WebSocket port, the live view's default.
pub const DEFAULT_PORT: u16 = 8765;

/// Where `leakwatch watch` listens by default and a gateway connects by
/// default: Zenoh's usual port on this machine.
pub const DEFAULT_WATCH_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// Highest rate of a decimated stream, Hz (the rig's own sample rate).
pub const MAX_RATE_HZ: f64 = 1000.0;
/// Lowest rate of a decimated stream, Hz.
pub const MIN_RATE_HZ: f64 = 0.1;

/// `[live_view]`: the Foxglove WebSocket live view.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LiveViewConfig {
    /// Serve the live view in `leakwatch run` (also `run --live-view [PORT]`).
    pub enabled: bool,
    /// Address to listen on: `127.0.0.1` (this machine only, the default) or
    /// `0.0.0.0` (every interface: anyone who reaches the port sees the rig).
    pub bind: String,
    /// TCP port, 1 to 65535 (8765 is Foxglove's default).
    pub port: u16,
    /// Sensor frames sent at most this often, Hz (of the rig's sample time).
    pub frames_hz: f64,
    /// Estimates sent at most this often, Hz (events and health: every one).
    pub estimates_hz: f64,
    /// Messages queued per client before the oldest are dropped (a slow
    /// client loses messages; the pipeline never waits for it), 1 to 65536.
    pub backlog: usize,
}

impl Default for LiveViewConfig {
    fn default() -> Self {
        LiveViewConfig {
            enabled: false,
            bind: "127.0.0.1".into(),
            port: DEFAULT_PORT,
            frames_hz: 50.0,
            estimates_hz: 50.0,
            backlog: 256,
        }
    }
}

/// `[zenoh]`: the fleet gateway and `leakwatch watch`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ZenohConfig {
    /// Run the gateway in `leakwatch run` (also `run --zenoh`).
    pub enabled: bool,
    /// Zenoh endpoints the gateway listens on, e.g. `["tcp/0.0.0.0:7447"]` (none by default).
    pub listen: Vec<String>,
    /// Zenoh endpoints the gateway connects to: a `leakwatch watch --listen`,
    /// a Zenoh router or another peer, e.g. `["tcp/10.0.0.5:7447"]` (default
    /// `tcp/127.0.0.1:7447`, a `leakwatch watch` on this machine).
    pub connect: Vec<String>,
    /// Zenoh's multicast scouting (finds peers on the local network by itself);
    /// off by default: only the endpoints given are used.
    pub multicast_scouting: bool,
    /// Estimates published at most this often, Hz (events and health: every one).
    pub estimates_hz: f64,
}

impl Default for ZenohConfig {
    fn default() -> Self {
        ZenohConfig {
            enabled: false,
            listen: Vec::new(),
            connect: vec![DEFAULT_WATCH_ENDPOINT.to_string()],
            multicast_scouting: false,
            estimates_hz: 10.0,
        }
    }
}

fn check_rate(section: &str, name: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&v) {
        Ok(())
    } else {
        Err(format!(
            "[{section}] {name} = {v:?}: must be a number from {MIN_RATE_HZ:?} to {MAX_RATE_HZ:?} Hz"
        ))
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

impl LiveViewConfig {
    /// Checks every field; the error names the field, its range and unit.
    pub fn validate(&self) -> Result<(), String> {
        self.bind.parse::<IpAddr>().map_err(|_| {
            format!(
                "[live_view] bind = {:?}: must be an IP address (127.0.0.1: this machine; 0.0.0.0: every interface)",
                self.bind
            )
        })?;
        if self.port == 0 {
            return Err("[live_view] port = 0: must be 1 to 65535 (a TCP port)".into());
        }
        check_rate("live_view", "frames_hz", self.frames_hz)?;
        check_rate("live_view", "estimates_hz", self.estimates_hz)?;
        if !(1..=65_536).contains(&self.backlog) {
            return Err(format!(
                "[live_view] backlog = {}: must be 1 to 65536 messages",
                self.backlog
            ));
        }
        Ok(())
    }
}

impl ZenohConfig {
    /// Checks every field; the error names the field, its range and unit.
    pub fn validate(&self) -> Result<(), String> {
        for e in self.listen.iter().chain(&self.connect) {
            check_endpoint(e).map_err(|m| format!("[zenoh] {m}"))?;
        }
        check_rate("zenoh", "estimates_hz", self.estimates_hz)
    }
}

/// The two sections as a stage reads them from the run's config file (every
/// other section ignored).
#[derive(Debug, Default, Deserialize)]
#[serde(default)]
pub struct LiveSections {
    /// `[live_view]`.
    pub live_view: LiveViewConfig,
    /// `[zenoh]`.
    pub zenoh: ZenohConfig,
}

impl LiveSections {
    /// Reads `[live_view]` and `[zenoh]` from a config file (defaults without one).
    pub fn load(path: Option<&std::path::Path>) -> Result<LiveSections, String> {
        let Some(path) = path else {
            return Ok(LiveSections::default());
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read config {}: {e}", path.display()))?;
        let s: LiveSections = toml::from_str(&text)
            .map_err(|e| format!("config {}: {}", path.display(), e.message().trim()))?;
        s.live_view
            .validate()
            .and_then(|_| s.zenoh.validate())
            .map_err(|e| format!("config {}: {e}", path.display()))?;
        Ok(s)
    }
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
}
