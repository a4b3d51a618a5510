//! A log whose recorder was killed: read up to its last complete chunk, and
//! repaired into a complete MCAP file with the same messages.

use std::path::Path;
use std::time::{Duration, Instant};

use frames::{HealthFrame, SensorFrame};
use recorder::{repair, Entry, Log, LogReader, LogWriter, WriterOptions};

/// Set in the child process that writes a log until it is killed.
const CHILD_ENV: &str = "RECORDER_TEST_KILLED_WRITER";

/// A fresh folder for one test, removed when the test passes.
fn dir(tag: &str) -> scratch::ScratchDir {
    scratch::ScratchDir::new(&format!("recorder-repair-{tag}"))
}

fn frame(i: u64) -> SensorFrame {
    SensorFrame {
        seq: i,
        acq_mono_ns: 1_000_000 * i,
        t_s: i as f64 * 1e-3,
        u_v: (i as f64 * 0.1).sin(),
        x_m: 0.3,
        p1_pa: 6.9e6 + i as f64,
        p2_pa: 6.8e6,
        x_sp_m: f64::NAN,
        f_load_n: -1.0,
        ref_m: 0.3,
        q_leak_lpm: 0.0,
        flags: 0,
        _pad: 0,
        temp_c: f64::NAN,
    }
}

fn health(i: u64) -> HealthFrame {
    HealthFrame {
        seq: i,
        mono_ns: i,
        t_s: i as f64 * 1e-2,
        status: 1,
        active_events: 0,
        leak_flow_lpm: [0.1, f64::NAN, -0.2],
        leak_flow_sigma_lpm: [0.01, 0.02, 0.03],
        leak_threshold_lpm: [0.05, 0.06, 0.07],
    }
}

fn bits<T: Copy>(v: &T) -> Vec<u8> {
    // SAFETY: the frames are repr(C) with explicit padding only: every byte is initialised
    unsafe { std::slice::from_raw_parts(v as *const T as *const u8, std::mem::size_of::<T>()).to_vec() }
}

/// The messages of a log that repair must keep, bit for bit.
fn same_messages(a: &Log, b: &Log, what: &str) {
    assert_eq!(a.frames.len(), b.frames.len(), "{what}: frames");
    assert_eq!(a.health.len(), b.health.len(), "{what}: health");
    assert_eq!(a.gaps, b.gaps, "{what}: gaps");
    for (x, y) in a.frames.iter().zip(&b.frames) {
        assert_eq!(bits(x), bits(y), "{what}");
    }
    for (x, y) in a.health.iter().zip(&b.health) {
        assert_eq!(bits(x), bits(y), "{what}");
    }
}

/// Repairs `damaged` into `fixed` and checks the result: complete, a summary
/// that counts every message, the same messages as `damaged` reads.
fn repair_and_check(damaged: &Path, fixed: &Path) -> Log {
    let before = LogReader::open(damaged).unwrap().read().unwrap();
    let r = repair(damaged, fixed, false).unwrap();
    assert_eq!(r.truncated, before.truncated);
    let after = LogReader::open(fixed).unwrap().read().unwrap();
    assert!(after.truncated.is_none(), "{:?}", after.truncated);
    assert!(after.chunks_skipped.is_empty());
    same_messages(&before, &after, &damaged.display().to_string());
    // the summary section is there and counts every message
    let bytes = std::fs::read(fixed).unwrap();
    let summary = mcap::read::Summary::read(&bytes).unwrap().expect("a summary");
    let stats = summary.stats.expect("statistics");
    // (every message: the frame batches and the frames channel's every 40th frame too)
    let n: u64 = after.channels.values().map(|c| c.messages).sum();
    assert_eq!(stats.message_count, n);
    assert_eq!(r.messages.values().sum::<u64>(), n);
    // every channel of the recorder is there, with its schema (once the file
    // reached the first chunk, which holds them)
    if after.frames.is_empty() {
        return after;
    }
    let mut topics: Vec<&str> = summary.channels.values().map(|c| c.topic.as_str()).collect();
    topics.sort();
    assert_eq!(
        topics,
        [
            "/leakwatch/rig1/estimates",
            "/leakwatch/rig1/events",
            "/leakwatch/rig1/frame_batches",
            "/leakwatch/rig1/frames",
            "/leakwatch/rig1/gaps",
            "/leakwatch/rig1/health",
            "/leakwatch/rig1/stats"
        ]
    );
    assert!(summary.channels.values().all(|c| c.schema.is_some()));
    // still a rosbag2 file: profile ros2, the QoS on every channel
    assert!(summary
        .channels
        .values()
        .all(|c| c.metadata.get("offered_qos_profiles").map(String::as_str)
            == Some(recorder::OFFERED_QOS_PROFILES)));
    match mcap::read::LinearReader::new(&bytes).unwrap().next() {
        Some(Ok(mcap::records::Record::Header(h))) => assert_eq!(h.profile, "ros2"),
        other => panic!("a header first: {other:?}"),
    }
    after
}

