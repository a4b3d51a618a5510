//! Monitoring goes on when what is around it fails, with real
//! processes and real files: a recorder whose log hits a file-size limit (a full
//! disk without root: RLIMIT_FSIZE set on the running recorder, which ignores
//! SIGXFSZ, so its write fails with EFBIG), and the shared memory a killed run
//! leaves (removed by the next start on its prefix and by `leakwatch clean`).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

mod common;
use common::*;

/// The runs share two cores: one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

/// `leakwatch run` on rig `tag`, the loaded-sine scenario for `seconds`, not started.
fn run_command(tag: &str, seconds: &str, fault: Option<&str>, out: &Path, cfg: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_leakwatch"));
    c.args([
        "run",
        "--rig",
        &rig_id(tag),
        "--scenario",
        "loaded-sine",
        "--seconds",
        seconds,
    ])
    .arg("--config")
    .arg(cfg)
    .arg("--out")
    .arg(out)
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    if let Some(f) = fault {
        c.args(["--fault", f]);
    }
    c
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A run this test started, SIGKILLed if the test fails before it ends it
/// (its stages die with it).
struct Running(Option<Child>);

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// The state letter of process `pid` (`T`: stopped), from /proc/PID/stat.
fn state(pid: i32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat.rsplit(") ").next()?.chars().next()
}

/// Kills a run as a crash would: the supervisor stopped first (so it restarts
/// nothing), every stage SIGKILLed, then the supervisor.
fn kill_run(mut run: Running, tag: &str) -> Output {
    let child = run.0.take().unwrap();
    let sup = child.id() as i32;
    signal(sup, libc::SIGSTOP);
    wait_until("the supervisor is stopped", || state(sup) == Some('T'));
    let stages = stage_pids(None, tag);
    assert_eq!(stages.len(), 4, "the four stages of {tag}: {stages:?}");
    for pid in stages {
        signal(pid, libc::SIGKILL);
    }
    wait_until("the stages are gone", || stage_pids(None, tag).is_empty());
    signal(sup, libc::SIGKILL);
    child.wait_with_output().unwrap()
}

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

/// The files of iceoryx2 prefix `prefix` in /dev/shm.
fn shm_files(prefix: &str) -> Vec<PathBuf> {
    let start = format!("lw_{prefix}_");
    let mut v: Vec<PathBuf> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(&start))
        .map(|e| e.path())
        .collect();
    v.sort();
    v
}

/// The number N in `... (N files or directories, ...` of `text`.
fn removed_count(text: &str) -> Option<usize> {
    let head = text.split(" files or directories").next()?;
    head.rsplit(['(', ' ']).next()?.parse().ok()
}

/// The paths listed in `text` (one per line, indented, followed by their size).
fn listed(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.strip_prefix("  "))
        .filter_map(|l| l.split(" (").next())
        .map(str::to_string)
        .collect()
}

