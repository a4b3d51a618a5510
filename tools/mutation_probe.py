#!/usr/bin/env python3
"""Bad-input probe for leakwatch (issue 13): feed mutated CSVs, MCAP logs and
configs to the CLI and classify every command run.

Classes (per command run):
  PANIC     exit 101 or "panicked" on stderr
  HANG      no exit within --timeout seconds (the process group is killed)
  ABORT     killed by a signal, or exit 134
  REJECTED  non-zero exit (the error line is recorded)
  REPORTED  exit 0, but a new line on stderr (compared with the run on the
            unmutated input, numbers ignored), non-zero bad/skipped/missing
            counts or damaged chunks in summary.json, or a new input-health
            event (detector `sensors`) in events.json
  SILENT    exit 0 and nothing said

Every mutation is labelled "garbage" (must be rejected or reported) or
"benign" (valid input; may be accepted silently).  Failures:
  PANIC, HANG, ABORT on anything; SILENT on garbage (for MCAP inputs only if
  the outputs differ from the unmutated log's: damage to redundant index
  records that leaves the data intact is not garbage reaching the output);
  non-finite numbers in the outputs of a command that exited 0 when the input
  had none (or in the filter's own columns whatever the input).

Python 3 standard library only.  Runs one command at a time.  Inputs: a 3 s
`simulate` CSV (CSV mutations), a 15 s one (config replays: long enough for the
classifier to arm), one log recorded with `run --seconds 4` (or --base-log).
With --with-run, `run --seconds 2 --config` on six configs (a live pipeline of
four processes each; leftover processes of its group count as ORPHANS).

  python3 tools/mutation_probe.py --bin target/release/leakwatch --out report.json
  python3 tools/mutation_probe.py --only 'mcap/chunk0_usize' --keep /tmp/inputs
"""

import argparse
import csv
import hashlib
import io
import json
import math
import os
import random
import re
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time

CLASSES = ["PANIC", "HANG", "ABORT", "REJECTED", "REPORTED", "SILENT"]
COLUMNS = ["t", "u", "x", "p1", "p2", "x_sp", "f_load", "ref", "q_leak"]
OPTIONAL = {"x_sp", "f_load", "ref", "q_leak"}
# Columns of estimates.csv that only echo the input.
ECHO_COLUMNS = {"t", "u", "x_meas", "p1_meas", "p2_meas", "x_sp"}


# --------------------------------------------------------------------------
# running one command


def run_cmd(argv, cwd, timeout, mem_limit_mb):
    """Run argv in its own process group with stdout/stderr to files.
    Returns a dict: rc, signal, timed_out, wall_s, maxrss_mb, stdout, stderr,
    orphans (processes of the group still alive after the leader exited)."""
    out_path = os.path.join(cwd, ".stdout")
    err_path = os.path.join(cwd, ".stderr")

    def preexec():
        if mem_limit_mb:
            lim = mem_limit_mb * 1024 * 1024
            resource.setrlimit(resource.RLIMIT_AS, (lim, lim))

    with open(out_path, "wb") as fo, open(err_path, "wb") as fe:
        t0 = time.monotonic()
        p = subprocess.Popen(argv, cwd=cwd, stdin=subprocess.DEVNULL, stdout=fo, stderr=fe,
                             start_new_session=True, preexec_fn=preexec)
        timed_out = False
        status = None
        hwm_kb = 0
        while True:
            pid, st, ru = os.wait4(p.pid, os.WNOHANG)
            if pid == p.pid:
                status = st
                break
            hwm_kb = max(hwm_kb, vm_hwm_kb(p.pid))
            if time.monotonic() - t0 > timeout:
                timed_out = True
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                _, status, _ = os.wait4(p.pid, 0)
                break
            time.sleep(0.005)
        wall = time.monotonic() - t0
        p.returncode = 0  # reaped by wait4 above; keep Popen from waiting again
    # processes of the group that outlived the leader (stages of `run`)
    orphans = 0
    try:
        os.killpg(p.pid, 0)
        orphans = 1
        time.sleep(0.5)
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    except ProcessLookupError:
        pass
    except PermissionError:
        pass
    rc = sig = None
    if os.WIFEXITED(status):
        rc = os.WEXITSTATUS(status)
    elif os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
    with open(out_path, "rb") as f:
        stdout = f.read(1 << 20)
    with open(err_path, "rb") as f:
        stderr = f.read(1 << 20)
    return {
        "argv": argv, "rc": rc, "signal": sig, "timed_out": timed_out,
        "wall_s": round(wall, 3), "peak_rss_mb": round(hwm_kb / 1024, 1),
        "stdout": stdout.decode("utf-8", "replace"),
        "stderr": stderr.decode("utf-8", "replace"),
        "orphans": orphans,
    }


def vm_hwm_kb(pid):
    """Peak resident set of a running process (polled; 0 once it has exited)."""
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


NUM_RE = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?:µs|ms|s)?")


def normalize(line, subs):
    for a, b in subs:
        if a:
            line = line.replace(a, b)
    return NUM_RE.sub("#", line).strip()


def error_line(stderr):
    lines = [l for l in stderr.splitlines() if l.strip()]
    for l in lines:
        if "error" in l.lower() or "panicked" in l:
            return l[:500]
    for l in lines:
        if not l.startswith("note: not commissioned"):
            return l[:500]
    return lines[0][:500] if lines else ""


def classify(res, baseline_lines, subs, summary_flags):
    """Returns (class, message, new_lines)."""
    err = res["stderr"]
    new = []
    for l in err.splitlines():
        if not l.strip():
            continue
        n = normalize(l, subs)
        if n not in baseline_lines:
            new.append(l[:400])
    if res["timed_out"]:
        return "HANG", error_line(err), new
    if res["rc"] == 101 or "panicked" in err:
        return "PANIC", error_line(err), new
    if res["signal"] is not None or res["rc"] == 134:
        return "ABORT", "signal %s rc %s: %s" % (res["signal"], res["rc"], error_line(err)), new
    if res["rc"] != 0:
        return "REJECTED", error_line(err), new
    if new or summary_flags:
        msg = "; ".join(summary_flags + new[:3])
        return "REPORTED", msg[:600], new
    return "SILENT", "", new


def summary_flags(path):
    """Non-zero problem counters in a replay summary.json."""
    try:
        with open(path) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return []
    flags = []
    for k in ("rows_skipped", "samples_missing"):
        if s.get(k):
            flags.append("%s=%s" % (k, s[k]))
    if s.get("rows_rejected"):
        flags.append("rows_rejected=%s" % json.dumps(s["rows_rejected"]))
    if s.get("issues"):
        flags.append("issues[%d]: %s" % (len(s["issues"]), s["issues"][0]))
    absent = {k: v for k, v in (s.get("optional_absent") or {}).items() if v}
    if absent:
        flags.append("optional_absent=%s" % json.dumps(absent))
    log = s.get("log") or {}
    if log.get("chunks_skipped"):
        flags.append("chunks_skipped=%s" % json.dumps(log["chunks_skipped"])[:200])
    for k, v in log.items():
        if k != "chunks_skipped" and v and isinstance(v, (int, float)):
            flags.append("log.%s=%s" % (k, v))
    return flags


