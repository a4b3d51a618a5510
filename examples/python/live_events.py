#!/usr/bin/env python3
"""Print leakwatch's live leak events and a once-a-second estimate summary.

Subscribes, with the official iceoryx2 Python bindings (pip install
iceoryx2==0.10.0), to the services of a running pipeline:

    LEAKWATCH_IOX_PREFIX=lab1 leakwatch run --rig rig1 --out run/ &
    python3 examples/python/live_events.py --rig rig1 --prefix lab1 --seconds 40

The frame layouts mirror frames/src/lib.rs (see frames/README.md); the type
names carry a layout version, which iceoryx2 checks with size and alignment.
"""
import argparse
import ctypes
import os
import stat
import sys
import time

import iceoryx2 as iox2


class LeakEventFrame(ctypes.Structure):
    _fields_ = [
        ("seq", ctypes.c_uint64),
        ("acq_mono_ns", ctypes.c_uint64),
        ("cls_done_mono_ns", ctypes.c_uint64),
        ("event_id", ctypes.c_uint64),
        ("kind", ctypes.c_uint32),
        ("phase", ctypes.c_uint32),
        ("t_detect_s", ctypes.c_double),
        ("t_onset_s", ctypes.c_double),
        ("size_lpm", ctypes.c_double),
        ("size_lpm_sigma", ctypes.c_double),
        ("confidence", ctypes.c_double),
        ("detector", ctypes.c_uint8 * 16),
        ("size_nominal_lpm", ctypes.c_double),
        ("coefficient_m3_s_sqrt_pa", ctypes.c_double),
        ("statistic", ctypes.c_double),
        ("threshold", ctypes.c_double),
        ("channel", ctypes.c_uint8 * 8),
        ("detail", ctypes.c_uint8 * 384),
    ]

    @staticmethod
    def type_name() -> str:
        return "leakwatch.LeakEventFrame.v3"


class EstimateFrame(ctypes.Structure):
    _fields_ = [
        ("seq", ctypes.c_uint64),
        ("acq_mono_ns", ctypes.c_uint64),
        ("est_recv_mono_ns", ctypes.c_uint64),
        ("est_done_mono_ns", ctypes.c_uint64),
        ("t_s", ctypes.c_double),
        ("n_states", ctypes.c_uint32),
        ("flags", ctypes.c_uint32),
        ("state", ctypes.c_double * 11),
        ("state_sigma", ctypes.c_double * 11),
        ("residual", ctypes.c_double * 3),
        ("innovation", ctypes.c_double * 3),
        ("innovation_sigma", ctypes.c_double * 3),
        ("measured", ctypes.c_double * 3),
        ("u_v", ctypes.c_double),
        ("nis", ctypes.c_double),
        ("mae_pa", ctypes.c_double * 2),
        ("th_flags", ctypes.c_uint32),
        ("_pad", ctypes.c_uint32),
        ("th_state", ctypes.c_double * 7),
        ("th_residual", ctypes.c_double * 3),
        ("th_innovation", ctypes.c_double * 3),
        ("th_mae_pa", ctypes.c_double * 2),
        ("th_nis", ctypes.c_double),
        ("bulk_scale", ctypes.c_double),
        ("bulk_scale_sigma", ctypes.c_double),
        ("oil_temp_c", ctypes.c_double),
        ("oil_temp_sigma_k", ctypes.c_double),
        ("laminar_factor_sigma", ctypes.c_double),
        ("null_leakage_band_lpm", ctypes.c_double),
        ("offset_response_p1_lpm_per_mpa", ctypes.c_double * 3),
        ("offset_response_p2_lpm_per_mpa", ctypes.c_double * 3),
        ("span_response_p1_lpm", ctypes.c_double * 3),
        ("span_response_p2_lpm", ctypes.c_double * 3),
        ("offset_response_x_lpm_per_mm", ctypes.c_double * 3),
        ("delay_response_p1_lpm_per_ms", ctypes.c_double * 3),
        ("delay_response_p2_lpm_per_ms", ctypes.c_double * 3),
    ]

    @staticmethod
    def type_name() -> str:
        return "leakwatch.EstimateFrame.v6"