/// A SIGKILLed run leaves its shared memory; the next run on the prefix removes
/// it and says so; `leakwatch clean` is refused while that run holds the prefix,
/// and after it too was killed, removes its files and lock and lists them.
#[test]
fn a_killed_runs_leftovers_are_removed_at_the_next_start_and_by_clean() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("leftovers");
    let cfg = short_warmup_config(&d);
    let prefix = format!("lwcl{}", std::process::id());
    let (root, lock) = root_and_lock(&prefix);
    let clean = || {
        Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .args(["clean", "--prefix", &prefix])
            .output()
            .unwrap()
    };

    // a run killed while it runs
    let a = Running(Some(
        run_command("left-a", "60", None, &d.join("a"), &cfg)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .spawn()
            .unwrap(),
    ));
    wait_for_stage("acquisition", "left-a");
    wait_until("run a publishes its stats", || {
        std::fs::read_to_string(d.join("a/recorder.log")).is_ok_and(|l| l.contains("recorder: rig"))
    });
    kill_run(a, "left-a");
    let left = shm_files(&prefix);
    assert!(left.len() > 10, "leftovers of the killed run: {left:?}");
    assert!(root.is_dir() && lock.is_file());

    // the next run on the prefix removes them and says so
    let b = Running(Some(
        run_command("left-b", "60", None, &d.join("b"), &cfg)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .spawn()
            .unwrap(),
    ));
    wait_for_stage("acquisition", "left-b");
    // ... and holds the prefix: clean is refused, nothing removed
    let refused = clean();
    assert_eq!(refused.status.code(), Some(1));
    let err = text(&refused.stderr);
    assert!(
        err.contains(&format!(
            "not cleaned: the iceoryx2 prefix {prefix:?} is in use by another leakwatch run"
        )),
        "{err}"
    );
    // (the running run's own files come and go as its stages connect; its
    // directory and lock are there from its start to its end)
    assert!(root.is_dir() && lock.is_file() && !shm_files(&prefix).is_empty());
    let b_out = kill_run(b, "left-b");
    let b_err = text(&b_out.stderr);
    assert!(
        b_err.contains(&format!(
            "leakwatch run: removed what a dead run left on the iceoryx2 prefix {prefix:?}"
        )),
        "{b_err}"
    );
    // every shm file of run a, and its directory
    let named = listed(&b_err);
    let extra: Vec<&String> = named
        .iter()
        .filter(|n| !left.iter().any(|f| f.display().to_string() == **n))
        .collect();
    assert_eq!(
        removed_count(&b_err),
        Some(left.len() + 1),
        "{b_err}\nnot counted before: {extra:?}"
    );
    for f in &left {
        assert!(
            b_err.contains(&f.display().to_string()),
            "{} not named:\n{b_err}",
            f.display()
        );
    }

    // run b's leftovers, removed on demand
    let left_b = shm_files(&prefix);
    assert!(
        left_b.len() > 10,
        "leftovers of the second killed run: {left_b:?}"
    );
    let done = clean();
    let said = text(&done.stdout);
    assert_eq!(done.status.code(), Some(0), "{said}{}", text(&done.stderr));
    assert!(
        said.starts_with(&format!(
            "leakwatch clean: removed {} files or directories",
            left_b.len() + 1
        )),
        "{said}"
    );
    assert!(said.contains(&root.display().to_string()), "{said}");
    for f in &left_b {
        assert!(
            said.contains(&f.display().to_string()),
            "{} not listed:\n{said}",
            f.display()
        );
    }
    assert!(shm_files(&prefix).is_empty() && !root.exists() && !lock.exists());
    let again = clean();
    assert_eq!(
        text(&again.stdout),
        format!("leakwatch clean: nothing left on the iceoryx2 prefix {prefix:?}\n")
    );
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

/// A prefix of `len` characters, unique to this test process, ending in `tag`.
fn prefix_of_len(len: usize, tag: char) -> String {
    let mut p = format!("p{}{tag}", std::process::id());
    while p.len() < len {
        p.push(tag);
    }
    p
}

/// The iceoryx2 root directory and the lock file of `prefix`, both in the
/// user's private directory.
fn root_and_lock(prefix: &str) -> (PathBuf, PathBuf) {
    let cfg = bus::BusConfig {
        iox_prefix: Some(prefix.to_string()),
        ..bus::BusConfig::default()
    };
    let (root, lock) = (cfg.iox_root().unwrap(), cfg.lock_path().unwrap());
    let private = bus::private_dir_path();
    assert!(root.starts_with(&private) && lock.starts_with(&private));
    (root, lock)
}

/// No iceoryx2 file of `prefix` is left: no segment in /dev/shm, no directory
/// in the private directory, no lock.
fn assert_no_files_of(prefix: &str) {
    assert!(shm_files(prefix).is_empty(), "{:?}", shm_files(prefix));
    let (root, lock) = root_and_lock(prefix);
    assert!(!root.exists(), "{} is left", root.display());
    assert!(!lock.exists(), "{} is left", lock.display());
}

