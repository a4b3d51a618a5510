//! Stages that keep failing or stop: the run ends, missed samples skipped, no false alarm.

use std::time::{Duration, Instant};

use crate::common::*;

use crate::{finish, frame_gaps, log_of, raised_leaks, start_run, SERIAL};

/// A stage that keeps failing ends the run (after its restarts with backoff)
/// with an error that names it, and events.json and latency.json still hold
/// what the run gathered. Here the classifier is killed after its config was
/// made unreadable, so every restart fails at once.
#[test]
fn a_stage_that_keeps_failing_ends_the_run_and_leaves_the_events_and_latency() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("give-up");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let t0 = Instant::now();
    let child = start_run("e2e-give-up", "60", Some("ext1:0.5lpm@10s"), &out, &cfg);
    let pid = wait_for_stage("classifier", "e2e-give-up");
    wait_for_stage("acquisition", "e2e-give-up");
    // the acquisition reads the config as it starts: spoil it once it has
    std::thread::sleep(Duration::from_secs(2));
    std::fs::write(out.join("config.toml"), "[classifier\nnot toml").unwrap();
    std::thread::sleep(Duration::from_secs(11));
    signal(pid, libc::SIGKILL);
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    assert!(
        stderr.contains("stage classifier keeps failing: it exited 11 times"),
        "{stderr}"
    );
    assert!(stderr.contains("restarting it in 5.0 s"), "{stderr}");
    let events = json(&out.join("events.json"));
    let leaks = raised_leaks(&events);
    assert_eq!(
        leaks.len(),
        1,
        "the leak raised before the failures is kept: {events:#}"
    );
    let lat = json(&out.join("latency.json"));
    assert_eq!(lat["restarts"]["classifier"], 10, "{lat:#}");
    assert!(
        lat["stages"]["estimator"]["frames_in"].as_u64().unwrap() > 20_000,
        "{lat:#}"
    );
    // and no stage is left behind
    std::thread::sleep(Duration::from_secs(1));
    assert!(stage_pids(None, "e2e-give-up").is_empty());
    eprintln!("gave up after {:.1} s", t0.elapsed().as_secs_f64());
}

/// A stopped acquisition (SIGSTOP for 2 s, then SIGCONT) is noticed by the
/// watchdog; the samples it missed are lost as on a real rig (a gap of about
/// 2000 samples, no burst of catching up); the rig time stays real time and
/// the healthy rig raises no alarm.
#[test]
fn a_stopped_acquisition_skips_the_missed_samples_without_a_burst() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("acq-stop");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let child = start_run("e2e-acq-stop", "12", Some("none"), &out, &cfg);
    let pid = wait_for_stage("acquisition", "e2e-acq-stop");
    std::thread::sleep(Duration::from_secs(4));
    signal(pid, libc::SIGSTOP);
    std::thread::sleep(Duration::from_secs(2));
    signal(pid, libc::SIGCONT);
    let o = finish(child);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("the acquisition has made no progress for 1.5 s (process")
            && stderr.contains("stopped: SIGSTOP?"),
        "{stderr}"
    );
    let lat = json(&out.join("latency.json"));
    let stall = &lat["stalls"]["acquisition"];
    let longest = stall["longest_s"].as_f64().unwrap();
    assert_eq!(stall["count"], 1, "{lat:#}");
    assert!((1.9..2.6).contains(&longest), "{lat:#}");
    let acq = &lat["stages"]["acquisition"];
    let est = &lat["stages"]["estimator"];
    let (published, skipped) = (
        acq["frames_out"].as_u64().unwrap(),
        acq["seq_gaps"].as_u64().unwrap(),
    );
    assert_eq!(published + skipped, 12_000, "{lat:#}");
    assert_eq!(est["frames_in"].as_u64().unwrap(), published, "{lat:#}");
    let est_gap = est["seq_gaps"].as_u64().unwrap();
    assert!((1800..2300).contains(&est_gap), "{lat:#}");
    let log = log_of(&out);
    assert_eq!(frame_gaps(&log), [est_gap], "{:?}", log.gaps);
    // No burst after the stall: of the 500 frames after the longest pause, fewer
    // than half published less than 0.2 ms after the one before (a catch-up would
    // publish the 2 s missed back to back: all 500). Only those: on a busy machine
    // the scheduler makes short bursts anywhere, which this test is not about
    // (57 of 500 seen with the pipeline tests running side by side on 2 cores).
    let pause_ends = log
        .frames
        .windows(2)
        .enumerate()
        .max_by_key(|(_, w)| w[1].acq_mono_ns.saturating_sub(w[0].acq_mono_ns))
        .map(|(i, _)| i + 1)
        .expect("frames");
    let after = &log.frames[pause_ends..(pause_ends + 500).min(log.frames.len())];
    assert!(after.len() == 500, "only {} frames after the pause", after.len());
    let burst = after
        .windows(2)
        .filter(|w| w[1].acq_mono_ns.saturating_sub(w[0].acq_mono_ns) < 200_000)
        .count();
    assert!(burst < 250, "{burst} of the 500 frames after the pause in bursts");
    assert!(lat["restarts"].as_object().unwrap().is_empty(), "{lat:#}");
    let events = json(&out.join("events.json"));
    assert!(raised_leaks(&events).is_empty(), "{events:#}");
    eprintln!(
        "acquisition stopped 2 s: stall {longest:.2} s, estimator gap {est_gap} samples, \
         {published} published + {skipped} skipped, {burst} frames in bursts"
    );
}

