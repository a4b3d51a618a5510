//! A recorder's log in continuations: the writer closes its file after
//! `part_span_ns` of the stream and continues in `run.1.mcap`, ...; the parts
//! read back as one log, bit for bit, and each part's summary (what the MCAP
//! writer holds in memory until the file is closed: a chunk index per chunk)
//! has a bounded number of chunk indexes however long the recording.

use frames::{EstimateFrame, SensorFrame};
use recorder::{with_continuations, Entry, Log, LogReader, LogWriter, WriterOptions};

/// `seconds` of 1 kHz frames (stamps 1 ms apart from 1000 s) and the 10 Hz estimates.
fn stream(seconds: u64) -> Vec<Entry> {
    let mut out = Vec::new();
    for i in 0..seconds * 1000 {
        let t = 1_000_000_000_000 + i * 1_000_000;
        let f = SensorFrame {
            seq: i,
            acq_mono_ns: t + i % 7 * 1_000,
            t_s: i as f64 * 1e-3,
            u_v: (i as f64 * 0.013).sin() * 3.0,
            x_m: 0.3 + 0.05 * (i as f64 * 0.002).sin(),
            p1_pa: 6.9e6 + (i % 97) as f64 * 381.5,
            p2_pa: 5.1e6 - (i % 89) as f64 * 381.5,
            temp_c: f64::NAN,
            ..SensorFrame::default()
        };
        out.push(Entry::Frame(f, t + 100_000));
        if i % 100 == 0 {
            let e = EstimateFrame {
                seq: i,
                acq_mono_ns: f.acq_mono_ns,
                t_s: f.t_s,
                nis: 1.0 + i as f64 * 1e-6,
                ..EstimateFrame::default()
            };
            out.push(Entry::Estimate(e, t + 200_000));
        }
    }
    out
}

fn write(path: &std::path::Path, entries: &[Entry], options: WriterOptions) -> recorder::WriterSummary {
    let mut w = LogWriter::create(path, options).unwrap();
    for e in entries {
        while !w.write(*e).unwrap() {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
    w.finish().unwrap()
}

/// The parts as one log, as `leakwatch` reads a run's log (`Log::append`).
fn read_joined(parts: &[std::path::PathBuf]) -> Log {
    let mut whole: Option<Log> = None;
    for p in parts {
        let l = LogReader::open(p).unwrap().read().unwrap();
        match whole.as_mut() {
            None => whole = Some(l),
            Some(w) => w.append(l, &p.display().to_string()),
        }
    }
    whole.unwrap()
}

fn frame_bits(f: &SensorFrame) -> [u64; 6] {
    [
        f.seq,
        f.acq_mono_ns,
        f.t_s.to_bits(),
        f.u_v.to_bits(),
        f.p1_pa.to_bits(),
        f.temp_c.to_bits(),
    ]
}

#[test]
fn a_log_continued_in_parts_reads_as_one_and_each_part_holds_a_bounded_index() {
    let d = scratch::ScratchDir::new("recorder-rotation");
    let entries = stream(10);
    // parts of 2 s of the stream, chunks of at most 0.25 s: 5 parts of 8 chunks of data
    let options = || WriterOptions {
        part_span_ns: 2_000_000_000,
        max_chunk_age_ns: 250_000_000,
        config_toml: Some("[classifier]\nwarmup_s = 8.0\n".into()),
        ..WriterOptions::default()
    };
    let path = d.join("run.mcap");
    let summary = write(&path, &entries, options());
    let names: Vec<String> = summary
        .parts
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        ["run.mcap", "run.1.mcap", "run.2.mcap", "run.3.mcap", "run.4.mcap"]
    );
    assert_eq!(
        with_continuations(&path),
        summary.parts,
        "the readers find them all"
    );
    let sizes: u64 = summary
        .parts
        .iter()
        .map(|p| std::fs::metadata(p).unwrap().len())
        .sum();
    assert_eq!(summary.bytes, sizes);
    assert_eq!(summary.messages["frames"], 10_000);
    // each part is a complete MCAP file with its own summary; what the writer
    // held for it: 9 chunk indexes (the schemas and channels, then 8 of 0.25 s),
    // the same in every part however long the log
    let chunk_indexes: Vec<usize> = summary
        .parts
        .iter()
        .map(|p| {
            let bytes = std::fs::read(p).unwrap();
            let s = mcap::Summary::read(&bytes).unwrap().expect("a summary");
            assert_eq!(s.channels.len(), 7, "{}: every channel", p.display());
            s.chunk_indexes.len()
        })
        .collect();
    assert_eq!(chunk_indexes, [9, 9, 9, 9, 9]);
    // every part has the run's configuration and the one time base
    for p in &summary.parts {
        let l = LogReader::open(p).unwrap().read().unwrap();
        assert_eq!(l.config_toml(), Some("[classifier]\nwarmup_s = 8.0\n"));
        assert!(l.truncated.is_none() && l.chunks_skipped.is_empty());
    }
    // the parts read as one log: every frame and estimate once, bit for bit,
    // as the same stream written into one file
    let joined = read_joined(&summary.parts);
    let single = d.join("single.mcap");
    write(
        &single,
        &entries,
        WriterOptions {
            max_chunk_age_ns: 250_000_000,
            ..WriterOptions::default()
        },
    );
    let one = LogReader::open(&single).unwrap().read().unwrap();
    let written: Vec<[u64; 6]> = entries
        .iter()
        .filter_map(|e| match e {
            Entry::Frame(f, _) => Some(frame_bits(f)),
            _ => None,
        })
        .collect();
    assert_eq!(joined.frames.iter().map(frame_bits).collect::<Vec<_>>(), written);
    assert_eq!(one.frames.iter().map(frame_bits).collect::<Vec<_>>(), written);
    let nis = |l: &Log| l.estimates.iter().map(|e| e.nis.to_bits()).collect::<Vec<_>>();
    assert_eq!(nis(&joined), nis(&one));
    assert_eq!(joined.estimates.len(), 100);
    assert_eq!(joined.frames_lost, 0);
    // the time span is the stream's, across the parts
    let f = &joined.channels["frames"];
    let g = &one.channels["frames"];
    assert_eq!(
        (f.first_log_time, f.last_log_time),
        (g.first_log_time, g.last_log_time)
    );
}

/// A restarted recorder looks for the earlier parts' last frame in their
/// continuations too (the latest part that holds a frame).
#[test]
fn the_last_logged_frame_is_found_in_the_latest_continuation() {
    let d = scratch::ScratchDir::new("recorder-rotation-resume");
    let path = d.join("run.mcap");
    let summary = write(
        &path,
        &stream(5),
        WriterOptions {
            part_span_ns: 2_000_000_000,
            ..WriterOptions::default()
        },
    );
    assert_eq!(summary.parts.len(), 3);
    let (last, problems) = recorder::resume::last_logged_frame(&with_continuations(&path));
    assert_eq!((last, problems.len()), (Some(4_999), 0));
}
