//! A restarted recorder continues the run's log in a new numbered part
//! (`run-1.mcap`, `run-2.mcap`, …). What the killed recorder had not yet
//! written (its last, unflushed chunk) and the frames sent while no recorder
//! ran are in no part: the new part records them as one gap of the `frames`
//! topic, from the frame after the last one the earlier parts hold to the
//! first one it received.
//!
//! The earlier parts are read in a thread (a long run's log takes a while),
//! so the new recorder starts draining its topics at once.

use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

use frames::Topic;

use crate::{GapRecord, LogReader};

/// The highest frame sequence number held by the log parts `parts` (earliest
/// first; a later part is looked at first, an earlier one only if the later
/// holds no frame), read up to the last complete chunk of a killed
/// recorder's file ([`LogReader::last_frame_seq`]: a part is held in memory
/// while it is read, its messages are not). `None` if no part could be read or none holds a frame;
/// the parts that could not be read are named in the second value.
pub fn last_logged_frame(parts: &[PathBuf]) -> (Option<u64>, Vec<String>) {
    let mut problems = Vec::new();
    for part in parts.iter().rev() {
        match LogReader::open(part).and_then(|r| r.last_frame_seq()) {
            Ok(Some(seq)) => return (Some(seq), problems),
            Ok(None) => {}
            Err(e) => problems.push(e.to_string()),
        }
    }
    (None, problems)
}

/// The gap between the earlier parts' last frame `last_logged` (`None`: they
/// hold none, so the run's frames from 0 are missing) and the first frame this
/// part received, `first_seq` at `recv_mono_ns`; `None` if nothing is missing.
pub fn continuation_gap(last_logged: Option<u64>, first_seq: u64, recv_mono_ns: u64) -> Option<GapRecord> {
    let expected_seq = last_logged.map_or(0, |s| s.saturating_add(1));
    (first_seq > expected_seq).then(|| GapRecord {
        topic: Topic::Frames,
        expected_seq,
        got_seq: first_seq,
        missing: first_seq - expected_seq,
        recv_mono_ns,
    })
}

/// The search of the earlier parts, running in its own thread.
pub(crate) struct Continuation {
    search: Option<JoinHandle<(Option<u64>, Vec<String>)>>,
    /// The earlier parts' last frame, once the search is done.
    last_logged: Option<Option<u64>>,
}

impl Continuation {
    /// Starts reading `parts` (the run's earlier log parts, earliest first).
    pub(crate) fn start(parts: Vec<PathBuf>) -> Result<Continuation, String> {
        let search = std::thread::Builder::new()
            .name("earlier-parts".into())
            .spawn(move || last_logged_frame(&parts))
            .map_err(|e| format!("cannot start reading the earlier log parts: {e}"))?;
        Ok(Continuation {
            search: Some(search),
            last_logged: None,
        })
    }

    /// The earlier parts' last frame if the search is over (`wait`: wait for it).
    fn poll(&mut self, wait: bool) -> Option<Option<u64>> {
        if let Some(h) = self.search.take_if(|h| wait || h.is_finished()) {
            let (last, problems) = h.join().unwrap_or((None, vec!["the search panicked".into()]));
            for p in problems {
                bus::say!("recorder: an earlier log part could not be read: {p}");
            }
            self.last_logged = Some(last);
        }
        self.last_logged
    }

    /// `None` until the search is over and this part's first frame (`first`:
    /// sequence number, receive time in ns) is known; then the gap to record, if
    /// any (the caller asks no more). `wait`: the recorder is ending; wait for
    /// the search.
    pub(crate) fn gap(&mut self, first: Option<(u64, u64)>, wait: bool) -> Option<Option<GapRecord>> {
        let (first_seq, recv) = first?;
        let last = self.poll(wait)?;
        let gap = continuation_gap(last, first_seq, recv);
        bus::say!(
            "recorder: continuing the run's log: the earlier parts end at frame {}, this part starts at frame \
             {first_seq}; {} frames are in no part (recorded as a gap)",
            last.map_or("none".to_string(), |s| s.to_string()),
            gap.map_or(0, |g| g.missing)
        );
        Some(gap)
    }
}

/// The earlier parts of the log `out` named on the command line, each followed
/// by its continuations ([`crate::with_continuations`]: `run.1.mcap`, ... after
/// `run.mcap`), checked to exist (a part the killed recorder never created is
/// left out).
pub(crate) fn existing_parts(parts: &[PathBuf], out: &Path) -> Vec<PathBuf> {
    parts
        .iter()
        .flat_map(|p| crate::with_continuations(p))
        .filter(|p| p.as_path() != out && p.is_file())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gap_runs_from_the_frame_after_the_last_logged_to_the_first_received() {
        let g = continuation_gap(Some(4_999), 7_321, 42).unwrap();
        assert_eq!(
            (g.topic, g.expected_seq, g.got_seq, g.missing, g.recv_mono_ns),
            (Topic::Frames, 5_000, 7_321, 2_321, 42)
        );
        assert_eq!(continuation_gap(Some(4_999), 5_000, 42), None, "nothing missing");
        assert_eq!(
            continuation_gap(Some(6_000), 5_000, 42),
            None,
            "overlap: nothing missing"
        );
        assert_eq!(continuation_gap(None, 300, 42).map(|g| g.missing), Some(300));
    }
}