/// `LEAKWATCH_IOX_PREFIX` of bus::MAX_PREFIX_LEN characters runs a whole
/// pipeline; one character more is refused before anything is made, with a
/// message naming the limit and why.
#[test]
fn a_prefix_of_the_limit_runs_and_one_longer_is_refused_naming_the_limit() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("prefix-limit");
    let cfg = short_warmup_config(&d);
    let longest = prefix_of_len(bus::MAX_PREFIX_LEN, 'l');
    assert_eq!(longest.len(), 20);
    let ok = run_command("limit-ok", "3", None, &d.join("ok"), &cfg)
        .env("LEAKWATCH_IOX_PREFIX", &longest)
        .output()
        .unwrap();
    // done (3: too short for the detector to arm)
    assert!(
        matches!(ok.status.code(), Some(0 | 3)),
        "{:?} {}",
        ok.status,
        text(&ok.stderr)
    );
    let log = recorder::LogReader::open(&d.join("ok/run.mcap"))
        .unwrap()
        .read()
        .unwrap();
    assert_eq!(log.frames.len(), 3000);
    assert_no_files_of(&longest);

    let too_long = prefix_of_len(bus::MAX_PREFIX_LEN + 1, 'm');
    let refused = run_command("limit-no", "3", None, &d.join("no"), &cfg)
        .env("LEAKWATCH_IOX_PREFIX", &too_long)
        .output()
        .unwrap();
    let err = text(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "{too_long:?} (from LEAKWATCH_IOX_PREFIX?) has 21 characters; at most 20 work"
        )),
        "{err}"
    );
    assert!(err.contains("must fit 108 bytes"), "the reason: {err}");
    assert!(!d.join("no/run.mcap").exists());
    assert_no_files_of(&too_long);
}

/// A start that fails once the run has opened its prefix (here: a stage's log
/// cannot be created, the stages before it already run) removes what it made:
/// no file of the prefix is left, and the error names the stage.
#[test]
fn a_start_that_fails_leaves_no_files_on_its_prefix() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("failed-start");
    let cfg = short_warmup_config(&d);
    let prefix = prefix_of_len(12, 'f');
    let out = d.join("run");
    // the acquisition, started last, cannot have its log: a directory is in the way
    std::fs::create_dir_all(out.join("acquisition.log")).unwrap();
    let failed = run_command("failed-start", "3", None, &out, &cfg)
        .arg("--force")
        .env("LEAKWATCH_IOX_PREFIX", &prefix)
        .output()
        .unwrap();
    let err = text(&failed.stderr);
    assert_eq!(failed.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot start the acquisition"), "{err}");
    assert!(
        err.contains(&format!(
            "the start failed: removed what it had made on the iceoryx2 prefix {prefix:?}"
        )),
        "{err}"
    );
    assert_no_files_of(&prefix);
    // the stages it had started are gone
    for stage in ["recorder", "estimator", "classifier"] {
        assert!(
            stage_pids(Some(stage), "failed-start").is_empty(),
            "{stage} still runs"
        );
    }
}

/// The global management segment of `prefix` in /dev/shm.
fn mgmt_segment(prefix: &str) -> PathBuf {
    shm_files(prefix)
        .into_iter()
        .find(|p| p.to_string_lossy().ends_with(".global_mgmt"))
        .expect("the prefix's management segment")
}

/// A management segment damaged under a running pipeline (3 bytes written
/// into it, as another local user can: it is 0666) is found before the killed
/// estimator is restarted: the run stops at once with exit status 1 and a
/// message naming the file, what is wrong with it, its owner and the way out,
/// instead of restarts that fail and a run that ends "no leak detected".
#[test]
fn a_damaged_management_segment_is_named_before_a_restart_and_ends_the_run() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("mgmt-restart");
    let cfg = short_warmup_config(&d);
    let prefix = prefix_of_len(12, 'g');
    let run = Running(Some(
        run_command("mgmt-restart", "60", None, &d.join("run"), &cfg)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .spawn()
            .unwrap(),
    ));
    wait_for_stage("acquisition", "mgmt-restart");
    let segment = mgmt_segment(&prefix);
    std::fs::write(&segment, b"bad").unwrap();
    let estimator = wait_for_stage("estimator", "mgmt-restart");
    signal(estimator, libc::SIGKILL);
    let t0 = Instant::now();
    let mut run = run;
    let out = run.0.take().unwrap().wait_with_output().unwrap();
    let err = text(&out.stderr);
    assert!(t0.elapsed() < Duration::from_secs(30), "{err}");
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "the estimator cannot be restarted: the management segment {} of prefix {prefix:?} is damaged (3 bytes, \
             iceoryx2 writes 16; owner uid {}, this user)",
            segment.display(),
            bus::current_uid()
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!("leakwatch clean --prefix {prefix}")),
        "{err}"
    );
    assert!(!err.contains("no leak detected"), "{err}");
    assert!(stage_pids(None, "mgmt-restart").is_empty());
    assert_no_files_of(&prefix);
}

