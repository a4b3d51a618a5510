//! leakwatch as a service: the systemd unit verified by `systemd-analyze`, a
//! real `run` telling a service manager's socket READY, WATCHDOG and
//! STOPPING and pruning its runs directory, and the Debian package built,
//! unpacked into a scratch root and run from there.

mod common;

use std::os::unix::net::UnixDatagram;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, SystemTime};

use common::{stderr, tmpdir};

/// The repository's root (the workspace).
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// True if `program` runs here; false (the test skips) only where it is not
/// required (LEAKWATCH_REQUIRE_SYSTEMD unset: CI sets it).
fn have(program: &str) -> bool {
    let ok = Command::new(program)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var("LEAKWATCH_REQUIRE_SYSTEMD").is_err(),
            "{program} is required (.ci/setup installs it)"
        );
        eprintln!("skipped: no {program}");
    }
    ok
}

/// What `systemd-analyze verify` says of the unit file `path`.
fn verify(path: &Path) -> String {
    let o = Command::new("systemd-analyze")
        .args(["verify", "--man=no"])
        .arg(path)
        .output()
        .unwrap();
    format!("{}{}", String::from_utf8_lossy(&o.stdout), stderr(&o))
}

#[test]
fn the_unit_passes_systemd_analyze_verify() {
    if !have("systemd-analyze") {
        return;
    }
    let dir = tmpdir("unit");
    let unit = std::fs::read_to_string(repo().join("packaging/leakwatch@.service")).unwrap();
    assert!(unit.contains("Type=notify") && unit.contains("WatchdogSec=") && unit.contains("Restart=always"));
    // the unit as installed, but for the binary's path (verify checks that it is executable)
    let here = unit.replace("/usr/bin/leakwatch", env!("CARGO_BIN_EXE_leakwatch"));
    assert_ne!(here, unit, "the unit starts /usr/bin/leakwatch");
    let path = dir.path().join("leakwatch@rig1.service");
    std::fs::write(&path, here).unwrap();
    let said = verify(&path);
    // only what it says about this unit counts (a container's own units may be incomplete)
    let ours: Vec<&str> = said.lines().filter(|l| l.contains("leakwatch")).collect();
    assert!(ours.is_empty(), "systemd-analyze verify: {said}");
    // a unit with a mistake is caught: the check can fail
    let bad = std::fs::read_to_string(&path)
        .unwrap()
        .replace("Type=notify", "Type=notifyy");
    std::fs::write(&path, bad).unwrap();
    let said = verify(&path);
    assert!(said.contains("notifyy"), "a bad Type= is reported: {said}");
}

#[test]
fn a_run_tells_the_service_manager_ready_watchdog_and_stopping_and_prunes_old_runs() {
    let dir = tmpdir("notify");
    let sock = dir.path().join("notify.sock");
    let rx = UnixDatagram::bind(&sock).unwrap();
    rx.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let runs = dir.path().join("runs");
    // an earlier run, written three days ago: older than --keep-days 1
    let old = runs.join("leakwatch-run-20260101-000000");
    std::fs::create_dir_all(&old).unwrap();
    let f = old.join("events.json");
    std::fs::write(&f, "[]").unwrap();
    let three_days = SystemTime::now() - Duration::from_secs(3 * 86_400);
    std::fs::File::options()
        .write(true)
        .open(&f)
        .unwrap()
        .set_modified(three_days)
        .unwrap();
    let keep = runs.join("notes.txt");
    std::fs::write(&keep, "not a run").unwrap();

    // the manager's side: every message, read as it comes
    let reader = std::thread::spawn(move || {
        let mut got = Vec::new();
        let mut buf = [0u8; 1024];
        while let Ok(n) = rx.recv(&mut buf) {
            let m = String::from_utf8_lossy(&buf[..n]).into_owned();
            let last = m.starts_with("STOPPING=1");
            got.push(m);
            if last {
                break;
            }
        }
        got
    });
    let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
        .args([
            "run",
            "--seconds",
            "4",
            "--fault",
            "none",
            "--rig",
            "svc1",
            "--keep-days",
            "1",
        ])
        .arg("--runs-dir")
        .arg(&runs)
        .env("NOTIFY_SOCKET", &sock)
        .env("WATCHDOG_USEC", "1000000")
        .output()
        .unwrap();
    // 4 s is too short to arm the detector: the run says so with status 3 (NOT_WATCHED)
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let got = reader.join().unwrap();
    let ready = got
        .iter()
        .position(|m| m.starts_with("READY=1"))
        .expect("READY=1 sent");
    let fed = got.iter().filter(|m| *m == "WATCHDOG=1").count();
    // 4 s of frames, fed every 0.5 s
    assert!((6..=10).contains(&fed), "{fed} feeds: {got:?}");
    assert!(
        got[..ready].iter().all(|m| m != "WATCHDOG=1"),
        "fed before ready: {got:?}"
    );
    assert!(got[ready].contains("STATUS=svc1: watching"), "{got:?}");
    assert!(
        got.last()
            .is_some_and(|m| m.starts_with("STOPPING=1\nSTATUS=the run ended")),
        "{got:?}"
    );
    // the old run went, the run's own folder and what is not a run stay
    assert!(!old.exists(), "the 3-day-old run is removed");
    assert!(keep.exists());
    let folders: Vec<_> = std::fs::read_dir(&runs)
        .unwrap()
        .flatten()
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(folders.len(), 1, "{folders:?}");
    assert!(folders[0].starts_with("leakwatch-run-"), "{folders:?}");
    assert!(runs.join(&folders[0]).join("events.json").is_file());
}

