//! The live view: Foxglove's WebSocket protocol, version 1, served by the
//! official `foxglove` crate (which names the subprotocol `foxglove.sdk.v1`,
//! the v1 protocol formerly announced as `foxglove.websocket.v1`), one channel per topic
//! (`/leakwatch/<rig>/frames`, `estimates`, `events`, `health`), JSON messages
//! with JSON Schemas ([`crate::json`]). Foxglove (app or web) connects with
//! "Open connection → Foxglove WebSocket → ws://HOST:8765".
//!
//! The server runs on its own tokio threads; [`LiveView::send`] hands a message
//! to the clients subscribed to its channel, each with a bounded backlog whose
//! oldest messages are dropped when the client is slow. Nothing is encoded for
//! a channel no client subscribes to.

use std::sync::Arc;

use foxglove::{ChannelBuilder, Context, RawChannel, Schema, WebSocketServer, WebSocketServerHandle};

use crate::{LiveTopic, Sink};

/// The WebSocket subprotocol the server accepts (the `foxglove` crate's name of
/// Foxglove's v1 protocol, `foxglove.websocket.v1` before).
pub const SUBPROTOCOL: &str = "foxglove.sdk.v1";

/// A running live view.
pub struct LiveView {
    server: Option<WebSocketServerHandle>,
    channels: Vec<Arc<RawChannel>>,
    _context: Arc<Context>,
}

impl LiveView {
    /// Starts the server for rig `rig` on `bind:port` (port 0: any free port,
    /// see [`LiveView::port`]); `backlog`: messages queued per client.
    pub fn start(rig: &str, bind: &str, port: u16, backlog: usize) -> Result<LiveView, String> {
        let context = Context::new();
        let mut channels = Vec::new();
        for topic in LiveTopic::ALL {
            let schema = crate::json::schema_of(topic);
            let name = schema["title"].as_str().unwrap_or("leakwatch").to_string();
            let data = serde_json::to_vec(&schema).map_err(|e| e.to_string())?;
            let channel = ChannelBuilder::new(format!("/leakwatch/{rig}/{}", topic.name()))
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
        let server = WebSocketServer::new()
            .name(format!("leakwatch {rig}"))
            .bind(bind, port)
            .message_backlog_size(backlog)
            .server_info(info.into_iter().collect())
            .context(&context)
            .start_blocking()
            .map_err(|e| format!("live view on {bind}:{port}: {e}"))?;
        Ok(LiveView {
            server: Some(server),
            channels,
            _context: context,
        })
    }

    /// The TCP port the server listens on.
    pub fn port(&self) -> u16 {
        self.server.as_ref().map_or(0, |s| s.port())
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.server.as_ref().map_or(0, |s| s.client_count())
    }

    /// Stops the server (clients are disconnected).
    pub fn stop(&mut self) {
        if let Some(s) = self.server.take() {
            s.stop().detach_all();
        }
    }
}

impl Sink for LiveView {
    fn wants(&self, topic: LiveTopic) -> bool {
        self.channels[topic.index()].has_sinks()
    }

    fn send(&mut self, topic: LiveTopic, json: &[u8]) {
        self.channels[topic.index()].log(json);
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        self.stop();
    }
}
