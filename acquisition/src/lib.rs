//! Sample sources for the acquisition stage: the simulated rig, file replay
//! and a real rig's UDP sensor stream ([`udp::UdpSource`]) behind one
//! [`Source`] trait.
//!
//! A source yields [`Acquired`] items in time order: usable samples, and the
//! problems of rows that could not be used (counted, never silently filled).
//! A *live* source ([`Source::is_live`], the UDP stream) is paced by its
//! sender: the acquisition publishes each of its samples on arrival.

pub mod shell;
pub mod udp;
use std::path::Path;

pub use udp::{scaled_sample, UdpCounts, UdpEnd, UdpOptions, UdpSource};

use model::sim::Simulator;
use model::Sample;

/// One item from a source.
#[derive(Debug, Clone, PartialEq)]
pub enum Acquired {
    /// A usable sample.
    Sample(Sample),
    /// A usable sample after a gap of `missing` samples.
    AfterGap {
        /// The sample.
        sample: Sample,
        /// Samples missing before it.
        missing: u64,
    },
    /// A row that could not be used, with the reason.
    Unusable(String),
}

/// Something that produces rig samples at a nominal rate.
pub trait Source: Send {
    /// The next item, or `None` when the source is exhausted.
    fn next_item(&mut self) -> Option<Acquired>;
    /// The nominal sample period, s.
    fn sample_period_s(&self) -> f64;
    /// A one-line description for logs.
    fn describe(&self) -> String;
    /// Whether the sender paces the source (a live stream): the acquisition
    /// publishes each sample as it arrives, with no pacing of its own and no
    /// look-ahead. Default: false (the acquisition paces, e.g. at 1 kHz).
    fn is_live(&self) -> bool {
        false
    }
    /// Whether the stream has ended: the next call of [`Source::next_item`]
    /// returns `None` (a live source that received its sender's end of stream
    /// says so right after the last sample). Default: false (not known ahead).
    fn ended(&self) -> bool {
        false
    }
    /// `CLOCK_MONOTONIC` when the last item arrived, ns (live sources; for
    /// the receive-to-publish latency). Default: `None`.
    fn arrival_mono_ns(&self) -> Option<u64> {
        None
    }
    /// A closing line with the source's own counts, if it keeps any. Default: `None`.
    fn summary(&self) -> Option<String> {
        None
    }
}

/// The simulated rig as a source, for a fixed number of samples.
pub struct SimSource {
    sim: Simulator,
    remaining: u64,
    name: String,
}

impl SimSource {
    /// Runs `sim` for `seconds`.
    pub fn new(sim: Simulator, seconds: f64) -> Self {
        let remaining = (seconds / sim.sample_period_s()).round().max(0.0) as u64;
        let name = format!("simulated rig, scenario {}, {seconds} s", sim.scenario().name);
        SimSource { sim, remaining, name }
    }

    /// The simulator (for its truth).
    pub fn simulator(&self) -> &Simulator {
        &self.sim
    }
}

impl Source for SimSource {
    fn next_item(&mut self) -> Option<Acquired> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        Some(Acquired::Sample(self.sim.step()))
    }
    fn sample_period_s(&self) -> f64 {
        self.sim.sample_period_s()
    }
    fn describe(&self) -> String {
        self.name.clone()
    }
}

/// A CSV file (the format of the `dataset` crate) as a source, streamed.
pub struct CsvSource {
    reader: dataset::CsvReader<dataset::FileSource>,
    period_s: f64,
}

impl CsvSource {
    /// Opens `path`; rows with pressures outside `limits` are reported unusable.
    pub fn open(path: &Path, limits: dataset::Limits) -> Result<Self, dataset::DatasetError> {
        Ok(CsvSource {
            reader: dataset::CsvReader::open(path, limits)?,
            period_s: limits.sample_period_s.unwrap_or(1e-3),
        })
    }
}

impl Source for CsvSource {
    fn next_item(&mut self) -> Option<Acquired> {
        Some(match self.reader.next_row()? {
            dataset::Row::Sample(s) => Acquired::Sample(s),
            dataset::Row::AfterGap(sample, issue) => Acquired::AfterGap {
                sample,
                missing: match issue.kind {
                    dataset::IssueKind::Gap { missing } => missing,
                    _ => 0,
                },
            },
            dataset::Row::Skipped(issue) => {
                Acquired::Unusable(format!("{}: {issue}", self.reader.path().display()))
            }
        })
    }
    fn sample_period_s(&self) -> f64 {
        self.period_s
    }
    fn describe(&self) -> String {
        format!("file {}", self.reader.path().display())
    }
}

/// Samples held in memory as a source (tests, logs already decoded).
pub struct VecSource {
    samples: std::vec::IntoIter<Sample>,
    period_s: f64,
    last_t: Option<f64>,
}

impl VecSource {
    /// Replays `samples` with nominal period `period_s`.
    pub fn new(samples: Vec<Sample>, period_s: f64) -> Self {
        VecSource {
            samples: samples.into_iter(),
            period_s,
            last_t: None,
        }
    }
}

impl Source for VecSource {
    fn next_item(&mut self) -> Option<Acquired> {
        let s = self.samples.next()?;
        let gap = self
            .last_t
            .map(|t| ((s.t_s - t) / self.period_s).round() as i64 - 1)
            .unwrap_or(0);
        self.last_t = Some(s.t_s);
        Some(if gap > 0 {
            Acquired::AfterGap {
                sample: s,
                missing: gap as u64,
            }
        } else {
            Acquired::Sample(s)
        })
    }
    fn sample_period_s(&self) -> f64 {
        self.period_s
    }
    fn describe(&self) -> String {
        "samples in memory".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use model::{ActuatorParams, FaultSchedule, Scenario};

    #[test]
    fn sim_source_counts_and_csv_source_matches() {
        let sc = Scenario::by_name("open-loop-sine", 1, 1.0).unwrap();
        let sim = Simulator::with_default_sensors(ActuatorParams::default(), sc, FaultSchedule::default(), 3)
            .unwrap();
        let mut src = SimSource::new(sim, 0.25);
        let mut samples = Vec::new();
        while let Some(Acquired::Sample(s)) = src.next_item() {
            samples.push(s);
        }
        assert_eq!(samples.len(), 250);
        let dir = scratch::ScratchDir::new("acquisition-csv");
        let p = dir.join("a.csv");
        dataset::write_csv(&p, &samples, true).unwrap();
        let mut csv = CsvSource::open(&p, dataset::Limits::default()).unwrap();
        let mut back = Vec::new();
        while let Some(item) = csv.next_item() {
            match item {
                Acquired::Sample(s) => back.push(s),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(back.len(), samples.len());
        assert!(back
            .iter()
            .zip(&samples)
            .all(|(a, b)| a.p1_pa.to_bits() == b.p1_pa.to_bits()));
    }

    #[test]
    fn vec_source_reports_gaps() {
        let s = |t| Sample::new(t, 0.0, 0.3, 6.9e6, 6.9e6);
        let mut src = VecSource::new(vec![s(0.0), s(0.001), s(0.005)], 1e-3);
        assert!(matches!(src.next_item(), Some(Acquired::Sample(_))));
        assert!(matches!(src.next_item(), Some(Acquired::Sample(_))));
        assert!(matches!(
            src.next_item(),
            Some(Acquired::AfterGap { missing: 3, .. })
        ));
        assert!(src.next_item().is_none());
    }
}
