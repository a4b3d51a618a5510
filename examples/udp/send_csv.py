#!/usr/bin/env python3
"""Stream a leakwatch CSV to the acquisition stage as UDP datagrams.

One row = one datagram in the leakwatch UDP format (frames/README.md,
examples/udp/leakwatch_udp.h): 72 bytes, little-endian, magic "LWUD",
version 1. Standard library only (Python 3.8+).

    python3 examples/udp/send_csv.py run.csv 127.0.0.1:5005             # 1 kHz
    python3 examples/udp/send_csv.py run.csv 127.0.0.1:5005 --rate-hz 0 # as fast as possible

with the receiver started first, e.g.

    leakwatch run --source udp://127.0.0.1:5005 --out live

The CSV is the leakwatch format: a header naming the columns t,u,x,p1,p2 and
optionally x_sp,f_load (others, such as ref and q_leak, are ignored), SI
units; `.csv.gz` is read too. An empty x_sp or f_load cell is sent as absent.
The datagrams are numbered from --start-seq; the last one carries the
end-of-stream flag.

For tests, faults can be injected (N counts datagrams from 1; the last two
rows are never touched, so the stream always ends cleanly):
  --drop-every N       do not send every Nth datagram      (receiver: lost)
  --duplicate-every N  send every Nth datagram twice       (receiver: duplicated)
  --swap-every N       send every Nth after the next one   (receiver: lost, then late)
  --garbage-every N    send a malformed datagram after every Nth (receiver: malformed)
At the end a summary line and a `counts:` line (key=value) go to stdout.
"""

import argparse
import csv
import gzip
import io
import math
import struct
import socket
import sys
import time

MAGIC = b"LWUD"
VERSION = 1
FLAG_X_SP_PRESENT = 1 << 0
FLAG_F_LOAD_PRESENT = 1 << 1
FLAG_END_OF_STREAM = 1 << 2
FLAG_NO_SAMPLE = 1 << 3
# Periods the sender may fall behind its schedule before it goes on from
# where it is instead of catching up (a backlog sent at once overflows a
# receiver's buffer as no sampling source would).
MAX_BEHIND_PERIODS = 20
# magic, version u16, flags u16, seq u64, t u x p1 p2 x_sp f_load f64: little-endian, no padding
LAYOUT = struct.Struct("<4sHHQ7d")
assert LAYOUT.size == 72


def encode(seq, flags, t, u, x, p1, p2, x_sp=math.nan, f_load=math.nan):
    """The 72 bytes of one datagram."""
    return LAYOUT.pack(MAGIC, VERSION, flags, seq, t, u, x, p1, p2, x_sp, f_load)


def parse_address(text):
    host, sep, port = text.rpartition(":")
    if not sep or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"{text!r}: expected HOST:PORT, e.g. 127.0.0.1:5005")
    return host.strip("[]"), int(port)


def positive_int(text):
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"{text}: must be 1 or more")
    return n


def read_rows(path):
    """(t, u, x, p1, p2, x_sp, f_load) per row; absent optional values NaN."""
    raw = open(path, "rb")
    stream = gzip.open(raw) if path.endswith(".gz") else raw
    text = io.TextIOWrapper(stream, encoding="utf-8", newline="")
    reader = csv.reader(text)
    header = [h.strip() for h in next(reader)]
    missing = [c for c in ("t", "u", "x", "p1", "p2") if c not in header]
    if missing:
        sys.exit(f"send_csv: {path}: the header has no column {', '.join(missing)}")
    cols = [header.index(c) if c in header else None for c in ("t", "u", "x", "p1", "p2", "x_sp", "f_load")]
    rows = []
    for line_no, cells in enumerate(reader, start=2):
        if not cells or all(not c.strip() for c in cells):
            continue
        values = []
        for c in cols:
            cell = cells[c].strip() if c is not None and c < len(cells) else ""
            try:
                values.append(float(cell) if cell else math.nan)
            except ValueError:
                print(f"send_csv: line {line_no}: {cell!r} is not a number (sent as NaN)", file=sys.stderr)
                values.append(math.nan)
        rows.append(tuple(values))
    text.close()
    return rows


