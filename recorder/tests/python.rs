//! Python's `mcap` reader with `mcap-ros2-support` (what Foxglove's and
//! rosbag2's users have) decodes a log from its stored ros2msg schemas alone,
//! and every field it names has the value the Rust reader gives, bit for bit.
//!
//! Needs python3 with `mcap` and `mcap-ros2-support` (.ci/setup installs them).
//! CI sets LEAKWATCH_REQUIRE_PYTHON=1, so the test must run there; elsewhere it
//! says it was skipped.

use std::path::Path;

use frames::{EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};
use recorder::{Entry, GapRecord, LogWriter, WriterOptions};
use serde_json::{json, Value};

#[path = "python/mcap_reader.rs"]
mod mcap_reader;
#[path = "python/rosbags_reader.rs"]
mod rosbags_reader;

fn f(x: f64) -> Value {
    json!({ "f64": x.to_bits() })
}

fn fs(names: &[&str], v: &[f64]) -> Value {
    assert_eq!(names.len(), v.len());
    Value::Object(names.iter().zip(v).map(|(n, x)| (n.to_string(), f(*x))).collect())
}

const LEAK_STATE: [&str; 11] = [
    "x_sp_m",
    "p1_pa",
    "p2_pa",
    "x_m",
    "v_m_s",
    "v_sp_m_s",
    "f_e_n",
    "q_e1_m3_s",
    "q_e2_m3_s",
    "q_i_m3_s",
    "bias_m",
];

const MEASUREMENT: [&str; 3] = ["x_m", "p1_pa", "p2_pa"];

const PRESSURES: [&str; 2] = ["p1_pa", "p2_pa"];

const LEAK_FLOWS: [&str; 3] = ["ext1", "ext2", "internal"];

/// What Python must decode for each record, by the names of the .msg files.
fn expected_sensor(x: &SensorFrame) -> Value {
    json!({
        "seq": x.seq, "acq_mono_ns": x.acq_mono_ns, "t_s": f(x.t_s), "u_v": f(x.u_v), "x_m": f(x.x_m),
        "p1_pa": f(x.p1_pa), "p2_pa": f(x.p2_pa), "x_sp_m": f(x.x_sp_m), "f_load_n": f(x.f_load_n),
        "ref_m": f(x.ref_m), "q_leak_lpm": f(x.q_leak_lpm), "flags": x.flags, "temp_c": f(x.temp_c),
    })
}

/// Whether the writer (default options) puts frame `x` on the `frames` channel
/// as well as in a batch: every 40th and every flagged one.
fn on_frames_channel(x: &SensorFrame) -> bool {
    x.seq.is_multiple_of(WriterOptions::default().frames_every) || x.flags != 0
}

/// The frames of a decoded `SensorFrameBatch`, each as [`expected_sensor`]
/// names it (the byte-shuffled columns, `uint8[]`, put back together).
fn unbatch(msg: &Value) -> Vec<Value> {
    let first = msg["first_seq"].as_u64().expect("first_seq");
    let unshuffle = |name: &str| -> Vec<u64> {
        let b: Vec<u64> = msg[name]
            .as_array()
            .unwrap_or_else(|| panic!("{name} in {msg}"))
            .iter()
            .map(|x| x.as_u64().expect("a byte"))
            .collect();
        assert_eq!(b.len() % 8, 0, "{name}: 8 bytes a value");
        let n = b.len() / 8;
        (0..n)
            .map(|i| (0..8).fold(0, |v, j| v | b[j * n + i] << (8 * j)))
            .collect()
    };
    let acq = unshuffle("acq_mono_ns_shuffled");
    let t = unshuffle("t_s_shuffled");
    let u = unshuffle("u_v_shuffled");
    let n = acq.len();
    assert_eq!((t.len(), u.len()), (n, n));
    let columns = [
        "x_m",
        "p1_pa",
        "p2_pa",
        "x_sp_m",
        "f_load_n",
        "ref_m",
        "q_leak_lpm",
        "flags",
        "temp_c",
    ];
    (0..n)
        .map(|i| {
            let mut m = serde_json::Map::new();
            m.insert("seq".into(), json!(first + i as u64));
            m.insert("acq_mono_ns".into(), json!(acq[i]));
            m.insert("t_s".into(), json!({ "f64": t[i] }));
            m.insert("u_v".into(), json!({ "f64": u[i] }));
            for c in columns {
                let column = msg[c].as_array().unwrap_or_else(|| panic!("{c} in {msg}"));
                assert_eq!(column.len(), n, "{c}: one element per frame");
                m.insert(c.into(), column[i].clone());
            }
            Value::Object(m)
        })
        .collect()
}