/// The estimator and then the classifier stopped for 2 s each (SIGSTOP, then
/// SIGCONT): each is noticed by the watchdog, neither is killed, and the
/// healthy rig raises no alarm. Then the estimator stopped for good is killed
/// after 5 s without progress and restarted.
#[test]
fn a_stopped_estimator_or_classifier_is_noticed_without_a_false_alarm() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("stop");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let child = start_run("e2e-stop", "24", Some("none"), &out, &cfg);
    let est = wait_for_stage("estimator", "e2e-stop");
    let cls = wait_for_stage("classifier", "e2e-stop");
    wait_for_stage("acquisition", "e2e-stop");
    std::thread::sleep(Duration::from_secs(4));
    for pid in [est, cls] {
        signal(pid, libc::SIGSTOP);
        std::thread::sleep(Duration::from_secs(2));
        signal(pid, libc::SIGCONT);
        std::thread::sleep(Duration::from_secs(3));
    }
    signal(est, libc::SIGSTOP);
    let t0 = Instant::now();
    while stage_pids(Some("estimator"), "e2e-stop").contains(&est) {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the stopped estimator was not killed"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let killed_after = t0.elapsed().as_secs_f64();
    let o = finish(child);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("the estimator has made no progress for 5.0 s; killing it to restart it"),
        "{stderr}"
    );
    let lat = json(&out.join("latency.json"));
    for (stage, stalls, killed) in [("estimator", 2, 1), ("classifier", 1, 0)] {
        assert!(
            stderr.contains(&format!("the {stage} has made no progress for 1.5 s")),
            "{stderr}"
        );
        let st = &lat["stalls"][stage];
        // each SIGSTOP is a stall of its own; a loaded machine may add one
        // (a stage starved at start), so they are counted from the warnings
        let stopped = stderr
            .lines()
            .filter(|l| {
                l.contains(&format!("the {stage} has made no progress for 1.5 s")) && l.contains("SIGSTOP?")
            })
            .count() as u64;
        assert_eq!(stopped, stalls, "{stderr}");
        assert!(
            st["count"].as_u64().is_some_and(|n| n >= stalls),
            "{lat:#}\n{stderr}"
        );
        assert_eq!(st["killed"].as_u64(), Some(killed), "{lat:#}\n{stderr}");
        let longest = st["longest_s"].as_f64().unwrap();
        let gap = lat["stages"][stage]["seq_gaps"].as_u64().unwrap();
        // the 256-frame subscriber buffer overflowed while it was stopped
        assert!(gap > 1000, "{lat:#}");
        eprintln!("{stage}: {stalls} stalls, longest {longest:.2} s, {gap} frames missed");
    }
    assert_eq!(lat["stalls"]["acquisition"]["count"], 0, "{lat:#}");
    assert_eq!(lat["restarts"]["estimator"], 1, "{lat:#}");
    let events = json(&out.join("events.json"));
    assert!(raised_leaks(&events).is_empty(), "{events:#}");
    eprintln!("the estimator stopped for good was killed {killed_after:.1} s after SIGSTOP");
}