def nonfinite_in_csv(path, only_state_columns=False, limit_bytes=200 << 20):
    """Names of columns of a CSV holding NaN/inf (or None if unreadable)."""
    try:
        if os.path.getsize(path) > limit_bytes:
            return None
        with open(path, newline="", errors="replace") as f:
            r = csv.reader(f)
            header = next(r, None)
            if header is None:
                return []
            bad = set()
            for row in r:
                for name, v in zip(header, row):
                    if only_state_columns and name in ECHO_COLUMNS:
                        continue
                    if name in bad:
                        continue
                    lv = v.strip().lower()
                    if "nan" in lv or "inf" in lv:
                        bad.add(name)
            return sorted(bad)
    except OSError:
        return None


CONTROL_RE = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")


def sensor_events(path):
    """Input-health events (detector `sensors`) in a replay's events.json."""
    try:
        with open(path) as f:
            ev = json.load(f)
    except (OSError, ValueError):
        return []
    return sorted({"%s:%s" % (e.get("kind"), e.get("channel", "")) for e in ev
                   if isinstance(e, dict) and e.get("detector") == "sensors"})


def hash_files(paths):
    h = hashlib.sha256()
    for p in paths:
        try:
            with open(p, "rb") as f:
                h.update(f.read())
        except OSError:
            h.update(b"<missing>")
    return h.hexdigest()[:16]


# --------------------------------------------------------------------------
# CSV mutations


