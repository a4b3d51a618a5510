// Foxglove's MCAP stack in Node.js on a leakwatch log: @mcap/core's indexed
// reader opens the file (its summary and message indexes), and every message is
// decoded with the ros2msg schema stored in the file (@foxglove/rosmsg parses
// it, @foxglove/rosmsg2-serialization reads the CDR); zstd chunks with fzstd.
// Prints one JSON object: the profile, per topic its schema, message count and
// decode errors, the first message of each topic, and every frame's seq and the
// bits of its p1_pa (hex, little-endian float64): from the frame_batches topic
// (SensorFrameBatch, every frame in columns), or in a log of an earlier version
// without it, from the frames topic.
//
//     npm install @mcap/core@2.2.2 @foxglove/rosmsg@5.0.5 @foxglove/rosmsg2-serialization@3.1.0 fzstd@0.1.1
//     node examples/mcap/decode_log.js run/run.mcap
const fs = require("fs/promises");
const { McapIndexedReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const { decompress } = require("fzstd");

async function main(path) {
  const file = await fs.open(path, "r");
  const size = BigInt((await file.stat()).size);
  const readable = {
    size: async () => size,
    read: async (offset, length) => {
      const buf = Buffer.alloc(Number(length));
      const { bytesRead } = await file.read(buf, 0, Number(length), Number(offset));
      if (bytesRead !== Number(length)) {
        throw new Error(`${path}: ${bytesRead} of ${length} bytes at ${offset}`);
      }
      return new Uint8Array(buf.buffer, buf.byteOffset, buf.byteLength);
    },
  };
  const reader = await McapIndexedReader.Initialize({
    readable,
    decompressHandlers: {
      zstd: (data, decompressedSize) => decompress(data, new Uint8Array(Number(decompressedSize))),
    },
  });
  const decoders = new Map();
  const topics = {};
  for (const [id, ch] of reader.channelsById) {
    const schema = reader.schemasById.get(ch.schemaId);
    if (!schema || schema.encoding !== "ros2msg" || ch.messageEncoding !== "cdr") {
      throw new Error(`${ch.topic}: not a ROS 2 channel (${schema && schema.encoding}, ${ch.messageEncoding})`);
    }
    const text = new TextDecoder().decode(schema.data);
    decoders.set(id, new MessageReader(parse(text, { ros2: true })));
    topics[ch.topic] = { schema: schema.name, count: 0, errors: 0, first_error: null, first: null };
  }
  const frames = [];
  const batched = [];
  const bits = Buffer.alloc(8);
  for await (const msg of reader.readMessages()) {
    const ch = reader.channelsById.get(msg.channelId);
    const t = topics[ch.topic];
    let m;
    try {
      m = decoders.get(msg.channelId).readMessage(msg.data);
    } catch (e) {
      t.errors += 1;
      t.first_error = t.first_error || String(e);
      continue;
    }
    t.count += 1;
    if (t.first === null) {
      t.first = m;
    }
    if (ch.topic.endsWith("/frames")) {
      bits.writeDoubleLE(m.p1_pa);
      frames.push([m.seq.toString(), bits.toString("hex")]);
    } else if (ch.topic.endsWith("/frame_batches")) {
      for (let i = 0; i < m.p1_pa.length; i++) {
        bits.writeDoubleLE(m.p1_pa[i]);
        batched.push([(BigInt(m.first_seq) + BigInt(i)).toString(), bits.toString("hex")]);
      }
    }
  }
  await file.close();
  let messages = 0n;
  for (const n of reader.statistics ? reader.statistics.channelMessageCounts.values() : []) {
    messages += n;
  }
  const replacer = (_k, v) => (typeof v === "bigint" ? v.toString() : v);
  console.log(
    JSON.stringify(
      {
        profile: reader.header.profile,
        statistics_messages: messages,
        topics,
        frames: batched.length > 0 ? batched : frames,
      },
      replacer,
    ),
  );
}

main(process.argv[2]).catch((e) => {
  console.error(`error: ${e && e.stack ? e.stack : e}`);
  process.exit(1);
});
