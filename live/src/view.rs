//! The live view: Foxglove's WebSocket protocol, version 1, served by the
//! official `foxglove` crate, one channel per topic (`/leakwatch/<rig>/frames`,
//! `estimates`, `events`, `health`), JSON messages with JSON Schemas
//! ([`crate::json`]), each stamped with its own time as the log has it. Foxglove
//! (app or web) connects with "Open connection → Foxglove WebSocket →
//! ws://HOST:8765".
//!
//! Subprotocols: the crate accepts only its own names of the v1 protocol,
//! `foxglove.sdk.v1` and `foxglove.sdk.v1.1`, and answers HTTP 400 to a client
//! that offers the protocol's earlier name `foxglove.websocket.v1` (Foxglove's
//! client library `@foxglove/ws-protocol`, Lichtblick up to 1.21). The crate
//! cannot be told otherwise, so the live view listens itself and puts a small
//! negotiation in front of it ([`negotiate_request`]): a client that offers
//! one of the crate's names is passed through as it is; one that offers only
//! `foxglove.websocket.v1` is handed to the crate as `foxglove.sdk.v1` (the
//! same messages) and answered with `foxglove.websocket.v1`, the name it
//! offered; one that offers none is answered 400 naming the accepted ones.
//! After the handshake the bytes are copied both ways (two threads per client).
//!
//! With a token ([`LiveView::start`], `[live_view] token`/`token_file`), a
//! client must send it, as the query parameter `token` of the WebSocket URL
//! (`ws://HOST:PORT/?token=TOKEN`, what Foxglove's "Open connection" can do)
//! or an `Authorization: Bearer TOKEN` header; without it the handshake is
//! answered with HTTP 401 before anything reaches the server ([`check_token`]).
//!
//! The server runs on its own tokio threads; [`LiveView::send`] hands a message
//! to the clients subscribed to its channel, each with a bounded backlog whose
//! oldest messages are dropped when the client is slow. Nothing is encoded for
//! a channel no client subscribes to.

use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use foxglove::{
    ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer, WebSocketServerHandle,
};

use crate::{LiveTopic, Sink};

/// The WebSocket subprotocols the live view accepts, the server's choice
/// first: the `foxglove` crate's `foxglove.sdk.v1.1` and `foxglove.sdk.v1`,
/// and `foxglove.websocket.v1`, the v1 protocol's earlier name that Foxglove's
/// client library `@foxglove/ws-protocol` offers. A client is answered with
/// one it offered.
pub const SUBPROTOCOLS: [&str; 3] = ["foxglove.sdk.v1.1", "foxglove.sdk.v1", LEGACY_SUBPROTOCOL];

/// The v1 protocol's earlier name, `foxglove.websocket.v1` (see [`SUBPROTOCOLS`]).
pub const LEGACY_SUBPROTOCOL: &str = "foxglove.websocket.v1";

/// The name the `foxglove` crate is offered for a client of [`LEGACY_SUBPROTOCOL`].
const CRATE_SUBPROTOCOL: &str = "foxglove.sdk.v1";

/// Longest HTTP head of a handshake read, bytes.
const MAX_HEAD: usize = 16 * 1024;

/// Longest wait for a client's or the server's handshake head.
const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(10);

/// A running live view.
pub struct LiveView {
    server: Option<WebSocketServerHandle>,
    channels: Vec<Arc<RawChannel>>,
    _context: Arc<Context>,
    port: u16,
    stop: Arc<AtomicBool>,
    acceptor: Option<JoinHandle<()>>,
}

