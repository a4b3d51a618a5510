//! The live outputs, end to end with real processes: the Foxglove live view of
//! a running pipeline read by a WebSocket client (Python's `websockets`), and
//! the Zenoh fleet: two rigs' gateways (a whole `leakwatch run --zenoh-connect`
//! and a gateway stage fed over the bus by the test) reaching one `leakwatch
//! watch`, and Python's `eclipse-zenoh` subscribing to a gateway.
//!
//! The Python clients need `websockets` and `eclipse-zenoh` (.ci/setup
//! installs them); CI sets LEAKWATCH_REQUIRE_PYTHON=1, so they must run there.

use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

mod common;

#[path = "live/live_view.rs"]
mod live_view;
#[path = "live/live_view_access.rs"]
mod live_view_access;
#[path = "live/zenoh_fleet.rs"]
mod zenoh_fleet;

const BIN: &str = env!("CARGO_BIN_EXE_leakwatch");

/// The tests that run a pipeline share two cores: one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn example(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(path)
}

/// A TCP port free on the loopback interface now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn sigterm(child: &Child) {
    // SAFETY: kill(2) on our own child's pid.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
}

/// A child whose stdout lines are gathered as they come.
struct Lines {
    child: Child,
    lines: Arc<Mutex<Vec<String>>>,
}

impl Lines {
    fn spawn(cmd: &mut Command) -> Lines {
        let mut child = cmd.stdout(Stdio::piped()).spawn().expect("the process starts");
        let out = child.stdout.take().unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let l = lines.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                l.lock().unwrap().push(line);
            }
        });
        Lines { child, lines }
    }

    fn text(&self) -> String {
        self.lines.lock().unwrap().join("\n")
    }

    fn has(&self, pred: impl Fn(&str) -> bool) -> bool {
        self.lines.lock().unwrap().iter().any(|l| pred(l))
    }

    /// Waits up to `secs` for a line matching `pred`, calling `tick` every 50 ms meanwhile.
    fn wait_for(&self, secs: f64, what: &str, pred: impl Fn(&str) -> bool, mut tick: impl FnMut()) {
        let t0 = Instant::now();
        while !self.has(&pred) {
            assert!(
                t0.elapsed().as_secs_f64() < secs,
                "no {what} within {secs} s; output:\n{}",
                self.text()
            );
            tick();
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}
