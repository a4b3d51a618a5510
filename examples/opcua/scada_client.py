#!/usr/bin/env python3
"""A SCADA's view of leakwatch's OPC UA server, with Python's asyncua client:
browses a rig's object, reads every state variable, tries a write (refused:
the server is read-only), subscribes to the rig's events and its state, and
prints one JSON object with what it saw.

    pip install asyncua==2.1.0
    leakwatch run --rig rig1 --seconds 30 --fault ext1:1lpm@10s --opcua 4840 &
    python3 examples/opcua/scada_client.py opc.tcp://127.0.0.1:4840/ --rig rig1 --seconds 25

With a user configured ([opcua] user, password_file), give --user and
--password-file; --security Basic256Sha256 (or Aes128Sha256RsaOaep) signs and
encrypts the session with a client certificate made for it in --cert-dir (the
server must trust it: [opcua] trust_client_certs, or its pki_dir/trusted/); --check-anonymous-refused also checks that an anonymous
session and a wrong password are refused. --until-leak stops once a leak's
raise with its kind named (ext1, ext2 or int; a raise of kind `leak`, the kind
pending, comes first and is kept too) has arrived.

The JSON: {"namespace": NS, "variables": {Name: {"value", "type", "unit",
"description"}}, "write": STATUS, "events": [{"kind", "phase", "event_number",
"size_lpm", "size_sigma_lpm", "detect_time_s", "onset_time_s", "confidence",
"severity", "message", "source_name", "time_ns", "arrival_ns"}],
"state_updates": N, "state_update_hz": RATE, "anonymous": STATUS, "wrong_password": STATUS}.
time_ns is the event's Time (the acquisition time of the sample it was decided
on, Unix ns), arrival_ns this client's clock when the notification arrived.
"""
import argparse
import asyncio
import datetime as dt
import json
import socket
import sys
import time
from pathlib import Path

from asyncua import Client, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from cryptography.x509.oid import ExtendedKeyUsageOID

NAMESPACE = "urn:leakwatch"
NAMED_LEAKS = {"ext1", "ext2", "int"}


def unix_ns(t):
    if t is None:
        return None
    if t.tzinfo is None:
        t = t.replace(tzinfo=dt.timezone.utc)
    return int(t.timestamp() * 1e6) * 1000


class Events:
    """Event and data-change handler: keeps what arrives, with its arrival time."""

    def __init__(self):
        self.events = []
        self.updates = []
        self.leak = asyncio.Event()

    def event_notification(self, event):
        arrival = time.time_ns()
        f = event.get_event_props_as_fields_dict()
        get = lambda name: getattr(f.get(name), "Value", None)
        e = {
            "kind": get("Kind"),
            "phase": get("Phase"),
            "event_number": get("EventNumber"),
            "size_lpm": get("SizeLpm"),
            "size_sigma_lpm": get("SizeSigmaLpm"),
            "detect_time_s": get("DetectTimeS"),
            "onset_time_s": get("OnsetTimeS"),
            "confidence": get("Confidence"),
            "channel": get("Channel"),
            "detector": get("Detector"),
            "severity": get("Severity"),
            "message": getattr(get("Message"), "Text", None),
            "source_name": get("SourceName"),
            "time_ns": unix_ns(get("Time")),
            "arrival_ns": arrival,
        }
        self.events.append(e)
        if e["kind"] in NAMED_LEAKS and e["phase"] == "raised":
            self.leak.set()

    def datachange_notification(self, node, val, data):
        self.updates.append(time.monotonic())


async def status_of(coro):
    """'Good' if the call succeeds, else the name of the refusal."""
    try:
        await coro
        return "Good"
    except ua.UaStatusCodeError as e:
        return type(e).__name__
    except Exception as e:  # a refused session ends in the client's own error types
        return f"{type(e).__name__}: {e}"


async def read_variables(rig, ns):
    out = {}
    for var in await rig.get_children(refs=ua.ObjectIds.HasComponent):
        if await var.read_node_class() != ua.NodeClass.Variable:
            continue
        name = (await var.read_browse_name()).Name
        dv = await var.read_data_value(raise_on_bad_status=False)
        unit = None
        for prop in await var.get_properties():
            if (await prop.read_browse_name()).Name == "EngineeringUnits":
                unit = (await prop.read_value()).DisplayName.Text
        dtype = await var.read_data_type_as_variant_type()
        out[name] = {
            "value": dv.Value.Value if dv.Value is not None else None,
            "type": dtype.name,
            "unit": unit,
            "description": (await var.read_description()).Text,
        }
    return out


