//! The isolation prefix's length limit is the one iceoryx2 can take: a prefix
//! of [`bus::MAX_PREFIX_LEN`] characters opens a rig's services (a subscriber
//! with its wake listener, a publisher), and a longer one is refused when the
//! configuration is made, naming the limit, before any file is created.

use bus::{Bus, BusConfig, WaitMode, MAX_PREFIX_LEN, PREFIX_ENV};
use frames::SensorFrame;

/// A prefix of `len` characters unique to this process.
fn prefix(len: usize, tag: char) -> String {
    let p: String = format!("p{}{tag}", std::process::id())
        .chars()
        .chain(std::iter::repeat('x'))
        .take(len)
        .collect();
    assert_eq!(p.len(), len);
    p
}

/// Every path under `dir`, recursively.
fn paths(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            out.push(p.clone());
            if p.is_dir() {
                paths(&p, out);
            }
        }
    }
}

#[test]
fn the_longest_accepted_prefix_opens_every_service() {
    assert_eq!(MAX_PREFIX_LEN, 20);
    // 20 with the private directory /tmp/leakwatch-0 (root, no XDG_RUNTIME_DIR)
    let longest = bus::max_prefix_len_under(&bus::private_dir_path());
    let p = prefix(longest, 'a');
    let cfg = BusConfig {
        iox_prefix: Some(p.clone()),
        ..BusConfig::default()
    };
    let bus = Bus::open("rig1", cfg.clone()).expect("a prefix of the longest accepted length opens");
    let rx = bus
        .subscriber::<SensorFrame>(WaitMode::Event)
        .expect("a subscriber and its listener");
    let tx = bus
        .publisher::<SensorFrame>()
        .expect("a publisher and its notifier");
    // the listener's Unix socket, the path that limits the prefix:
    // <private dir>/<prefix>/lw_<prefix>_<id>.event
    use std::os::unix::fs::FileTypeExt;
    let mut all = Vec::new();
    let root = cfg.iox_root().expect("a root");
    assert_eq!(root, bus::private_dir().expect("private").join(&p));
    paths(&root, &mut all);
    let sockets: Vec<String> = all
        .iter()
        .filter(|p| std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_socket()))
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    assert!(!sockets.is_empty(), "{all:#?}");
    for s in &sockets {
        let id = s
            .strip_prefix(&format!("{}/lw_{p}_", root.display()))
            .and_then(|r| r.strip_suffix(".event"))
            .unwrap_or_else(|| panic!("an unexpected socket name: {s}"));
        assert!(id.bytes().all(|b| b.is_ascii_digit()) && id.len() >= 29, "{s}");
        // with the widest id a process can make (u128 whose top 32 bits are a
        // count: 39 digits) it still fits the 108 bytes of a socket address
        let widest = s.len() - id.len() + 39;
        let dir = bus::private_dir_path();
        assert_eq!(widest, dir.as_os_str().len() + 12 + 2 * longest + 39, "{s}");
        assert!(widest <= 108, "{widest} bytes");
        // one more character of prefix would not fit (two more bytes), unless
        // the limit is MAX_PREFIX_LEN with a shorter private directory
        assert!(widest + 2 > 108 || longest == MAX_PREFIX_LEN, "{widest} bytes");
    }
    drop((rx, tx, bus));
    cfg.remove_leftovers().expect("its files are removed");
}

#[test]
fn a_longer_prefix_is_refused_with_the_limit_before_any_file_is_made() {
    let p = prefix(MAX_PREFIX_LEN + 1, 'b');
    let cfg = BusConfig {
        iox_prefix: Some(p.clone()),
        ..BusConfig::default()
    };
    let e = cfg.iceoryx2_config().expect_err("too long").to_string();
    assert!(e.contains("has 21 characters; at most 20 work"), "{e}");
    assert!(e.contains(&p) && e.contains(PREFIX_ENV), "{e}");
    let e = Bus::open("rig1", cfg.clone()).err().expect("refused").to_string();
    assert!(e.contains("at most 20"), "{e}");
    let e = match cfg.lock_prefix() {
        Ok(_) => panic!("a lock on a prefix that is too long"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("at most 20"), "{e}");
    assert!(cfg.prefix_files().is_empty(), "{:?}", cfg.prefix_files());
    assert!(!cfg.iox_root().expect("a root").exists());
    // 20 of the allowed characters pass; a bad character is still named
    assert_eq!(bus::validate_prefix(&prefix(20, 'c')), Ok(()));
    let e = bus::validate_prefix("a b").expect_err("a space").0;
    assert!(e.contains("1 to 20 characters of A-Z a-z 0-9 _ -"), "{e}");
}

/// `BusConfig::from_env` (every stage's parsing) refuses the long prefix.
#[test]
fn the_environment_prefix_is_checked_when_it_is_read() {
    let exe = std::env::current_exe().expect("the test binary");
    if std::env::var("PREFIX_PROBE_CHILD").is_ok() {
        let r = BusConfig::from_env();
        println!(
            "{}",
            r.err().map(|e| e.to_string()).unwrap_or_else(|| "ok".into())
        );
        return;
    }
    for (len, want) in [(20, "ok"), (21, "has 21 characters; at most 20 work")] {
        let o = std::process::Command::new(&exe)
            .args([
                "--exact",
                "the_environment_prefix_is_checked_when_it_is_read",
                "--nocapture",
            ])
            .env("PREFIX_PROBE_CHILD", "1")
            .env(PREFIX_ENV, prefix(len, 'd'))
            .output()
            .expect("the test binary runs");
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains(want), "{len}: {out}");
    }
}

/// The limit follows the private directory's length: 20 under
/// `/tmp/leakwatch-0`, 16 under `/run/user/1000/leakwatch`, never above 20.
#[test]
fn the_prefix_limit_follows_the_private_directory() {
    use std::path::Path;
    assert_eq!(bus::max_prefix_len_under(Path::new("/tmp/leakwatch-0")), 20);
    assert_eq!(bus::max_prefix_len_under(Path::new("/tmp/leakwatch-1000")), 19);
    assert_eq!(
        bus::max_prefix_len_under(Path::new("/run/user/1000/leakwatch")),
        16
    );
    assert_eq!(bus::max_prefix_len_under(Path::new("/t")), MAX_PREFIX_LEN);
    // the socket of the widest id: <dir>/<prefix>/lw_<prefix>_<39 digits>.event
    let dir = "/run/user/1000/leakwatch";
    let fits = |n: usize| dir.len() + 1 + n + 1 + 3 + n + 1 + 39 + 6 <= 108;
    assert!(fits(16) && !fits(17));
}
