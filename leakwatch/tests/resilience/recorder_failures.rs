//! A recorder that cannot write, or keeps failing: it stops or is given up, monitoring goes on.

use crate::common::*;

use crate::{run_command, text, Running, SERIAL};

/// The recorder's log hits a file-size limit 40 kB into the run (its write
/// fails with EFBIG, as on a full disk): the recorder says which file and why
/// and stops, is not restarted, and the run monitors on to its end: the leak at
/// 12 s is printed and in events.json, the summary names the file and the
/// error, the exit status is 4, and the one log file is the cut run.mcap.
#[test]
fn a_recorder_that_cannot_write_stops_and_monitoring_goes_on() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("fsize");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let tag = "fsize";
    let mut run = Running(Some(
        run_command(tag, "20", Some("ext1:0.5lpm@12s"), &out, &cfg)
            .spawn()
            .expect("leakwatch runs"),
    ));
    // once the recorder has set up its bus (its shared memory must not be limited) and its file
    let rec = wait_for_stage("recorder", tag);
    wait_until("the recorder created its log", || {
        std::fs::read_to_string(out.join("recorder.log")).is_ok_and(|l| l.contains("recorder: rig"))
    });
    const LIMIT: u64 = 40_000;
    let lim = libc::rlimit {
        rlim_cur: LIMIT,
        rlim_max: LIMIT,
    };
    // SAFETY: prlimit on the recorder process of this test's run, with a valid rlimit.
    let rc = unsafe { libc::prlimit(rec, libc::RLIMIT_FSIZE, &lim, std::ptr::null_mut()) };
    assert_eq!(rc, 0, "prlimit: {}", std::io::Error::last_os_error());
    let o = run.0.take().unwrap().wait_with_output().unwrap();
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    let log = out.join("run.mcap");
    let why = format!(
        "the recorder cannot write the log {}: File too large (os error 27)",
        log.display()
    );
    assert_eq!(o.status.code(), Some(4), "stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(
        stdout.contains(&format!("LOG FAILED: {why}; monitoring went on")),
        "{stdout}"
    );
    assert_eq!(stderr.matches(&why).count(), 1, "{stderr}");
    assert!(
        !stderr.contains("stage recorder exited"),
        "the recorder was restarted:\n{stderr}"
    );
    let rec_log = std::fs::read_to_string(out.join("recorder.log")).unwrap();
    assert!(
        rec_log.contains(&format!(
            "recorder: error: cannot write the log {}: File too large",
            log.display()
        )) && !rec_log.contains("panicked"),
        "{rec_log}"
    );
    // monitoring went on: the leak at 12 s printed live and in events.json
    assert!(stdout.contains("raised   ext1"), "{stdout}");
    let events: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("events.json")).unwrap()).unwrap();
    let ext1: Vec<&serde_json::Value> = events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == "ext1" && e["phase"] == "raised" && e["detector"] == "leak-size")
        .collect();
    assert_eq!(ext1.len(), 1, "{events}");
    let t = ext1[0]["t_detect_s"].as_f64().unwrap();
    assert!((12.0..16.0).contains(&t), "ext1 raised at {t} s");
    // the estimator and classifier took every frame after the recorder stopped
    let latency: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("latency.json")).unwrap()).unwrap();
    for stage in ["estimator", "classifier"] {
        assert_eq!(
            latency["stages"][stage]["frames_in"], 20_000,
            "{stage}: {latency}"
        );
    }
    assert!(latency["restarts"].get("recorder").is_none(), "{latency}");
    // one log file, cut at the limit; no further parts
    let size = std::fs::metadata(&log).unwrap().len();
    assert!(size <= LIMIT, "run.mcap {size} bytes");
    let mcaps: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".mcap"))
        .collect();
    assert_eq!(mcaps, ["run.mcap"]);
}

/// A recorder that keeps dying (SIGKILLed each time it starts, 11 times) is
/// given up after the restart budget instead of ending the run: the leak after
/// that is still printed and in events.json, every frame was estimated, and the
/// run exits 4 with the recorder's failure in the summary.
#[test]
fn a_recorder_that_keeps_failing_is_given_up_and_monitoring_goes_on() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("rec-given-up");
    let cfg = short_warmup_config(&d);
    let out = d.join("out");
    let tag = "rec-given-up";
    let mut run = Running(Some(
        run_command(tag, "50", Some("ext1:0.5lpm@42s"), &out, &cfg)
            .spawn()
            .expect("leakwatch runs"),
    ));
    let mut killed = Vec::new();
    for _ in 0..11 {
        let mut pid = 0;
        wait_until("the recorder (re)started", || {
            pid = stage_pids(Some("recorder"), tag)
                .into_iter()
                .find(|p| !killed.contains(p))
                .unwrap_or(0);
            pid != 0
        });
        signal(pid, libc::SIGKILL);
        killed.push(pid);
    }
    let o = run.0.take().unwrap().wait_with_output().unwrap();
    let (stdout, stderr) = (text(&o.stdout), text(&o.stderr));
    assert_eq!(o.status.code(), Some(4), "stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(
        stdout.contains("LOG FAILED: stage recorder keeps failing: it exited 11 times without running 30 s"),
        "{stdout}"
    );
    assert!(
        stderr.contains("given up: monitoring goes on without it"),
        "{stderr}"
    );
    assert!(stage_pids(Some("recorder"), tag).is_empty());
    let events: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("events.json")).unwrap()).unwrap();
    let ext1: Vec<f64> = events
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == "ext1" && e["phase"] == "raised" && e["detector"] == "leak-size")
        .filter_map(|e| e["t_detect_s"].as_f64())
        .collect();
    assert_eq!(ext1.len(), 1, "{events}");
    assert!((42.0..46.0).contains(&ext1[0]), "ext1 raised at {} s", ext1[0]);
    let latency: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("latency.json")).unwrap()).unwrap();
    assert_eq!(latency["restarts"]["recorder"], 10, "{latency}");
    for stage in ["estimator", "classifier"] {
        assert_eq!(
            latency["stages"][stage]["frames_in"], 50_000,
            "{stage}: {latency}"
        );
    }
}
