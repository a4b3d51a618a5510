//! When the supervisor restarts a stage that exited: exponential backoff,
//! forgiven after a healthy run, and a limit after which the run ends.

use std::time::Duration;

/// Delay before the first restart.
pub(super) const FIRST_DELAY: Duration = Duration::from_millis(200);
/// Longest delay between restarts (the delay doubles up to it).
pub(super) const MAX_DELAY: Duration = Duration::from_secs(5);
/// A stage that ran this long before it exited was healthy: its backoff starts again.
pub(super) const HEALTHY_RUN: Duration = Duration::from_secs(30);
/// Restarts without a healthy run in between after which the next failure ends the run
/// (with [`FIRST_DELAY`] and [`MAX_DELAY`]: about 31 s of trying).
pub(super) const MAX_RESTARTS: u32 = 10;

/// What to do with a stage that exited.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Decision {
    /// Start it again after this delay.
    RestartIn(Duration),
    /// It failed [`MAX_RESTARTS`] + 1 times without a healthy run: end the run.
    GiveUp,
}

/// The restart policy of one stage.
#[derive(Debug, Clone)]
pub(super) struct Backoff {
    /// Restarts since the stage last ran [`HEALTHY_RUN`].
    failures: u32,
    /// The delay of the next restart.
    next_delay: Duration,
}

impl Default for Backoff {
    fn default() -> Self {
        Backoff {
            failures: 0,
            next_delay: FIRST_DELAY,
        }
    }
}

impl Backoff {
    /// The stage exited after running for `ran_for` since its last start.
    pub(super) fn on_exit(&mut self, ran_for: Duration) -> Decision {
        if ran_for >= HEALTHY_RUN {
            *self = Backoff::default();
        }
        if self.failures >= MAX_RESTARTS {
            return Decision::GiveUp;
        }
        self.failures += 1;
        let delay = self.next_delay;
        self.next_delay = (delay * 2).min(MAX_DELAY);
        Decision::RestartIn(delay)
    }

    /// Restarts since the stage last ran [`HEALTHY_RUN`].
    pub(super) fn failures(&self) -> u32 {
        self.failures
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_delay_doubles_to_its_cap_and_the_eleventh_quick_failure_gives_up() {
        let mut b = Backoff::default();
        let quick = Duration::from_millis(100);
        let delays: Vec<u64> = (0..MAX_RESTARTS)
            .map(|_| match b.on_exit(quick) {
                Decision::RestartIn(d) => d.as_millis() as u64,
                Decision::GiveUp => panic!("gave up early"),
            })
            .collect();
        assert_eq!(delays, [200, 400, 800, 1600, 3200, 5000, 5000, 5000, 5000, 5000]);
        assert_eq!(b.on_exit(quick), Decision::GiveUp);
    }

    #[test]
    fn a_healthy_run_starts_the_backoff_again() {
        let mut b = Backoff::default();
        for _ in 0..MAX_RESTARTS {
            b.on_exit(Duration::from_secs(1));
        }
        assert_eq!(b.failures(), MAX_RESTARTS);
        assert_eq!(b.on_exit(HEALTHY_RUN), Decision::RestartIn(FIRST_DELAY));
        assert_eq!(b.failures(), 1);
        assert_eq!(
            b.on_exit(Duration::from_secs(29)),
            Decision::RestartIn(FIRST_DELAY * 2)
        );
    }
}
