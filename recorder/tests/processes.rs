//! Real processes over real iceoryx2 services: the acquisition binary
//! publishing into the recorder binary, each run isolated by its own
//! `LEAKWATCH_IOX_PREFIX`.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use acquisition::{Acquired, SimSource, Source};
use model::{ActuatorParams, FaultSchedule, Scenario, Simulator};
use recorder::LogReader;

const RECORDER: &str = env!("CARGO_BIN_EXE_recorder");

/// Newest modification time of the files directly in `dirs` (relative to the workspace).
fn newest_source(dirs: &[&str]) -> std::time::SystemTime {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    dirs.iter()
        .filter_map(|d| std::fs::read_dir(root.join(d)).ok())
        .flatten()
        .filter_map(|e| e.ok()?.metadata().ok()?.modified().ok())
        .max()
        .unwrap_or(std::time::UNIX_EPOCH)
}

/// The acquisition binary, next to the recorder binary. Built (same cargo,
/// target directory and profile) only if it is missing or older than its
/// sources: a rebuild with this package's feature set can take a minute.
fn acquisition_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let recorder = Path::new(RECORDER);
        let bin = recorder.with_file_name("acquisition");
        let built = std::fs::metadata(&bin).and_then(|m| m.modified()).ok();
        let sources = newest_source(&[
            "acquisition/src",
            "bus/src",
            "frames/src",
            "model/src",
            "dataset/src",
        ]);
        if built.is_some_and(|b| b >= sources) {
            return bin;
        }
        let profile_dir = recorder.parent().unwrap();
        let target_dir = profile_dir.parent().unwrap();
        let mut cmd = Command::new(env!("CARGO"));
        cmd.args(["build", "-q", "-p", "acquisition", "--bin", "acquisition"])
            .env("CARGO_TARGET_DIR", target_dir)
            .current_dir(env!("CARGO_MANIFEST_DIR"));
        if profile_dir.file_name().is_some_and(|p| p == "release") {
            cmd.arg("--release");
        }
        let status = cmd
            .status()
            .expect("cannot run cargo to build the acquisition binary");
        assert!(status.success(), "building the acquisition binary failed");
        bin
    })
}

struct Run {
    prefix: String,
    dir: scratch::ScratchDir,
}

impl Run {
    fn new(tag: &str) -> Run {
        let prefix = format!("p{}{tag}", std::process::id());
        let dir = scratch::ScratchDir::new(&format!("rec-proc-{tag}"));
        Run { prefix, dir }
    }

    fn spawn(&self, bin: &Path, args: &[&str]) -> Child {
        Command::new(bin)
            .args(args)
            .env("LEAKWATCH_IOX_PREFIX", &self.prefix)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", bin.display()))
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        let cfg = bus::BusConfig {
            iox_prefix: Some(self.prefix.clone()),
            ..bus::BusConfig::default()
        };
        cfg.remove_isolated_files().ok();
    }
}

