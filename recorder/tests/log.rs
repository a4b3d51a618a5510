//! The log file on its own: round trip, truncation, CSV export.

use frames::{detector_bytes, EstimateFrame, HealthFrame, LeakEventFrame, SensorFrame, StatsFrame, Topic};
use recorder::{export_csv, Entry, GapRecord, Log, LogReader, LogWriter, WriterOptions};

/// A fresh folder for one test, removed when the test passes.
fn dir(tag: &str) -> scratch::ScratchDir {
    scratch::ScratchDir::new(&format!("recorder-{tag}"))
}

fn sensor(i: u64) -> SensorFrame {
    SensorFrame {
        seq: i,
        acq_mono_ns: 1_000_000_000 + i * 1_000_000,
        t_s: i as f64 * 1e-3,
        u_v: (i as f64 * 0.37).sin() * 10.0,
        x_m: 0.1 + 1e-17 * i as f64,
        p1_pa: 6.9e6 + std::f64::consts::PI * i as f64,
        p2_pa: 5e-324, // the smallest subnormal
        x_sp_m: f64::NAN,
        f_load_n: if i & 1 == 0 {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        },
        ref_m: -0.0,
        q_leak_lpm: 0.1 + 0.2,
        // (after a gap on every other frame; the end of the stream closes a batch: never here)
        flags: (i % 2) as u32,
        _pad: 0,
        temp_c: 35.5,
    }
}

fn estimate(i: u64) -> EstimateFrame {
    let mut e = EstimateFrame {
        seq: i,
        acq_mono_ns: u64::MAX - i,
        est_recv_mono_ns: 3,
        est_done_mono_ns: 4,
        t_s: 1.0 / 3.0,
        n_states: 7,
        flags: 5,
        ..EstimateFrame::default()
    };
    for k in 0..7 {
        e.state[k] = (k as f64 + i as f64).exp();
        e.state_sigma[k] = 1.0 / (k as f64 + 1.0);
    }
    e.residual = [1e-300, -1e300, 0.5];
    e.innovation = [f64::MIN_POSITIVE, f64::MAX, f64::EPSILON];
    e.mae_pa = [12.5, 13.75];
    e.nis = 2.0f64.sqrt();
    e
}

fn bits<T: Copy>(v: &T) -> Vec<u8> {
    // SAFETY: the frames are repr(C) with explicit padding only: every byte is initialised
    unsafe { std::slice::from_raw_parts(v as *const T as *const u8, std::mem::size_of::<T>()).to_vec() }
}

fn write_sample_log(path: &std::path::Path, n: u64, options: WriterOptions) -> Vec<Entry> {
    let mut entries = Vec::new();
    for i in 0..n {
        entries.push(Entry::Frame(sensor(i), 10 + i));
        entries.push(Entry::Estimate(estimate(i), 11 + i));
        if i % 100 == 0 {
            entries.push(Entry::Health(
                HealthFrame {
                    seq: i / 100,
                    mono_ns: i,
                    t_s: i as f64 * 1e-3,
                    status: 1,
                    active_events: 0,
                    leak_flow_lpm: [0.1, f64::NAN, -0.2],
                    leak_flow_sigma_lpm: [0.01, 0.02, 0.03],
                    leak_threshold_lpm: [0.05, 0.06, 0.07],
                },
                12 + i,
            ));
        }
    }
    entries.push(Entry::Event(
        LeakEventFrame {
            seq: 7,
            acq_mono_ns: 8,
            cls_done_mono_ns: 9,
            event_id: 1,
            kind: frames::event_kind::EXT1,
            phase: frames::event_phase::RAISED,
            t_detect_s: 1.25,
            t_onset_s: 1.0,
            size_lpm: 0.25,
            size_lpm_sigma: 0.03,
            confidence: 0.999,
            detector: detector_bytes("sprt"),
            size_nominal_lpm: 0.3,
            coefficient_m3_s_sqrt_pa: 1.9e-9,
            statistic: 7.5,
            threshold: 4.9,
            channel: frames::text_bytes(""),
            detail: frames::text_bytes("0.25 L/min at the measured pressures, k = 1.9e-9 m³/(s·√Pa)"),
        },
        20,
    ));
    entries.push(Entry::Stats(
        StatsFrame {
            mono_ns: 1,
            pid: 42,
            stage: 1,
            frames_in: 2,
            frames_out: 3,
            seq_gaps: 4,
            deadline_misses: 5,
            proc_ns_p50: 6,
            proc_ns_p99: 7,
            proc_ns_max: 8,
            lat_ns_p50: 9,
            lat_ns_p99: 10,
            lat_ns_max: 11,
            cpu_fraction: 0.031,
            rss_bytes: 12,
        },
        21,
    ));
    entries.push(Entry::Gap(GapRecord {
        topic: Topic::Estimates,
        expected_seq: 5,
        got_seq: 9,
        missing: 4,
        recv_mono_ns: 22,
    }));
    let mut w = LogWriter::create(path, options).unwrap();
    for e in &entries {
        assert!(w.write(*e).unwrap());
    }
    let summary = w.finish().unwrap();
    assert_eq!(summary.messages["frames"], n);
    entries
}

