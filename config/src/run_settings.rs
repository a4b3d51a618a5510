//! `[run]`: how `leakwatch run` places its stage processes on the machine.

use std::collections::BTreeMap;

use schema::int;
use serde::{Deserialize, Serialize};

/// The stage processes a CPU can be given to.
pub const PINNABLE: [&str; 5] = [
    "acquisition",
    "estimator",
    "classifier",
    "recorder",
    "estimator+classifier",
];

schema::config_struct! {
    /// `[run]` settings.
    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    pub struct RunSettings {
        /// CPU (core index, as the kernel numbers them) each named stage process is
        /// pinned to (`sched_setaffinity` before it starts); a stage not named runs
        /// wherever the scheduler puts it. E.g. `cpus = { acquisition = 0, "estimator+classifier" = 1 }`.
        pub cpus: BTreeMap<String, usize> = BTreeMap::new(),
        /// In low-latency mode, how long the acquisition's pacer spins before each
        /// deadline instead of sleeping, µs (0 = sleep only; event mode always sleeps).
        pub low_latency_spin_us: u64 = 60 => ["µs", int!(0, 900, "(less than the 1 ms period)")],
    }
}

impl RunSettings {
    /// Checks the declared ranges, the stage names and that each CPU exists on this machine.
    pub fn validate(&self) -> Result<(), String> {
        self.check_ranges("").map_err(|e| format!("[run] {e}"))?;
        let online = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        for (stage, cpu) in &self.cpus {
            if !PINNABLE.contains(&stage.as_str()) {
                return Err(format!(
                    "[run] cpus: unknown stage {stage:?}; the stages are {}",
                    PINNABLE.join(", ")
                ));
            }
            if *cpu >= online.max(cpu_count()) {
                return Err(format!(
                    "[run] cpus.{stage} = {cpu}: this machine has CPUs 0 to {}",
                    online.max(cpu_count()) - 1
                ));
            }
        }
        Ok(())
    }

    /// The CPU `stage` is pinned to, if any.
    pub fn cpu_of(&self, stage: &str) -> Option<usize> {
        self.cpus.get(stage).copied()
    }
}

/// CPUs configured on this machine (`_SC_NPROCESSORS_CONF`), at least 1.
fn cpu_count() -> usize {
    // SAFETY: sysconf has no preconditions.
    let n = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_CONF) };
    if n > 0 {
        n as usize
    } else {
        1
    }
}
