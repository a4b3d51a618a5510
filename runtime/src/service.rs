//! What `run` does for a service manager each round of its watch: the
//! notifications ([`crate::notify`]) and the pruning of old runs
//! ([`crate::retention`]).

use std::path::PathBuf;
use std::time::{Duration, Instant, SystemTime};

use bus::say as errln;

use crate::notify::ServiceNotify;
use crate::retention::{Retention, PRUNE_EVERY_S};

/// Frames count as flowing while the newest is at most this old, s.
const FLOWING_WITHIN_S: f64 = 1.0;

/// The service side of a run: notifications, and the runs directory kept within its limits.
#[derive(Debug)]
pub struct Service {
    /// The service manager's notifications (inactive outside a service).
    pub notify: ServiceNotify,
    /// The runs directory's limits, with `--runs-dir`.
    pub retention: Option<Retention>,
    /// This run's folder (never pruned).
    pub out_dir: PathBuf,
    /// When the runs directory was last pruned.
    last_prune: Option<Instant>,
    /// When the newest frame arrived.
    last_frame: Option<Instant>,
    /// Frames received.
    frames: u64,
    /// The rig id, named in the status line.
    rig: String,
}

impl Service {
    /// The service side of the run writing into `out_dir`.
    pub fn new(notify: ServiceNotify, retention: Option<Retention>, out_dir: PathBuf, rig: &str) -> Service {
        Service {
            rig: rig.to_string(),
            notify,
            retention,
            out_dir,
            last_prune: None,
            last_frame: None,
            frames: 0,
        }
    }

    /// Prunes the runs directory now (at the start) and says what went.
    pub fn prune(&mut self, now: Instant) {
        self.last_prune = Some(now);
        let Some(keep) = &self.retention else {
            return;
        };
        match keep.prune(&self.out_dir, SystemTime::now()) {
            Ok(removed) => {
                for r in removed {
                    errln!(
                        "leakwatch run: removed the old run {} (--keep-days/--keep-gib)",
                        r.display()
                    );
                }
            }
            Err(e) => errln!("leakwatch run: {e}"),
        }
    }

    /// `n` frames arrived at `now`.
    pub fn on_frames(&mut self, n: u64, now: Instant) {
        if n > 0 {
            self.frames += n;
            self.last_frame = Some(now);
        }
    }

    /// One round of the watch: notifications, and pruning every 10 minutes.
    pub fn tick(&mut self, now: Instant, events: usize) {
        let frames = self.frames;
        let rig = &self.rig;
        self.notify.tick(
            now,
            self.last_frame,
            Duration::from_secs_f64(FLOWING_WITHIN_S),
            || match frames {
                0 => format!("{rig}: waiting for the first frame"),
                _ => format!("{rig}: watching, {frames} frames, {events} events"),
            },
        );
        if self
            .last_prune
            .is_some_and(|t| now.saturating_duration_since(t) >= Duration::from_secs(PRUNE_EVERY_S))
        {
            self.prune(now);
        }
    }
}
