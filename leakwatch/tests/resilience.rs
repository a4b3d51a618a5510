//! Monitoring goes on when what is around it fails, with real
//! processes and real files: a recorder whose log hits a file-size limit (a full
//! disk without root: RLIMIT_FSIZE set on the running recorder, which ignores
//! SIGXFSZ, so its write fails with EFBIG), and the shared memory a killed run
//! leaves (removed by the next start on its prefix and by `leakwatch clean`).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::Mutex;

mod common;
use common::*;

#[path = "resilience/leftovers.rs"]
mod leftovers;
#[path = "resilience/recorder_failures.rs"]
mod recorder_failures;
#[path = "resilience/shared_memory_checks.rs"]
mod shared_memory_checks;

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