async def connect_and_read(url, user=None, password=None):
    c = Client(url=url, timeout=5)
    if user is not None:
        c.set_user(user)
        c.set_password(password)
    async with c:
        ns = await c.get_namespace_index(NAMESPACE)
        await c.nodes.objects.get_child([f"{ns}:Leakwatch"])


CLIENT_URI = "urn:leakwatch:scada-client"


async def secure(client, policy, cert_dir):
    """Sign and encrypt the session with `policy`, with a client certificate
    made (once) in `cert_dir`."""
    d = Path(cert_dir)
    d.mkdir(parents=True, exist_ok=True)
    key, cert = d / "client-key.pem", d / "client-cert.der"
    await setup_self_signed_certificate(
        key, cert, CLIENT_URI, socket.gethostname(), [ExtendedKeyUsageOID.CLIENT_AUTH], {"commonName": "leakwatch scada client"}
    )
    client.application_uri = CLIENT_URI
    await client.set_security_string(f"{policy},SignAndEncrypt,{cert},{key}")


async def watch(args, password):
    client = Client(url=args.url, timeout=5)
    if args.security:
        await secure(client, args.security, args.cert_dir)
    result = {"security": args.security or "None"}
    if args.user is not None:
        client.set_user(args.user)
        client.set_password(password)
    async with client:
        ns = await client.get_namespace_index(NAMESPACE)
        result["namespace"] = ns
        rig = await client.nodes.objects.get_child([f"{ns}:Leakwatch", f"{ns}:{args.rig}"])
        result["variables"] = await read_variables(rig, ns)
        running = await rig.get_child([f"{ns}:Running"])
        result["write"] = await status_of(running.write_value(ua.DataValue(ua.Variant(False, ua.VariantType.Boolean))))
        handler = Events()
        evtype = client.get_node(ua.NodeId("LeakwatchEventType", ns))
        sub = await client.create_subscription(20, handler)
        # no where clause: the server (async-opcua 0.19) does not compare NodeIds in
        # InList, the filter asyncua generates on EventType; the rig's object emits
        # only LeakwatchEventType events anyway
        await sub.subscribe_events(rig, evtype, where_clause_generation=False)
        state_sub = await client.create_subscription(20, handler)
        t0 = time.monotonic()
        await state_sub.subscribe_data_change(await rig.get_child([f"{ns}:SampleTimeS"]), sampling_interval=0)
        try:
            if args.until_leak:
                await asyncio.wait_for(handler.leak.wait(), args.seconds)
                await asyncio.sleep(0.5)
            else:
                await asyncio.sleep(args.seconds)
        except asyncio.TimeoutError:
            pass
        elapsed = time.monotonic() - t0
        result["after"] = await read_variables(rig, ns)
        result["events"] = handler.events
        ups = handler.updates
        result["state_updates"] = len(ups)
        result["state_update_hz"] = (len(ups) - 1) / (ups[-1] - ups[0]) if len(ups) > 2 else 0.0
        result["watched_s"] = elapsed
        await sub.delete()
        await state_sub.delete()
    return result


async def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("url")
    ap.add_argument("--rig", required=True)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--until-leak", action="store_true")
    ap.add_argument("--user")
    ap.add_argument("--password-file")
    ap.add_argument("--check-anonymous-refused", action="store_true")
    ap.add_argument("--security", choices=["Basic256Sha256", "Aes128Sha256RsaOaep"])
    ap.add_argument("--cert-dir", default="scada-client-pki")
    ap.add_argument("--wait-s", type=float, default=20.0, help="how long to wait for the server to listen")
    args = ap.parse_args()
    password = None
    if args.password_file:
        with open(args.password_file) as f:
            password = f.readline().strip()
    deadline = time.monotonic() + args.wait_s
    while True:
        try:
            result = await watch(args, password)
            break
        except (ConnectionError, OSError, asyncio.TimeoutError) as e:
            if time.monotonic() > deadline:
                raise SystemExit(f"no OPC UA server at {args.url}: {e}")
            await asyncio.sleep(0.2)
    if args.check_anonymous_refused:
        result["anonymous"] = await status_of(connect_and_read(args.url))
        result["wrong_password"] = await status_of(connect_and_read(args.url, args.user, "not-the-password"))
    json.dump(result, sys.stdout, default=str)
    print()


if __name__ == "__main__":
    asyncio.run(main())
