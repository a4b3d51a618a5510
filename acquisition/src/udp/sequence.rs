//! Following the sender's sequence numbers and timestamps: new, late and
//! duplicated datagrams, restarts, foreign senders, time jumps and the rate.

use std::net::SocketAddr;

use super::{UdpSource, NAMED, RATE_TOLERANCE, REORDER_WINDOW, RESTART_SILENCE_PERIODS, TIME_JUMP_PERIODS};

/// What [`UdpSource::track`] made of a sequence number.
pub(super) enum Tracked {
    /// New to the stream (a jump forward counted lost): go on with the sample.
    New,
    /// The first datagram of a restarted sender: a new stream.
    Restart,
    /// Duplicated or late: dropped, counted.
    Dropped,
}

impl UdpSource {
    /// Follows the sequence number of a valid datagram of time `t_s` (s).
    pub(super) fn track(&mut self, seq: u64, t_s: f64, from: SocketAddr) -> Tracked {
        let Some((newest, seen)) = self.newest else {
            self.newest = Some((seq, 1));
            self.newest_t = t_s;
            self.stream_mono_ns = self.arrival_mono_ns;
            return Tracked::New;
        };
        if seq > newest {
            let jump = seq - newest;
            let lost = jump - 1;
            self.counts.lost += lost;
            self.pending_missing += lost;
            let seen = if jump >= REORDER_WINDOW {
                1
            } else {
                (seen << jump) | 1
            };
            self.newest = Some((seq, seen));
            self.newest_t = t_s;
            self.stream_mono_ns = self.arrival_mono_ns;
            self.consecutive_late = 0;
            return Tracked::New;
        }
        let age = newest - seq;
        if age >= REORDER_WINDOW {
            let silence_ns = self.arrival_mono_ns.saturating_sub(self.stream_mono_ns);
            let went_back =
                t_s < self.newest_t && silence_ns >= RESTART_SILENCE_PERIODS.saturating_mul(self.period_ns());
            if went_back || t_s > self.newest_t {
                self.restart(seq, t_s, silence_ns, from);
                return Tracked::Restart;
            }
        }
        if age < REORDER_WINDOW && seen & (1 << age) != 0 {
            self.counts.duplicated += 1;
            if self.counts.duplicated <= NAMED {
                bus::say!("udp: duplicated datagram seq {seq} from {from} dropped");
            }
            return Tracked::Dropped;
        }
        if age < REORDER_WINDOW {
            self.newest = Some((newest, seen | (1 << age)));
        }
        self.counts.late += 1;
        self.consecutive_late += 1;
        if self.counts.late <= NAMED {
            bus::say!("udp: late datagram seq {seq} from {from} (newest {newest}) dropped: reordered");
        }
        if self.consecutive_late == 1000 {
            bus::say!(
                "udp: 1000 late datagrams in a row (seq {seq}, newest {newest}) and the time did not go back \
                 by a restart: is the sender's clock stuck? Restart the receiver with the sender"
            );
        }
        Tracked::Dropped
    }

    /// A restart of the sender (module docs): a new stream from `seq`, after
    /// a gap of the silence before it.
    pub(super) fn restart(&mut self, seq: u64, t_s: f64, silence_ns: u64, from: SocketAddr) {
        let (old_seq, old_t) = (self.newest.map_or(0, |(n, _)| n), self.newest_t);
        let periods = (silence_ns as f64 / self.period_ns() as f64).round() as u64;
        let gap = periods.saturating_sub(1).max(1);
        self.counts.reboots += 1;
        if self.counts.reboots <= NAMED {
            let how = if t_s < old_t {
                "sequence and time started again: a reboot"
            } else {
                "sequence started again, time went on"
            };
            bus::say!(
                "udp: sender {from} restarted ({how}): seq {old_seq} -> {seq}, t {old_t} s -> {t_s} s after \
                 {:.1} ms without a datagram; a new stream, {gap} samples missing",
                silence_ns as f64 * 1e-6
            );
        }
        self.pending_missing += gap;
        self.newest = Some((seq, 1));
        self.newest_t = t_s;
        self.stream_mono_ns = self.arrival_mono_ns;
        self.last = None;
        self.consecutive_late = 0;
        self.rate.restart();
    }

