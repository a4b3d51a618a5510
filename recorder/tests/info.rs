//! The summary of a log (`leakwatch info`): channels, counts, rates, gaps,
//! events, the stored configuration, truncation.

use std::collections::BTreeMap;

use frames::{EstimateFrame, LeakEventFrame, SensorFrame, Topic};
use recorder::{Entry, GapRecord, Info, LogReader, LogWriter, WriterOptions};

const CONFIG: &str = "[model]\nmass_kg = 10.0\n\n[classifier]\nwarmup_s = 8.0\n";

/// A fresh folder for one test, removed when the test passes.
fn dir(tag: &str) -> scratch::ScratchDir {
    scratch::ScratchDir::new(&format!("recorder-info-{tag}"))
}

/// 2 s at 1 kHz with frames 501..=505 missing (and their gap record), the
/// estimates at 10 Hz, a leak raised, updated and cleared, a sensor event.
fn write(path: &std::path::Path, options: WriterOptions) {
    let mut w = LogWriter::create(path, options).unwrap();
    let t0 = 5_000_000_000u64;
    for i in (0..2000u64).filter(|i| !(501..506).contains(i)) {
        let t = t0 + i * 1_000_000;
        if i == 506 {
            let gap = GapRecord {
                topic: Topic::Frames,
                expected_seq: 501,
                got_seq: 506,
                missing: 5,
                recv_mono_ns: t + 50_000,
            };
            assert!(w.write(Entry::Gap(gap)).unwrap());
        }
        let f = SensorFrame {
            seq: i,
            acq_mono_ns: t,
            t_s: i as f64 * 1e-3,
            ..SensorFrame::default()
        };
        assert!(w.write(Entry::Frame(f, t + 50_000)).unwrap());
        if i % 100 == 0 {
            let e = EstimateFrame {
                seq: i,
                acq_mono_ns: t,
                t_s: i as f64 * 1e-3,
                ..EstimateFrame::default()
            };
            assert!(w.write(Entry::Estimate(e, t + 60_000)).unwrap());
        }
    }
    let event = |kind, phase, t_s: f64, size_lpm| {
        let e = LeakEventFrame {
            seq: (t_s * 1e3) as u64,
            acq_mono_ns: t0 + (t_s * 1e9) as u64,
            event_id: kind as u64,
            kind,
            phase,
            t_detect_s: t_s,
            t_onset_s: 1.0,
            size_lpm,
            size_lpm_sigma: 0.01,
            detector: frames::detector_bytes("leak-size"),
            ..LeakEventFrame::default()
        };
        Entry::Event(e, t0 + (t_s * 1e9) as u64 + 100_000)
    };
    use frames::{event_kind as k, event_phase as p};
    for e in [
        event(k::EXT2, p::RAISED, 1.25, 0.5),
        event(k::EXT2, p::UPDATED, 1.5, 0.52),
        event(k::SENSOR_DEAD, p::RAISED, 1.75, f64::NAN),
        event(k::EXT2, p::CLEARED, 1.9, 0.0),
    ] {
        assert!(w.write(e).unwrap());
    }
    w.finish().unwrap();
}

