//! Real WebSocket handshakes with the live view (no bus: the view is fed by
//! the test): a client that offers `foxglove.websocket.v1`, the name
//! Foxglove's client library `@foxglove/ws-protocol` offers, is accepted and
//! answered with that name, gets the server's `serverInfo` and `advertise`,
//! subscribes and receives a message at the time it was given; the crate's own
//! names still work; a client offering none is refused with 400 naming the
//! accepted subprotocols.

use std::net::TcpStream;
use std::time::{Duration, Instant};

use live::view::LiveView;
use live::{LiveTopic, Sink};
use serde_json::Value;
use tungstenite::client::IntoClientRequest;
use tungstenite::http::HeaderValue;
use tungstenite::{Message, WebSocket};

/// Connects to the view on `port` offering `protocols`; the socket and the
/// subprotocol the server answered.
fn connect(port: u16, protocols: &str) -> Result<(WebSocket<TcpStream>, Option<String>), tungstenite::Error> {
    connect_to(port, "/", protocols)
}

/// [`connect`] to the URL path (and query) `path`.
fn connect_to(
    port: u16,
    path: &str,
    protocols: &str,
) -> Result<(WebSocket<TcpStream>, Option<String>), tungstenite::Error> {
    let mut req = format!("ws://127.0.0.1:{port}{path}").into_client_request()?;
    req.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        HeaderValue::from_str(protocols).expect("a header value"),
    );
    let stream = TcpStream::connect(("127.0.0.1", port)).expect("the live view listens");
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .expect("a read timeout");
    let (ws, response) = tungstenite::client(req, stream).map_err(|e| match e {
        tungstenite::HandshakeError::Failure(e) => e,
        tungstenite::HandshakeError::Interrupted(_) => panic!("a blocking handshake"),
    })?;
    let answered = response
        .headers()
        .get("sec-websocket-protocol")
        .map(|v| v.to_str().expect("ASCII").to_string());
    Ok((ws, answered))
}

/// The next JSON text message.
fn next_json(ws: &mut WebSocket<TcpStream>) -> Value {
    loop {
        match ws.read().expect("a message") {
            Message::Text(t) => return serde_json::from_str(t.as_str()).expect("JSON"),
            Message::Ping(_) | Message::Pong(_) => {}
            other => panic!("expected a text message, got {other:?}"),
        }
    }
}

/// The client's session: serverInfo, the four channels, a subscription to the
/// frames, one frame message at `log_time_ns`.
fn session(view: &mut LiveView, protocols: &str, answered_want: &str, log_time_ns: u64) {
    session_at(view, "/", protocols, answered_want, log_time_ns);
}