    /// Whether the datagram from `from` belongs to the stream; a foreign one
    /// is counted (the first named). The stream's sender is locked by the
    /// caller once a datagram decoded.
    pub(super) fn is_foreign(&mut self, from: SocketAddr) -> bool {
        let Some(sender) = self.sender else {
            return false;
        };
        if from == sender {
            return false;
        }
        self.counts.foreign += 1;
        if self.counts.foreign == 1 {
            if self.opts.sender.is_some() {
                bus::say!(
                    "udp: error: datagrams from {from} dropped: not the configured sender {sender} ([udp] sender); \
                     they are counted as foreign"
                );
            } else {
                bus::say!(
                    "udp: error: datagrams from a second sender {from} dropped (the stream is from {sender}, the \
                     first sender); if {from} is the rig's, set `[udp] sender = \"{from}\"` in the config, else \
                     `[udp] sender = \"{sender}\"` so that no other device can take the stream over"
                );
            }
        }
        true
    }

    /// The time step from the stream's last sample to `(seq, t_s)`: a time
    /// jump is counted, named and its gap made pending (module docs). Returns
    /// whether the time goes on (false: it does not increase, and it was no jump).
    pub(super) fn time_step(&mut self, seq: u64, t_s: f64) -> bool {
        let Some((last_seq, last_t)) = self.last else {
            return true;
        };
        let period = self.opts.sample_period_s;
        let dt = t_s - last_t;
        let dseq = seq.saturating_sub(last_seq).max(1);
        let by_seq = dseq as f64;
        let by_time = dt / period;
        if (by_time - by_seq).abs() > TIME_JUMP_PERIODS.max(0.5 * by_seq) && by_time.is_finite() {
            self.counts.time_jumps += 1;
            let missing = if dt > 0.0 {
                (by_time.round() as u64).saturating_sub(1).max(dseq - 1)
            } else {
                dseq - 1
            }
            .max(1);
            if self.counts.time_jumps <= NAMED {
                bus::say!(
                    "udp: time jump: t {last_t} s -> {t_s} s (by {dt:.6} s) at seq {last_seq} -> {seq}, which \
                     says {:.6} s: the sender's clock stepped (or it paused); reported as a gap of {missing} samples",
                    by_seq * period
                );
            }
            self.pending_missing = self.pending_missing.max(missing);
            return true;
        }
        dt > 0.0
    }

    /// Feeds the step to `(seq, t_s)` to the rate measurement; returns whether
    /// the sample is at the right rate (false: dropped while a rate error lasts).
    pub(super) fn rate_ok(&mut self, seq: u64, t_s: f64) -> bool {
        if let Some((last_seq, last_t)) = self.last {
            let dseq = seq.saturating_sub(last_seq).max(1) as f64;
            if let Some((measured, tolerance)) = self.rate.push((t_s - last_t) / dseq) {
                let configured = self.opts.sample_period_s;
                let off = (measured / configured - 1.0).abs();
                if off > tolerance && self.rate_error.is_none() {
                    self.counts.rate_errors += 1;
                    let msg = format!(
                        "the sender's sample period is {:.4} ms ({:.1} Hz), the configured one {:.4} ms ({:.1} Hz; \
                         [sim] sample_period_s), {:.0} % off: its samples are dropped, the detector is blind until \
                         the sender keeps the configured rate",
                        measured * 1e3,
                        1.0 / measured,
                        configured * 1e3,
                        1.0 / configured,
                        off * 100.0
                    );
                    bus::say!("udp: error: {msg}");
                    self.rate_error = Some(msg);
                } else if off <= RATE_TOLERANCE && tolerance == RATE_TOLERANCE && self.rate_error.is_some() {
                    self.rate_error = None;
                    bus::say!(
                        "udp: the sender's sample period is {:.4} ms again (configured {:.4} ms): samples are \
                         passed on again",
                        measured * 1e3,
                        configured * 1e3
                    );
                }
            }
        }
        self.rate_error.is_none()
    }
}
