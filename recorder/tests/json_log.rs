//! Logs written before the CDR encoding (JSON messages with JSON Schemas) still
//! read: `tests/fixtures/json_v1.mcap` was written by the JSON writer.

use std::path::Path;

use frames::{detector_bytes, EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};
use recorder::{Entry, GapRecord, LogReader, LogWriter, WriterOptions};

const FIXTURE: &str = "tests/fixtures/json_v1.mcap";

/// Frames of the fixture (each field set, NaN and the infinities included).
fn sensor(i: u64) -> SensorFrame {
    SensorFrame {
        seq: i,
        acq_mono_ns: 5_000_000_000 + i * 1_000_000,
        t_s: i as f64 * 1e-3,
        u_v: (i as f64 * 0.37).sin() * 10.0,
        x_m: 0.1 + 1e-17 * i as f64,
        p1_pa: 6.9e6 + std::f64::consts::PI * i as f64,
        p2_pa: 5e-324,
        x_sp_m: f64::NAN,
        f_load_n: if i & 1 == 0 {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        },
        ref_m: -0.0,
        q_leak_lpm: 0.1 + 0.2,
        flags: (i % 4) as u32,
        _pad: 0,
        temp_c: f64::NAN, // the fixture is of the version before temp_c
    }
}

fn estimate(i: u64) -> EstimateFrame {
    let mut e = EstimateFrame {
        seq: i,
        acq_mono_ns: 5_000_000_000 + i * 1_000_000,
        est_recv_mono_ns: 5_000_000_100 + i * 1_000_000,
        est_done_mono_ns: 5_000_000_200 + i * 1_000_000,
        t_s: i as f64 * 1e-3,
        n_states: 11,
        flags: 16,
        u_v: 1.5,
        nis: 2.0f64.sqrt(),
        th_flags: 1,
        th_nis: 3.5,
        ..EstimateFrame::default()
    };
    for k in 0..11 {
        e.state[k] = (k as f64 + i as f64 * 1e-3).exp();
        e.state_sigma[k] = 1.0 / (k as f64 + 1.0);
    }
    for k in 0..7 {
        e.th_state[k] = k as f64 * 0.5 - i as f64;
    }
    e.residual = [1e-300, -1e300, 0.5];
    e.innovation = [f64::MIN_POSITIVE, f64::MAX, f64::EPSILON];
    e.innovation_sigma = [1.0, 2.0, 3.0];
    e.measured = [0.25, 6.9e6, 4e6];
    e.mae_pa = [12.5, 13.75];
    e.th_residual = [-1.0, -2.0, -3.0];
    e.th_innovation = [4.0, 5.0, 6.0];
    e.th_mae_pa = [7.0, 8.0];
    e
}

fn event() -> LeakEventFrame {
    LeakEventFrame {
        seq: 70,
        acq_mono_ns: 5_070_000_000,
        cls_done_mono_ns: 5_070_000_900,
        event_id: 3,
        kind: frames::event_kind::EXT1,
        phase: frames::event_phase::RAISED,
        t_detect_s: 0.07,
        t_onset_s: 0.05,
        size_lpm: 0.25,
        size_lpm_sigma: 0.03,
        confidence: 0.999,
        detector: detector_bytes("leak-size"),
        size_nominal_lpm: 0.3,
        coefficient_m3_s_sqrt_pa: 1.9e-9,
        statistic: 7.5,
        threshold: 4.9,
        channel: frames::text_bytes(""),
        detail: frames::text_bytes("0.25 L/min at the measured pressures, k = 1.9e-9 m³/(s·√Pa)"),
    }
}

fn health(i: u64) -> HealthFrame {
    HealthFrame {
        seq: i,
        mono_ns: 5_000_000_000 + i * 100_000_000,
        t_s: i as f64 * 0.1,
        status: frames::health_status::LEAK,
        active_events: 1,
        leak_flow_lpm: [0.25, f64::NAN, -0.0],
        leak_flow_sigma_lpm: [0.01, 0.02, 0.03],
        // the fixture's version had no thresholds: read as absent
        leak_threshold_lpm: [f64::NAN; 3],
    }
}

fn stats() -> StatsFrame {
    StatsFrame {
        mono_ns: 5_100_000_000,
        pid: 42,
        stage: frames::stage::ESTIMATOR,
        frames_in: 100,
        frames_out: 99,
        seq_gaps: 1,
        deadline_misses: 0,
        proc_ns_p50: 6_000,
        proc_ns_p99: 9_000,
        proc_ns_max: 20_000,
        lat_ns_p50: 30_000,
        lat_ns_p99: 90_000,
        lat_ns_max: 200_000,
        cpu_fraction: 0.031,
        rss_bytes: 11 << 20,
    }
}

fn gap() -> GapRecord {
    GapRecord {
        topic: Topic::Frames,
        expected_seq: 40,
        got_seq: 42,
        missing: 2,
        recv_mono_ns: 5_042_000_500,
    }
}

/// The fixture's entries: 100 frames and estimates (frames 40 and 41 missing,
/// with a gap record), 2 health frames, an event and a stats frame.
fn entries() -> Vec<Entry> {
    let mut out = Vec::new();
    for i in (0..100).filter(|i| !(40..42).contains(i)) {
        if i == 42 {
            out.push(Entry::Gap(gap()));
        }
        out.push(Entry::Frame(sensor(i), 5_000_000_300 + i * 1_000_000));
        out.push(Entry::Estimate(estimate(i), 5_000_000_400 + i * 1_000_000));
        if i == 0 || i == 50 {
            out.push(Entry::Health(health(i / 50), 5_000_000_500 + i * 1_000_000));
        }
        if i == 70 {
            out.push(Entry::Event(event(), 5_070_001_000));
        }
    }
    out.push(Entry::Stats(stats(), 5_100_000_100));
    out
}