/// Checks one decoded message of `topic` against the next expected ones
/// (`seen` counts them per topic): a batch against as many frames as it holds.
fn check_message(
    topic: &str,
    msg: &Value,
    expected: &std::collections::BTreeMap<&str, Vec<Value>>,
    seen: &mut std::collections::BTreeMap<String, usize>,
) {
    let i = seen.entry(topic.to_string()).or_default();
    if topic == "frame_batches" {
        for frame in unbatch(msg) {
            assert_eq!(&frame, &expected[topic][*i], "batched frame {i}");
            *i += 1;
        }
    } else {
        assert_eq!(msg, &expected[topic][*i], "{topic} message {i}");
        *i += 1;
    }
}

/// Every record of `log` as Python must decode it, per channel name: the
/// batches hold every frame, the frames channel the thinned ones.
fn expected_records(log: &recorder::Log) -> std::collections::BTreeMap<&'static str, Vec<Value>> {
    let mut expected: std::collections::BTreeMap<&str, Vec<Value>> = Default::default();
    expected.insert("frame_batches", log.frames.iter().map(expected_sensor).collect());
    expected.insert(
        "frames",
        log.frames
            .iter()
            .filter(|f| on_frames_channel(f))
            .map(expected_sensor)
            .collect(),
    );
    expected.insert("estimates", log.estimates.iter().map(expected_estimate).collect());
    expected.insert("events", log.events.iter().map(expected_event).collect());
    expected.insert("health", log.health.iter().map(expected_health).collect());
    expected.insert("stats", log.stats.iter().map(expected_stats).collect());
    expected.insert("gaps", log.gaps.iter().map(expected_gap).collect());
    expected
}

fn expected_estimate(x: &EstimateFrame) -> Value {
    json!({
        "seq": x.seq, "acq_mono_ns": x.acq_mono_ns, "est_recv_mono_ns": x.est_recv_mono_ns,
        "est_done_mono_ns": x.est_done_mono_ns, "t_s": f(x.t_s), "n_states": x.n_states, "flags": x.flags,
        "state": fs(&LEAK_STATE, &x.state), "state_sigma": fs(&LEAK_STATE, &x.state_sigma),
        "residual": fs(&MEASUREMENT, &x.residual), "innovation": fs(&MEASUREMENT, &x.innovation),
        "innovation_sigma": fs(&MEASUREMENT, &x.innovation_sigma), "measured": fs(&MEASUREMENT, &x.measured),
        "u_v": f(x.u_v), "nis": f(x.nis), "mae_pa": fs(&PRESSURES, &x.mae_pa), "th_flags": x.th_flags,
        "th_state": fs(&LEAK_STATE[..7], &x.th_state), "th_residual": fs(&MEASUREMENT, &x.th_residual),
        "th_innovation": fs(&MEASUREMENT, &x.th_innovation), "th_mae_pa": fs(&PRESSURES, &x.th_mae_pa),
        "th_nis": f(x.th_nis), "bulk_scale": f(x.bulk_scale), "bulk_scale_sigma": f(x.bulk_scale_sigma),
        "oil_temp_c": f(x.oil_temp_c), "oil_temp_sigma_k": f(x.oil_temp_sigma_k),
        "laminar_factor_sigma": f(x.laminar_factor_sigma), "null_leakage_band_lpm": f(x.null_leakage_band_lpm),
        "offset_response_p1_lpm_per_mpa": fs(&LEAK_FLOWS, &x.offset_response_p1_lpm_per_mpa),
        "offset_response_p2_lpm_per_mpa": fs(&LEAK_FLOWS, &x.offset_response_p2_lpm_per_mpa),
        "span_response_p1_lpm": fs(&LEAK_FLOWS, &x.span_response_p1_lpm),
        "span_response_p2_lpm": fs(&LEAK_FLOWS, &x.span_response_p2_lpm),
        "offset_response_x_lpm_per_mm": fs(&LEAK_FLOWS, &x.offset_response_x_lpm_per_mm),
        "delay_response_p1_lpm_per_ms": fs(&LEAK_FLOWS, &x.delay_response_p1_lpm_per_ms),
        "delay_response_p2_lpm_per_ms": fs(&LEAK_FLOWS, &x.delay_response_p2_lpm_per_ms),
    })
}