#[test]
fn round_trip_is_bit_identical() {
    let d = dir("rt");
    let path = d.join("rt.mcap");
    let entries = write_sample_log(&path, 500, WriterOptions::default());
    let log = LogReader::open(&path).unwrap().read().unwrap();
    assert!(log.truncated.is_none(), "{:?}", log.truncated);
    let (mut f, mut e, mut h, mut ev, mut s, mut g) = (0, 0, 0, 0, 0, 0);
    for entry in &entries {
        match entry {
            Entry::Frame(x, _) => {
                assert_eq!(bits(x), bits(&log.frames[f]), "frame {f}");
                f += 1;
            }
            Entry::Estimate(x, _) => {
                assert_eq!(bits(x), bits(&log.estimates[e]), "estimate {e}");
                e += 1;
            }
            Entry::Health(x, _) => {
                assert_eq!(bits(x), bits(&log.health[h]));
                h += 1;
            }
            Entry::Event(x, _) => {
                assert_eq!(bits(x), bits(&log.events[ev]));
                ev += 1;
            }
            Entry::Stats(x, _) => {
                assert_eq!(bits(x), bits(&log.stats[s]));
                s += 1;
            }
            Entry::Gap(x) => {
                assert_eq!(*x, log.gaps[g]);
                g += 1;
            }
        }
    }
    assert_eq!(
        (f, e, h, ev, s, g),
        (
            log.frames.len(),
            log.estimates.len(),
            log.health.len(),
            log.events.len(),
            log.stats.len(),
            log.gaps.len()
        )
    );
}

/// Writes the sample log of 3000 frames in chunks of 32 KiB to `d/full.mcap`;
/// returns its bytes and the log read back.
fn small_chunk_log(d: &std::path::Path) -> (Vec<u8>, Log) {
    let path = d.join("full.mcap");
    let options = WriterOptions {
        chunk_size: 32 * 1024,
        // batches of 10 frames: each chunk holds several
        frame_batch_len: 10,
        ..WriterOptions::default()
    };
    write_sample_log(&path, 3000, options);
    let bytes = std::fs::read(&path).unwrap();
    let full = LogReader::open(&path).unwrap().read().unwrap();
    (bytes, full)
}

