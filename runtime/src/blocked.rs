//! A prefix on which no iceoryx2 node can start (a global management segment
//! of another user, or a damaged one: docs/security.md): found at the start of
//! a run and before each restart of a stage, and named, instead of stages that
//! keep failing to start.

use std::path::Path;

use bus::BusConfig;

/// The start of the line a stage writes when its iceoryx2 node cannot be created.
const NODE_FAILURE: &str = "cannot create the iceoryx2 node";

/// Why a stage of the run on `cfg` cannot start (again): what
/// [`BusConfig::diagnose_blocked_start`] finds on the prefix's files, else the
/// line of the stage's log `stage_log` that says its node could not be created.
pub(super) fn why_blocked(cfg: &BusConfig, stage_log: Option<&Path>) -> Option<String> {
    if let Some(why) = cfg.diagnose_blocked_start() {
        return Some(why);
    }
    let log = stage_log?;
    let text = std::fs::read(log).ok()?;
    let text = String::from_utf8_lossy(&text);
    let line = text.lines().rev().find(|l| l.contains(NODE_FAILURE))?;
    let rest = line
        .split_once(NODE_FAILURE)
        .map_or(line, |(_, r)| r)
        .trim_start_matches(':')
        .trim();
    Some(format!(
        "its iceoryx2 node could not be created ({rest}); see {}",
        log.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stages_node_failure_is_read_off_its_log() {
        let d = scratch::ScratchDir::new("run-blocked");
        let cfg = BusConfig {
            iox_prefix: Some(format!("blk{}", std::process::id())),
            ..BusConfig::default()
        };
        let log = d.join("estimator-1.log");
        std::fs::write(&log, "estimator: rig r\n").unwrap();
        assert_eq!(why_blocked(&cfg, Some(&log)), None);
        assert_eq!(why_blocked(&cfg, None), None);
        std::fs::write(
            &log,
            "estimator: error: cannot create the iceoryx2 node: UnableToGenerateUniqueNodeId\n",
        )
        .unwrap();
        assert_eq!(
            why_blocked(&cfg, Some(&log)).as_deref(),
            Some(
                format!(
                    "its iceoryx2 node could not be created (UnableToGenerateUniqueNodeId); see {}",
                    log.display()
                )
                .as_str()
            )
        );
    }
}