/// A damaged management segment that cannot be removed at the start (a
/// process of the prefix still runs: here this test's own node) stops the run
/// before any stage starts, naming the file.
#[test]
fn a_damaged_management_segment_is_named_at_the_start() {
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("mgmt-start");
    let cfg = short_warmup_config(&d);
    let prefix = prefix_of_len(12, 'h');
    let bus_cfg = bus::BusConfig {
        iox_prefix: Some(prefix.clone()),
        ..bus::BusConfig::default()
    };
    let node = bus::Bus::open("holder", bus_cfg.clone()).expect("a node of the prefix");
    let segment = mgmt_segment(&prefix);
    std::fs::write(&segment, [0u8; 16]).unwrap();
    let out = run_command("mgmt-start", "3", None, &d.join("run"), &cfg)
        .env("LEAKWATCH_IOX_PREFIX", &prefix)
        .output()
        .unwrap();
    let err = text(&out.stderr);
    drop(node);
    bus_cfg.remove_isolated_files().unwrap();
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "cannot start on the iceoryx2 prefix {prefix:?}: the management segment {} of prefix {prefix:?} is \
             damaged (its version word is 0x0, iceoryx2 0.10.0 writes 0xa0000",
            segment.display()
        )),
        "{err}"
    );
    assert!(stage_pids(None, "mgmt-start").is_empty());
    assert!(!d.join("run/run.mcap").exists());
    assert_no_files_of(&prefix);
}

/// A private directory that other users can write (here `LEAKWATCH_RUNTIME_DIR`
/// with mode 777) is refused before anything starts, naming it and its mode;
/// a missing one is made 0700 and holds the run's lock and iceoryx2 root.
#[test]
fn a_run_refuses_a_private_directory_others_can_write() {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let _g = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let d = tmpdir("private-dir");
    let cfg = short_warmup_config(&d);
    let open = d.join("open");
    std::fs::create_dir(&open).unwrap();
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o777)).unwrap();
    let out = run_command("private-open", "3", None, &d.join("run"), &cfg)
        .env("LEAKWATCH_RUNTIME_DIR", &open)
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "leakwatch's private directory {} is open to other users (mode 777, not 700)",
            open.display()
        )),
        "{err}"
    );
    assert!(stage_pids(None, "private-open").is_empty());
    assert_eq!(std::fs::read_dir(&open).unwrap().count(), 0, "nothing made in it");
    assert!(!d.join("run/run.mcap").exists());

    // a missing one is made 0700; the run's root and lock are in it while it runs
    // (short: the directory's length limits the prefix's, bus::max_prefix_len_under)
    let fresh = PathBuf::from(format!("/tmp/lwf{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&fresh);
    let prefix = prefix_of_len(12, 'k');
    let run = Running(Some(
        run_command("private-fresh", "60", None, &d.join("run2"), &cfg)
            .env("LEAKWATCH_RUNTIME_DIR", &fresh)
            .env("LEAKWATCH_IOX_PREFIX", &prefix)
            .spawn()
            .unwrap(),
    ));
    wait_for_stage("acquisition", "private-fresh");
    let m = std::fs::symlink_metadata(&fresh).unwrap();
    assert!(m.is_dir() && m.mode() & 0o777 == 0o700 && m.uid() == bus::current_uid());
    assert!(fresh.join(format!("{prefix}.lock")).is_file());
    assert!(fresh.join(&prefix).is_dir());
    kill_run(run, "private-fresh");
    let cleaned = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args(["clean", "--prefix", &prefix])
        .env("LEAKWATCH_RUNTIME_DIR", &fresh)
        .output()
        .unwrap();
    assert!(cleaned.status.success(), "{}", text(&cleaned.stderr));
    assert!(!fresh.join(&prefix).exists() && !fresh.join(format!("{prefix}.lock")).exists());
    assert!(shm_files(&prefix).is_empty());
    std::fs::remove_dir(&fresh).unwrap();
}