fn expected_event(x: &LeakEventFrame) -> Value {
    json!({
        "seq": x.seq, "acq_mono_ns": x.acq_mono_ns, "cls_done_mono_ns": x.cls_done_mono_ns,
        "event_id": x.event_id,
        "kind": frames::code_name(&frames::event_kind::NAMES, x.kind),
        "phase": frames::code_name(&frames::event_phase::NAMES, x.phase),
        "t_detect_s": f(x.t_detect_s), "t_onset_s": f(x.t_onset_s), "size_lpm": f(x.size_lpm),
        "size_lpm_sigma": f(x.size_lpm_sigma), "confidence": f(x.confidence),
        "detector": frames::detector_name(&x.detector), "size_nominal_lpm": f(x.size_nominal_lpm),
        "coefficient_m3_s_sqrt_pa": f(x.coefficient_m3_s_sqrt_pa), "statistic": f(x.statistic),
        "threshold": f(x.threshold), "channel": frames::text(&x.channel), "detail": frames::text(&x.detail),
    })
}

fn expected_health(x: &HealthFrame) -> Value {
    json!({
        "seq": x.seq, "mono_ns": x.mono_ns, "t_s": f(x.t_s),
        "status": frames::code_name(&frames::health_status::NAMES, x.status),
        "active_events": x.active_events, "leak_flow_lpm": fs(&LEAK_FLOWS, &x.leak_flow_lpm),
        "leak_flow_sigma_lpm": fs(&LEAK_FLOWS, &x.leak_flow_sigma_lpm),
        "leak_threshold_lpm": fs(&LEAK_FLOWS, &x.leak_threshold_lpm),
    })
}

fn expected_stats(x: &StatsFrame) -> Value {
    json!({
        "mono_ns": x.mono_ns, "pid": x.pid, "stage": frames::code_name(&frames::stage::NAMES, x.stage),
        "frames_in": x.frames_in, "frames_out": x.frames_out, "seq_gaps": x.seq_gaps,
        "deadline_misses": x.deadline_misses, "proc_ns_p50": x.proc_ns_p50, "proc_ns_p99": x.proc_ns_p99,
        "proc_ns_max": x.proc_ns_max, "lat_ns_p50": x.lat_ns_p50, "lat_ns_p99": x.lat_ns_p99,
        "lat_ns_max": x.lat_ns_max, "cpu_fraction": f(x.cpu_fraction), "rss_bytes": x.rss_bytes,
    })
}

fn expected_gap(x: &GapRecord) -> Value {
    json!({
        "topic": x.topic.as_str(), "expected_seq": x.expected_seq, "got_seq": x.got_seq,
        "missing": x.missing, "recv_mono_ns": x.recv_mono_ns,
    })
}

/// A log with every record type: distinct values in every field, NaN, the
/// infinities, text, a kind this version does not name.
/// The wall clock minus `CLOCK_MONOTONIC` the test log is written with, ns
/// (2025-11-24 16:00:00 UTC at monotonic 0).
const EPOCH_OFFSET_NS: i64 = 1_764_000_000_000_000_000;

