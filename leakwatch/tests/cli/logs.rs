//! Recorded logs: `repair` of a killed recorder's log, `info`, `plot` of a log.

use crate::common::*;

#[test]
fn repair_rewrites_a_killed_recorders_log_and_export_reads_it_whole() {
    let d = tmpdir("repair");
    let full = d.join("full.mcap");
    let options = recorder::WriterOptions {
        chunk_size: 4096,
        ..recorder::WriterOptions::default()
    };
    let mut w = recorder::LogWriter::create(&full, options).unwrap();
    for i in 0..1500u64 {
        let f = frames::SensorFrame {
            seq: i,
            t_s: i as f64 * 1e-3,
            x_m: 0.3,
            p1_pa: 6.9e6,
            p2_pa: 6.8e6,
            ..frames::SensorFrame::default()
        };
        assert!(w.write(recorder::Entry::Frame(f, i)).unwrap());
    }
    w.finish().unwrap();
    // a recorder killed mid-chunk: no summary, a cut last chunk (at 30 %: the
    // frames compress so well that the index and summary are much of the file)
    let bytes = std::fs::read(&full).unwrap();
    let killed = d.join("killed.mcap");
    std::fs::write(&killed, &bytes[..bytes.len() * 3 / 10]).unwrap();
    let kept = recorder::LogReader::open(&killed).unwrap().read().unwrap();
    assert!(
        kept.truncated.is_some() && kept.frames.len() > 100 && kept.frames.len() < 1500,
        "{:?}, {} frames of {} bytes",
        kept.truncated,
        kept.frames.len(),
        bytes.len()
    );
    let fixed = d.join("fixed.mcap");
    let o = leakwatch(&[
        "repair",
        killed.to_str().unwrap(),
        "--out",
        fixed.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("killed.mcap: ends early"), "{err}");
    // every frame in the batches; the frames channel holds every 40th
    assert!(err.contains("messages (frame_batches "), "{err}");
    assert_eq!(
        recorder::LogReader::open(&fixed)
            .unwrap()
            .read()
            .unwrap()
            .frames
            .len(),
        kept.frames.len()
    );
    // the repaired file is complete; export reads every frame of it without a warning
    let csv = d.join("csv");
    let o = leakwatch(&["export", fixed.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let dataset = std::fs::read_to_string(csv.join("dataset.csv")).unwrap();
    assert_eq!(dataset.lines().count(), kept.frames.len() + 1);
    // not over an existing file without --force, never over the input
    let o = leakwatch(&[
        "repair",
        killed.to_str().unwrap(),
        "--out",
        fixed.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("exists"),
        "{}",
        stderr(&o)
    );
    let o = leakwatch(&[
        "repair",
        killed.to_str().unwrap(),
        "--out",
        killed.to_str().unwrap(),
        "--force",
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("is the input"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(&killed).unwrap(), &bytes[..bytes.len() * 3 / 10]);
}

/// A log like `run`'s: 3 s of frames with the configuration stored, a leak raised.
fn write_run_log(path: &std::path::Path, config: Option<&str>) {
    let options = recorder::WriterOptions {
        config_toml: config.map(str::to_string),
        ..recorder::WriterOptions::default()
    };
    let mut w = recorder::LogWriter::create(path, options).unwrap();
    for i in 0..3000u64 {
        let t = 2_000_000_000 + i * 1_000_000;
        let f = frames::SensorFrame {
            seq: i,
            acq_mono_ns: t,
            t_s: i as f64 * 1e-3,
            u_v: (i as f64 * 0.01).sin(),
            x_m: 0.3 + 0.01 * (i as f64 * 0.01).sin(),
            p1_pa: 6.9e6,
            p2_pa: 6.8e6,
            ..frames::SensorFrame::default()
        };
        assert!(w.write(recorder::Entry::Frame(f, t)).unwrap());
        if i % 100 == 0 {
            let h = frames::HealthFrame {
                seq: i / 100,
                mono_ns: t,
                t_s: i as f64 * 1e-3,
                leak_flow_lpm: [i as f64 * 1e-4, 0.0, 0.0],
                ..frames::HealthFrame::default()
            };
            assert!(w.write(recorder::Entry::Health(h, t)).unwrap());
        }
    }
    let e = frames::LeakEventFrame {
        seq: 2100,
        acq_mono_ns: 4_100_000_000,
        event_id: 1,
        kind: frames::event_kind::EXT1,
        phase: frames::event_phase::RAISED,
        t_detect_s: 2.1,
        t_onset_s: 1.5,
        size_lpm: 0.3,
        size_lpm_sigma: 0.01,
        detector: frames::detector_bytes("leak-size"),
        ..frames::LeakEventFrame::default()
    };
    assert!(w.write(recorder::Entry::Event(e, 4_100_000_100)).unwrap());
    w.finish().unwrap();
}

#[test]
fn info_summarises_a_log_and_writes_the_config_it_holds() {
    let d = tmpdir("info");
    let log = d.join("run.mcap");
    let config = "[classifier]\nwarmup_s = 8.0\n";
    write_run_log(&log, Some(config));
    let o = leakwatch(&["info", log.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    for want in [
        "File:        ",
        // from the first frame to the last on the frames channel (every 40th; a
        // batch is logged at its first frame's time)
        "Duration:    2.960 s",
        "frames                75 msgs      25.0 Hz  cdr leakwatch_msgs/msg/SensorFrame (ros2msg)",
        "frame_batches         30 msgs    10.000 Hz  cdr leakwatch_msgs/msg/SensorFrameBatch (ros2msg)",
        "health                30 msgs",
        "Gaps:        none recorded",
        "Events:      1 raised",
        "ext1             leak-size  id 1  onset 1.50 s  size 0.300 ± 0.010 L/min",
        "Truncated:   no",
        "Config:      stored (2 lines): [classifier]",
    ] {
        assert!(out.contains(want), "{want:?} in\n{out}");
    }
    // the configuration, to a file or to standard output
    let cfg = d.join("config.toml");
    let o = leakwatch(&[
        "info",
        log.to_str().unwrap(),
        "--config-out",
        cfg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&cfg).unwrap(), config);
    assert!(stderr(&o).contains("wrote "), "{}", stderr(&o));
    let o = leakwatch(&["info", log.to_str().unwrap(), "--config-out", "-"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), config);
    // not over an existing file without --force
    let o = leakwatch(&[
        "info",
        log.to_str().unwrap(),
        "--config-out",
        cfg.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("exists"),
        "{}",
        stderr(&o)
    );
    // a log without one says so; a file that is not a log is an error naming it
    let bare = d.join("bare.mcap");
    write_run_log(&bare, None);
    let o = leakwatch(&["info", bare.to_str().unwrap(), "--config-out", "-"]);
    assert!(
        !o.status.success() && stderr(&o).contains("bare.mcap: the log holds no configuration"),
        "{}",
        stderr(&o)
    );
    let junk = d.join("junk.mcap");
    std::fs::write(&junk, b"not a log").unwrap();
    let o = leakwatch(&["info", junk.to_str().unwrap()]);
    assert!(
        !o.status.success() && stderr(&o).contains("junk.mcap"),
        "{}",
        stderr(&o)
    );
    // the JSON log of the version before the CDR encoding
    let old =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../recorder/tests/fixtures/json_v1.mcap");
    let o = leakwatch(&["info", old.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("json leakwatch.SensorFrame.v1 (jsonschema)"),
        "{out}"
    );
    assert!(out.contains("Config:      not stored in the log"), "{out}");
}

/// `plot run.mcap` draws the log (it used to read it as a CSV: "stream did not
/// contain valid UTF-8").
#[test]
fn plot_draws_a_recorded_log() {
    let d = tmpdir("plot-log");
    let log = d.join("run.mcap");
    write_run_log(&log, None);
    let png = d.join("run.png");
    let o = leakwatch(&["plot", log.to_str().unwrap(), "--out", png.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert!(bytes.len() > 10_000, "{} bytes", bytes.len());
    assert!(stderr(&o).contains("wrote "), "{}", stderr(&o));
}
