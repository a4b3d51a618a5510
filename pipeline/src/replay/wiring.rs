//! How a replay's stages are connected ([`super::Wiring`]): the reader, the
//! estimator and the sink in the calling thread or on three threads over
//! bounded channels, with the progress shown and counted as it goes.

use dataset::{Issue, Row, RowSource};
use filter::{EstimatorStage, StageEstimate};
use model::Sample;

use super::{ReplayRequest, Summary};

/// What the reader thread sends: a batch of samples, or an issue that ended one.
enum Batch {
    Samples(Vec<Sample>),
    Issue(Issue),
}

/// Samples per batch on the reader's channel.
const BATCH: usize = 2048;

/// Counts an input problem in `summary`: a skipped row by its reason, and its
/// text among the first 100 issues.
fn on_issue(issue: &Issue, summary: &mut Summary) {
    if issue.skipped {
        summary.rows_skipped += 1;
        *summary
            .rows_rejected
            .entry(issue.kind.name().to_string())
            .or_insert(0) += 1;
    }
    if summary.issues.len() < 100 {
        summary.issues.push(issue.to_string());
    }
}

/// The replay's progress: the bar on a terminal and the samples counted in
/// `req.samples_done`.
pub(super) struct Progress<'a> {
    /// The spinner (hidden when not asked for or off a terminal).
    pub(super) bar: indicatif::ProgressBar,
    /// Samples already added to `done`.
    counted: std::cell::Cell<u64>,
    done: Option<&'a std::sync::Arc<std::sync::atomic::AtomicU64>>,
}

