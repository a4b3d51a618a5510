//! The service manager's notifications (systemd's `sd_notify` protocol,
//! written over a Unix datagram socket, no library): `READY=1` once frames
//! flow, `WATCHDOG=1` only while they flow, `STATUS=` lines, `STOPPING=1` at
//! the end. Outside a service (`NOTIFY_SOCKET` unset) every call does nothing.

use std::os::unix::net::UnixDatagram;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How often the status line is refreshed, s.
const STATUS_EVERY_S: f64 = 1.0;

/// The service manager's socket and watchdog, read from the environment once.
#[derive(Debug)]
pub struct ServiceNotify {
    /// The socket messages go to, if a service manager gave one.
    socket: Option<(UnixDatagram, Target)>,
    /// Half the manager's watchdog interval: how often it is fed while frames flow.
    feed_every: Option<Duration>,
    /// When the watchdog was last fed.
    last_fed: Option<Instant>,
    /// When the status line was last sent.
    last_status: Option<Instant>,
    /// Whether `READY=1` was sent.
    ready: bool,
}

/// Where the manager listens: a path, or a name in Linux's abstract namespace (`@name`).
#[derive(Debug, Clone)]
enum Target {
    /// A socket file.
    Path(PathBuf),
    /// An abstract socket name (without the leading `@`).
    Abstract(Vec<u8>),
}

impl ServiceNotify {
    /// From `NOTIFY_SOCKET`, `WATCHDOG_USEC` and `WATCHDOG_PID` (the watchdog is
    /// this process's only if `WATCHDOG_PID` is unset or names it). An unusable
    /// value is said once on stderr and ignored: the run goes on without it.
    pub fn from_env() -> ServiceNotify {
        let socket = std::env::var_os("NOTIFY_SOCKET").map(PathBuf::from);
        let ours = std::env::var("WATCHDOG_PID")
            .ok()
            .is_none_or(|p| p.trim() == std::process::id().to_string());
        let usec = std::env::var("WATCHDOG_USEC")
            .ok()
            .filter(|_| ours)
            .and_then(|u| u.trim().parse::<u64>().ok())
            .filter(|&u| u > 0);
        ServiceNotify::new(socket, usec.map(Duration::from_micros))
    }

    /// A notifier writing to `socket` (a path, or `@name` for an abstract
    /// one), whose watchdog must be fed within `watchdog`.
    pub fn new(socket: Option<PathBuf>, watchdog: Option<Duration>) -> ServiceNotify {
        let socket = socket.and_then(|path| {
            let bytes = path.as_os_str().as_encoded_bytes();
            let target = match bytes.strip_prefix(b"@") {
                Some(name) => Target::Abstract(name.to_vec()),
                None => Target::Path(path.clone()),
            };
            // never blocks the watch: a message the manager's queue has no room for is dropped
            match UnixDatagram::unbound().and_then(|s| s.set_nonblocking(true).map(|()| s)) {
                Ok(s) => Some((s, target)),
                Err(e) => {
                    bus::say!(
                        "leakwatch run: NOTIFY_SOCKET {}: {e}; no service notifications",
                        path.display()
                    );
                    None
                }
            }
        });
        ServiceNotify {
            feed_every: watchdog.filter(|_| socket.is_some()).map(|w| w / 2),
            socket,
            last_fed: None,
            last_status: None,
            ready: false,
        }
    }

    /// Sends one message (`KEY=value` lines); a failed send is ignored (the
    /// manager's watchdog then acts, which is what it is for).
    fn send(&self, message: &str) {
        let Some((socket, target)) = &self.socket else {
            return;
        };
        let _ = match target {
            Target::Path(p) => socket.send_to(message.as_bytes(), p),
            Target::Abstract(name) => {
                use std::os::linux::net::SocketAddrExt;
                std::os::unix::net::SocketAddr::from_abstract_name(name)
                    .and_then(|a| socket.send_to_addr(message.as_bytes(), &a))
            }
        };
    }

