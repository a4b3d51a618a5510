// Foxglove's own WebSocket client library, @foxglove/ws-protocol, against
// leakwatch's live view: connects with the library's default subprotocol
// (foxglove.websocket.v1).
//
// Without --seconds: subscribes to the frames channel and prints the first
// message as one JSON line (subprotocol, topic, log time in ns, payload).
// With --seconds N: subscribes to every channel, counts the messages per topic
// for N seconds (or until the server goes away) and prints one JSON line
// (subprotocol, counts per topic, the first message of each topic).
//
//     npm install @foxglove/ws-protocol@0.8.0 ws@8
//     node examples/liveview/ws_protocol_client.js ws://127.0.0.1:8765 [--seconds 30]
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");

const url = process.argv[2] || "ws://127.0.0.1:8765";
const secondsAt = process.argv.indexOf("--seconds");
const seconds = secondsAt > 0 ? Number(process.argv[secondsAt + 1]) : null;
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const topics = new Map();
const counts = {};
const first = {};
let serverName = null;
let done = false;

function report() {
  if (done) return;
  done = true;
  console.log(JSON.stringify({ subprotocol: ws.protocol, server: serverName, counts, first }));
  client.close();
  process.exit(0);
}

client.on("serverInfo", (info) => {
  serverName = info.name;
});
client.on("advertise", (channels) => {
  for (const ch of channels) {
    if (seconds !== null || ch.topic.endsWith("/frames")) {
      topics.set(client.subscribe(ch.id), ch.topic);
      counts[ch.topic] = counts[ch.topic] || 0;
    }
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const topic = topics.get(subscriptionId);
  const payload = Buffer.from(data.buffer, data.byteOffset, data.byteLength).toString("utf8");
  if (seconds === null) {
    console.log(JSON.stringify({
      subprotocol: ws.protocol,
      server: serverName,
      topic,
      log_time_ns: timestamp.toString(),
      payload,
    }));
    client.close();
    return;
  }
  counts[topic] = (counts[topic] || 0) + 1;
  if (!(topic in first)) {
    first[topic] = JSON.parse(payload);
  }
});
client.on("error", (e) => {
  if (seconds !== null && Object.keys(first).length > 0) {
    report();
  }
  console.error(`error: ${e && e.message ? e.message : e}`);
  process.exit(1);
});
client.on("close", () => {
  if (seconds !== null) report();
});
ws.on("unexpected-response", (_req, res) => {
  console.error(`HTTP ${res.statusCode}`);
  process.exit(1);
});
if (seconds !== null) {
  setTimeout(report, seconds * 1000);
}
