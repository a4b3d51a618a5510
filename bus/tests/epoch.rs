//! The run's one time base: `bus::init_epoch_offset` takes the offset `run`
//! hands its stages (`LEAKWATCH_EPOCH_OFFSET_NS`), refuses a value that is not
//! a whole number of ns naming it, and without it measures wall − monotonic.
//! Each case runs in a child process (the offset is fixed once per process).

use std::process::Command;

use bus::EPOCH_OFFSET_ENV;

const CHILD: &str = "EPOCH_PROBE_CHILD";

/// Runs this test binary's `probe` in a child with `value` in the variable.
fn run_probe(value: Option<&str>) -> String {
    let exe = std::env::current_exe().expect("the test binary");
    let mut cmd = Command::new(exe);
    cmd.args(["--exact", "probe", "--nocapture"]).env(CHILD, "1");
    match value {
        Some(v) => cmd.env(EPOCH_OFFSET_ENV, v),
        None => cmd.env_remove(EPOCH_OFFSET_ENV),
    };
    let o = cmd.output().expect("the test binary runs");
    let out = String::from_utf8_lossy(&o.stdout);
    out.lines()
        .find_map(|l| l.strip_prefix("PROBE "))
        .unwrap_or_else(|| panic!("no probe line in {out}"))
        .to_string()
}

/// The child's side: prints what `init_epoch_offset` gave, and `epoch_ns(5)`.
#[test]
fn probe() {
    if std::env::var(CHILD).is_err() {
        return;
    }
    let wall0 = bus::wall_clock_ns() as i128;
    let mono0 = bus::monotonic_ns() as i128;
    let r = bus::init_epoch_offset();
    let wall1 = bus::wall_clock_ns() as i128;
    let mono1 = bus::monotonic_ns() as i128;
    match r {
        Ok(off) => {
            // a measured offset lies between the two readings' bounds
            let measured = (wall0 - mono1) <= off as i128 && off as i128 <= (wall1 - mono0);
            println!(
                "PROBE ok {off} {} {} {measured}",
                bus::epoch_ns(5),
                bus::epoch_offset_ns() == off
            );
        }
        Err(e) => println!("PROBE err {e}"),
    }
}

#[test]
fn the_offset_comes_from_the_run_or_is_measured_once() {
    assert_eq!(
        run_probe(Some("1764000000000000000")),
        "ok 1764000000000000000 1764000000000000005 true false"
    );
    assert_eq!(run_probe(Some(" -7 ")), "ok -7 0 true false");
    let e = run_probe(Some("1.5e18"));
    assert!(
        e.starts_with("err LEAKWATCH_EPOCH_OFFSET_NS=\"1.5e18\": expected the wall clock minus CLOCK_MONOTONIC in ns, a whole number"),
        "{e}"
    );
    let m = run_probe(None);
    let parts: Vec<&str> = m.split(' ').collect();
    assert_eq!((parts[0], parts[3], parts[4]), ("ok", "true", "true"), "{m}");
    // (fields: offset, epoch_ns(5), the offset kept, the offset measured)
    // the wall clock of today, not the boot clock
    let off: i64 = parts[1].parse().expect("a number");
    assert!(off > 1_600_000_000_000_000_000, "{off}");
}