fn write_log(path: &Path) {
    let options = WriterOptions {
        rig: "press-3".into(),
        epoch_offset_ns: Some(EPOCH_OFFSET_NS),
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(path, options).unwrap();
    let mut put = |e: Entry| assert!(w.write(e).unwrap());
    for i in 0..50u64 {
        let t = 1_000_000_000 + i * 1_000_000;
        put(Entry::Frame(
            SensorFrame {
                seq: i,
                acq_mono_ns: t,
                t_s: i as f64 * 1e-3,
                u_v: (i as f64).sin(),
                x_m: 0.3 + i as f64 * 1e-6,
                p1_pa: 6.9e6 + i as f64,
                p2_pa: 4.1e6 - i as f64,
                x_sp_m: f64::NAN,
                f_load_n: f64::NEG_INFINITY,
                ref_m: -0.0,
                q_leak_lpm: 5e-324,
                flags: (i % 3) as u32,
                _pad: 0,
                temp_c: 30.0 + i as f64 * 0.1,
            },
            t + 10,
        ));
        let mut e = EstimateFrame {
            seq: i,
            acq_mono_ns: t,
            est_recv_mono_ns: t + 1,
            est_done_mono_ns: t + 2,
            t_s: i as f64 * 1e-3,
            n_states: 11,
            flags: 16,
            u_v: 0.5,
            nis: 1.25,
            th_flags: 1,
            th_nis: 2.5,
            bulk_scale: 0.95,
            oil_temp_c: 41.5,
            laminar_factor_sigma: 0.02,
            offset_response_p1_lpm_per_mpa: [0.1, -0.2, 0.3],
            span_response_p2_lpm: [1.5, -2.5, 0.5],
            offset_response_x_lpm_per_mm: [0.25, -0.5, 0.125],
            delay_response_p2_lpm_per_ms: [0.75, -0.0625, 2.0],
            ..EstimateFrame::default()
        };
        for k in 0..11 {
            e.state[k] = (k * 100) as f64 + i as f64;
            e.state_sigma[k] = 1.0 / (k as f64 + 2.0);
        }
        for k in 0..7 {
            e.th_state[k] = -((k * 100) as f64 + i as f64);
        }
        e.residual = [1.0, 2.0, 3.0];
        e.innovation = [4.0, 5.0, 6.0];
        e.innovation_sigma = [7.0, 8.0, 9.0];
        e.measured = [10.0, 11.0, 12.0];
        e.mae_pa = [13.0, 14.0];
        e.th_residual = [15.0, 16.0, 17.0];
        e.th_innovation = [18.0, 19.0, 20.0];
        e.th_mae_pa = [21.0, 22.0];
        put(Entry::Estimate(e, t + 20));
    }
    for (kind, phase, detector, detail) in [
        (
            frames::event_kind::EXT1,
            frames::event_phase::RAISED,
            "leak-size",
            "0.25 L/min, k = 1.9e-9 m³/(s·√Pa)",
        ),
        (99, frames::event_phase::CLEARED, "sensors", ""),
    ] {
        put(Entry::Event(
            LeakEventFrame {
                seq: 30,
                acq_mono_ns: 1_030_000_000,
                cls_done_mono_ns: 1_030_000_500,
                event_id: 4,
                kind,
                phase,
                t_detect_s: 0.03,
                t_onset_s: f64::NAN,
                size_lpm: 0.25,
                size_lpm_sigma: 0.01,
                confidence: 0.99,
                detector: frames::detector_bytes(detector),
                size_nominal_lpm: 0.3,
                coefficient_m3_s_sqrt_pa: 1.9e-9,
                statistic: 7.5,
                threshold: 4.9,
                channel: frames::text_bytes("p1"),
                detail: frames::text_bytes(detail),
            },
            1_030_001_000,
        ));
    }
    put(Entry::Health(
        HealthFrame {
            seq: 3,
            mono_ns: 1_040_000_000,
            t_s: 0.04,
            status: frames::health_status::SENSOR_FAULT,
            active_events: 2,
            leak_flow_lpm: [0.25, f64::NAN, -0.0],
            leak_flow_sigma_lpm: [0.01, 0.02, 0.03],
            leak_threshold_lpm: [0.05, 0.06, 0.07],
        },
        1_040_000_100,
    ));
    put(Entry::Stats(
        StatsFrame {
            mono_ns: 1_045_000_000,
            pid: 42,
            stage: frames::stage::CLASSIFIER,
            frames_in: 1,
            frames_out: 2,
            seq_gaps: 3,
            deadline_misses: 4,
            proc_ns_p50: 5,
            proc_ns_p99: 6,
            proc_ns_max: 7,
            lat_ns_p50: 8,
            lat_ns_p99: 9,
            lat_ns_max: 10,
            cpu_fraction: 0.031,
            rss_bytes: u64::MAX,
        },
        1_045_000_100,
    ));
    put(Entry::Gap(GapRecord {
        topic: Topic::Health,
        expected_seq: 1,
        got_seq: 3,
        missing: 2,
        recv_mono_ns: 1_040_000_100,
    }));
    w.finish().unwrap();
}