def csv_mutations(base_text, rng, sink):
    lines = base_text.splitlines()
    header, rows = lines[0], lines[1:]
    n = len(rows)
    R = 1500  # the row mutated in the "one row" cases (file line R + 2)
    out = []

    def emit(name, label, text_or_bytes, expect=None, nonfinite=False):
        data = text_or_bytes if isinstance(text_or_bytes, bytes) else text_or_bytes.encode()
        out.append(sink({"name": name, "label": label, "data": data, "expect": expect or [],
                         "nonfinite_input": nonfinite}))

    def join(hdr, rs):
        return hdr + "\n" + "\n".join(rs) + "\n"

    def set_col(row, ci, v):
        f = row.split(",")
        f[ci] = v
        return ",".join(f)

    values = ["NaN", "inf", "-inf", "1e308", "-1e308", "", "abc", "1e400"]
    for ci, col in enumerate(COLUMNS):
        for v in values:
            vname = {"": "empty", "-inf": "neginf", "-1e308": "neg1e308"}.get(v, v)
            for scope in ("one", "all"):
                rs = list(rows)
                if scope == "one":
                    rs[R] = set_col(rs[R], ci, v)
                else:
                    rs = [set_col(r, ci, v) for r in rs]
                label = "benign" if (v == "" and col in OPTIONAL) else "garbage"
                emit("csv/%s_%s_%s_row" % (col, vname, scope), label, join(header, rs),
                     expect=[col], nonfinite=v in ("NaN", "inf", "-inf", "1e400"))

    phys = [("x", "-10"), ("x", "10"), ("u", "1000"), ("p1", "0"), ("p1", "-1e6"), ("p1", "1e9"),
            ("p2", "0"), ("p2", "-1e6"), ("p2", "1e9")]
    for col, v in phys:
        ci = COLUMNS.index(col)
        for scope in ("one", "all"):
            rs = list(rows)
            if scope == "one":
                rs[R] = set_col(rs[R], ci, v)
            else:
                rs = [set_col(r, ci, v) for r in rs]
            emit("csv/phys_%s=%s_%s_row" % (col, v, scope), "garbage", join(header, rs), expect=[col])
    emit("csv/phys_u=1e300_all_row", "garbage",
         join(header, [set_col(r, 1, "1e300") for r in rows]), expect=["u"])

    # time column
    t = [float(r.split(",")[0]) for r in rows]

    def with_t(ts, rs=None):
        rs = rs if rs is not None else rows
        return [set_col(r, 0, repr(x)) for r, x in zip(rs, ts)]

    emit("csv/time_reversed_all", "garbage", join(header, list(reversed(rows))), expect=["t"])
    rs = list(rows); rs[R], rs[R + 1] = rs[R + 1], rs[R]
    emit("csv/time_swap_pair", "garbage", join(header, rs), expect=["t"])
    rs = list(rows); rs.insert(R, rows[R])
    emit("csv/time_duplicate_row", "garbage", join(header, rs), expect=["t"])
    rs = list(rows); rs[R + 1] = set_col(rs[R + 1], 0, repr(t[R]))
    emit("csv/time_duplicate_timestamp", "garbage", join(header, rs), expect=["t"])
    rs = list(rows); rs[R + 1] = set_col(rs[R + 1], 0, repr(t[R] + 1e-6))
    emit("csv/time_1us_step_one", "garbage", join(header, rs), expect=["t"])
    emit("csv/time_1us_step_all", "garbage", join(header, with_t([i * 1e-6 for i in range(n)])), expect=["t"])
    emit("csv/time_gap_100s", "garbage",
         join(header, with_t([x + (100.0 if i >= R else 0.0) for i, x in enumerate(t)])), expect=["t"])
    emit("csv/time_gap_drop3", "garbage", join(header, rows[:R] + rows[R + 3:]), expect=["t"])
    emit("csv/time_gap_drop50", "garbage", join(header, rows[:R] + rows[R + 50:]), expect=["t"])
    emit("csv/time_period_2ms", "garbage", join(header, rows[::2]), expect=["t"])
    emit("csv/time_all_zero", "garbage", join(header, with_t([0.0] * n)), expect=["t"])
    emit("csv/time_offset_1e9", "benign", join(header, with_t([x + 1e9 for x in t])))
    emit("csv/time_negative_start", "benign", join(header, with_t([x - 10.0 for x in t])))
    emit("csv/time_jitter_1us", "benign",
         join(header, with_t([x + rng.uniform(-1e-6, 1e-6) for x in t])))

    # structure
    body = join(header, rows)
    cut = rows[-1].split(",")
    emit("csv/truncated_last_line_mid_number", "garbage",
         header + "\n" + "\n".join(rows[:-1]) + "\n" + ",".join(cut[:3]) + "," + cut[3][:4], expect=["line"])
    emit("csv/truncated_last_line_no_newline", "benign", body[:-1])
    emit("csv/extra_column_named", "benign", join(header + ",extra", [r + ",1.0" for r in rows]))
    rs = list(rows); rs[R] = rs[R] + ",1.0"
    emit("csv/extra_value_one_row", "garbage", join(header, rs), expect=["line"])
    emit("csv/extra_value_all_rows_no_header", "garbage", join(header, [r + ",1.0" for r in rows]))

    def drop_col(name):
        ci = COLUMNS.index(name)
        h = ",".join(c for c in COLUMNS if c != name)
        return join(h, [",".join(f for j, f in enumerate(r.split(",")) if j != ci) for r in rows])

    emit("csv/missing_column_p2", "garbage", drop_col("p2"), expect=["p2"])
    emit("csv/missing_column_t", "garbage", drop_col("t"), expect=["t"])
    emit("csv/missing_column_q_leak", "benign", drop_col("q_leak"))
    emit("csv/only_required_columns", "benign",
         join("t,u,x,p1,p2", [",".join(r.split(",")[:5]) for r in rows]))
    rs = list(rows); rs[R] = ",".join(rs[R].split(",")[:-1])
    emit("csv/missing_value_one_row", "garbage", join(header, rs), expect=["line"])
    order = [8, 7, 6, 5, 4, 3, 2, 1, 0]
    emit("csv/columns_reordered", "benign",
         join(",".join(COLUMNS[i] for i in order),
              [",".join(r.split(",")[i] for i in order) for r in rows]))
    emit("csv/bom", "benign", b"\xef\xbb\xbf" + body.encode())
    emit("csv/crlf", "benign", body.replace("\n", "\r\n"))
    emit("csv/bom_crlf", "benign", b"\xef\xbb\xbf" + body.replace("\n", "\r\n").encode())
    emit("csv/empty_file", "garbage", b"")
    emit("csv/header_only", "garbage", header + "\n")
    emit("csv/header_only_no_newline", "garbage", header)
    emit("csv/no_header", "garbage", "\n".join(rows) + "\n")
    emit("csv/header_case_P1", "garbage", join(header.replace("p1", "P1"), rows), expect=["p1"])
    emit("csv/header_duplicate_column", "garbage", join(header.replace("p2", "p1"), rows), expect=["p1"])
    rs = list(rows); rs.insert(R, header)
    emit("csv/header_repeated_midfile", "garbage", join(header, rs), expect=["line"])
    rs = list(rows); rs.insert(R, "")
    emit("csv/blank_line_midfile", "benign", join(header, rs))
    rs = list(rows); rs.insert(R, "# a comment")
    emit("csv/comment_line_midfile", "garbage", join(header, rs), expect=["line"])
    emit("csv/separator_semicolon", "garbage", body.replace(",", ";"), expect=["separator", ";"])
    emit("csv/separator_tab", "garbage", body.replace(",", "\t"), expect=["separator", "tab"])
    emit("csv/quoted_fields", "benign",
         join(header, [",".join('"%s"' % f for f in r.split(",")) for r in rows]))
    emit("csv/whitespace_padded", "benign",
         join(header, [", ".join(r.split(",")) for r in rows]))
    emit("csv/binary_garbage_4k", "garbage", bytes(rng.getrandbits(8) for _ in range(4096)))
    rs = [r.encode() for r in rows]
    rs[R] = bytes(rng.getrandbits(8) for _ in range(80)).replace(b"\n", b"\x00")
    emit("csv/binary_garbage_row", "garbage", header.encode() + b"\n" + b"\n".join(rs) + b"\n", expect=["line"])
    rs = [r.encode() for r in rows]
    rs[R] = rs[R][:10] + b"\x00" + rs[R][10:]
    emit("csv/nul_byte_in_row", "garbage", header.encode() + b"\n" + b"\n".join(rs) + b"\n", expect=["line"])
    rs = [r.encode() for r in rows]
    f = rs[R].split(b","); f[2] = b"0.\xff\xfe3"; rs[R] = b",".join(f)
    emit("csv/invalid_utf8_in_x", "garbage", header.encode() + b"\n" + b"\n".join(rs) + b"\n", expect=["line"])
    rs = list(rows); rs[R] = set_col(rs[R], 1, "1" + "0" * (5 << 20))
    emit("csv/line_5mb_digits_in_u", "garbage", join(header, rs), expect=["line"])
    rs = list(rows); rs[R] = "a" * (5 << 20)
    emit("csv/line_5mb_text", "garbage", join(header, rs), expect=["line"])
    rs = list(rows); rs[R] = "9" * (50 << 20)
    emit("csv/line_50mb", "garbage", join(header, rs), expect=["line"])

    def bad_fraction(k):
        idx = set(range(n - k, n)) if k < n else set(range(n))
        return join(header, [set_col(r, 2, "abc") if i in idx else r for i, r in enumerate(rows)])

    emit("csv/bad_rows_99.9pct", "garbage", bad_fraction(n - 3), expect=["x"])
    emit("csv/bad_rows_1pct", "garbage", bad_fraction(n // 100), expect=["x"])
    emit("csv/bad_rows_2pct", "garbage", bad_fraction(n // 50), expect=["x"])

    def perturb(r):
        f = r.split(",")
        f[2] = repr(float(f[2]) + rng.gauss(0, 1e-7))
        f[3] = repr(float(f[3]) + rng.gauss(0, 10))
        f[4] = repr(float(f[4]) + rng.gauss(0, 10))
        return ",".join(f)

    emit("csv/benign_perturbation", "benign", join(header, [perturb(r) for r in rows]))

    def perturb_clamped(r):
        f = perturb(r).split(",")
        f[3] = repr(max(0.0, float(f[3])))
        f[4] = repr(max(0.0, float(f[4])))
        return ",".join(f)

    emit("csv/benign_perturbation_p_clamped_at_0", "benign", join(header, [perturb_clamped(r) for r in rows]))
    emit("csv/number_formats_exp_plus", "benign",
         join(header, [",".join(("%+.9e" % float(v)) for v in r.split(",")) for r in rows]))
    rs = list(rows); rs[R] = set_col(rs[R], 1, "5e-324")
    emit("csv/u_denormal_one_row", "benign", join(header, rs))
    rs = list(rows); rs[R] = set_col(rs[R], 1, "-0.0")
    emit("csv/u_negative_zero_one_row", "benign", join(header, rs))
    rs = list(rows); rs[R] = set_col(rs[R], 2, "0x10")
    emit("csv/x_hex_one_row", "garbage", join(header, rs), expect=["x"])
    rs = list(rows); rs[R] = set_col(rs[R], 2, "nan")
    emit("csv/x_nan_lowercase_one_row", "garbage", join(header, rs), expect=["x"], nonfinite=True)
    rs = list(rows); rs[R] = set_col(rs[R], 2, "Infinity")
    emit("csv/x_Infinity_one_row", "garbage", join(header, rs), expect=["x"], nonfinite=True)
    rs = list(rows); rs[R] = set_col(rs[R], 3, "6,9e6")
    emit("csv/p1_decimal_comma_one_row", "garbage", join(header, rs), expect=["line"])
    emit("csv/single_row", "benign", join(header, rows[:1]))
    return out


# --------------------------------------------------------------------------
# MCAP mutations

MAGIC = b"\x89MCAP0\r\n"


def parse_mcap(d):
    """Top-level records: list of dicts with op, pos, len (content length)."""
    recs = []
    pos = 8
    while pos + 9 <= len(d) - 8:
        op = d[pos]
        ln = struct.unpack_from("<Q", d, pos + 1)[0]
        rec = {"op": op, "pos": pos, "len": ln}
        if op == 0x06:
            c = pos + 9
            rec["usize_off"] = c + 16
            rec["crc_off"] = c + 24
            sl = struct.unpack_from("<I", d, c + 28)[0]
            rec["comp_len_off"] = c + 28
            rec["comp_off"] = c + 32
            rec["comp"] = d[c + 32:c + 32 + sl]
            rec["rlen_off"] = c + 32 + sl
            rec["data_off"] = c + 32 + sl + 8
            rec["data_len"] = struct.unpack_from("<Q", d, rec["rlen_off"])[0]
        recs.append(rec)
        pos += 9 + ln
    return recs


def zstd_rle_bomb(total, pad_to):
    """A zstd frame of RLE blocks decompressing to `total` bytes, followed by a
    skippable frame so the result is exactly `pad_to` bytes long."""
    frame = struct.pack("<I", 0xFD2FB528) + bytes([0x00, 0x38])  # no FCS, window 128 KiB
    block = 128 * 1024
    nblocks = total // block
    hdr = (1 << 1) | (block << 3)  # RLE block, not last
    last = hdr | 1
    body = (struct.pack("<I", hdr)[:3] + b"\x05") * (nblocks - 1) + struct.pack("<I", last)[:3] + b"\x05"
    frame += body
    pad = pad_to - len(frame) - 8
    assert pad >= 0, "bomb does not fit"
    return frame + struct.pack("<II", 0x184D2A50, pad) + b"\x00" * pad


def mcap_mutations(base, rng, sink):
    recs = parse_mcap(base)
    chunks = [r for r in recs if r["op"] == 0x06]
    by_op = {}
    for r in recs:
        by_op.setdefault(r["op"], []).append(r)
    size = len(base)
    out = []

    def emit(name, label, data, note=""):
        out.append(sink({"name": name, "label": label, "data": bytes(data), "expect": ["input.mcap"], "note": note,
                         "nonfinite_input": False}))

    def flip(pos, mask=0xFF):
        b = bytearray(base)
        b[pos] ^= mask
        return b

    def put_u64(pos, v, data=None):
        b = bytearray(base if data is None else data)
        struct.pack_into("<Q", b, pos, v)
        return b

    emit("mcap/control_unmodified", "benign", base)
    # magic and header
    emit("mcap/flip_magic_byte0", "garbage", flip(0))
    emit("mcap/flip_magic_version", "garbage", flip(5))
    hdr = by_op[0x01][0]
    emit("mcap/flip_header_opcode", "garbage", flip(hdr["pos"]))
    emit("mcap/flip_header_len_low", "garbage", flip(hdr["pos"] + 1))
    emit("mcap/flip_header_len_high", "garbage", flip(hdr["pos"] + 8))
    emit("mcap/flip_header_profile", "garbage", flip(hdr["pos"] + 9 + 6))
    if 0x0C in by_op:
        md = by_op[0x0C][0]
        emit("mcap/flip_metadata_len_high", "garbage", flip(md["pos"] + 8))
        emit("mcap/flip_metadata_content", "garbage", flip(md["pos"] + 9 + md["len"] // 2))
    # chunks
    for tag, c in (("chunk0", chunks[0]), ("chunkmid", chunks[len(chunks) // 2]), ("chunklast", chunks[-1])):
        emit("mcap/%s_flip_opcode" % tag, "garbage", flip(c["pos"]))
        emit("mcap/%s_flip_len_low" % tag, "garbage", flip(c["pos"] + 1))
        emit("mcap/%s_flip_len_high" % tag, "garbage", flip(c["pos"] + 8))
        emit("mcap/%s_usize_1" % tag, "garbage", put_u64(c["usize_off"], 1))
        emit("mcap/%s_usize_2^62" % tag, "garbage", put_u64(c["usize_off"], 1 << 62))
        mid = c["data_off"] + c["data_len"] // 2
        emit("mcap/%s_flip_compressed_mid" % tag, "garbage", flip(mid))
        emit("mcap/%s_bitflip_compressed_mid" % tag, "garbage", flip(mid + 7, 0x01))
    c0 = chunks[0]
    emit("mcap/chunk0_usize_0", "garbage", put_u64(c0["usize_off"], 0))
    emit("mcap/chunk0_usize_u64max", "garbage", put_u64(c0["usize_off"], (1 << 64) - 1))
    emit("mcap/chunk0_usize_plus1", "garbage",
         put_u64(c0["usize_off"], struct.unpack_from("<Q", base, c0["usize_off"])[0] + 1))
    b = bytearray(base)
    struct.pack_into("<I", b, c0["crc_off"], 0)
    emit("mcap/chunk0_usize_1_crc0", "garbage", put_u64(c0["usize_off"], 1, b))
    emit("mcap/chunk0_flip_crc", "garbage", flip(c0["crc_off"]))
    emit("mcap/chunk0_flip_compression_strlen", "garbage", flip(c0["comp_len_off"]))
    emit("mcap/chunk0_compression_zstx", "garbage", flip(c0["comp_off"] + 3, ord("d") ^ ord("x")))
    emit("mcap/chunk0_flip_records_len_low", "garbage", flip(c0["rlen_off"]))
    emit("mcap/chunk0_flip_records_len_high", "garbage", flip(c0["rlen_off"] + 7))
    emit("mcap/chunk0_flip_zstd_magic", "garbage", flip(c0["data_off"]))
    emit("mcap/chunk0_flip_zstd_frame_header", "garbage", flip(c0["data_off"] + 4))
    emit("mcap/chunk0_flip_compressed_last", "garbage", flip(c0["data_off"] + c0["data_len"] - 1))
    # decompression bomb in the largest chunk (offsets kept by a skippable frame)
    big = max(chunks, key=lambda c: c["data_len"])
    bomb = zstd_rle_bomb(1 << 30, big["data_len"])
    b = bytearray(base)
    b[big["data_off"]:big["data_off"] + big["data_len"]] = bomb
    emit("mcap/bomb_1GiB_declared_small", "garbage", b, note="zstd RLE frame -> 1 GiB, declared size unchanged")
    b2 = put_u64(big["usize_off"], 1 << 30, b)
    struct.pack_into("<I", b2, big["crc_off"], 0)
    emit("mcap/bomb_1GiB_declared_1GiB_crc0", "garbage", b2, note="zstd RLE frame -> 1 GiB, declared 1 GiB, crc 0")
    # duplicate first chunk (messages twice; summary offsets now wrong)
    c1 = chunks[1]
    dup = base[:c1["pos"]] + base[c0["pos"]:c0["pos"] + 9 + c0["len"]] + base[c1["pos"]:]
    emit("mcap/chunk0_duplicated", "garbage", dup)
    # message index, data end
    if 0x07 in by_op:
        mi = by_op[0x07][0]
        emit("mcap/msgindex_flip_opcode", "garbage", flip(mi["pos"]))
        emit("mcap/msgindex_flip_len_high", "garbage", flip(mi["pos"] + 8))
        emit("mcap/msgindex_flip_content", "garbage", flip(mi["pos"] + 9 + mi["len"] // 2))
    de = by_op[0x0F][0]
    emit("mcap/dataend_flip_crc", "garbage", flip(de["pos"] + 9))
    # summary section
    for op, tag in ((0x03, "schema"), (0x04, "channel"), (0x0B, "statistics"), (0x08, "chunkindex"),
                    (0x0D, "metadataindex"), (0x0E, "summaryoffset")):
        if op in by_op:
            r = by_op[op][0]
            emit("mcap/summary_%s_flip_content" % tag, "garbage", flip(r["pos"] + 9 + min(8, r["len"] - 1)))
    if 0x0B in by_op:
        st = by_op[0x0B][0]
        emit("mcap/summary_statistics_message_count_0", "garbage", put_u64(st["pos"] + 9, 0))
    if 0x08 in by_op:
        ci = by_op[0x08][0]
        # ChunkIndex: start, end, chunk_start_offset, chunk_length, map<u16,u64>(u32 len), mi_len, compression, compressed_size, uncompressed_size
        c = ci["pos"] + 9
        emit("mcap/summary_chunkindex_offset_0", "garbage", put_u64(c + 16, 0))
        emit("mcap/summary_chunkindex_offset_huge", "garbage", put_u64(c + 16, 1 << 62))
        usize_off = ci["pos"] + 9 + ci["len"] - 8
        emit("mcap/summary_chunkindex_usize_1", "garbage", put_u64(usize_off, 1))
        emit("mcap/summary_chunkindex_usize_2^62", "garbage", put_u64(usize_off, 1 << 62))
    # footer
    ft = by_op[0x02][0]
    emit("mcap/footer_summary_start_flip", "garbage", flip(ft["pos"] + 9))
    emit("mcap/footer_summary_start_huge", "garbage", put_u64(ft["pos"] + 9, 1 << 62))
    emit("mcap/footer_summary_offset_start_flip", "garbage", flip(ft["pos"] + 9 + 8))
    emit("mcap/footer_summary_crc_flip", "garbage", flip(ft["pos"] + 9 + 16))
    emit("mcap/flip_trailing_magic", "garbage", flip(size - 3))
    # random single-byte flips in the data section
    lo, hi = c0["pos"], de["pos"]
    positions = sorted(rng.randrange(lo, hi) for _ in range(10))
    for p in positions:
        emit("mcap/random_flip_at_%d" % p, "garbage", flip(p))
    b = bytearray(base)
    for p in positions:
        b[p] ^= 0xFF
    emit("mcap/random_flips_10_at_once", "garbage", b)
    # truncation (killed recorder): must be read up to the cut, with a note
    cuts = {
        "0": 0, "8_magic_only": 8, "16": 16, "100": 100,
        "before_first_chunk": c0["pos"], "mid_chunk0": c0["pos"] + c0["len"] // 2,
        "after_chunk0": c0["pos"] + 9 + c0["len"],
        "10pct": size // 10, "25pct": size // 4, "50pct": size // 2, "75pct": size * 3 // 4,
        "mid_last_chunk": chunks[-1]["pos"] + chunks[-1]["len"] // 2,
        "at_dataend_no_summary": de["pos"], "after_dataend": de["pos"] + 9 + de["len"],
        "mid_summary": (de["pos"] + ft["pos"]) // 2, "before_footer": ft["pos"],
        "no_trailing_magic": size - 8, "minus_1": size - 1,
    }
    for tag, n in cuts.items():
        emit("mcap/truncated_%s" % tag, "garbage", base[:n], note="cut at %d of %d bytes" % (n, size))
    # not MCAP at all
    emit("mcap/random_1k", "garbage", bytes(rng.getrandbits(8) for _ in range(1024)))
    emit("mcap/random_100k", "garbage", bytes(rng.getrandbits(8) for _ in range(100_000)))
    emit("mcap/random_8_bytes", "garbage", bytes(rng.getrandbits(8) for _ in range(8)))
    emit("mcap/magic_then_random_100k", "garbage", MAGIC + bytes(rng.getrandbits(8) for _ in range(100_000)))
    emit("mcap/magic_header_then_random", "garbage",
         base[:c0["pos"]] + bytes(rng.getrandbits(8) for _ in range(100_000)))
    emit("mcap/magic_twice", "garbage", MAGIC + MAGIC)
    emit("mcap/csv_text_named_mcap", "garbage", b"t,u,x,p1,p2\n0,0,0.3,6.9e6,6.9e6\n")
    return out


# --------------------------------------------------------------------------
# config mutations


def config_mutations(default_text, sink):
    out = []

    def emit(name, label, text, expect=None):
        data = text if isinstance(text, bytes) else text.encode()
        out.append(sink({"name": name, "label": label, "data": data, "expect": expect or [],
                         "nonfinite_input": False}))

    fields = [  # (section, key, values that are valid)
        ("model", "piston_area_m2", set()), ("model", "mass_kg", set()), ("model", "x_max_m", set()),
        ("model", "bulk_modulus_pa", set()), ("model", "supply_pressure_pa", set()),
        ("model.friction", "static_n", set()), ("model.load", "contact_m", {"0", "-1"}),
        ("sensors", "pressure_noise_pa", {"0"}), ("sensors", "pressure_full_scale_pa", set()),
        ("sim", "sample_period_s", set()), ("estimator", "r_p_pa2", {"1e12"}),
        ("estimator", "q_leak_m6_s2", {"0"}), ("estimator", "convergence_time_s", {"0"}),
        ("leak_filter", "init_pressure_pa", {"0"}), ("classifier", "threshold_sigma", {"0"}),
        ("classifier", "settle_s", {"0"}), ("classifier", "supply_pressure_pa", set()),
    ]
    for sec, key, ok in fields:
        for v in ("1e308", "-1", "0", "nan", "1e12"):
            emit("config/%s.%s=%s" % (sec, key, v), "benign" if v in ok else "garbage",
                 "[%s]\n%s = %s\n" % (sec, key, v), expect=[key])

    def one(sec, key, v, label="garbage", tag=None):
        emit("config/%s.%s=%s" % (sec, key, tag or v), label, "[%s]\n%s = %s\n" % (sec, key, v), expect=[key])

    for v in ("1000000000000", "0", "-1", "9223372036854775807"):
        one("estimator", "mae_window_samples", v)
    one("leak_filter", "mae_window_samples", "1000000000000")
    one("estimator", "max_bridged_gap_samples", "1000000000000")
    for sec in ("sim", "estimator", "leak_filter"):
        one(sec, "sample_period_s", "1e-300")
    for v in ("0", "64", "65", "-1"):
        one("sensors", "adc_bits", v)
    one("sensors", "adc_bits", "24", label="benign")
    one("sensors", "adc_bits", "99999999999999999999", tag="int_overflow")
    one("sensors", "adc_bits", "12.5")
    one("sim", "substeps_per_sample", "4000000000")
    one("sim", "substeps_per_sample", "0")
    one("estimator", "substeps", "4000000000")
    one("classifier", "stuck_samples", "0")
    one("classifier", "stuck_samples", "1000000000000")
    one("classifier", "false_alarms_per_hour", "0")
    one("estimator", "divergence_reset_m", "-1")
    one("estimator", "states", "5")
    one("leak_filter", "states", "99")
    one("estimator", "init", '"bogus"')
    one("model", "mass_kg", "inf")
    one("model", "mass_kg", "-inf", tag="neginf")
    one("model", "mass_kg", '"ten"', tag="string")
    one("sensors", "enabled", '"yes"', tag="string")
    one("model", "leaks", "5")
    one("model", "leaks", '[{path="ext1", law="sqrt", coefficient=-1}]', tag="leak_coefficient_-1")
    one("model", "leaks", '[{path="ext1", law="sqrt", coefficient=1e308}]', tag="leak_coefficient_1e308")
    one("model", "leaks", '[{path="ext1", law="sqrt", coefficient=1e-9}]', label="benign", tag="leak_valid")
    emit("config/model.x_min_gt_x_max", "garbage", "[model]\nx_min_m = 1.0\nx_max_m = 0.5\n", expect=["x_min_m"])
    emit("config/classifier.min_warmup_gt_warmup", "garbage",
         "[classifier]\nwarmup_s = 1.0\nmin_warmup_s = 3.0\n", expect=["warmup"])
    emit("config/rig.mass_kg=-1", "garbage", "[rig]\nmass_kg = -1\n", expect=["mass_kg"])
    emit("config/rig.supply_pressure_pa=1e308", "garbage", "[rig]\nsupply_pressure_pa = 1e308\n",
         expect=["supply_pressure_pa"])
    emit("config/top_level_model=5", "garbage", "model = 5\n", expect=["model"])
    emit("config/model.friction=3", "garbage", "[model]\nfriction = 3\n", expect=["friction"])
    emit("config/unknown_key_typo", "garbage", "[model]\nmasss_kg = 10.0\n", expect=["masss_kg"])
    emit("config/unknown_section", "garbage", "[modle]\nmass_kg = 10.0\n", expect=["modle"])
    emit("config/unknown_top_level_key", "garbage", "verbose = true\n", expect=["verbose"])
    emit("config/duplicate_key", "garbage", "[model]\nmass_kg = 10.0\nmass_kg = 12.0\n", expect=["mass_kg"])
    emit("config/duplicate_section", "garbage", "[model]\nmass_kg = 10.0\n[model]\nx_max_m = 0.6\n",
         expect=["model"])
    emit("config/only_classifier_section", "benign", "[classifier]\nthreshold_sigma = 5.0\n")
    emit("config/only_one_model_field", "benign", "[model]\nmass_kg = 12.0\n")
    emit("config/default_full", "benign", default_text)
    emit("config/default_full_crlf", "benign", default_text.replace("\n", "\r\n"))
    emit("config/default_full_bom", "benign", b"\xef\xbb\xbf" + default_text.encode())
    emit("config/empty_file", "benign", "")
    emit("config/comments_only", "benign", "# nothing here\n")
    emit("config/not_toml_text", "garbage", "hello world, this is not a config\n")
    emit("config/not_toml_json", "garbage", '{"model": {"mass_kg": 10}}\n')
    emit("config/not_toml_yaml", "garbage", "model:\n  mass_kg: 10\n")
    emit("config/binary_garbage", "garbage", bytes(random.Random(7).getrandbits(8) for _ in range(2048)))
    emit("config/truncated_default", "garbage", default_text[: len(default_text) // 2] + "[estim")
    return out


# --------------------------------------------------------------------------


def names_problem(msg, expect):
    """Rough judgement: does a rejection message point at the problem?"""
    if not msg:
        return False
    if expect:
        return any(e.lower() in msg.lower() for e in expect) or bool(re.search(r"line \d+", msg))
    return len(msg) > 20


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default="target/release/leakwatch")
    ap.add_argument("--out", default="mutation_probe.json", help="JSON report")
    ap.add_argument("--md", help="markdown summary (default: --out with .md)")
    ap.add_argument("--timeout", type=float, default=10.0, help="seconds before a command counts as a hang")
    ap.add_argument("--mem-limit-mb", type=int, default=8192,
                    help="RLIMIT_AS for every command except `run` (0: none)")
    ap.add_argument("--seed", type=int, default=13)
    ap.add_argument("--base-log", help="an existing run.mcap to mutate (default: record one with `run`)")
    ap.add_argument("--with-run", action="store_true",
                    help="also run `run --seconds 2 --config` on a few configs (4 processes each)")
    ap.add_argument("--only", help="regex on mutation names")
    ap.add_argument("--keep", help="directory to save every mutated input to")
    args = ap.parse_args()

    binary = os.path.abspath(args.bin)
    t_start = time.monotonic()
    work = tempfile.mkdtemp(prefix="lw-mutation-probe-")
    rng = random.Random(args.seed)
    rig = "probe%d" % os.getpid()
    only = re.compile(args.only) if args.only else None
    print("work dir %s" % work, file=sys.stderr)

    def fresh(name):
        p = os.path.join(work, name)
        if os.path.lexists(p):
            if os.path.isdir(p) and not os.path.islink(p):
                shutil.rmtree(p)
            else:
                os.unlink(p)
        return p

    # base inputs
    r = run_cmd([binary, "simulate", "--scenario", "loaded-sine", "--seconds", "3",
                 "--fault", "ext1:0.5lpm@1s", "--out", "base.csv"], work, 30, 0)
    if r["rc"] != 0:
        sys.exit("simulate failed: %s" % r["stderr"])
    base_csv = open(os.path.join(work, "base.csv")).read()
    # long enough for the classifier to arm (8 s after convergence): used by the config replays
    r = run_cmd([binary, "simulate", "--scenario", "loaded-sine", "--seconds", "15",
                 "--fault", "ext1:0.5lpm@11s", "--out", "base_long.csv"], work, 30, 0)
    if r["rc"] != 0:
        sys.exit("simulate failed: %s" % r["stderr"])
    base_long_csv = open(os.path.join(work, "base_long.csv")).read()
    r = run_cmd([binary, "config", "--print-default"], work, 30, 0)
    default_toml = r["stdout"]
    if args.base_log:
        base_log = open(args.base_log, "rb").read()
    else:
        r = run_cmd([binary, "run", "--seconds", "4", "--fault", "ext1:0.5lpm@1s", "--rig", rig,
                     "--out", "baserun"], work, 120, 0)
        logs = [f for f in os.listdir(os.path.join(work, "baserun")) if f.endswith(".mcap")] \
            if os.path.isdir(os.path.join(work, "baserun")) else []
        if r["rc"] != 0 or not logs:
            sys.exit("run failed: rc %s %s" % (r["rc"], r["stderr"][-2000:]))
        base_log = open(os.path.join(work, "baserun", logs[0]), "rb").read()

    # every mutated input is written to disk at once (kept small in memory)
    store = args.keep or os.path.join(work, "inputs")
    os.makedirs(store, exist_ok=True)
    open(os.path.join(store, "base.csv"), "w").write(base_csv)
    open(os.path.join(store, "base_long.csv"), "w").write(base_long_csv)
    open(os.path.join(store, "base.mcap"), "wb").write(base_log)
    EXT = {"csv": ".csv", "mcap": ".mcap", "config": ".toml"}

    def make_sink(kind):
        def sink(m):
            data = m.pop("data")
            m["kind"] = kind
            if only and not only.search(m["name"]):
                return None
            m["path"] = os.path.join(store, m["name"].replace("/", "__") + EXT[kind])
            with open(m["path"], "wb") as f:
                f.write(data)
            return m
        return sink

    mutations = csv_mutations(base_csv, rng, make_sink("csv"))
    mutations += mcap_mutations(base_log, rng, make_sink("mcap"))
    mutations += config_mutations(default_toml, make_sink("config"))
    mutations = [m for m in mutations if m is not None]
    del base_log

    # commands per kind: (label, argv builder, output checks)
    def cmds_for(kind, inp):
        if kind == "csv":
            return [("replay", [binary, "replay", inp, "--out", "out"])]
        if kind == "mcap":
            return [("replay", [binary, "replay", inp, "--out", "out"]),
                    ("export", [binary, "export", inp, "--csv", "out"]),
                    ("repair", [binary, "repair", inp, "--out", "out.mcap"])]
        c = [("check", [binary, "config", "--check", inp]),
             ("simulate", [binary, "simulate", "--scenario", "loaded-sine", "--seconds", "3",
                           "--config", inp, "--out", "out.csv"]),
             ("replay", [binary, "replay", "base_long.csv", "--config", inp, "--out", "out"])]
        return c

    def outputs_of(kind, cmd):
        """(files to hash, files to scan for non-finite values, state columns only?)"""
        if cmd == "replay":
            files = ["out/estimates.csv", "out/events.json"]
            if kind == "mcap":
                files.append("out/log-export/dataset.csv")
            return files, ["out/estimates.csv"] + (["out/log-export/dataset.csv"] if kind == "mcap" else [])
        if cmd == "export":
            fs = ["out/dataset.csv", "out/frames.csv", "out/estimates.csv", "out/events.csv",
                  "out/health.csv", "out/stats.csv", "out/gaps.csv"]
            return fs, ["out/dataset.csv", "out/frames.csv", "out/estimates.csv"]
        if cmd == "repair":
            return ["out.mcap"], []
        if cmd == "simulate":
            return ["out.csv"], ["out.csv"]
        return [], []

    def execute(kind, inp_name, cmd, argv, timeout=None, mem=None):
        for o in ("out", "out.csv", "out.mcap"):
            fresh(o)
        res = run_cmd(argv, work, timeout or args.timeout,
                      args.mem_limit_mb if mem is None else mem)
        hashed, scan = outputs_of(kind, cmd)
        if cmd == "repair":
            # the repaired file's summary order is not reproducible: compare what it says it wrote
            wrote = [re.sub(r"\(\d+ bytes\)", "", l) for l in res["stderr"].splitlines()
                     if l.startswith("wrote ")]
            res["out_hash"] = hashlib.sha256("\n".join(wrote).encode()).hexdigest()[:16] if wrote else None
        elif cmd == "check":
            res["out_hash"] = hashlib.sha256(res["stdout"].encode()).hexdigest()[:16]
        else:
            res["out_hash"] = hash_files([os.path.join(work, f) for f in hashed]) if hashed else None
        nonfinite = {}
        for f in scan:
            p = os.path.join(work, f)
            if os.path.exists(p):
                cols = nonfinite_in_csv(p)
                if cols:
                    nonfinite[f] = cols
        res["nonfinite"] = nonfinite
        state_nf = {}
        if "out/estimates.csv" in scan and os.path.exists(os.path.join(work, "out/estimates.csv")):
            cols = nonfinite_in_csv(os.path.join(work, "out/estimates.csv"), only_state_columns=True)
            if cols:
                state_nf["out/estimates.csv"] = cols
        res["nonfinite_state"] = state_nf
        res["summary"] = summary_flags(os.path.join(work, "out", "summary.json")) if cmd == "replay" else []
        res["sensor_events"] = sensor_events(os.path.join(work, "out", "events.json")) if cmd == "replay" else []
        res["control_chars"] = bool(CONTROL_RE.search(res["stderr"]))
        return res

    # baselines: every command on the unmutated input
    baseline = {}
    base_inputs = {"csv": ("input.csv", os.path.join(store, "base.csv")),
                   "mcap": ("input.mcap", os.path.join(store, "base.mcap")), "config": ("input.toml", None)}
    for kind, (name, src) in base_inputs.items():
        if src:
            shutil.copyfile(src, fresh(name))
        else:
            open(fresh(name), "w").close()
        for cmd, argv in cmds_for(kind, name):
            res = execute(kind, name, cmd, argv)
            subs = [(os.path.join(work, ""), "<W>/"), (name, "<IN>")]
            lines = {normalize(l, subs) for l in res["stderr"].splitlines() if l.strip()}
            baseline[(kind, cmd)] = {"lines": lines, "hash": res["out_hash"], "rc": res["rc"],
                                     "sensor_events": set(res["sensor_events"]),
                                     "stderr": res["stderr"][-1500:]}
            if res["rc"] != 0:
                print("WARNING: baseline %s %s exit %s: %s" % (kind, cmd, res["rc"], res["stderr"][-500:]),
                      file=sys.stderr)

    results = []
    for i, m in enumerate(mutations):
        ext = {"csv": ".csv", "mcap": ".mcap", "config": ".toml"}[m["kind"]]
        name = "input" + ext
        shutil.copyfile(m["path"], fresh(name))
        if not args.keep:
            os.unlink(m["path"])
        for cmd, argv in cmds_for(m["kind"], name):
            res = execute(m["kind"], name, cmd, argv)
            b = baseline[(m["kind"], cmd)]
            subs = [(os.path.join(work, ""), "<W>/"), (name, "<IN>")]
            flags = res["summary"] + ["event %s" % e for e in res["sensor_events"]
                                      if e not in b["sensor_events"]]
            cls, msg, new = classify(res, b["lines"], subs, flags)
            identical = res["out_hash"] is not None and res["out_hash"] == b["hash"]
            failure = None
            if cls in ("PANIC", "HANG", "ABORT"):
                failure = cls
            elif cls == "SILENT" and m["label"] == "garbage":
                if m["kind"] == "mcap" and identical:
                    failure = None  # damage to redundant records; data read unchanged
                else:
                    failure = "SILENT-garbage"
            if failure is None and res["rc"] == 0:
                if res["nonfinite_state"] or (res["nonfinite"] and not m["nonfinite_input"]):
                    failure = "NAN-OUTPUT" + ("" if cls == "SILENT" else " (%s)" % cls)
            rec = {
                "kind": m["kind"], "mutation": m["name"], "label": m["label"], "command": cmd,
                "argv": [("<bin>" if a == binary else a) for a in argv],
                "class": cls, "failure": failure, "message": msg,
                "names_problem": names_problem(msg, m["expect"]) if cls == "REJECTED" else None,
                "new_stderr": new[:5], "summary_flags": res["summary"], "rc": res["rc"],
                "signal": res["signal"], "wall_s": res["wall_s"], "peak_rss_mb": res["peak_rss_mb"],
                "output_identical_to_base": identical, "nonfinite_output": res["nonfinite"],
                "control_chars_in_stderr": res["control_chars"],
                "nonfinite_state_output": res["nonfinite_state"], "orphans": res["orphans"],
                "note": m.get("note", ""),
                "repro": "python3 tools/mutation_probe.py --only '^%s$' --keep DIR; cd DIR && %s" % (
                    re.escape(m["name"]), " ".join(
                        [os.path.basename(m["path"]) if a == name else
                         ("BASE_LONG.csv" if a == "base_long.csv" else ("LEAKWATCH" if a == binary else a))
                         for a in argv])),
            }
            results.append(rec)
            print("%4d/%d %-7s %-55s %-8s %-9s %5.2fs %s" % (
                i + 1, len(mutations), m["kind"], m["name"][:55], cmd, cls, res["wall_s"],
                ("FAIL " + failure) if failure else ""), file=sys.stderr)

    # optional: `run` with a few configs (each a live pipeline of 4 processes)
    if args.with_run:
        run_cfgs = [("config/default_empty", "benign", ""),
                    ("config/estimator.mae_window_samples=1000000000000", "garbage",
                     "[estimator]\nmae_window_samples = 1000000000000\n"),
                    ("config/model.supply_pressure_pa=1e308", "garbage", "[model]\nsupply_pressure_pa = 1e308\n"),
                    ("config/sim.substeps_per_sample=4000000000", "garbage",
                     "[sim]\nsubsteps_per_sample = 4000000000\n"),
                    ("config/sensors.adc_bits=0", "garbage", "[sensors]\nadc_bits = 0\n"),
                    ("config/sim.sample_period_s=1e-300", "garbage", "[sim]\nsample_period_s = 1e-300\n")]
        run_base = None
        for name, label, text in run_cfgs:
            if only and not only.search(name):
                continue
            with open(fresh("input.toml"), "w") as f:
                f.write(text)
            fresh("out")
            argv = [binary, "run", "--seconds", "2", "--rig", rig, "--config", "input.toml", "--out", "out"]
            res = run_cmd(argv, work, args.timeout, 0)
            subs = [(os.path.join(work, ""), "<W>/"), ("input.toml", "<IN>")]
            lines = {normalize(l, subs) for l in res["stderr"].splitlines() if l.strip()}
            if run_base is None:
                run_base = lines
            cls, msg, new = classify(res, run_base, subs, [])
            failure = cls if cls in ("PANIC", "HANG", "ABORT") else None
            if cls == "SILENT" and label == "garbage":
                failure = "SILENT-garbage"
            if res["orphans"]:
                failure = (failure + "+" if failure else "") + "ORPHANS"
            results.append({"kind": "config", "mutation": name, "label": label, "command": "run",
                            "argv": [("<bin>" if a == binary else a) for a in argv], "class": cls,
                            "failure": failure, "message": msg, "names_problem":
                            names_problem(msg, [name.split("=")[0].split(".")[-1]]) if cls == "REJECTED" else None,
                            "new_stderr": new[:5], "summary_flags": [], "rc": res["rc"],
                            "signal": res["signal"], "wall_s": res["wall_s"], "peak_rss_mb": res["peak_rss_mb"],
                            "output_identical_to_base": None, "nonfinite_output": {},
                            "nonfinite_state_output": {}, "orphans": res["orphans"], "note": "",
                            "stderr_tail": res["stderr"][-800:]})
            print("run    %-55s %-9s %5.2fs %s" % (name, cls, res["wall_s"], failure or ""), file=sys.stderr)

    wall = time.monotonic() - t_start

    # tables
    table = {}
    for r in results:
        key = "%s/%s" % (r["kind"], r["command"])
        table.setdefault(key, {c: 0 for c in CLASSES})[r["class"]] += 1
    inputs = {}
    for m in mutations:
        inputs[m["kind"]] = inputs.get(m["kind"], 0) + 1
    failures = [r for r in results if r["failure"]]
    unnamed = [r for r in results if r["class"] == "REJECTED" and r["names_problem"] is False]
    control = [r for r in results if r.get("control_chars_in_stderr")]
    harmless = [r for r in results if r["class"] == "SILENT" and r["label"] == "garbage" and not r["failure"]]
    benign_rejected = [r for r in results if r["class"] == "REJECTED" and r["label"] == "benign"]
    report = {
        "binary": binary, "seed": args.seed, "timeout_s": args.timeout, "wall_s": round(wall, 1),
        "inputs": inputs, "table": table, "failures": failures,
        "rejected_without_naming_the_problem": unnamed, "benign_rejected": benign_rejected,
        "raw_control_characters_on_stderr": [(r["mutation"], r["command"]) for r in control],
        "silent_garbage_with_output_identical_to_base": [(r["mutation"], r["command"]) for r in harmless],
        "baseline": {"%s/%s" % k: {"rc": v["rc"], "stderr": v["stderr"]} for k, v in baseline.items()},
        "results": results,
    }
    with open(args.out, "w") as f:
        json.dump(report, f, indent=1)

    md = ["# leakwatch mutation probe", "",
          "inputs: %s; wall time %.1f s; timeout %.0f s" % (
              ", ".join("%d %s" % (v, k) for k, v in inputs.items()), wall, args.timeout), "",
          "| input / command | " + " | ".join(CLASSES) + " | failures |",
          "|---|" + "---|" * (len(CLASSES) + 1)]
    for key in sorted(table):
        nf = sum(1 for r in failures if "%s/%s" % (r["kind"], r["command"]) == key)
        md.append("| %s | " % key + " | ".join(str(table[key][c]) for c in CLASSES) + " | %d |" % nf)
    tot = {c: sum(t[c] for t in table.values()) for c in CLASSES}
    md.append("| **total** | " + " | ".join(str(tot[c]) for c in CLASSES) + " | %d |" % len(failures))
    md += ["", "## Failures", ""]
    for r in failures:
        md.append("- **%s** `%s` `%s` (%s): %s%s" % (
            r["failure"], r["mutation"], " ".join(r["argv"]), r["label"], r["message"][:300] or "(nothing said)",
            (" — non-finite output: %s" % json.dumps(r["nonfinite_state_output"] or r["nonfinite_output"]))
            if (r["nonfinite_output"] or r["nonfinite_state_output"]) else ""))
        if r.get("repro"):
            md.append("  - repro: `%s`" % r["repro"])
    md += ["", "## Benign inputs rejected", ""]
    for r in benign_rejected:
        md.append("- `%s` %s: %s" % (r["mutation"], r["command"], r["message"][:300]))
    md += ["", "## Rejections that may not name the problem (heuristic)", ""]
    for r in unnamed:
        md.append("- `%s` %s: %s" % (r["mutation"], r["command"], r["message"][:300]))
    md += ["", "## Damaged MCAP read silently with outputs identical to the undamaged log's (not failures)", ""]
    md.append(", ".join(sorted({"`%s`" % r["mutation"] for r in harmless})) or "none")
    md += ["", "## Raw control characters from the input echoed on stderr", ""]
    md.append(", ".join(sorted({"`%s` (%s)" % (r["mutation"], r["command"]) for r in control})) or "none")
    md_path = args.md or os.path.splitext(args.out)[0] + ".md"
    with open(md_path, "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md[:len(table) + 6]), file=sys.stderr)
    print("wrote %s and %s (work dir %s, wall %.1f s)" % (args.out, md_path, work, wall), file=sys.stderr)
    shutil.rmtree(work, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