#[test]
fn a_truncated_file_reads_up_to_its_last_complete_chunk() {
    let d = dir("trunc");
    let (bytes, full) = small_chunk_log(&d);
    let mut seen_counts = Vec::new();
    for frac in [0.3, 0.55, 0.8] {
        let cut = (bytes.len() as f64 * frac) as usize;
        let p = d.join(format!("cut{cut}.mcap"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let log = LogReader::open(&p).unwrap().read().unwrap();
        assert!(log.truncated.is_some());
        assert!(!log.frames.is_empty() && log.frames.len() < full.frames.len());
        // a prefix of the full log, bit for bit
        for (a, b) in log.frames.iter().zip(&full.frames) {
            assert_eq!(bits(a), bits(b));
        }
        seen_counts.push(log.frames.len());
    }
    assert!(seen_counts.windows(2).all(|w| w[0] < w[1]), "{seen_counts:?}");
    // not an MCAP file at all: an error naming the file
    let p = d.join("junk.mcap");
    std::fs::write(&p, b"hello, this is not a log").unwrap();
    let e = LogReader::open(&p).unwrap().read().unwrap_err().to_string();
    assert!(e.contains("junk.mcap"), "{e}");
}

/// Byte offsets of the top-level chunk records (opcode 0x06) of an MCAP file.
fn chunk_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut at = 8;
    let mut out = Vec::new();
    while at + 9 <= bytes.len() {
        let op = bytes[at];
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if op == 0x06 {
            out.push(at);
        }
        if op == 0x0F {
            break; // data end
        }
        at += 9 + len;
    }
    out
}

#[test]
fn a_chunk_declaring_a_false_uncompressed_size_is_skipped_not_decompressed() {
    let d = dir("chunks");
    let (bytes, full) = small_chunk_log(&d);
    assert_eq!(full.frames.len(), 3000);
    assert!(full.chunks_skipped.is_empty() && full.frames_lost == 0);
    let chunks = chunk_offsets(&bytes);
    assert!(chunks.len() >= 6, "{} chunks", chunks.len());
    // the uncompressed size sits after opcode, length, start and end time
    let size_at = |c: usize| c + 9 + 16;
    let declared = |c: usize| u64::from_le_bytes(bytes[size_at(c)..size_at(c) + 8].try_into().unwrap());
    for (name, which, value, why) in [
        (
            "one",
            0,
            1u64,
            "declares 1 bytes uncompressed, but the data holds more",
        ),
        (
            "huge",
            0,
            1u64 << 62,
            "declares 4611686018427387904 bytes uncompressed, more than the 67108864 accepted",
        ),
        ("short", 3, 0, "holds more"),
        ("long", 3, declared(chunks[3]) + 100, "but the data holds"),
    ] {
        let mut b = bytes.clone();
        b[size_at(chunks[which])..size_at(chunks[which]) + 8].copy_from_slice(&value.to_le_bytes());
        let p = d.join(format!("{name}.mcap"));
        std::fs::write(&p, &b).unwrap();
        let started = std::time::Instant::now();
        let log = LogReader::open(&p).unwrap().read().unwrap();
        assert!(
            started.elapsed().as_secs_f64() < 5.0,
            "{name}: {:?}",
            started.elapsed()
        );
        assert_eq!(log.chunks_skipped.len(), 1, "{name}: {:?}", log.chunks_skipped);
        let msg = &log.chunks_skipped[0];
        assert!(
            msg.starts_with(&format!("chunk at byte {}: ", chunks[which])) && msg.contains(why),
            "{name}: {msg}"
        );
        // every other chunk is read; the frames of the skipped one are counted as lost
        let lost = full.frames.len() - log.frames.len();
        if which == 0 {
            // the first chunk holds the channel records: the others still decode
            // (channels from the summary); its frames are counted from sequence 0
            assert!(log.frames.len() > 2500, "{name}: {} frames", log.frames.len());
            assert_eq!(log.frames_lost, lost as u64, "{name}");
        } else {
            assert!(lost >= 20, "{name}: {lost}");
            assert_eq!(log.frames_lost, lost as u64, "{name}");
        }
        let mut k = 0;
        for f in &log.frames {
            while full.frames[k].seq != f.seq {
                k += 1;
            }
            assert_eq!(bits(f), bits(&full.frames[k]));
        }
        assert!(log.truncated.is_none(), "{name}");
    }
    // A damaged opcode byte turns a chunk into a "private record" that MCAP readers
    // skip silently; leakwatch writes none, so it is a damaged chunk, counted.
    for which in [1, 3] {
        let mut b = bytes.clone();
        b[chunks[which]] = 0xF9;
        let p = d.join(format!("opcode{which}.mcap"));
        std::fs::write(&p, &b).unwrap();
        let log = LogReader::open(&p).unwrap().read().unwrap();
        assert_eq!(log.chunks_skipped.len(), 1, "{:?}", log.chunks_skipped);
        assert!(
            log.chunks_skipped[0]
                .starts_with(&format!("record at byte {}: unknown opcode 0xf9", chunks[which])),
            "{:?}",
            log.chunks_skipped
        );
        let lost = full.frames.len() - log.frames.len();
        assert!(lost >= 20, "{lost}");
        assert_eq!(log.frames_lost, lost as u64, "opcode of chunk {which}");
    }
}

#[test]
fn csv_export_round_trips_and_the_dataset_file_reads_back() {
    let d = dir("csv");
    let path = d.join("x.mcap");
    write_sample_log(&path, 50, WriterOptions::default());
    let log = LogReader::open(&path).unwrap().read().unwrap();
    let out = d.join("csv");
    let files = export_csv(&log, &out, false).unwrap();
    assert_eq!(files.len(), 7);
    // a second export into the same directory replaces nothing without overwrite
    let e = export_csv(&log, &out, false).unwrap_err().to_string();
    assert!(e.contains("frames.csv: exists: not overwritten"), "{e}");
    assert_eq!(export_csv(&log, &out, true).unwrap().len(), 7);
    // and a second log over the first one neither
    let e = LogWriter::create(&path, WriterOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("x.mcap: exists: not overwritten"), "{e}");
    // a symbolic link as the log is never followed, even with overwrite
    let link = d.join("link.mcap");
    std::os::unix::fs::symlink(&path, &link).unwrap();
    let options = WriterOptions {
        overwrite: true,
        ..WriterOptions::default()
    };
    let e = LogWriter::create(&link, options).err().unwrap().to_string();
    assert!(e.contains("link.mcap: is a symbolic link"), "{e}");
    let frames_csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut lines = frames_csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "seq,acq_mono_ns,t_s,u_v,x_m,p1_pa,p2_pa,x_sp_m,f_load_n,ref_m,q_leak_lpm,flags,temp_c"
    );
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(first[6], "5e-324");
    assert_eq!(first[7], "NaN");
    let est = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    assert!(est.lines().next().unwrap().contains("state_10,state_sigma_0"));
    // every float of the frames table parses back to the same bits
    for (line, f) in frames_csv.lines().skip(1).zip(&log.frames) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[5].parse::<f64>().unwrap().to_bits(), f.p1_pa.to_bits());
        assert_eq!(cells[3].parse::<f64>().unwrap().to_bits(), f.u_v.to_bits());
    }
    let dataset_csv = std::fs::read_to_string(out.join("dataset.csv")).unwrap();
    assert_eq!(
        dataset_csv.lines().next().unwrap(),
        "t,u,x,p1,p2,x_sp,f_load,ref,q_leak,temp_c"
    );
    assert_eq!(dataset_csv.lines().count(), 51);
}