/// Writes the fixture again (`cargo test -p recorder --test json_log -- --ignored`)
/// with the JSON writer. (The committed file was written by the version before
/// the CDR encoding, whose only writer that was; keep it unless the entries change.)
#[test]
#[ignore]
fn write_fixture() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(FIXTURE);
    let _ = std::fs::remove_file(&p);
    let options = WriterOptions {
        encoding: recorder::Encoding::Json,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(&p, options).unwrap();
    for e in entries() {
        assert!(w.write(e).unwrap());
    }
    w.finish().unwrap();
}

fn bits<T: Copy>(v: &T) -> Vec<u8> {
    // SAFETY: the frames are repr(C) with explicit padding only: every byte is initialised
    unsafe { std::slice::from_raw_parts(v as *const T as *const u8, std::mem::size_of::<T>()).to_vec() }
}

fn fixture() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(FIXTURE)
}

/// Every record of `log` against the fixture's entries, bit for bit.
fn check_entries(log: &recorder::Log, what: &str) {
    let (mut f, mut e, mut h, mut ev, mut s, mut g) = (0, 0, 0, 0, 0, 0);
    for entry in entries() {
        match entry {
            Entry::Frame(x, _) => {
                assert_eq!(bits(&x), bits(&log.frames[f]), "{what}: frame {f}");
                f += 1;
            }
            Entry::Estimate(x, _) => {
                assert_eq!(bits(&x), bits(&log.estimates[e]), "{what}: estimate {e}");
                e += 1;
            }
            Entry::Health(x, _) => {
                assert_eq!(bits(&x), bits(&log.health[h]), "{what}: health {h}");
                h += 1;
            }
            Entry::Event(x, _) => {
                assert_eq!(bits(&x), bits(&log.events[ev]), "{what}: event {ev}");
                ev += 1;
            }
            Entry::Stats(x, _) => {
                assert_eq!(bits(&x), bits(&log.stats[s]), "{what}: stats {s}");
                s += 1;
            }
            Entry::Gap(x) => {
                assert_eq!(x, log.gaps[g], "{what}: gap {g}");
                g += 1;
            }
        }
    }
    let counts = (
        log.frames.len(),
        log.estimates.len(),
        log.health.len(),
        log.events.len(),
        log.stats.len(),
        log.gaps.len(),
    );
    assert_eq!((f, e, h, ev, s, g), counts, "{what}");
}

#[test]
fn the_json_log_of_the_version_before_reads_bit_for_bit() {
    let log = LogReader::open(&fixture()).unwrap().read().unwrap();
    assert!(log.truncated.is_none() && log.chunks_skipped.is_empty());
    for (topic, c) in &log.channels {
        assert_eq!(c.message_encoding, "json", "{topic}");
        assert_eq!(c.schema_encoding, "jsonschema", "{topic}");
    }
    check_entries(&log, "fixture");
}

#[test]
fn a_json_log_exports_repairs_and_summarises() {
    let d = scratch::ScratchDir::new("recorder-json");
    let log = LogReader::open(&fixture()).unwrap().read().unwrap();
    // CSV export, the dataset file included
    let files = recorder::export_csv(&log, &d.join("csv"), false).unwrap();
    assert_eq!(files.len(), 7);
    let dataset = std::fs::read_to_string(d.join("csv/dataset.csv")).unwrap();
    assert_eq!(dataset.lines().count(), 1 + 98);
    // repair copies the JSON channels as they are: the copy reads the same
    let fixed = d.join("fixed.mcap");
    let r = recorder::repair(&fixture(), &fixed, false).unwrap();
    assert_eq!(r.messages["frames"], 98);
    let back = LogReader::open(&fixed).unwrap().read().unwrap();
    assert_eq!(back.channels["frames"].message_encoding, "json");
    check_entries(&back, "repaired");
    // info: the counts, the gap, the event; no config in a log of that version
    let bytes = std::fs::metadata(fixture()).unwrap().len();
    let info = recorder::Info::from_log(&fixture(), bytes, &log);
    let text = info.render();
    assert!(text.contains("frames            98 msgs"), "{text}");
    assert!(
        text.contains("json leakwatch.SensorFrame.v1 (jsonschema)"),
        "{text}"
    );
    assert!(text.contains("Gaps:        frames 1 (2 missing)"), "{text}");
    assert!(text.contains("Frame seq:   1 jumps, 2 frames missing"), "{text}");
    assert!(
        text.contains("ext1") && text.contains("size 0.250 ± 0.030 L/min"),
        "{text}"
    );
    assert!(text.contains("Config:      not stored in the log"), "{text}");
}

/// The JSON writer (kept for such logs) still writes what the fixture holds.
#[test]
fn the_json_writer_writes_what_the_fixture_holds() {
    let d = scratch::ScratchDir::new("recorder-json-writer");
    let p = d.join("log.mcap");
    let options = WriterOptions {
        encoding: recorder::Encoding::Json,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(&p, options).unwrap();
    for e in entries() {
        assert!(w.write(e).unwrap());
    }
    w.finish().unwrap();
    let log = LogReader::open(&p).unwrap().read().unwrap();
    assert_eq!(log.channels["estimates"].message_encoding, "json");
    check_entries(&log, "json writer");
    std::fs::remove_file(&p).ok();
}
