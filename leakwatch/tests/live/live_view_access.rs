//! Who reads the live view: a token file refuses others; Foxglove's ws-protocol gets every topic.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::*;
use bus::BusConfig;
use serde_json::Value;

use crate::{example, free_port, sigterm, BIN, SERIAL};

/// The status line of a WebSocket handshake for `path` on `port` (offering
/// `foxglove.sdk.v1`); a refused connection panics with the server's `log`.
fn handshake_status(port: u16, path: &str, log: &Path) -> String {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap_or_else(|e| {
        let log = std::fs::read_to_string(log).unwrap_or_default();
        panic!("the live view on port {port} refused {path}: {e}\n{log}")
    });
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\
         Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n"
    )
    .unwrap();
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n") && s.read(&mut b).unwrap_or(0) == 1 {
        head.push(b[0]);
    }
    String::from_utf8_lossy(&head).trim().to_string()
}

/// The live view stage with `[live_view] token_file` (mode 0600) in its
/// config: a client without the token, or with a wrong one, is answered 401;
/// one with `?token=` is switched to the WebSocket protocol.
#[test]
fn a_live_view_with_a_token_file_refuses_a_client_without_the_token() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmpdir("token");
    let token = "tok-0123456789abcdefghij";
    let token_file = dir.join("token");
    std::fs::write(&token_file, format!("{token}\n")).unwrap();
    std::fs::set_permissions(&token_file, std::fs::Permissions::from_mode(0o600)).unwrap();
    let cfg = dir.join("cfg.toml");
    std::fs::write(
        &cfg,
        format!(
            "[live_view]\ntoken_file = {:?}\n",
            token_file.display().to_string()
        ),
    )
    .unwrap();
    let prefix = format!("lwtk{}", std::process::id());
    let log_path = dir.join("liveview.log");
    let log = std::fs::File::create(&log_path).unwrap();
    // port 0: the stage binds any free port and says which in its log
    let mut view = Command::new(BIN)
        .args(["stage", "liveview", "--rig", "tk", "--port", "0", "--config"])
        .arg(&cfg)
        .env(bus::PREFIX_ENV, &prefix)
        .stderr(log)
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let port = loop {
        let log = std::fs::read_to_string(&log_path).unwrap_or_default();
        if let Some(port) = log
            .split("Foxglove WebSocket on ws://127.0.0.1:")
            .nth(1)
            .and_then(|rest| rest.split(' ').next())
            .and_then(|p| p.parse::<u16>().ok())
        {
            break port;
        }
        if let Ok(Some(status)) = view.try_wait() {
            panic!("the live view stage ended ({status}) before it listened:\n{log}");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the live view never said it listens:\n{log}"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let none = handshake_status(port, "/", &log_path);
    let wrong = handshake_status(port, "/?token=tok-0123456789abcdefghiX", &log_path);
    let right = handshake_status(port, &format!("/?token={token}"), &log_path);
    sigterm(&view);
    let _ = view.wait();
    BusConfig {
        iox_prefix: Some(prefix),
        ..BusConfig::default()
    }
    .remove_isolated_files()
    .unwrap();
    let log = std::fs::read_to_string(&log_path).unwrap();
    assert_eq!(none, "HTTP/1.1 401 Unauthorized", "{log}");
    assert_eq!(wrong, "HTTP/1.1 401 Unauthorized", "{log}");
    assert!(right.starts_with("HTTP/1.1 101"), "{right}\n{log}");
    assert!(
        log.contains("refused (HTTP 401): no token") && log.contains("refused (HTTP 401): a wrong token"),
        "{log}"
    );
}

/// Foxglove's own client library, `@foxglove/ws-protocol` (node), on a running
/// `leakwatch run --live-view` of a leak: with its default subprotocol it
/// receives frames, estimates, health and the leak's event (ext1). It runs
/// where `LEAKWATCH_NODE_MODULES` holds the package (.ci/setup installs it;
/// required with LEAKWATCH_REQUIRE_NODE=1, skipped elsewhere).
#[test]
fn foxglove_ws_protocol_receives_every_topic_of_a_running_rig() {
    let required = std::env::var("LEAKWATCH_REQUIRE_NODE").is_ok_and(|v| v == "1");
    let modules = std::env::var("LEAKWATCH_NODE_MODULES").ok().filter(|m| {
        Path::new(m)
            .join("node_modules/@foxglove/ws-protocol/package.json")
            .is_file()
    });
    let Some(modules) = modules else {
        assert!(
            !required,
            "LEAKWATCH_NODE_MODULES must hold @foxglove/ws-protocol"
        );
        eprintln!("SKIPPED: LEAKWATCH_NODE_MODULES names no @foxglove/ws-protocol (optional check)");
        return;
    };
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tmpdir("wsprotocol");
    let cfg = short_warmup_config_with(&dir, "");
    let port = free_port().to_string();
    let run = Command::new(BIN)
        .args([
            "run",
            "--rig",
            "lv3",
            "--seconds",
            "16",
            "--fault",
            "ext1:1lpm@10s",
        ])
        .args(["--live-view", &port, "--config"])
        .arg(&cfg)
        .arg("--out")
        .arg(dir.join("run"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // the live view starts with the run: retry the connection until it answers
    let start = Instant::now();
    let client = loop {
        let o = Command::new("node")
            .arg(example("liveview/ws_protocol_client.js"))
            .arg(format!("ws://127.0.0.1:{port}"))
            .args(["--seconds", "40"])
            .env("NODE_PATH", Path::new(&modules).join("node_modules"))
            .output()
            .unwrap();
        if o.status.success() || start.elapsed() > Duration::from_secs(20) {
            break o;
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    let run = run.wait_with_output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let stdout = String::from_utf8_lossy(&client.stdout);
    assert!(
        client.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&client.stderr)
    );
    let c: Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(c["subprotocol"], "foxglove.websocket.v1");
    for t in ["frames", "estimates", "health", "events"] {
        let topic = format!("/leakwatch/lv3/{t}");
        assert!(c["counts"][&topic].as_u64().unwrap_or(0) >= 1, "no {topic}: {c}");
    }
    assert!(
        c["counts"]["/leakwatch/lv3/frames"].as_u64().unwrap() > 100,
        "{c}"
    );
    let event = &c["first"]["/leakwatch/lv3/events"];
    assert!(
        event["kind"] == "ext1" || event["kind"] == "leak",
        "the first event is the leak: {event}"
    );
}