/// An event record written before the event frame carried its nominal size,
/// coefficient, statistic, threshold, channel and detail (LeakEventFrame.v1)
/// still reads: those fields come back absent (NaN, empty).
#[test]
fn event_records_of_the_first_version_still_read() {
    use recorder::Record;
    let mut f = LeakEventFrame {
        kind: frames::event_kind::EXT2,
        size_lpm: 0.2,
        statistic: 6.0,
        detail: frames::text_bytes("x"),
        ..LeakEventFrame::default()
    };
    let mut v = f.to_json();
    let obj = v.as_object_mut().expect("an object");
    for added in [
        "size_nominal_lpm",
        "coefficient_m3_s_sqrt_pa",
        "statistic",
        "threshold",
        "channel",
        "detail",
    ] {
        assert!(obj.remove(added).is_some(), "{added} is written");
    }
    let back = LeakEventFrame::from_json(&v).expect("a v1 record reads");
    assert_eq!(back.kind, frames::event_kind::EXT2);
    assert_eq!(back.size_lpm, 0.2);
    assert!(back.statistic.is_nan() && back.size_nominal_lpm.is_nan());
    assert_eq!(frames::text(&back.detail), "");
    // a field that is there but wrong is still an error that names it
    f.detail = frames::text_bytes("y");
    let mut bad = f.to_json();
    bad["statistic"] = serde_json::json!("many");
    let e = LeakEventFrame::from_json(&bad).expect_err("a bad statistic");
    assert!(e.contains("LeakEventFrame.v2.statistic"), "{e}");
}

