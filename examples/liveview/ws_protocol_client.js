// Foxglove's own WebSocket client library, @foxglove/ws-protocol, against
// leakwatch's live view: connects with the library's default subprotocol
// (foxglove.websocket.v1), subscribes to the frames channel and prints the
// first message as one JSON line (subprotocol, topic, log time in ns, payload).
//
//     npm install @foxglove/ws-protocol@0.8.0 ws@8
//     node examples/liveview/ws_protocol_client.js ws://127.0.0.1:8765
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const url = process.argv[2] || "ws://127.0.0.1:8765";
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const topics = new Map();
let serverName = null;
client.on("serverInfo", (info) => {
  serverName = info.name;
});
client.on("advertise", (channels) => {
  for (const ch of channels) {
    if (ch.topic.endsWith("/frames")) {
      topics.set(client.subscribe(ch.id), ch.topic);
    }
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const payload = Buffer.from(data.buffer, data.byteOffset, data.byteLength).toString("utf8");
  console.log(JSON.stringify({
    subprotocol: ws.protocol,
    server: serverName,
    topic: topics.get(subscriptionId),
    log_time_ns: timestamp.toString(),
    payload,
  }));
  client.close();
});
client.on("error", (e) => {
  console.error(`error: ${e && e.message ? e.message : e}`);
  process.exit(1);
});
ws.on("unexpected-response", (_req, res) => {
  console.error(`HTTP ${res.statusCode}`);
  process.exit(1);
});