def every(n, k):
    """True for the k-th datagram (1-based) if n is set and k is a multiple of n."""
    return n is not None and k % n == 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv", help="leakwatch CSV (t,u,x,p1,p2[,x_sp,f_load,...]), SI units")
    ap.add_argument("address", type=parse_address, help="receiver HOST:PORT, e.g. 127.0.0.1:5005")
    ap.add_argument("--rate-hz", type=float, default=1000.0, help="datagrams per second (0 = as fast as possible); a sender more than %d periods behind goes on from there, without a burst" % MAX_BEHIND_PERIODS)
    ap.add_argument("--start-seq", type=int, default=0, help="sequence number of the first datagram")
    ap.add_argument("--drop-every", type=positive_int, help="do not send every Nth datagram")
    ap.add_argument("--duplicate-every", type=positive_int, help="send every Nth datagram twice")
    ap.add_argument("--swap-every", type=positive_int, help="send every Nth datagram after the next one")
    ap.add_argument("--garbage-every", type=positive_int, help="send a malformed datagram after every Nth")
    ap.add_argument("--no-end", action="store_true", help="do not flag the last datagram as the end of stream")
    args = ap.parse_args()
    if not (args.rate_hz >= 0 and math.isfinite(args.rate_hz)):
        ap.error("--rate-hz must be 0 or more")

    rows = read_rows(args.csv)
    if not rows:
        sys.exit(f"send_csv: {args.csv}: no rows")
    family = socket.AF_INET6 if ":" in args.address[0] else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 1 << 20)
    dest = args.address
    period = 1.0 / args.rate_hz if args.rate_hz > 0 else 0.0
    counts = {"samples": len(rows), "datagrams": 0, "dropped": 0, "duplicated": 0, "swapped": 0, "garbage": 0}
    garbage = encode(0, 0, 0.0, 0.0, 0.0, 0.0, 0.0).replace(MAGIC, b"JUNK", 1)

    def send(datagram):
        sock.sendto(datagram, dest)
        counts["datagrams"] += 1

    held = None
    last = len(rows) - 1
    start = time.perf_counter()
    for i, (t, u, x, p1, p2, x_sp, f_load) in enumerate(rows):
        if period > 0:
            delay = start + i * period - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            elif delay < -MAX_BEHIND_PERIODS * period:
                # descheduled: go on at the rate from here, as a sampling
                # source does, rather than send the backlog in one burst
                start -= delay
        k = i + 1
        inject = i < last - 1
        flags = 0
        if not math.isnan(x_sp):
            flags |= FLAG_X_SP_PRESENT
        if not math.isnan(f_load):
            flags |= FLAG_F_LOAD_PRESENT
        if i == last and not args.no_end:
            flags |= FLAG_END_OF_STREAM
        d = encode(args.start_seq + i, flags, t, u, x, p1, p2, x_sp, f_load)
        if inject and every(args.drop_every, k):
            counts["dropped"] += 1
            continue
        out = [d]
        if inject and every(args.duplicate_every, k):
            out.append(d)
            counts["duplicated"] += 1
        elif inject and held is None and every(args.swap_every, k):
            held = out
            continue
        for datagram in out:
            send(datagram)
        if held is not None:
            for datagram in held:
                send(datagram)
            held = None
            counts["swapped"] += 1
        if inject and every(args.garbage_every, k):
            send(garbage)
            counts["garbage"] += 1
    elapsed = time.perf_counter() - start
    rate = len(rows) / elapsed if elapsed > 0 else float("inf")
    print(
        f"send_csv: {len(rows)} samples as {counts['datagrams']} datagrams to {dest[0]}:{dest[1]} in {elapsed:.2f} s "
        f"({rate:.0f} samples/s); {counts['dropped']} dropped, {counts['duplicated']} duplicated, "
        f"{counts['swapped']} swapped, {counts['garbage']} garbage"
    )
    print("counts: " + " ".join(f"{k}={v}" for k, v in counts.items()))


if __name__ == "__main__":
    main()