impl LiveView {
    /// Starts the server for rig `rig` on `bind:port` (port 0: any free port,
    /// see [`LiveView::port`]); `backlog`: messages queued per client; `token`:
    /// what every client must send (none: any client is served).
    pub fn start(
        rig: &str,
        bind: &str,
        port: u16,
        backlog: usize,
        token: Option<String>,
    ) -> Result<LiveView, String> {
        let context = Context::new();
        let mut channels = Vec::new();
        for topic in LiveTopic::ALL {
            let schema = crate::json::schema_of(topic);
            let name = schema["title"].as_str().unwrap_or("leakwatch").to_string();
            let data = serde_json::to_vec(&schema).map_err(|e| e.to_string())?;
            let channel = ChannelBuilder::new(crate::layout::topic_name(rig, topic))
                .message_encoding("json")
                .schema(Schema::new(name, "jsonschema", data))
                .context(&context)
                .build_raw()
                .map_err(|e| format!("live view channel {}: {e}", topic.name()))?;
            channels.push(channel);
        }
        let info = [
            ("rig".to_string(), rig.to_string()),
            (
                "units".to_string(),
                "SI; names end in their unit (_pa, _m, _n, _lpm, _s)".to_string(),
            ),
        ];
        // clients connect here; the crate's server listens on a loopback port behind it
        let listener =
            TcpListener::bind((bind, port)).map_err(|e| format!("live view on {bind}:{port}: {e}"))?;
        let port = listener
            .local_addr()
            .map_err(|e| format!("live view on {bind}:{port}: {e}"))?
            .port();
        listener
            .set_nonblocking(true)
            .map_err(|e| format!("live view on {bind}:{port}: {e}"))?;
        let server = WebSocketServer::new()
            .name(format!("leakwatch {rig}"))
            .bind("127.0.0.1", 0)
            .message_backlog_size(backlog)
            .server_info(info.into_iter().collect())
            .context(&context)
            .start_blocking()
            .map_err(|e| format!("live view server on 127.0.0.1: {e}"))?;
        let inner_port = server.port();
        let stop = Arc::new(AtomicBool::new(false));
        let acceptor = {
            let stop = stop.clone();
            let token = Arc::new(token);
            std::thread::Builder::new()
                .name("liveview-accept".into())
                .spawn(move || accept_loop(listener, inner_port, &stop, &token))
                .map_err(|e| format!("live view: cannot start its accept thread: {e}"))?
        };
        Ok(LiveView {
            server: Some(server),
            channels,
            _context: context,
            port,
            stop,
            acceptor: Some(acceptor),
        })
    }

    /// The TCP port the live view listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.server.as_ref().map_or(0, |s| s.client_count())
    }

    /// Stops the server (clients are disconnected).
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(a) = self.acceptor.take() {
            let _ = a.join();
        }
        if let Some(s) = self.server.take() {
            s.stop().detach_all();
        }
    }
}

impl Sink for LiveView {
    fn wants(&self, topic: LiveTopic) -> bool {
        self.channels[topic.index()].has_sinks()
    }

    fn send(&mut self, topic: LiveTopic, json: &[u8], log_time_ns: u64) {
        // the message's own time, as the log has it (not the time it is sent)
        self.channels[topic.index()].log_with_meta(json, PartialMetadata::with_log_time(log_time_ns));
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Accepts clients until `stop` (polled every 50 ms), each handed to its own thread.
fn accept_loop(listener: TcpListener, inner_port: u16, stop: &AtomicBool, token: &Arc<Option<String>>) {
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((client, _)) => {
                let token = token.clone();
                let spawned = std::thread::Builder::new()
                    .name("liveview-client".into())
                    .spawn(move || {
                        if let Err(e) = serve_client(client, inner_port, token.as_deref()) {
                            bus::say!("liveview: a client: {e}");
                        }
                    });
                if let Err(e) = spawned {
                    bus::say!("liveview: cannot start a client's thread: {e}");
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(50))
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => {
                bus::say!("liveview: accept: {e}");
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    }
}

/// Reads an HTTP head (up to and with the blank line, at most [`MAX_HEAD`]
/// bytes) from `s`; returns it and the bytes read after it.
fn read_head(s: &mut TcpStream, what: &str) -> Result<(String, Vec<u8>), String> {
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 2048];
    loop {
        if let Some(end) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            let rest = buf.split_off(end + 4);
            let head = String::from_utf8(buf).map_err(|_| format!("{what}: the HTTP head is not UTF-8"))?;
            return Ok((head, rest));
        }
        if buf.len() > MAX_HEAD {
            return Err(format!("{what}: HTTP head longer than {MAX_HEAD} bytes"));
        }
        let n = s.read(&mut chunk).map_err(|e| format!("{what}: {e}"))?;
        if n == 0 {
            return Err(format!("{what}: closed during the handshake"));
        }
        buf.extend_from_slice(&chunk[..n]);
    }
}

/// What to do with a client's handshake request (see [`negotiate_request`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Negotiation {
    /// Hand the request to the server as it is (it offers one of the crate's names).
    PassThrough,
    /// Hand the server this request (offering `foxglove.sdk.v1`) and answer the
    /// client with the name it offered, [`LEGACY_SUBPROTOCOL`].
    Renamed(String),
    /// Answer this HTTP response (400: no subprotocol the live view speaks).
    Refuse(String),
}