/// A restarted recorder's view of the earlier parts: the last frame of the
/// latest part that holds one, read up to a killed recorder's last complete
/// chunk; a part that is not a log is named and passed over.
#[test]
fn the_last_logged_frame_of_the_earlier_parts_is_found() {
    use recorder::resume::{continuation_gap, last_logged_frame};
    let d = dir("parts");
    let (bytes, full) = small_chunk_log(&d);
    assert_eq!(full.frames.last().map(|f| f.seq), Some(2999));
    let whole = d.join("full.mcap");
    // a killed recorder's part: cut in the middle
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let held = LogReader::open(&cut).unwrap().read().unwrap().frames.len() as u64;
    assert!((1..3000).contains(&held));
    let junk = d.join("junk.mcap");
    std::fs::write(&junk, b"not a log").unwrap();
    let (last, problems) = last_logged_frame(&[whole.clone(), cut.clone()]);
    assert_eq!((last, problems.len()), (Some(held - 1), 0));
    let (last, problems) = last_logged_frame(&[whole, junk.clone()]);
    assert_eq!(last, Some(2999), "an earlier part, the later one unreadable");
    assert!(
        problems.len() == 1 && problems[0].contains("junk.mcap"),
        "{problems:?}"
    );
    assert_eq!(last_logged_frame(&[junk]).0, None);
    // the new part starts at frame 4000: 1000 frames in no part
    let g = continuation_gap(last, 4000, 7).unwrap();
    assert_eq!((g.topic, g.expected_seq, g.missing), (Topic::Frames, 3000, 1000));
}

#[test]
fn a_later_part_appends_after_the_frames_the_earlier_holds() {
    let d = dir("append");
    let write = |name: &str, seqs: std::ops::Range<u64>, with_config: &str| {
        let p = d.join(name);
        let options = WriterOptions {
            config_toml: Some(with_config.to_string()),
            // small chunks, so that a part cut in half keeps some of them
            chunk_size: 4096,
            // the layout of earlier versions (every frame on the frames
            // channel), whose message counts the repeated frames would inflate
            frame_batch_len: 0,
            ..WriterOptions::default()
        };
        let mut w = LogWriter::create(&p, options).unwrap();
        for i in seqs {
            assert!(w.write(Entry::Frame(sensor(i), 1_000 + i)).unwrap());
        }
        w.finish().unwrap();
        LogReader::open(&p).unwrap().read().unwrap()
    };
    let mut first = write("run.mcap", 0..1500, "first");
    // the restarted recorder's part overlaps the earlier one by 100 frames
    let later = write("run-1.mcap", 1400..3000, "second");
    let (first_time, later_last) = (
        first.channels["frames"].first_log_time,
        later.channels["frames"].last_log_time,
    );
    first.append(later, "run-1.mcap");
    let seqs: Vec<u64> = first.frames.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, (0..3000).collect::<Vec<_>>(), "every frame once, in order");
    let c = &first.channels["frames"];
    assert_eq!(
        (c.messages, c.first_log_time, c.last_log_time),
        (3000, first_time, later_last),
        "the 100 repeated frames are not counted twice"
    );
    assert_eq!(
        first.config_toml(),
        Some("first"),
        "the first part's record is kept"
    );
    assert!(first.truncated.is_none() && first.chunks_skipped.is_empty());
    // a damaged later part: what is wrong names it
    let bytes = std::fs::read(d.join("run-1.mcap")).unwrap();
    std::fs::write(d.join("run-2.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let cut = LogReader::open(&d.join("run-2.mcap")).unwrap().read().unwrap();
    assert!(cut.truncated.is_some());
    first.append(cut, "run-2.mcap");
    assert!(
        first
            .truncated
            .as_deref()
            .is_some_and(|t| t.starts_with("run-2.mcap: ")),
        "{:?}",
        first.truncated
    );
    assert_eq!(
        first.frames.len(),
        3000,
        "the cut part's frames were all held already"
    );
}

/// A log on a full device (`/dev/full`: every write fails with ENOSPC): the
/// error names the file and the reason, and counts as a write error (the
/// recorder stops with exit status 74 and is not restarted).
#[test]
fn a_full_disk_is_named_with_the_file_and_the_reason() {
    let options = WriterOptions {
        overwrite: true,
        ..WriterOptions::default()
    };
    let e = match LogWriter::create(std::path::Path::new("/dev/full"), options) {
        Err(e) => e,
        Ok(_) => panic!("a log was created on /dev/full"),
    };
    assert!(e.is_write_error(), "{e:?}");
    assert_eq!(e.to_string(), "/dev/full: No space left on device (os error 28)");
}