/// Waits until the log at `path` reads back at least `frames` frames.
fn wait_for_frames_on_disk(path: &Path, frames: usize, timeout: Duration) {
    let start = Instant::now();
    loop {
        let on_disk = LogReader::open(path)
            .and_then(|r| r.read())
            .map(|log| log.frames.len())
            .unwrap_or(0);
        if on_disk >= frames {
            return;
        }
        assert!(
            start.elapsed() < timeout,
            "{} holds {on_disk} frames after {timeout:?}",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn wait_with_timeout(child: &mut Child, timeout: Duration) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if start.elapsed() > timeout {
            child.kill().ok();
            panic!("process {} did not end within {timeout:?}", child.id());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn stderr_of(child: Child) -> String {
    let out = child.wait_with_output().unwrap();
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn simulate(seed: u64, seconds: f64, fault: &str) -> Vec<model::Sample> {
    let rig = ActuatorParams::default();
    let mut schedule = FaultSchedule::default();
    schedule.faults.push(model::Fault::parse(fault, &rig).unwrap());
    let scenario = Scenario::by_name("closed-loop-sine", seed, seconds).unwrap();
    let sim = Simulator::with_default_sensors(rig, scenario, schedule, seed).unwrap();
    let mut src = SimSource::new(sim, seconds);
    let mut out = Vec::new();
    while let Some(item) = src.next_item() {
        match item {
            Acquired::Sample(s) => out.push(s),
            other => panic!("{other:?}"),
        }
    }
    out
}

#[test]
fn acquisition_to_recorder_loses_nothing_and_matches_the_simulation() {
    let run = Run::new("a");
    let log_path = run.dir.join("run.mcap");
    let acq = acquisition_bin();
    let recorder = run.spawn(
        Path::new(RECORDER),
        &["--rig", "e2e", "--out", log_path.to_str().unwrap()],
    );
    let mut acquisition = run.spawn(
        acq,
        &[
            "--rig",
            "e2e",
            "--scenario",
            "closed-loop-sine",
            "--seconds",
            "3",
            "--seed",
            "11",
            "--fault",
            "ext1:0.3lpm@1s",
            "--wait-subscribers",
            "1",
        ],
    );
    let status = wait_with_timeout(&mut acquisition, Duration::from_secs(15));
    let acq_err = stderr_of(acquisition);
    assert!(status.success(), "acquisition failed: {acq_err}");
    let mut recorder = recorder;
    let status = wait_with_timeout(&mut recorder, Duration::from_secs(10));
    let rec_err = stderr_of(recorder);
    assert!(status.success(), "recorder failed: {rec_err}");
    eprintln!("{acq_err}{rec_err}");

    let log = LogReader::open(&log_path).unwrap().read().unwrap();
    assert!(log.truncated.is_none(), "{:?}", log.truncated);
    assert_eq!(log.frames.len(), 3000, "every published frame is in the log");
    assert!(log.gaps.is_empty(), "{:?}", log.gaps);
    assert!(log.frames.iter().enumerate().all(|(i, f)| f.seq == i as u64));
    assert!(log.frames.last().unwrap().flags & frames::sensor_flags::END_OF_STREAM != 0);
    assert!(log.frames.windows(2).all(|w| w[1].acq_mono_ns > w[0].acq_mono_ns));
    // the same simulation run directly, bit for bit
    let direct = simulate(11, 3.0, "ext1:0.3lpm@1s");
    assert_eq!(direct.len(), 3000);
    for (f, s) in log.frames.iter().zip(&direct) {
        let pairs = [
            (f.t_s, s.t_s),
            (f.u_v, s.u_v),
            (f.x_m, s.x_m),
            (f.p1_pa, s.p1_pa),
            (f.p2_pa, s.p2_pa),
            (f.x_sp_m, s.x_sp_m),
            (f.f_load_n, s.f_load_n),
            (f.ref_m, s.ref_m),
            (f.q_leak_lpm, s.q_leak_lpm),
        ];
        for (a, b) in pairs {
            assert_eq!(a.to_bits(), b.to_bits(), "seq {}: {a} != {b}", f.seq);
        }
    }
    // both processes published their stats into the log
    let stages: std::collections::BTreeSet<u32> = log.stats.iter().map(|s| s.stage).collect();
    assert!(stages.contains(&frames::stage::ACQUISITION) && stages.contains(&frames::stage::RECORDER));
    let acq_stats = log
        .stats
        .iter()
        .rfind(|s| s.stage == frames::stage::ACQUISITION)
        .unwrap();
    assert_eq!(acq_stats.frames_out, 3000);
    // the dataset export reads back through the dataset crate
    let csv_dir = run.dir.join("csv");
    recorder::export_csv(&log, &csv_dir, false).unwrap();
    let mut reader =
        dataset::CsvReader::open(&csv_dir.join("dataset.csv"), dataset::Limits::default()).unwrap();
    let mut n = 0;
    while let Some(row) = reader.next_row() {
        match row {
            dataset::Row::Sample(s) => assert_eq!(s.p1_pa.to_bits(), direct[n].p1_pa.to_bits()),
            other => panic!("row {n}: {other:?}"),
        }
        n += 1;
    }
    assert_eq!(n, 3000);
}

#[test]
fn a_killed_recorder_leaves_a_readable_file_and_sigterm_finishes_it() {
    let run = Run::new("k");
    let killed = run.dir.join("killed.mcap");
    let stopped = run.dir.join("stopped.mcap");
    let acq = acquisition_bin();
    let mut rec_kill = run.spawn(
        Path::new(RECORDER),
        &["--rig", "kill", "--out", killed.to_str().unwrap()],
    );
    let mut rec_term = run.spawn(
        Path::new(RECORDER),
        &["--rig", "kill", "--out", stopped.to_str().unwrap()],
    );
    let mut acquisition = run.spawn(
        acq,
        &[
            "--rig",
            "kill",
            "--seconds",
            "10",
            "--seed",
            "3",
            "--wait-subscribers",
            "2",
        ],
    );
    // kill once the first chunk (closed every 2 s) is on disk: a slow start
    // on a loaded machine must not leave the killed file empty
    wait_for_frames_on_disk(&killed, 500, Duration::from_secs(30));
    // SAFETY: plain kill(2) of our own children
    unsafe {
        libc::kill(rec_kill.id() as i32, libc::SIGKILL);
        libc::kill(rec_term.id() as i32, libc::SIGTERM);
    }
    let s_kill = wait_with_timeout(&mut rec_kill, Duration::from_secs(5));
    assert!(!s_kill.success());
    let s_term = wait_with_timeout(&mut rec_term, Duration::from_secs(5));
    let term_err = stderr_of(rec_term);
    assert!(s_term.success(), "{term_err}");
    assert!(term_err.contains("stopped by signal"), "{term_err}");
    wait_with_timeout(&mut acquisition, Duration::from_secs(30));

    let log = LogReader::open(&killed).unwrap().read().unwrap();
    assert!(log.truncated.is_some(), "a killed recorder leaves no footer");
    // chunks closed every 2 s: at least the first chunk is on disk
    assert!(log.frames.len() >= 500, "{} frames", log.frames.len());
    {
        let s: Vec<u64> = log.frames.iter().map(|f| f.seq).collect();
        let bad: Vec<_> = s
            .iter()
            .enumerate()
            .filter(|(i, f)| **f != *i as u64)
            .take(5)
            .collect();
        assert!(
            bad.is_empty(),
            "{} frames, {:?} batched {:?}",
            s.len(),
            bad,
            log.channels.keys().collect::<Vec<_>>()
        );
    }
    let log = LogReader::open(&stopped).unwrap().read().unwrap();
    assert!(log.truncated.is_none());
    // SIGTERM came before the 10 s run ended, after the first chunk
    assert!(
        log.frames.len() >= 500 && log.frames.len() < 10_000,
        "{}",
        log.frames.len()
    );
    assert!(log.frames.iter().enumerate().all(|(i, f)| f.seq == i as u64));
}