/// The subprotocols a request head offers (every `Sec-WebSocket-Protocol`
/// header, comma-separated names, in order).
pub fn offered_subprotocols(head: &str) -> Vec<String> {
    head.split("\r\n")
        .skip(1)
        .filter_map(|line| line.split_once(':'))
        .filter(|(name, _)| name.trim().eq_ignore_ascii_case("sec-websocket-protocol"))
        .flat_map(|(_, v)| v.split(','))
        .map(|p| p.trim().to_string())
        .filter(|p| !p.is_empty())
        .collect()
}

/// The negotiation of a client's handshake request head: the crate's names
/// pass through (the crate prefers `foxglove.sdk.v1.1`), `foxglove.websocket.v1`
/// alone is renamed `foxglove.sdk.v1` for the crate, anything else is refused
/// with a 400 that names the accepted subprotocols.
pub fn negotiate_request(head: &str) -> Negotiation {
    let offered = offered_subprotocols(head);
    if offered.iter().any(|p| SUBPROTOCOLS[..2].contains(&p.as_str())) {
        return Negotiation::PassThrough;
    }
    if offered.iter().any(|p| p == LEGACY_SUBPROTOCOL) {
        let mut out = String::with_capacity(head.len());
        for (i, line) in head.split_terminator("\r\n").enumerate() {
            let is_protocol = i > 0
                && line
                    .split_once(':')
                    .is_some_and(|(n, _)| n.trim().eq_ignore_ascii_case("sec-websocket-protocol"));
            if !is_protocol && !line.is_empty() {
                out.push_str(line);
                out.push_str("\r\n");
            }
        }
        out.push_str(&format!("Sec-WebSocket-Protocol: {CRATE_SUBPROTOCOL}\r\n\r\n"));
        return Negotiation::Renamed(out);
    }
    let body = format!(
        "expected a Sec-WebSocket-Protocol header offering one of {}; offered: {}\n",
        SUBPROTOCOLS.join(", "),
        if offered.is_empty() {
            "none".to_string()
        } else {
            offered.join(", ")
        }
    );
    Negotiation::Refuse(format!(
        "HTTP/1.1 400 Bad Request\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    ))
}

/// The token a request head carries: the query parameter `token` of its
/// request target (`GET /?token=TOKEN HTTP/1.1`), else an `Authorization:
/// Bearer TOKEN` header.
pub fn request_token(head: &str) -> Option<&str> {
    let target = head.split("\r\n").next()?.split(' ').nth(1)?;
    let from_query = target
        .split_once('?')
        .and_then(|(_, q)| q.split('&').find_map(|kv| kv.strip_prefix("token=")));
    from_query.or_else(|| {
        head.split("\r\n")
            .skip(1)
            .filter_map(|line| line.split_once(':'))
            .filter(|(name, _)| name.trim().eq_ignore_ascii_case("authorization"))
            .find_map(|(_, v)| v.trim().strip_prefix("Bearer "))
            .map(str::trim)
    })
}

/// Whether `a` and `b` are equal, in a time that depends on their lengths only.
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// `Ok` when a request head carries `token` ([`request_token`]); else the
/// HTTP 401 response to answer.
pub fn check_token(head: &str, token: &str) -> Result<(), String> {
    let sent = request_token(head);
    if sent.is_some_and(|s| same_secret(s.as_bytes(), token.as_bytes())) {
        return Ok(());
    }
    let body = format!(
        "{}: this live view needs its token: connect to ws://HOST:PORT/?token=TOKEN (the token of its \
         [live_view] token or token_file)\n",
        if sent.is_some() { "wrong token" } else { "no token" }
    );
    Err(format!(
        "HTTP/1.1 401 Unauthorized\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    ))
}

/// The server's handshake response head for a client that offered
/// [`LEGACY_SUBPROTOCOL`]: its `Sec-WebSocket-Protocol` answer named so.
pub fn rename_response(head: &str) -> String {
    let mut out = String::with_capacity(head.len() + 8);
    for line in head.split_terminator("\r\n").filter(|l| !l.is_empty()) {
        match line.split_once(':') {
            Some((n, v))
                if n.trim().eq_ignore_ascii_case("sec-websocket-protocol")
                    && v.trim() == CRATE_SUBPROTOCOL =>
            {
                out.push_str(&format!("{n}: {LEGACY_SUBPROTOCOL}"));
            }
            _ => out.push_str(line),
        }
        out.push_str("\r\n");
    }
    out.push_str("\r\n");
    out
}

/// One client: the handshake negotiated (see [`negotiate_request`]), then the
/// bytes copied both ways between it and the crate's server until either closes.
fn serve_client(mut client: TcpStream, inner_port: u16, token: Option<&str>) -> Result<(), String> {
    let peer = client
        .peer_addr()
        .map(|a| a.to_string())
        .unwrap_or_else(|_| "?".into());
    let what = format!("client {peer}");
    client
        .set_nonblocking(false)
        .map_err(|e| format!("{what}: {e}"))?;
    client
        .set_read_timeout(Some(HANDSHAKE_TIMEOUT))
        .map_err(|e| format!("{what}: {e}"))?;
    let (head, rest) = read_head(&mut client, &what)?;
    if let Some(token) = token {
        if let Err(response) = check_token(&head, token) {
            let _ = client.write_all(response.as_bytes());
            let _ = client.shutdown(Shutdown::Both);
            return Err(format!(
                "{what}: refused (HTTP 401): {}",
                if request_token(&head).is_some() {
                    "a wrong token"
                } else {
                    "no token"
                }
            ));
        }
    }
    let (request, renamed) = match negotiate_request(&head) {
        Negotiation::PassThrough => (head, false),
        Negotiation::Renamed(r) => (r, true),
        Negotiation::Refuse(response) => {
            let _ = client.write_all(response.as_bytes());
            let _ = client.shutdown(Shutdown::Both);
            return Err(format!(
                "{what}: refused, it offered no subprotocol the live view speaks ({:?})",
                offered_subprotocols(&head)
            ));
        }
    };
    let mut inner =
        TcpStream::connect(("127.0.0.1", inner_port)).map_err(|e| format!("{what}: the server: {e}"))?;
    inner
        .set_read_timeout(Some(HANDSHAKE_TIMEOUT))
        .map_err(|e| format!("{what}: {e}"))?;
    let _ = inner.set_nodelay(true);
    let _ = client.set_nodelay(true);
    inner
        .write_all(request.as_bytes())
        .and_then(|()| inner.write_all(&rest))
        .map_err(|e| format!("{what}: the server: {e}"))?;
    let (response, rest) = read_head(&mut inner, &format!("{what}: the server"))?;
    let response = if renamed {
        rename_response(&response)
    } else {
        response
    };
    client
        .write_all(response.as_bytes())
        .and_then(|()| client.write_all(&rest))
        .map_err(|e| format!("{what}: {e}"))?;
    client
        .set_read_timeout(None)
        .map_err(|e| format!("{what}: {e}"))?;
    inner.set_read_timeout(None).map_err(|e| format!("{what}: {e}"))?;
    // client -> server on a thread of its own, server -> client here
    let (mut c_read, mut i_write) = (
        client.try_clone().map_err(|e| format!("{what}: {e}"))?,
        inner.try_clone().map_err(|e| format!("{what}: {e}"))?,
    );
    let up = std::thread::Builder::new()
        .name("liveview-up".into())
        .spawn(move || {
            let _ = std::io::copy(&mut c_read, &mut i_write);
            let _ = i_write.shutdown(Shutdown::Both);
        })
        .map_err(|e| format!("{what}: cannot start its thread: {e}"))?;
    let _ = std::io::copy(&mut inner, &mut client);
    let _ = client.shutdown(Shutdown::Both);
    let _ = inner.shutdown(Shutdown::Both);
    let _ = up.join();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEY: &str =
        "GET / HTTP/1.1\r\nHost: 127.0.0.1:8765\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
                       Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n";

    #[test]
    fn the_earlier_name_is_renamed_both_ways_and_the_sdk_names_pass() {
        let legacy = format!("{KEY}Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n");
        assert_eq!(offered_subprotocols(&legacy), ["foxglove.websocket.v1"]);
        let Negotiation::Renamed(r) = negotiate_request(&legacy) else {
            panic!("renamed")
        };
        assert_eq!(r, format!("{KEY}Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n"));
        let both = format!("{KEY}sec-websocket-protocol: foxglove.websocket.v1, foxglove.sdk.v1\r\n\r\n");
        assert_eq!(negotiate_request(&both), Negotiation::PassThrough);
        let v11 = format!("{KEY}Sec-WebSocket-Protocol: foxglove.sdk.v1.1\r\n\r\n");
        assert_eq!(negotiate_request(&v11), Negotiation::PassThrough);
        let response = "HTTP/1.1 101 Switching Protocols\r\nconnection: Upgrade\r\nupgrade: websocket\r\n\
                        sec-websocket-protocol: foxglove.sdk.v1\r\nsec-websocket-accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\n\r\n";
        assert_eq!(
            rename_response(response),
            response.replace(
                "sec-websocket-protocol: foxglove.sdk.v1",
                "sec-websocket-protocol: foxglove.websocket.v1"
            )
        );
        let none = format!("{KEY}Sec-WebSocket-Protocol: mqtt\r\n\r\n");
        let Negotiation::Refuse(r) = negotiate_request(&none) else {
            panic!("refused")
        };
        assert!(r.starts_with("HTTP/1.1 400 Bad Request\r\n"), "{r}");
        assert!(
            r.ends_with(
                "expected a Sec-WebSocket-Protocol header offering one of foxglove.sdk.v1.1, foxglove.sdk.v1, \
                 foxglove.websocket.v1; offered: mqtt\n"
            ),
            "{r}"
        );
    }

    #[test]
    fn the_token_is_read_from_the_query_or_a_bearer_header() {
        let rest = "Host: h\r\nUpgrade: websocket\r\n";
        let token = "abcdefghijklmnop";
        let q = format!("GET /?x=1&token={token} HTTP/1.1\r\n{rest}\r\n");
        assert_eq!(request_token(&q), Some(token));
        assert_eq!(check_token(&q, token), Ok(()));
        let bearer = format!("GET / HTTP/1.1\r\n{rest}authorization: Bearer {token}\r\n\r\n");
        assert_eq!(check_token(&bearer, token), Ok(()));
        let none = format!("GET / HTTP/1.1\r\n{rest}\r\n");
        let r = check_token(&none, token).expect_err("no token");
        assert!(
            r.starts_with("HTTP/1.1 401 Unauthorized\r\n") && r.contains("no token"),
            "{r}"
        );
        let wrong = format!("GET /?token={token}x HTTP/1.1\r\n{rest}\r\n");
        assert!(check_token(&wrong, token)
            .expect_err("wrong")
            .contains("wrong token"));
        let empty = "GET /?token= HTTP/1.1\r\n\r\n";
        assert!(check_token(empty, token).is_err());
    }
}
