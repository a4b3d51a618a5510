#!/usr/bin/env python3
"""A minimal Foxglove WebSocket client (protocol v1: subprotocol foxglove.sdk.v1,
the name the foxglove SDK gives foxglove.websocket.v1; both are offered, or
only those given with --subprotocol) for leakwatch's live view: connects,
reads serverInfo and advertise, subscribes to every channel, decodes the
binary message frames (JSON payloads) and prints a JSON summary on stdout: the
server info, the advertised channels with their schemas, message counts and
rates per topic, the first and last message of each topic, the range [min,
max] of each numeric field, every event, and each message's time (ns since
the Unix epoch, the log's time of the same message) by its seq.

    pip install websockets==17.4
    leakwatch run --live-view &          # ws://127.0.0.1:8765
    python3 examples/liveview/foxglove_client.py ws://127.0.0.1:8765 --seconds 10

It stops after --seconds, or as soon as every channel has given --min messages
(--until-all). Exit status 1 if it could not connect within --connect-timeout.
"""
import argparse
import asyncio
import json
import struct
import sys
import time

import websockets

# the current name of the v1 protocol first, then its earlier name
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
OP_MESSAGE_DATA = 0x01


async def connect(url, timeout, subprotocols):
    deadline = time.monotonic() + timeout
    while True:
        try:
            return await websockets.connect(url, subprotocols=subprotocols, max_size=None)
        except (OSError, websockets.exceptions.InvalidHandshake):
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.2)


async def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("url")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--min", type=int, default=1, help="messages per channel for --until-all")
    ap.add_argument("--until-all", action="store_true")
    ap.add_argument("--connect-timeout", type=float, default=20.0)
    ap.add_argument("--stall", action="store_true",
                    help="subscribe, then stop reading (a slow client: the server must drop, not wait)")
    ap.add_argument("--subprotocol", action="append",
                    help="offer only this subprotocol (repeatable; default: %s)" % ", ".join(SUBPROTOCOLS))
    args = ap.parse_args()

    try:
        ws = await connect(args.url, args.connect_timeout, args.subprotocol or SUBPROTOCOLS)
    except Exception as e:  # noqa: BLE001 - report any failure to connect
        print(f"cannot connect to {args.url}: {e}", file=sys.stderr)
        return 1
    out = {"subprotocol": ws.subprotocol, "server_info": None, "channels": {}, "counts": {},
           "first": {}, "last": {}, "events": [], "ranges": {}, "bad": 0, "closed": False,
           "stamps": {}}
    by_sub = {}
    t_first, t_last = {}, {}
    start = time.monotonic()
    async with ws:
        while time.monotonic() - start < args.seconds:
            try:
                raw = await asyncio.wait_for(ws.recv(), timeout=0.5)
            except asyncio.TimeoutError:
                continue
            except websockets.exceptions.ConnectionClosed:
                out["closed"] = True
                break
            if isinstance(raw, str):
                msg = json.loads(raw)
                if msg.get("op") == "serverInfo":
                    out["server_info"] = msg
                elif msg.get("op") == "advertise":
                    subs = []
                    for ch in msg["channels"]:
                        sub_id = len(by_sub) + 1
                        by_sub[sub_id] = ch["topic"]
                        out["channels"][ch["topic"]] = {
                            "id": ch["id"], "encoding": ch["encoding"], "schemaName": ch["schemaName"],
                            "schemaEncoding": ch.get("schemaEncoding"), "schema": json.loads(ch["schema"]),
                        }
                        subs.append({"id": sub_id, "channelId": ch["id"]})
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
                    if args.stall:
                        # read nothing more: the socket buffers fill, the server's backlog drops
                        await asyncio.sleep(max(0.0, args.seconds - (time.monotonic() - start)))
                        break
                continue
            if len(raw) < 13 or raw[0] != OP_MESSAGE_DATA:
                out["bad"] += 1
                continue
            sub_id, stamp_ns = struct.unpack_from("<IQ", raw, 1)
            topic = by_sub.get(sub_id)
            if topic is None:
                out["bad"] += 1
                continue
            body = json.loads(raw[13:].decode("utf-8"))
            n = out["counts"].get(topic, 0) + 1
            out["counts"][topic] = n
            now = time.monotonic()
            t_first.setdefault(topic, now)
            t_last[topic] = now
            out["first"].setdefault(topic, body)
            # each message's time (ns since the Unix epoch) by its seq
            if "seq" in body:
                out["stamps"].setdefault(topic, {})[str(body["seq"])] = stamp_ns
            out["last"][topic] = body
            ranges = out["ranges"].setdefault(topic, {})
            for k, v in body.items():
                if isinstance(v, (int, float)) and not isinstance(v, bool):
                    lo, hi = ranges.get(k, (v, v))
                    ranges[k] = (min(lo, v), max(hi, v))
            if topic.endswith("/events"):
                out["events"].append(body)
            if args.until_all and by_sub and all(
                out["counts"].get(t, 0) >= args.min for t in by_sub.values()
            ):
                break
    # messages per second of wall time received, per topic
    out["rate_hz"] = {
        t: (out["counts"][t] - 1) / (t_last[t] - t_first[t]) if t_last[t] > t_first[t] else None
        for t in out["counts"]
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(asyncio.run(main()))
