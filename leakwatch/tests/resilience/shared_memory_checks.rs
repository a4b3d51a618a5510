//! Shared memory checked: the prefix's length limit, a damaged management segment, the directory.

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::*;

use crate::{assert_no_files_of, kill_run, prefix_of_len, run_command, shm_files, text, Running, SERIAL};

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