KINDS = {1: "ext1", 2: "ext2", 3: "int", 10: "estimator-reset", 11: "sensor-stuck",
         12: "sensor-saturated", 13: "sensor-dead", 14: "not-armed",
         15: "sensor-offset", 16: "sensor-spikes"}
PHASES = {0: "raised", 1: "updated", 2: "cleared"}


def subscribe(node, rig, topic, frame_type, deadline):
    name = iox2.ServiceName.new(f"leakwatch/{rig}/{topic}")
    while True:
        try:
            service = node.service_builder(name).publish_subscribe(frame_type).open()
            return service.subscriber_builder().create()
        except Exception as e:  # the pipeline may not be up yet
            if time.monotonic() > deadline:
                raise SystemExit(f"cannot open leakwatch/{rig}/{topic}: {e}")
            time.sleep(0.05)


def private_dir():
    """leakwatch's private directory of this user (bus::private_dir_path): where
    a run's iceoryx2 root is, <private dir>/<prefix>/."""
    d = os.environ.get("LEAKWATCH_RUNTIME_DIR")
    if d:
        return d
    x = os.environ.get("XDG_RUNTIME_DIR")
    if x and os.path.isabs(x):
        try:
            st = os.lstat(x)
            if stat.S_ISDIR(st.st_mode) and st.st_uid == os.geteuid() and st.st_mode & 0o077 == 0:
                return os.path.join(x, "leakwatch")
        except OSError:
            pass
    return f"/tmp/leakwatch-{os.geteuid()}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rig", default="rig1")
    ap.add_argument("--prefix", default=None, help="LEAKWATCH_IOX_PREFIX of the pipeline")
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()

    cfg = iox2.config.default()
    if args.prefix:
        cfg.global_cfg.prefix = iox2.FileName.new(f"lw_{args.prefix}_")
        cfg.global_cfg.root_path = iox2.Path.new(f"{private_dir()}/{args.prefix}/")
    node = iox2.NodeBuilder.new().config(cfg).create(iox2.ServiceType.Ipc)
    end = time.monotonic() + args.seconds
    events = subscribe(node, args.rig, "events", LeakEventFrame, end)
    estimates = subscribe(node, args.rig, "estimates", EstimateFrame, end)
    n_est, next_print = 0, time.monotonic() + 1.0
    last = None
    while time.monotonic() < end:
        got = False
        while True:
            s = events.receive()
            if s is None:
                break
            got = True
            e = s.payload().contents
            det = bytes(e.detector).rstrip(b"\0").decode()
            print(f"EVENT t={e.t_detect_s:.3f} s {det} {PHASES.get(e.phase, e.phase)} "
                  f"{KINDS.get(e.kind, e.kind)} onset={e.t_onset_s:.2f} s "
                  f"size={e.size_lpm:.3f}±{e.size_lpm_sigma:.3f} L/min "
                  f"(at p_s/2 {e.size_nominal_lpm:.3f}) statistic={e.statistic:.1f}/{e.threshold:.1f} "
                  f"confidence={e.confidence:.2f}",
                  flush=True)
        while True:
            s = estimates.receive()
            if s is None:
                break
            got = True
            n_est += 1
            f = s.payload().contents
            last = (f.t_s, f.state[3], f.state[1], f.state[2], f.state[7] * 6e4, f.state[8] * 6e4, f.state[9] * 6e4)
        if time.monotonic() >= next_print and last is not None:
            next_print += 1.0
            print("ESTIMATE t={:.2f} s x={:.4f} m p1={:.2f} MPa p2={:.2f} MPa leaks (L/min) "
                  "ext1={:.3f} ext2={:.3f} int={:.3f} [{} estimates]".format(
                      last[0], last[1], last[2] / 1e6, last[3] / 1e6, *last[4:], n_est), flush=True)
        if not got:
            time.sleep(0.002)
    print(f"done: {n_est} estimates received", flush=True)


if __name__ == "__main__":
    sys.exit(main())
