//! Replaying recorded logs: a damaged chunk, nothing readable, a log in parts, an old JSON log.

use std::path::{Path, PathBuf};

use crate::common::*;

use crate::{json, ran, replay, simulate};

#[test]
fn a_recorded_log_with_a_damaged_chunk_replays_the_rest_and_counts_the_lost_samples() {
    use recorder::{Entry, LogWriter, WriterOptions};
    let d = tmpdir("mcap");
    let log = d.join("run.mcap");
    let options = WriterOptions {
        chunk_size: 16 * 1024,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(&log, options).unwrap();
    for i in 0..4000u64 {
        let t = i as f64 * 1e-3;
        let frame = frames::SensorFrame {
            seq: i,
            acq_mono_ns: i * 1_000_000,
            t_s: t,
            u_v: 0.5 * (t * 6.0).sin(),
            x_m: 0.3,
            p1_pa: 6.9e6,
            p2_pa: 6.9e6,
            x_sp_m: f64::NAN,
            f_load_n: f64::NAN,
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
            flags: 0,
            _pad: 0,
            temp_c: f64::NAN,
        };
        assert!(w.write(Entry::Frame(frame, i)).unwrap());
    }
    w.finish().unwrap();
    // declare a wrong uncompressed size in the 10th chunk (offset of the size field:
    // opcode, record length, start and end time)
    let mut bytes = std::fs::read(&log).unwrap();
    let (mut at, mut seen) = (8usize, 0);
    while bytes[at] != 0x06 || seen < 9 {
        if bytes[at] == 0x06 {
            seen += 1;
        }
        at += 9 + u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
    }
    bytes[at + 25..at + 33].copy_from_slice(&1u64.to_le_bytes());
    let bad = d.join("bad.mcap");
    std::fs::write(&bad, &bytes).unwrap();
    let out = d.join("out");
    // with the thesis filter (--model 7): neither filter is poisoned
    let o = replay(&bad, &out, &["--model", "7"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(ran(&o), "{err}");
    assert!(
        err.contains(&format!(
            "damaged chunk at byte {at}: declares 1 bytes uncompressed, but the data holds more; skipped"
        )),
        "{err}"
    );
    let s = json(&out.join("summary.json"));
    let lost = s["log"]["frames_lost"].as_u64().unwrap();
    assert!(lost >= 50, "{s:#}");
    assert_eq!(s["samples"].as_u64().unwrap() + lost, 4000, "{s:#}");
    assert_eq!(s["samples_missing"].as_u64().unwrap(), lost, "{s:#}");
    assert_eq!(s["log"]["chunks_skipped"].as_array().unwrap().len(), 1, "{s:#}");
}

/// A log with nothing readable (an 8-byte file of MCAP magic, an empty file) is an
/// error naming the log in `export` and `replay` alike, never an empty export.
#[test]
fn a_log_with_nothing_readable_is_an_error_naming_it() {
    let d = tmpdir("empty-log");
    for (name, bytes) in [("magic.mcap", &b"\x89MCAP0\r\n"[..]), ("empty.mcap", &b""[..])] {
        let log = d.join(name);
        std::fs::write(&log, bytes).unwrap();
        let log_s = log.to_str().unwrap();
        let o = leakwatch(&[
            "export",
            log_s,
            "--csv",
            d.join(format!("{name}-csv")).to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(err.contains(log_s), "{name}: {err}");
        let o = replay(&log, &d.join(format!("{name}-out")), &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(log_s) && !err.contains("dataset.csv"),
            "{name}: {err}"
        );
    }
}

/// Writes the samples of `csv` as the sensor frames of a log (CDR, or JSON as
/// logs were before), with a health frame at 10 Hz.
fn log_of(csv: &Path, log: &Path, encoding: recorder::Encoding) {
    log_in_parts(
        csv,
        log,
        encoding,
        recorder::WriterOptions::default().part_span_ns,
    );
}

/// [`log_of`], the file continued in a new part (`run.1.mcap`, ...) after
/// `part_span_ns` of the stream.
fn log_in_parts(csv: &Path, log: &Path, encoding: recorder::Encoding, part_span_ns: u64) {
    let ds = dataset::read_csv(csv, dataset::Limits::default()).unwrap();
    let options = recorder::WriterOptions {
        encoding,
        queue_len: 1 << 16,
        part_span_ns,
        ..recorder::WriterOptions::default()
    };
    let mut w = recorder::LogWriter::create(log, options).unwrap();
    for (i, s) in ds.samples.iter().enumerate() {
        let t = 1_000_000_000 + i as u64 * 1_000_000;
        let frame = frames::SensorFrame {
            seq: i as u64,
            acq_mono_ns: t,
            ..frames::SensorFrame::from(s)
        };
        assert!(w.write(recorder::Entry::Frame(frame, t)).unwrap());
        if i % 100 == 0 {
            let h = frames::HealthFrame {
                seq: i as u64 / 100,
                mono_ns: t,
                t_s: s.t_s,
                ..frames::HealthFrame::default()
            };
            assert!(w.write(recorder::Entry::Health(h, t)).unwrap());
        }
    }
    w.finish().unwrap();
}

/// A log its recorder continued in parts (`run.1.mcap`, ... after each hour
/// of the stream; here after 3 s) replays and exports as the same stream in
/// one file: the same events and estimates, every frame bit for bit.
#[test]
fn a_log_continued_in_parts_replays_and_exports_as_one_file() {
    let d = tmpdir("parts-log");
    let csv = simulate(&d, "loaded-sine", "14", "ext2:0.5lpm@9s");
    let (one, parts) = (d.join("one"), d.join("parts"));
    std::fs::create_dir_all(&one).unwrap();
    std::fs::create_dir_all(&parts).unwrap();
    log_of(&csv, &one.join("run.mcap"), recorder::Encoding::Cdr);
    log_in_parts(
        &csv,
        &parts.join("run.mcap"),
        recorder::Encoding::Cdr,
        3_000_000_000,
    );
    let files: Vec<String> = recorder::with_continuations(&parts.join("run.mcap"))
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        files,
        ["run.mcap", "run.1.mcap", "run.2.mcap", "run.3.mcap", "run.4.mcap"]
    );
    let mut outputs = Vec::new();
    for dir in [&one, &parts] {
        let out = dir.join("replay");
        let o = replay(&dir.join("run.mcap"), &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let csv_dir = dir.join("csv");
        let o = leakwatch(&[
            "export",
            dir.join("run.mcap").to_str().unwrap(),
            "--csv",
            csv_dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let read = |p: PathBuf| std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        outputs.push([
            read(out.join("events.json")),
            read(out.join("estimates.csv")),
            read(csv_dir.join("frames.csv")),
            read(csv_dir.join("dataset.csv")),
        ]);
    }
    for (k, name) in ["events.json", "estimates.csv", "frames.csv", "dataset.csv"]
        .iter()
        .enumerate()
    {
        assert!(
            outputs[0][k] == outputs[1][k],
            "{name}: the parts differ from one file"
        );
    }
    let events = json(&parts.join("replay").join("events.json"));
    assert!(
        events
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "ext2" && e["phase"] == "raised"),
        "{events:#}"
    );
    // 14 s at 1 kHz, each sample once
    assert_eq!(String::from_utf8_lossy(&outputs[1][3]).lines().count(), 14_001);
}

/// A log of the JSON encoding (what earlier versions wrote) replays, exports and
/// plots as the CDR log of the same samples does, and as their CSV does.
#[test]
fn a_json_log_of_an_earlier_version_replays_like_the_cdr_log_and_the_csv() {
    let d = tmpdir("json-log");
    let csv = simulate(&d, "loaded-sine", "14", "ext2:0.5lpm@9s");
    let (cdr, json_log) = (d.join("cdr.mcap"), d.join("json.mcap"));
    log_of(&csv, &cdr, recorder::Encoding::Cdr);
    log_of(&csv, &json_log, recorder::Encoding::Json);
    let read = |p: &Path| recorder::LogReader::open(p).unwrap().read().unwrap();
    assert_eq!(read(&json_log).channels["frames"].message_encoding, "json");
    assert_eq!(read(&cdr).channels["frames"].message_encoding, "cdr");
    let mut estimates = Vec::new();
    for (name, input) in [("csv", &csv), ("cdr", &cdr), ("json", &json_log)] {
        let out = d.join(format!("out-{name}"));
        let o = replay(input, &out, &[]);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let events = json(&out.join("events.json"));
        assert!(
            events
                .as_array()
                .unwrap()
                .iter()
                .any(|e| e["kind"] == "ext2" && e["phase"] == "raised"),
            "{name}: {events:#}"
        );
        estimates.push((name, std::fs::read(out.join("estimates.csv")).unwrap()));
    }
    assert!(estimates[1].1 == estimates[0].1, "cdr log and csv replay alike");
    assert!(estimates[2].1 == estimates[0].1, "json log and csv replay alike");
    // export and plot read the JSON log too
    let o = leakwatch(&[
        "export",
        json_log.to_str().unwrap(),
        "--csv",
        d.join("csv").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = d.join("json.png");
    let o = leakwatch(&["plot", json_log.to_str().unwrap(), "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}
