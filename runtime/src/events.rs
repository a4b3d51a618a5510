//! The events a run receives: only those of this run's classifier are kept,
//! and each is printed as it comes.

use std::collections::BTreeMap;
use std::process::Child;

use classifier::wire::EventWire;
use detect::LeakEvent;
use frames::LeakEventFrame;

use crate::stages::Stage;
use bus::say as errln;
use pipeline::out::outln;

/// The classifier's process id in `children` (a map of running children, or of pids).
pub(super) trait ClassifierPid {
    fn classifier_pid(&self) -> Option<u32>;
}

impl ClassifierPid for BTreeMap<Stage, Child> {
    fn classifier_pid(&self) -> Option<u32> {
        self.iter().find(|(s, _)| s.classifies()).map(|(_, c)| c.id())
    }
}

impl ClassifierPid for BTreeMap<Stage, u32> {
    fn classifier_pid(&self) -> Option<u32> {
        self.iter().find(|(s, _)| s.classifies()).map(|(_, pid)| *pid)
    }
}

/// The event of a frame if this run's classifier published it (iceoryx2's sample
/// header names the publishing process); a frame from any other publisher, or one
/// not understood, is reported on stderr, counted in `foreign` and left out.
pub(super) fn own_event(
    f: &bus::Received<LeakEventFrame>,
    children: &impl ClassifierPid,
    foreign: &mut u64,
) -> Option<LeakEvent> {
    let own = children.classifier_pid();
    if f.publisher_pid != 0 && own.is_some_and(|pid| pid != f.publisher_pid) {
        *foreign += 1;
        if *foreign <= 10 {
            errln!(
                "leakwatch run: warning: an event from process {} (not this run's classifier, process {}) was left out",
                f.publisher_pid,
                own.unwrap_or(0)
            );
        }
        return None;
    }
    match LeakEvent::from_frame(&f.frame) {
        Ok(ev) => Some(ev),
        Err(e) => {
            errln!("leakwatch run: an event frame was not understood ({e}); left out");
            None
        }
    }
}

pub(super) fn print_event(ev: &LeakEvent) -> Result<(), String> {
    let size = if ev.size_lpm.is_finite() {
        format!(" size {:.3} ± {:.3} L/min", ev.size_lpm, ev.size_lpm_sigma)
    } else {
        String::new()
    };
    outln!(
        "  t = {:7.3} s  {:<10} {:<8} {:<16} onset {:.2} s{size}  confidence {:.2}",
        ev.t_detect_s,
        ev.detector,
        format!("{:?}", ev.phase).to_lowercase(),
        ev.kind.name(),
        ev.t_onset_s,
        ev.confidence
    );
    Ok(())
}