#[test]
fn runs_dir_flags_are_checked_before_anything_starts() {
    let dir = tmpdir("flags");
    let runs = dir.path().join("runs");
    for (args, said) in [
        (
            vec!["--keep-days", "7"],
            "--keep-days and --keep-gib are for --runs-dir",
        ),
        (vec!["--runs-dir", "R", "--out", "O"], "--out and --runs-dir"),
        (vec!["--runs-dir", "R", "--keep-gib=-1"], "--keep-gib -1"),
        (vec!["--runs-dir", "R", "--keep-days", "NaN"], "--keep-days NaN"),
    ] {
        let args: Vec<String> = args
            .iter()
            .map(|a| match *a {
                "R" => runs.display().to_string(),
                "O" => dir.path().join("out").display().to_string(),
                a => a.to_string(),
            })
            .collect();
        let o = Command::new(env!("CARGO_BIN_EXE_leakwatch"))
            .arg("run")
            .args(&args)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{args:?} accepted");
        assert!(stderr(&o).contains(said), "{args:?}: {}", stderr(&o));
    }
    assert!(!runs.exists(), "nothing made for a refused run");
}

#[test]
fn the_debian_package_builds_unpacks_into_a_root_and_runs_from_there() {
    if !have("dpkg-deb") {
        return;
    }
    let dir = tmpdir("deb");
    let o = Command::new("bash")
        .arg(repo().join("packaging/deb.sh"))
        .args([
            "--binary",
            env!("CARGO_BIN_EXE_leakwatch"),
            "--compress",
            "none",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "deb.sh: {}", stderr(&o));
    let deb = PathBuf::from(
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .last()
            .unwrap_or_default(),
    );
    assert!(deb.is_file(), "{deb:?}");
    let info = Command::new("dpkg-deb")
        .arg("--field")
        .arg(&deb)
        .output()
        .unwrap();
    let info = String::from_utf8_lossy(&info.stdout).into_owned();
    assert!(
        info.contains("Package: leakwatch") && info.contains("Version: 0.1.0"),
        "{info}"
    );
    // dpkg installs it into a scratch root (unpack: no maintainer script runs on this host)
    let root = dir.path().join("root");
    std::fs::create_dir_all(root.join("var/lib/dpkg/updates")).unwrap();
    std::fs::create_dir_all(root.join("var/lib/dpkg/info")).unwrap();
    std::fs::write(root.join("var/lib/dpkg/status"), "").unwrap();
    let o = Command::new("dpkg")
        .arg(format!("--root={}", root.display()))
        .args(["--force-not-root", "--force-depends", "--unpack"])
        .arg(&deb)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "dpkg --unpack: {}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );
    for f in [
        "lib/systemd/system/leakwatch@.service",
        "usr/share/doc/leakwatch/service.md",
        "usr/share/doc/leakwatch/examples/rig.toml",
        "usr/share/doc/leakwatch/examples/rig.env.example",
    ] {
        assert!(root.join(f).is_file(), "{f} installed");
    }
    let o = Command::new(root.join("usr/bin/leakwatch"))
        .arg("--version")
        .output()
        .unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "leakwatch 0.1.0");
    // the example config the package ships is one leakwatch accepts
    let o = Command::new(root.join("usr/bin/leakwatch"))
        .args(["config", "--check"])
        .arg(root.join("usr/share/doc/leakwatch/examples/rig.toml"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}