/// Writes frames (and a health frame every 10) until killed, flushing every 20 ms.
fn write_until_killed(path: &Path) -> ! {
    let options = WriterOptions {
        chunk_size: 4096,
        max_chunk_age_ns: 20_000_000,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(path, options).unwrap();
    for i in 0.. {
        w.write(Entry::Frame(frame(i), i)).unwrap();
        if i % 10 == 0 {
            w.write(Entry::Health(health(i / 10), i)).unwrap();
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    unreachable!()
}

/// Not a test of its own: the child process of
/// [`a_killed_recorders_log_reads_and_repairs`], started with `--ignored`.
#[test]
#[ignore = "the child process of a_killed_recorders_log_reads_and_repairs"]
fn child_writer() {
    let path = std::env::var(CHILD_ENV).expect("started by a_killed_recorders_log_reads_and_repairs");
    write_until_killed(Path::new(&path));
}

#[test]
fn a_killed_recorders_log_reads_and_repairs() {
    let d = dir("killed");
    let path = d.join("killed.mcap");
    let mut child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "child_writer",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &path)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // kill it (SIGKILL: no chance to finish the file) once it has written some chunks
    let started = Instant::now();
    while std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0) < 60_000 {
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "the child wrote nothing"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    // no summary, no footer
    assert!(!bytes.ends_with(b"\x89MCAP0\r\n"));
    assert!(
        mcap::read::Summary::read(&bytes).is_err() || mcap::read::Summary::read(&bytes).unwrap().is_none()
    );
    let log = LogReader::open(&path).unwrap().read().unwrap();
    let why = log.truncated.clone().expect("reported as ending early");
    assert!(!why.is_empty());
    assert!(log.frames.len() > 100, "{} frames", log.frames.len());
    // what it has is the start of the stream, in order, nothing lost
    for (k, f) in log.frames.iter().enumerate() {
        assert_eq!(bits(f), bits(&frame(k as u64)), "frame {k}");
    }
    let fixed = repair_and_check(&path, &d.join("fixed.mcap"));
    assert_eq!(fixed.frames.len(), log.frames.len());
    // the repaired file is not the input and is not replaced without --force
    let e = repair(&path, &d.join("fixed.mcap"), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("fixed.mcap: exists: not overwritten"), "{e}");
    let e = repair(&path, &path, true).unwrap_err().to_string();
    assert!(e.contains("is the input"), "{e}");
}

/// Byte offsets and opcodes of the top-level records of an MCAP file.
fn records(bytes: &[u8]) -> Vec<(usize, u8)> {
    let mut at = 8;
    let mut out = Vec::new();
    while at + 9 <= bytes.len() {
        out.push((at, bytes[at]));
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        at += 9 + len;
    }
    out
}

#[test]
fn a_log_cut_anywhere_reads_its_intact_prefix_and_repairs_to_it() {
    let d = dir("cut");
    let path = d.join("full.mcap");
    let options = WriterOptions {
        chunk_size: 4096,
        ..WriterOptions::default()
    };
    let mut w = LogWriter::create(&path, options).unwrap();
    for i in 0..2000 {
        assert!(w.write(Entry::Frame(frame(i), i)).unwrap());
        if i % 10 == 0 {
            assert!(w.write(Entry::Health(health(i / 10), i)).unwrap());
        }
    }
    w.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let full = LogReader::open(&path).unwrap().read().unwrap();
    assert!(full.truncated.is_none());
    assert_eq!(full.frames.len(), 2000);
    let recs = records(&bytes);
    let chunks: Vec<usize> = recs.iter().filter(|r| r.1 == 0x06).map(|r| r.0).collect();
    let data_end = recs.iter().find(|r| r.1 == 0x0F).expect("a data end record").0;
    assert!(chunks.len() >= 8, "{} chunks", chunks.len());
    // cut: where the summary starts (killed after its last flush), in the middle
    // of a chunk, right after a chunk's opcode, in the header, after the magic
    let mut cuts = vec![
        ("no summary", data_end),
        ("mid chunk 3", chunks[3] + 300),
        ("mid last chunk", chunks[chunks.len() - 1] + 100),
        ("chunk opcode", chunks[5] + 1),
        ("chunk start", chunks[6]),
        ("in the header", 20),
        ("magic only", 8),
    ];
    cuts.sort_by_key(|c| c.1);
    let mut frames_seen = Vec::new();
    for (what, cut) in cuts {
        let p = d.join(format!("cut{cut}.mcap"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let log = LogReader::open(&p).unwrap().read().unwrap();
        assert!(log.truncated.is_some(), "{what}: not reported as ending early");
        // a prefix of the full log, bit for bit
        for (a, b) in log.frames.iter().zip(&full.frames) {
            assert_eq!(bits(a), bits(b), "{what}");
        }
        let fixed = repair_and_check(&p, &d.join(format!("fixed{cut}.mcap")));
        frames_seen.push((what, fixed.frames.len()));
    }
    // more file, more frames; cut where the summary starts: every frame
    assert!(
        frames_seen.windows(2).all(|w| w[0].1 <= w[1].1),
        "{frames_seen:?}"
    );
    assert_eq!(frames_seen.last().unwrap(), &("no summary", 2000));
    assert_eq!(frames_seen[0].1, 0, "{frames_seen:?}");
    // a complete log repairs to itself (same messages) and a file that is not
    // MCAP is refused by name without writing anything
    repair_and_check(&path, &d.join("same.mcap"));
    let junk = d.join("junk.mcap");
    std::fs::write(&junk, b"not a log at all").unwrap();
    let e = repair(&junk, &d.join("junk-fixed.mcap"), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("junk.mcap") && e.contains("not an MCAP file"), "{e}");
    assert!(!d.join("junk-fixed.mcap").exists());
}
