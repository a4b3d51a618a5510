//! Signed Zenoh messages end to end (in one process, over TCP on loopback): a
//! `watch` with the shared key prints a gateway's signed event as it is, marks
//! a forged event (published unsigned on the rig's key, or signed with another
//! key) `UNVERIFIED`, and leaves out replays of a signed message (the same
//! message again, or one signed too long ago), counting each.

use std::io::Write;
use std::net::TcpListener;
use std::os::unix::fs::PermissionsExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use config::live::ZenohConfig;
use live::gateway::{open_session, Gateway};
use live::sign::{unix_ns, Signer};
use live::{LiveTopic, Sink};
use zenoh::Wait;

/// What the watch printed, shared with the test.
#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Shared {
    fn text(&self) -> String {
        String::from_utf8_lossy(&self.0.lock().unwrap_or_else(|e| e.into_inner())).into_owned()
    }
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A key file of `key`, mode 0600, in `dir`.
fn key_file(dir: &std::path::Path, name: &str, key: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, format!("{key}\n")).unwrap();
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o600)).unwrap();
    p
}

fn event(t: f64, size: f64) -> Vec<u8> {
    serde_json::json!({"t_detect_s": t, "phase": "raised", "kind": "ext1", "size_lpm": size,
        "size_lpm_sigma": 0.01, "t_onset_s": t - 1.0, "confidence": 0.97, "detector": "leak-size", "event_id": 7})
    .to_string()
    .into_bytes()
}

/// Waits until the watch printed a line with `what`, calling `tick` in between.
fn wait_for(out: &Shared, what: &str, mut tick: impl FnMut()) {
    let t0 = Instant::now();
    while !out.text().contains(what) {
        assert!(
            t0.elapsed() < Duration::from_secs(30),
            "never printed {what:?}:\n{}",
            out.text()
        );
        tick();
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn a_watch_with_the_key_marks_forged_events_and_leaves_out_replays() {
    let dir = std::env::temp_dir().join(format!("lw-zenoh-auth-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let key = "0123456789abcdef0123456789abcdef-shared";
    let shared = key_file(&dir, "key", key);
    let other = key_file(&dir, "other", "another key, also of thirty-two bytes or more");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let watch_cfg = ZenohConfig {
        listen: vec![endpoint.clone()],
        connect: vec![],
        key_file: Some(shared.clone()),
        ..ZenohConfig::default()
    };
    let out = Shared::default();
    static STOP: AtomicBool = AtomicBool::new(false);
    let watcher = {
        let mut out = out.clone();
        std::thread::spawn(move || live::watch::watch(&watch_cfg, Some(60.0), &STOP, &mut out))
    };
    wait_for(&out, "subscribed to leakwatch/**", || {});
    let gw_cfg = |key_file: Option<PathBuf>| ZenohConfig {
        connect: vec![endpoint.clone()],
        key_file,
        ..ZenohConfig::default()
    };
    let mut signed = Gateway::open("zS", &gw_cfg(Some(shared.clone()))).expect("the signed gateway");
    let health = br#"{"t_s": 1.0, "status": "healthy"}"#;
    wait_for(&out, "status healthy", || {
        signed.send(LiveTopic::Health, health, 0)
    });
    // a forger on the same network without the key, and one with another key
    let mut unsigned = Gateway::open("zS", &gw_cfg(None)).expect("an unsigned gateway");
    let mut wrong = Gateway::open("zS", &gw_cfg(Some(other))).expect("a gateway with another key");
    wait_for(&out, "UNVERIFIED (no signature)", || {
        unsigned.send(LiveTopic::Events, &event(43.0, 99.0), 0)
    });
    wait_for(
        &out,
        "UNVERIFIED (a signature the shared key did not make)",
        || wrong.send(LiveTopic::Events, &event(44.0, 98.0), 0),
    );
    // forged health is left out: the status stays
    unsigned.send(LiveTopic::Health, br#"{"t_s": 2.0, "status": "leak"}"#, 0);
    signed.send(LiveTopic::Events, &event(42.5, 0.8125), 0);
    wait_for(&out, "t =   42.500 s", || {});
    // replays: the same signed message twice, and one signed 60 s ago
    let session = open_session(&gw_cfg(None)).expect("a raw session");
    let key_expr = "leakwatch/zS/events";
    let mut signer = Signer::new(key.as_bytes().to_vec());
    let payload = event(45.0, 0.5);
    let att = signer.sign(key_expr, &payload);
    let old = signer.sign_at(key_expr, &event(46.0, 0.5), unix_ns() - 60_000_000_000);
    wait_for(&out, "t =   45.000 s", || {
        session
            .put(key_expr, payload.clone())
            .attachment(att.clone())
            .wait()
            .unwrap();
    });
    for _ in 0..3 {
        session
            .put(key_expr, payload.clone())
            .attachment(att.clone())
            .wait()
            .unwrap();
        session
            .put(key_expr, event(46.0, 0.5))
            .attachment(old.clone())
            .wait()
            .unwrap();
    }
    std::thread::sleep(Duration::from_millis(500));
    STOP.store(true, Ordering::Relaxed);
    let seen = watcher.join().unwrap().expect("the watch ends");
    let text = out.text();
    let lines: Vec<&str> = text.lines().collect();
    // the signed event as it is, once; the forged ones marked
    let plain = |t: &str| {
        lines
            .iter()
            .filter(|l| l.starts_with(&format!("zS           t = {t}")))
            .count()
    };
    assert_eq!(plain("  42.500 s  raised   ext1"), 1, "{text}");
    assert_eq!(
        plain("  45.000 s"),
        1,
        "the replays of 45 s are left out:\n{text}"
    );
    assert_eq!(
        plain("  46.000 s"),
        0,
        "a message signed 60 s ago is left out:\n{text}"
    );
    for l in lines
        .iter()
        .filter(|l| l.contains("size 99.000") || l.contains("size 98.000"))
    {
        assert!(l.starts_with("UNVERIFIED ("), "{l}");
    }
    assert!(
        !text.contains("status leak"),
        "forged health is left out:\n{text}"
    );
    let r = &seen["zS"];
    assert!(r.unverified >= 3, "{}", r.unverified);
    assert!(r.replayed >= 6, "{}", r.replayed);
    assert!(
        text.contains(&format!(
            "UNVERIFIED {}, replays left out {}",
            r.unverified, r.replayed
        )),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A key file other users can read is refused, naming the file and the fix; a
/// short key too.
#[test]
fn a_key_file_must_be_private_and_long_enough() {
    let dir = std::env::temp_dir().join(format!("lw-zenoh-key-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let open = key_file(&dir, "open", "0123456789abcdef0123456789abcdef");
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o644)).unwrap();
    let cfg = ZenohConfig {
        key_file: Some(open.clone()),
        ..ZenohConfig::default()
    };
    let e = cfg.validate().unwrap_err();
    assert!(
        e.contains(&format!("[zenoh] key_file {}: mode 644", open.display())) && e.contains("chmod 600"),
        "{e}"
    );
    let short = key_file(&dir, "short", "too short");
    let e = ZenohConfig {
        key_file: Some(short),
        ..ZenohConfig::default()
    }
    .validate()
    .unwrap_err();
    assert!(e.contains("the key has 9 bytes; at least 32"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