#[test]
fn info_names_the_channels_gaps_events_and_config() {
    let d = dir("full");
    let path = d.join("run.mcap");
    let options = WriterOptions {
        metadata: BTreeMap::from([("rig".to_string(), "rig7".to_string())]),
        config_toml: Some(CONFIG.to_string()),
        rig: "rig7".into(),
        // 2025-11-24 16:00:00 UTC at monotonic 0
        epoch_offset_ns: Some(1_764_000_000_000_000_000),
        ..WriterOptions::default()
    };
    write(&path, options);
    let log = LogReader::open(&path).unwrap().read().unwrap();
    assert_eq!(log.config_toml(), Some(CONFIG));
    assert_eq!(log.channels["frames"].topic, "/leakwatch/rig7/frames");
    let bytes = std::fs::metadata(&path).unwrap().len();
    let info = Info::from_log(&path, bytes, &log);
    // the span is the messages' acquisition stamps as Unix time: from the first
    // frame (5 s) to the last frame on the frames channel (every 40th: 6.960 s;
    // the last batch, frames 1906-1999, is logged at its first frame's time)
    assert_eq!(
        info.span_ns,
        Some((1_764_000_005_000_000_000, 1_764_000_006_960_000_000))
    );
    assert!((info.duration_s() - 1.96).abs() < 1e-9);
    assert_eq!(log.frames.len(), 1995, "every frame, from the batches");
    let frames = &info.channels[0];
    assert_eq!((frames.topic.as_str(), frames.messages), ("frames", 50));
    assert_eq!(frames.schema, "leakwatch_msgs/msg/SensorFrame (ros2msg)");
    assert_eq!(frames.message_encoding, "cdr");
    // 49 intervals over 1.96 s
    assert!((frames.rate_hz.unwrap() - 25.0).abs() < 1e-6);
    // batches of 100 frames, one cut short by the jump after frame 500
    let batches = &info.channels[1];
    assert_eq!((batches.topic.as_str(), batches.messages), ("frame_batches", 21));
    assert_eq!(batches.schema, "leakwatch_msgs/msg/SensorFrameBatch (ros2msg)");
    let names: Vec<&str> = info.channels.iter().map(|c| c.topic.as_str()).collect();
    assert_eq!(
        names,
        [
            "frames",
            "frame_batches",
            "estimates",
            "events",
            "health",
            "stats",
            "gaps"
        ]
    );
    assert!((info.channels[2].rate_hz.unwrap() - 10.0).abs() < 0.01);
    assert_eq!(info.channels[4].rate_hz, None); // no health frames
    assert_eq!(info.gap_records.len(), 1);
    assert_eq!(
        (info.gap_records[0].1.gaps, info.gap_records[0].1.missing),
        (1, 5)
    );
    assert_eq!((info.frame_seq_jumps.gaps, info.frame_seq_jumps.missing), (1, 5));
    assert_eq!(info.events.len(), 2, "the raised ones");
    // log times are Unix time: dates without a monotonic reading
    assert_eq!(info.wall_offset_ns, Some(0));
    let text = info.render();
    for want in [
        "Duration:    1.960 s",
        "Rig:         rig7",
        "Messages:    96",
        "Start:       2025-11-24 16:00:05.000 UTC\n",
        "End:         2025-11-24 16:00:06.960 UTC\n",
        "/leakwatch/rig7/frames                50 msgs      25.0 Hz  cdr leakwatch_msgs/msg/SensorFrame (ros2msg)",
        "/leakwatch/rig7/estimates             20 msgs      10.0 Hz  cdr leakwatch_msgs/msg/EstimateFrame (ros2msg)",
        "Gaps:        frames 1 (5 missing)",
        "Frame seq:   1 jumps, 5 frames missing",
        "Events:      2 raised",
        "t =     1.250 s  ext2             leak-size  id 2  onset 1.00 s  size 0.500 ± 0.010 L/min",
        "t =     1.750 s  sensor-dead",
        "Truncated:   no",
        "Damaged:     none",
        "Config:      stored (5 lines): [model] [classifier]",
    ] {
        assert!(text.contains(want), "{want:?} in\n{text}");
    }
    assert!(!text.contains("monotonic"), "{text}");
    // a file cut in its middle: what is complete, and that it is truncated
    let all = std::fs::read(&path).unwrap();
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &all[..all.len() * 2 / 3]).unwrap();
    let log = LogReader::open(&cut).unwrap().read().unwrap();
    let info = Info::from_log(&cut, 0, &log);
    assert!(info.truncated.is_some());
    let text = info.render();
    assert!(text.contains("Truncated:   yes: "), "{text}");
    // the config record comes first: a cut log still has it
    assert!(text.contains("Config:      stored"), "{text}");
}

#[test]
fn a_log_without_config_or_messages_says_so() {
    let d = dir("empty");
    let path = d.join("empty.mcap");
    LogWriter::create(&path, WriterOptions::default())
        .unwrap()
        .finish()
        .unwrap();
    let log = LogReader::open(&path).unwrap().read().unwrap();
    let info = Info::from_log(&path, 0, &log);
    assert_eq!(info.span_ns, None);
    let text = info.render();
    assert!(text.contains("Messages:    0"), "{text}");
    assert!(text.contains("Config:      not stored in the log"), "{text}");
    assert!(text.contains("Events:      none raised"), "{text}");
}