/// [`session`] with the URL path (and query) `path`.
fn session_at(view: &mut LiveView, path: &str, protocols: &str, answered_want: &str, log_time_ns: u64) {
    let (mut ws, answered) = connect_to(view.port(), path, protocols).expect("the handshake succeeds");
    assert_eq!(answered.as_deref(), Some(answered_want));
    let info = next_json(&mut ws);
    assert_eq!(
        (&info["op"], &info["name"]),
        (&Value::from("serverInfo"), &Value::from("leakwatch rig9"))
    );
    assert_eq!(info["metadata"]["rig"], "rig9");
    let adv = next_json(&mut ws);
    assert_eq!(adv["op"], "advertise", "{adv}");
    let channels = adv["channels"].as_array().expect("channels");
    let mut topics: Vec<&str> = channels
        .iter()
        .map(|c| c["topic"].as_str().expect("a topic"))
        .collect();
    topics.sort();
    assert_eq!(
        topics,
        [
            "/leakwatch/rig9/estimates",
            "/leakwatch/rig9/events",
            "/leakwatch/rig9/frames",
            "/leakwatch/rig9/health"
        ]
    );
    let frames_id = channels
        .iter()
        .find(|c| c["topic"] == "/leakwatch/rig9/frames")
        .and_then(|c| c["id"].as_u64())
        .expect("the frames channel's id");
    let sub = serde_json::json!({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": frames_id}]});
    ws.send(Message::text(sub.to_string())).expect("subscribe");
    // the view sees the subscription (a bounded wait, no timing asserted)
    let start = Instant::now();
    while !view.wants(LiveTopic::Frames) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "the subscription never arrived"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let payload = br#"{"t_s":1.5,"p1_pa":6900000.0}"#;
    view.send(LiveTopic::Frames, payload, log_time_ns);
    let data = loop {
        match ws.read().expect("the message") {
            Message::Binary(b) => break b,
            // (a status or another advertisement may come first)
            Message::Text(_) | Message::Ping(_) | Message::Pong(_) => {}
            other => panic!("expected the message, got {other:?}"),
        }
    };
    // opcode 1 (message data), subscription id, log time (ns, little-endian), payload
    assert_eq!(data[0], 1);
    assert_eq!(u32::from_le_bytes(data[1..5].try_into().expect("4 bytes")), 7);
    assert_eq!(
        u64::from_le_bytes(data[5..13].try_into().expect("8 bytes")),
        log_time_ns
    );
    assert_eq!(&data[13..], payload);
    let _ = ws.close(None);
    // the view no longer has the client's subscription once it is gone
    let start = Instant::now();
    while view.wants(LiveTopic::Frames) {
        assert!(start.elapsed() < Duration::from_secs(20), "the client never left");
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn foxglove_websocket_v1_is_accepted_and_answered_by_its_name() {
    let mut view = LiveView::start("rig9", "127.0.0.1", 0, 16, None).expect("the live view starts");
    // 2025-11-24 16:00:01.5 UTC: the time given is the time sent
    session(
        &mut view,
        "foxglove.websocket.v1",
        "foxglove.websocket.v1",
        1_764_000_001_500_000_000,
    );
    // the crate's names, as before
    session(
        &mut view,
        "foxglove.sdk.v1",
        "foxglove.sdk.v1",
        1_764_000_002_000_000_000,
    );
    session(
        &mut view,
        "foxglove.websocket.v1, foxglove.sdk.v1.1",
        "foxglove.sdk.v1.1",
        1_764_000_003_000_000_000,
    );
    view.stop();
}

#[test]
fn a_client_offering_no_known_subprotocol_is_refused_naming_them() {
    let view = LiveView::start("rig9", "127.0.0.1", 0, 16, None).expect("the live view starts");
    match connect(view.port(), "mqtt, foxglove.websocket.v2") {
        Err(tungstenite::Error::Http(response)) => {
            assert_eq!(response.status().as_u16(), 400);
            let body = String::from_utf8(response.body().clone().unwrap_or_default()).expect("UTF-8");
            assert_eq!(
                body,
                "expected a Sec-WebSocket-Protocol header offering one of foxglove.sdk.v1.1, foxglove.sdk.v1, \
                 foxglove.websocket.v1; offered: mqtt, foxglove.websocket.v2\n"
            );
        }
        Err(e) => panic!("expected HTTP 400, got {e}"),
        Ok(_) => panic!("expected HTTP 400, the handshake succeeded"),
    }
}

/// Foxglove's own client library, `@foxglove/ws-protocol` (run with node),
/// connects with its default subprotocol `foxglove.websocket.v1`, subscribes
/// and receives a frame at the time given. Optional: it runs where
/// `LEAKWATCH_NODE_MODULES` names a folder whose `node_modules` holds
/// `@foxglove/ws-protocol` and `ws` (.ci/setup installs .ci/node/package.json
/// there), and says it was skipped elsewhere; LEAKWATCH_REQUIRE_NODE=1 (CI)
/// makes it required.
#[test]
fn foxglove_ws_protocol_client_connects_when_node_has_it() {
    let required = std::env::var("LEAKWATCH_REQUIRE_NODE").is_ok_and(|v| v == "1");
    let modules = std::env::var("LEAKWATCH_NODE_MODULES").ok().filter(|m| {
        std::path::Path::new(m)
            .join("node_modules/@foxglove/ws-protocol/package.json")
            .is_file()
    });
    let Some(modules) = modules else {
        assert!(
            !required,
            "LEAKWATCH_NODE_MODULES must name a folder whose node_modules holds @foxglove/ws-protocol \
             (.ci/setup installs it; LEAKWATCH_REQUIRE_NODE=1)"
        );
        eprintln!("SKIPPED: LEAKWATCH_NODE_MODULES names no @foxglove/ws-protocol (optional check)");
        return;
    };
    let mut view = LiveView::start("rig9", "127.0.0.1", 0, 16, None).expect("the live view starts");
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/liveview/ws_protocol_client.js");
    let child = std::process::Command::new("node")
        .arg(&script)
        .arg(format!("ws://127.0.0.1:{}", view.port()))
        .env("NODE_PATH", std::path::Path::new(&modules).join("node_modules"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("node runs");
    let start = Instant::now();
    while !view.wants(LiveTopic::Frames) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the client never subscribed"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    view.send(LiveTopic::Frames, br#"{"t_s":2.5}"#, 1_764_000_004_000_000_001);
    let o = child.wait_with_output().expect("node ends");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).expect("a JSON line");
    assert_eq!(v["subprotocol"], "foxglove.websocket.v1");
    assert_eq!(v["server"], "leakwatch rig9");
    assert_eq!(v["topic"], "/leakwatch/rig9/frames");
    assert_eq!(v["log_time_ns"], "1764000004000000001");
    assert_eq!(v["payload"], r#"{"t_s":2.5}"#);
}

/// With a token, a client without it or with a wrong one is refused with HTTP
/// 401 (before the server sees it: no client is counted), and one that sends
/// it as the URL's `token` query parameter gets the channels and a frame.
#[test]
fn with_a_token_only_a_client_that_sends_it_is_served() {
    let token = "s3cret-token_of.24chars~";
    let mut view =
        LiveView::start("rig9", "127.0.0.1", 0, 16, Some(token.to_string())).expect("the live view starts");
    for path in ["/".to_string(), "/?token=wrong-token-of-24-chars".to_string()] {
        match connect_to(view.port(), &path, "foxglove.sdk.v1") {
            Err(tungstenite::Error::Http(r)) => {
                assert_eq!(r.status().as_u16(), 401, "{path}");
                let body = String::from_utf8_lossy(r.body().as_deref().unwrap_or_default()).into_owned();
                assert!(body.contains("ws://HOST:PORT/?token=TOKEN"), "{body}");
            }
            Err(e) => panic!("{path}: expected HTTP 401, got {e}"),
            Ok(_) => panic!("{path}: a client without the token was served"),
        }
    }
    assert_eq!(view.clients(), 0);
    session_at(
        &mut view,
        &format!("/?token={token}"),
        "foxglove.sdk.v1",
        "foxglove.sdk.v1",
        1_764_000_005_000_000_002,
    );
}