    /// Called each round of the supervisor's watch: `READY=1` with the first
    /// frame, then `WATCHDOG=1` every half interval as long as a frame arrived
    /// within `stall` (`last_frame`: when the newest arrived), and `status`
    /// once a second.
    pub fn tick(
        &mut self,
        now: Instant,
        last_frame: Option<Instant>,
        stall: Duration,
        status: impl FnOnce() -> String,
    ) {
        if self.socket.is_none() {
            return;
        }
        let flowing = last_frame.is_some_and(|t| now.saturating_duration_since(t) <= stall);
        if flowing && !self.ready {
            self.ready = true;
            self.send(&format!("READY=1\nSTATUS={}", status()));
            self.last_status = Some(now);
            self.feed(now);
            return;
        }
        if flowing {
            if let Some(every) = self.feed_every {
                if self
                    .last_fed
                    .is_none_or(|t| now.saturating_duration_since(t) >= every)
                {
                    self.feed(now);
                }
            }
        }
        if self
            .last_status
            .is_none_or(|t| now.saturating_duration_since(t).as_secs_f64() >= STATUS_EVERY_S)
        {
            self.last_status = Some(now);
            self.send(&format!("STATUS={}", status()));
        }
    }

    /// Feeds the watchdog.
    fn feed(&mut self, now: Instant) {
        if self.feed_every.is_some() {
            self.send("WATCHDOG=1");
            self.last_fed = Some(now);
        }
    }

    /// Says the run is ending, with why.
    pub fn stopping(&self, why: &str) {
        self.send(&format!("STOPPING=1\nSTATUS={why}"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every message the socket has, in order.
    fn drain(rx: &UnixDatagram) -> Vec<String> {
        rx.set_nonblocking(true).expect("nonblocking");
        let mut out = Vec::new();
        let mut buf = [0u8; 512];
        while let Ok(n) = rx.recv(&mut buf) {
            out.push(String::from_utf8_lossy(&buf[..n]).into_owned());
        }
        out
    }

    #[test]
    fn ready_comes_with_the_first_frame_and_the_watchdog_is_fed_only_while_frames_flow() {
        let dir = scratch::ScratchDir::new("notify");
        let path = dir.path().join("notify.sock");
        let rx = UnixDatagram::bind(&path).expect("bind");
        let mut n = ServiceNotify::new(Some(path), Some(Duration::from_secs(2)));
        let t0 = Instant::now();
        let stall = Duration::from_millis(500);
        let status = || "watching".to_string();
        // no frame yet: a status, no READY, no WATCHDOG
        n.tick(t0, None, stall, status);
        assert_eq!(drain(&rx), vec!["STATUS=watching"]);
        // the first frame: READY (with the status) and a first feed
        n.tick(
            t0 + Duration::from_millis(10),
            Some(t0 + Duration::from_millis(10)),
            stall,
            status,
        );
        assert_eq!(drain(&rx), vec!["READY=1\nSTATUS=watching", "WATCHDOG=1"]);
        // frames flow: fed once per half interval (1 s: at 1.01 and 2.01 s), the status once a second
        let ms = |k: u64| t0 + Duration::from_millis(k);
        for k in (20..=2010).step_by(10) {
            n.tick(ms(k), Some(ms(k)), stall, status);
        }
        let got = drain(&rx);
        assert_eq!(got.iter().filter(|m| *m == "WATCHDOG=1").count(), 2, "{got:?}");
        assert!(
            got.iter().all(|m| m == "WATCHDOG=1" || m == "STATUS=watching"),
            "{got:?}"
        );
        // frames stop: no more feeding, however long
        for k in (2020..=6000).step_by(10) {
            n.tick(ms(k), Some(ms(2010)), stall, status);
        }
        let got = drain(&rx);
        assert!(!got.iter().any(|m| m == "WATCHDOG=1"), "{got:?}");
        assert!(got.len() >= 3, "the status goes on: {got:?}");
        n.stopping("the stream ended");
        assert_eq!(drain(&rx), vec!["STOPPING=1\nSTATUS=the stream ended"]);
    }

    #[test]
    fn without_a_socket_nothing_is_sent_and_nothing_fails() {
        let mut n = ServiceNotify::new(None, Some(Duration::from_secs(1)));
        let t = Instant::now();
        n.tick(t, Some(t), Duration::from_secs(1), || {
            unreachable!("no status without a manager")
        });
        n.stopping("end");
    }
}