impl<'a> Progress<'a> {
    /// The progress of the replay `req`.
    pub(super) fn new(req: &'a ReplayRequest) -> Progress<'a> {
        Progress {
            bar: progress_bar(req.progress),
            counted: std::cell::Cell::new(0),
            done: req.samples_done.as_ref(),
        }
    }

    /// Adds the samples processed since the last call to `req.samples_done`.
    pub(super) fn count(&self, samples: u64) {
        if let Some(c) = self.done {
            c.fetch_add(samples - self.counted.get(), std::sync::atomic::Ordering::Relaxed);
            self.counted.set(samples);
        }
    }

    /// Shows and counts `samples` processed so far.
    fn tick(&self, samples: u64) {
        self.bar.set_position(samples);
        self.count(samples);
    }
}

/// Replays `reader` through `stage` into `sink` in the calling thread; returns
/// the counts of absent optional values.
pub(super) fn replay_single_thread(
    mut reader: impl RowSource,
    stage: &mut EstimatorStage,
    summary: &mut Summary,
    sink: &mut impl FnMut(&StageEstimate, &mut Summary),
    progress: &Progress<'_>,
) -> [u64; dataset::N_OPTIONAL] {
    let mut e = StageEstimate::default();
    while let Some(row) = reader.next_row() {
        let sample = match row {
            Row::Sample(s) => s,
            Row::AfterGap(s, issue) => {
                on_issue(&issue, summary);
                s
            }
            Row::Skipped(issue) => {
                on_issue(&issue, summary);
                continue;
            }
        };
        stage.on_sample_flagged_into(&sample, false, &mut e);
        sink(&e, summary);
        if summary.samples.is_multiple_of(65536) {
            progress.tick(summary.samples);
        }
    }
    reader.absent()
}

/// Replays `reader` through `stage` into `sink` on three threads (reader,
/// estimator, the caller's) over bounded channels; returns the counts of
/// absent optional values. The batches' buffers go back to the thread that
/// fills them once read, so a replay allocates them once, not per batch.
pub(super) fn replay_channels(
    reader: impl RowSource + Send,
    stage: &mut EstimatorStage,
    summary: &mut Summary,
    sink: &mut impl FnMut(&StageEstimate, &mut Summary),
    progress: &Progress<'_>,
) -> [u64; dataset::N_OPTIONAL] {
    let (tx_in, rx_in) = crossbeam_channel::bounded::<Batch>(IN_FLIGHT);
    let (tx_out, rx_out) = crossbeam_channel::bounded::<(Vec<StageEstimate>, Vec<Issue>)>(IN_FLIGHT);
    // the emptied buffers, back to the reader and to the estimator
    let (tx_free_in, rx_free_in) = crossbeam_channel::bounded::<Vec<Sample>>(RECYCLED);
    let (tx_free_out, rx_free_out) = crossbeam_channel::bounded::<Vec<StageEstimate>>(RECYCLED);
    std::thread::scope(|scope| {
        let read = scope.spawn(move || read_batches(reader, &tx_in, &rx_free_in));
        let stage = &mut *stage;
        scope.spawn(move || {
            for b in rx_in {
                let msg = match b {
                    Batch::Samples(samples) => {
                        let mut ests = rx_free_out
                            .try_recv()
                            .unwrap_or_else(|_| Vec::with_capacity(BATCH));
                        // (a recycled buffer has the batch's length already)
                        ests.resize(samples.len(), StageEstimate::default());
                        for (s, e) in samples.iter().zip(ests.iter_mut()) {
                            stage.on_sample_flagged_into(s, false, e);
                        }
                        // (a full return channel: the buffer is dropped)
                        let _ = tx_free_in.try_send(samples);
                        (ests, Vec::new())
                    }
                    Batch::Issue(issue) => (Vec::new(), vec![issue]),
                };
                if tx_out.send(msg).is_err() {
                    return;
                }
            }
        });
        for (ests, issues) in rx_out {
            for e in &ests {
                sink(e, summary);
            }
            for issue in &issues {
                on_issue(issue, summary);
            }
            progress.tick(summary.samples);
            if ests.capacity() > 0 {
                let _ = tx_free_out.try_send(ests);
            }
        }
        read.join().unwrap_or_default()
    })
}

/// Batches on each channel at most.
const IN_FLIGHT: usize = 8;

/// Emptied buffers kept for reuse on each return channel (more than can be
/// in flight at once, so none is dropped).
const RECYCLED: usize = 2 * IN_FLIGHT + 4;

/// Reads `reader` to its end in batches of [`BATCH`] samples onto `tx_in`, an
/// issue (a gap, a skipped row) ending a batch and following it, each batch
/// in a buffer from `free` when one is back (else a new one); returns the
/// counts of absent optional values. Stops early when the receiver is gone.
fn read_batches(
    mut reader: impl RowSource,
    tx_in: &crossbeam_channel::Sender<Batch>,
    free: &crossbeam_channel::Receiver<Vec<Sample>>,
) -> [u64; dataset::N_OPTIONAL] {
    let empty = || {
        let mut v = free.try_recv().unwrap_or_else(|_| Vec::with_capacity(BATCH));
        v.clear();
        v
    };
    let mut batch = empty();
    while let Some(row) = reader.next_row() {
        match row {
            Row::Sample(s) => batch.push(s),
            Row::AfterGap(s, issue) => {
                batch.push(s);
                let full = std::mem::replace(&mut batch, empty());
                if tx_in.send(Batch::Samples(full)).is_err() || tx_in.send(Batch::Issue(issue)).is_err() {
                    return reader.absent();
                }
            }
            Row::Skipped(issue) => {
                let full = std::mem::replace(&mut batch, empty());
                if tx_in.send(Batch::Samples(full)).is_err() || tx_in.send(Batch::Issue(issue)).is_err() {
                    return reader.absent();
                }
            }
        }
        if batch.len() == BATCH {
            let full = std::mem::replace(&mut batch, empty());
            if tx_in.send(Batch::Samples(full)).is_err() {
                return reader.absent();
            }
        }
    }
    let _ = tx_in.send(Batch::Samples(batch));
    reader.absent()
}

/// A spinner of samples and their rate on stderr, if `enabled` and a terminal; else a hidden one.
fn progress_bar(enabled: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !enabled || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {pos} samples  {per_sec}  {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar
}
