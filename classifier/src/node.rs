//! The classifier's work on each estimate, whichever process runs it: the
//! classifier process (estimates received over iceoryx2, [`crate::shell`]) or
//! the fused estimator+classifier process (estimates handed over in memory,
//! [`crate::fused`]). It publishes the events, a 10 Hz health frame and, once a
//! second, the classifier's stats frame.
//!
//! An estimate reaches the detectors in its wire form ([`EstimateFrame`],
//! decoded by [`EstimateWire::from_frame`]) in both, so both give the same events.

use crate::wire::EventWire;
use bus::{monotonic_ns, Bus, BusError, Publisher, StageStats};
use detect::{Classifier, ClassifierConfig, LeakEvent};
use estimator::wire::EstimateWire;
use filter::StageEstimate;
use frames::{health_status, EstimateFrame, HealthFrame, LeakEventFrame, StatsFrame};

/// Stats frames come this often, ns.
const STATS_PERIOD_NS: u64 = 1_000_000_000;

/// Events found while handling one estimate (at most a few; no allocation).
struct Pending {
    events: [Option<LeakEvent>; 4],
    n: usize,
}

/// The classifier with its output topics.
pub struct ClassifierNode {
    cfg: ClassifierConfig,
    cls: Classifier,
    events_tx: Publisher<LeakEventFrame>,
    health_tx: Publisher<HealthFrame>,
    stats_tx: Publisher<StatsFrame>,
    stats: StageStats,
    next_stats_ns: u64,
    next_health_t_s: f64,
    health_seq: u64,
    pending: Pending,
    restarted_after: Option<u64>,
}

impl ClassifierNode {
    /// A classifier with settings `cfg` publishing on `bus`. `restarted_after`:
    /// this process takes over from a classifier that read the estimates up to
    /// this sequence number (its first estimate's gap is reported on stderr).
    pub fn new(bus: &Bus, cfg: ClassifierConfig, restarted_after: Option<u64>) -> Result<Self, String> {
        let e = |e: BusError| e.to_string();
        Ok(ClassifierNode {
            cls: Classifier::new(cfg.clone())?,
            cfg,
            events_tx: bus.publisher::<LeakEventFrame>().map_err(e)?,
            health_tx: bus.publisher::<HealthFrame>().map_err(e)?,
            stats_tx: bus.publisher::<StatsFrame>().map_err(e)?,
            stats: StageStats::new(frames::stage::CLASSIFIER),
            next_stats_ns: monotonic_ns() + STATS_PERIOD_NS,
            next_health_t_s: f64::NEG_INFINITY,
            health_seq: 0,
            pending: Pending {
                events: [None, None, None, None],
                n: 0,
            },
            restarted_after,
        })
    }

    /// When the next stats frame is due, `CLOCK_MONOTONIC` ns.
    pub fn next_stats_ns(&self) -> u64 {
        self.next_stats_ns
    }

    /// Publishes the stats frame if it is due at `now_ns`.
    #[inline]
    pub fn tick(&mut self, now_ns: u64) -> Result<(), BusError> {
        if now_ns >= self.next_stats_ns {
            self.stats_tx.send(&self.stats.take_frame())?;
            self.next_stats_ns = (self.next_stats_ns + STATS_PERIOD_NS).max(now_ns + 1);
        }
        Ok(())
    }

    /// Reads one estimate `frame`, received at `recv_mono_ns` after
    /// `missing_before` missing ones; `end_of_stream`: it is the last of its
    /// stream (the detectors finish, and start again for the next stream).
    #[inline]
    pub fn on_estimate(
        &mut self,
        frame: &EstimateFrame,
        missing_before: u64,
        recv_mono_ns: u64,
        end_of_stream: bool,
    ) -> Result<(), String> {
        let e = |e: BusError| e.to_string();
        let stats = &mut self.stats;
        stats.frames_in += 1;
        stats.seq_gaps += missing_before;
        if let Some(last) = self.restarted_after.take() {
            bus::say!(
                "classifier: restarted after estimate {last}: {missing_before} estimates not read before estimate {} \
                 (a gap)",
                frame.seq
            );
        }
        if frame.acq_mono_ns > 0 && recv_mono_ns >= frame.acq_mono_ns {
            stats.record_latency_ns(recv_mono_ns - frame.acq_mono_ns);
        }
        let t0 = monotonic_ns();
        let se = StageEstimate::from_frame(frame, missing_before);
        let pending = &mut self.pending;
        pending.n = 0;
        self.cls.on_stage(&se, |ev| {
            if pending.n < pending.events.len() {
                pending.events[pending.n] = Some(ev);
                pending.n += 1;
            }
        });
        let done = monotonic_ns();
        stats.record_proc_ns(done - t0);
        for ev in pending.events.iter_mut().take(pending.n) {
            let Some(ev) = ev.take() else { continue };
            let out = ev.to_frame(frame.seq, frame.acq_mono_ns, done);
            self.events_tx.send(&out).map_err(e)?;
            stats.frames_out += 1;
        }
        if se.leak.t_s >= self.next_health_t_s {
            self.next_health_t_s = se.leak.t_s + 0.1;
            self.health_seq += 1;
            let rise = self.cls.leak_size.rise_lpm(&se.leak);
            let active = u32::from(self.cls.leak_size.has_active_leak());
            let status = if active > 0 {
                health_status::LEAK
            } else if self.cls.leak_size.is_armed() {
                health_status::HEALTHY
            } else {
                health_status::WARMING_UP
            };
            let h = HealthFrame {
                seq: self.health_seq,
                mono_ns: monotonic_ns(),
                t_s: se.leak.t_s,
                status,
                active_events: active,
                leak_flow_lpm: rise,
                leak_flow_sigma_lpm: [
                    se.leak.sigma[7] * 6e4,
                    se.leak.sigma[8] * 6e4,
                    se.leak.sigma[9] * 6e4,
                ],
                leak_threshold_lpm: self.cls.leak_size.thresholds_lpm(),
            };
            self.health_tx.send(&h).map_err(e)?;
        }
        if end_of_stream {
            let events_tx = &mut self.events_tx;
            self.cls.finish(se.leak.t_s, |ev| {
                let out = ev.to_frame(frame.seq, frame.acq_mono_ns, monotonic_ns());
                let _ = events_tx.send(&out);
            });
            // ready for the next stream
            self.cls = Classifier::new(self.cfg.clone())?;
        }
        Ok(())
    }

    /// Publishes the last stats frame; returns the estimates read, the events
    /// published and the estimates missing, for the exit message.
    pub fn finish(mut self) -> Result<(u64, u64, u64), String> {
        self.stats_tx
            .send(&self.stats.take_frame())
            .map_err(|e| e.to_string())?;
        Ok((self.stats.frames_in, self.stats.frames_out, self.stats.seq_gaps))
    }
}
