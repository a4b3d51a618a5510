//! `leakwatch watch`: every rig's events over Zenoh, as they happen ([`live::watch`]).

use std::path::Path;

/// Watches `leakwatch/**` listening on `listen` and connecting to `connect`
/// (neither: listening on tcp/127.0.0.1:7447), for `seconds` or until Ctrl-C.
pub fn command(
    listen: Vec<String>,
    connect: Vec<String>,
    seconds: Option<f64>,
    config: Option<&Path>,
) -> Result<(), String> {
    let mut cfg = match config {
        Some(p) => config::Config::load(p)?.zenoh,
        None => config::live::ZenohConfig::default(),
    };
    cfg.listen = listen;
    cfg.connect = connect;
    if cfg.listen.is_empty() && cfg.connect.is_empty() {
        cfg.listen = vec![config::live::DEFAULT_WATCH_ENDPOINT.to_string()];
    }
    cfg.validate()?;
    if let Some(s) = seconds {
        if !(s.is_finite() && s > 0.0) {
            return Err(format!("--seconds {s}: must be a positive number of seconds"));
        }
    }
    let stop = bus::stop_on_signals();
    let mut out = std::io::stdout().lock();
    live::watch::watch(&cfg, seconds, stop, &mut out).map(|_| ())
}
