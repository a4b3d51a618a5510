#!/usr/bin/env python3
"""Subscribes to leakwatch's Zenoh key space (leakwatch/<rig>/<topic>, JSON
messages) with Python's eclipse-zenoh and prints one JSON line per message:
{"key": ..., "encoding": ..., "msg": {...}}.

    pip install eclipse-zenoh==1.10.2
    leakwatch stage gateway --rig rig1 --listen tcp/127.0.0.1:7448 &   # or run --zenoh ...
    python3 examples/zenoh/subscribe.py --connect tcp/127.0.0.1:7448 --seconds 30

Peer mode, multicast scouting off: only the endpoints given are used (--connect
to a gateway or router that listens, --listen for gateways that connect).
--until-event stops after the first event message.
"""
import argparse
import json
import sys
import time

import zenoh


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--connect", action="append", default=[])
    ap.add_argument("--listen", action="append", default=[])
    ap.add_argument("--key", default="leakwatch/**")
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--until-event", action="store_true")
    args = ap.parse_args()

    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("connect/endpoints", json.dumps(args.connect))
    conf.insert_json5("listen/endpoints", json.dumps(args.listen))
    with zenoh.open(conf) as session:
        sub = session.declare_subscriber(args.key)
        deadline = time.monotonic() + args.seconds
        while time.monotonic() < deadline:
            sample = sub.try_recv()
            if sample is None:
                time.sleep(0.01)
                continue
            key = str(sample.key_expr)
            try:
                msg = json.loads(sample.payload.to_bytes())
            except ValueError:
                msg = None
            print(json.dumps({"key": key, "encoding": str(sample.encoding), "msg": msg}), flush=True)
            if args.until_event and key.endswith("/events"):
                break
    return 0


if __name__ == "__main__":
    sys.exit(main())
