//! A leak detected end to end, every frame estimated and recorded; the fused placement's events.

use std::process::Command;
use std::time::Instant;

use crate::common::*;

use crate::{alarms_before, event_keys, finish, log_of, raised_leaks, start_run, start_run_with, SERIAL};

#[test]
fn a_leak_is_detected_and_every_frame_is_estimated_and_recorded() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("leak");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let o = finish(start_run("e2e-leak", "20", Some("ext1:0.5lpm@10s"), &out, &cfg));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("ext1"),
        "events are printed as they happen:\n{stdout}"
    );

    let events = json(&out.join("events.json"));
    let r = raised_leaks(&events);
    assert_eq!(r.len(), 1, "{events:#}");
    assert_eq!(r[0]["kind"], "ext1");
    let t = r[0]["t_detect_s"].as_f64().unwrap();
    assert!((10.0..13.0).contains(&t), "detected at {t} s");

    // Every frame published was estimated and recorded.
    let lat = json(&out.join("latency.json"));
    let published = lat["stages"]["acquisition"]["frames_out"].as_u64().unwrap();
    assert_eq!(published, 20_000, "{lat:#}");
    assert_eq!(
        lat["stages"]["estimator"]["frames_in"].as_u64().unwrap(),
        published,
        "{lat:#}"
    );
    assert_eq!(lat["stages"]["estimator"]["seq_gaps"].as_u64().unwrap(), 0);
    for hop in ["estimator", "classifier"] {
        assert!(
            lat["stages"][hop]["latency_p50_us"].as_f64().unwrap() > 0.0,
            "{lat:#}"
        );
    }
    let log = recorder::LogReader::open(&out.join("run.mcap"))
        .unwrap()
        .read()
        .unwrap();
    assert!(log.truncated.is_none());
    assert_eq!(log.frames.len(), 20_000);
    assert!(
        log.frames.windows(2).all(|w| w[1].seq == w[0].seq + 1),
        "frame sequence continuous"
    );
    assert!(log.gaps.is_empty(), "{:?}", log.gaps);
    // The estimates at 10 Hz (every 100th, and the marked ones: the replay of the
    // log below gives every one), each belonging to its frame: same sequence
    // number, sample time and measurement.
    assert!(
        (200..=210).contains(&log.estimates.len()),
        "{} estimates",
        log.estimates.len()
    );
    for e in &log.estimates {
        assert!(recorder::shell::keep_estimate(e, 100), "{}", e.seq);
        let f = &log.frames[e.seq as usize];
        assert_eq!((f.seq, f.t_s.to_bits()), (e.seq, e.t_s.to_bits()));
        assert_eq!(e.measured[1].to_bits(), f.p1_pa.to_bits());
    }
    // The run's configuration is in the log.
    assert_eq!(
        log.config_toml(),
        Some(std::fs::read_to_string(out.join("config.toml")).unwrap().as_str())
    );
    // The channels are CDR with their ros2msg schemas.
    assert_eq!(log.channels["frames"].message_encoding, "cdr");
    assert_eq!(log.channels["estimates"].schema_encoding, "ros2msg");
    // The leak event is in the log too.
    assert!(
        log.events.iter().any(|e| e.kind == frames::event_kind::EXT1),
        "{:?}",
        log.events
    );

    // Live and offline are one chain: the log replayed with the run's own config
    // gives the same events at the same samples, with the same sizes, bit for bit.
    let rep = d.join("replayed");
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["replay", out.join("run.mcap").to_str().unwrap(), "--config"])
        .arg(out.join("config.toml"))
        .arg("--out")
        .arg(&rep)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (live, replayed) = (event_keys(&events), event_keys(&json(&rep.join("events.json"))));
    assert!(!live.is_empty());
    assert_eq!(live, replayed, "live events vs the replay of the run's log");
}

/// The estimator and the classifier in one process (`--placement
/// estimator+classifier`, one iceoryx2 hop fewer) give the events of the split
/// placement (a process each) for the same run: same kinds, phases, ids,
/// detection samples and sizes, bit for bit. Every frame is estimated and
/// classified, and the log is the same shape (every frame, the estimates at 10 Hz).
#[test]
fn the_fused_placement_gives_the_events_of_the_split_one() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("placement");
    let cfg = short_warmup_config(&d);
    let t0 = Instant::now();
    let mut keys = Vec::new();
    let mut lat_p50_us = Vec::new();
    for placement in ["split", "estimator+classifier"] {
        let out = d.join(placement);
        let o = finish(start_run_with(
            "e2e-place",
            "14",
            Some("ext1:0.5lpm@8s"),
            &out,
            &cfg,
            &["--placement", placement],
        ));
        let stdout = String::from_utf8_lossy(&o.stdout);
        let fused = placement != "split";
        assert_eq!(
            stdout.contains("estimator+classifier in one process"),
            fused,
            "{stdout}"
        );
        for (log, present) in [
            ("estimator+classifier.log", fused),
            ("estimator.log", !fused),
            ("classifier.log", !fused),
        ] {
            assert_eq!(out.join(log).is_file(), present, "{placement}: {log}");
        }
        // the estimating process says at exit how stiff the oil is (the simulated
        // rig's is the model's: θ about 1)
        let est_log = if fused {
            "estimator+classifier.log"
        } else {
            "estimator.log"
        };
        let text = std::fs::read_to_string(out.join(est_log)).unwrap();
        let theta: f64 = text
            .split("oil stiffness: ")
            .nth(1)
            .and_then(|rest| rest.split(' ').next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{placement}: no oil stiffness in {est_log}:\n{text}"));
        assert!((theta - 1.0).abs() < 0.05, "{placement}: θ {theta}");
        let lat = json(&out.join("latency.json"));
        for stage in ["estimator", "classifier"] {
            let st = &lat["stages"][stage];
            assert_eq!(st["frames_in"].as_u64(), Some(14_000), "{placement}: {lat:#}");
            assert_eq!(st["seq_gaps"].as_u64(), Some(0), "{placement}: {lat:#}");
        }
        assert!(lat["restarts"].as_object().unwrap().is_empty(), "{lat:#}");
        let log = log_of(&out);
        assert_eq!(log.frames.len(), 14_000, "{placement}");
        assert!(
            (140..=150).contains(&log.estimates.len()),
            "{placement}: {}",
            log.estimates.len()
        );
        let events = json(&out.join("events.json"));
        let leaks = raised_leaks(&events);
        assert_eq!(leaks.len(), 1, "{placement}: {events:#}");
        assert_eq!(leaks[0]["kind"], "ext1");
        assert!(alarms_before(&events, 8.0).is_empty(), "{placement}: {events:#}");
        assert_eq!(
            log.events.len(),
            events.as_array().unwrap().len(),
            "{placement}: the log has them too"
        );
        keys.push(event_keys(&events));
        lat_p50_us.push(lat["stages"]["classifier"]["latency_p50_us"].as_f64().unwrap());
    }
    assert!(!keys[0].is_empty());
    assert_eq!(keys[0], keys[1], "split vs estimator+classifier in one process");
    eprintln!(
        "{} events, identical; classifier input latency since acquisition, p50 of the 1-s p50s: split {:.1} µs, \
         fused {:.1} µs; test took {:.1} s",
        keys[0].len(),
        lat_p50_us[0],
        lat_p50_us[1],
        t0.elapsed().as_secs_f64()
    );
}
