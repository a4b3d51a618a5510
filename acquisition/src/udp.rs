//! The UDP sensor stream of a real rig as a [`Source`]: a DAQ board or PLC
//! sends one datagram per sample in the format of [`frames::udp`] (72 bytes,
//! little-endian); [`UdpSource`] receives them, scales raw values to SI
//! ([`UdpScaling`], the `[udp]` section of the configuration), checks the
//! physical ranges ([`dataset::Limits`], as for a CSV file) and follows the
//! sequence numbers:
//!
//! - **lost**: a jump forward; the next sample is [`Acquired::AfterGap`] with
//!   the number of missing samples;
//! - **duplicated**: a sequence number received again: dropped, counted;
//! - **late** (reordered): older than the newest received and not received
//!   before: dropped, counted (the pipeline never goes back in time; its
//!   sample was already reported missing in the gap);
//! - **malformed**: not a valid datagram ([`frames::udp::DecodeError`]):
//!   dropped, counted, the first ten named on stderr;
//! - **rejected**: a valid datagram whose sample is outside its physical
//!   range or whose time does not increase: dropped, counted, reported
//!   missing in the next gap.
//!
//! The receiver survives its sender (`T` below is the configured sample
//! period, [`UdpOptions::sample_period_s`]):
//!
//! - **one sender**: the stream is taken from one address only, the
//!   configured one (`[udp] sender = "IP:PORT"`, [`UdpOptions::sender`]) or
//!   else the first that sends a valid datagram. Datagrams from any other
//!   address are **foreign**: dropped before they are decoded (never mixed
//!   into the sequence tracking), counted, the first one named on stderr.
//! - **reboot** (a restart of the sender): a valid datagram whose sequence
//!   number is below the newest by more than the 64-entry reorder window
//!   ([`REORDER_WINDOW`]) is a new stream when its time went back (below the
//!   newest datagram's time) after at least [`RESTART_SILENCE_PERIODS`]
//!   sample periods without a datagram of the stream, or when its time went
//!   on (past the newest's: a sender that restarts its sequence but keeps its
//!   clock; no old datagram of the stream can be newer than the newest). It is
//!   recognised on the first datagram of the new stream: counted (`reboots`),
//!   named on stderr (old and new sequence number and time), the sequence
//!   window, the last time and the rate measurement start again, and the
//!   sample is [`Acquired::AfterGap`]: missing are the samples of the silence
//!   as the arrival clock measured it, `round(silence / T) − 1`, at least 1
//!   (the sender's own times of two streams say nothing about the time
//!   between them). An old datagram that arrives out of order while the
//!   stream flows (seq far below, time below, no silence) stays **late**; a
//!   sender that restarts without a pause has its first datagrams counted
//!   late until `RESTART_SILENCE_PERIODS` periods have passed.
//! - **time jump**: between two samples of the stream, the time says
//!   `Δt / T` periods passed and the sequence numbers `Δseq`. When they
//!   differ by more than `max(10, Δseq / 2)` periods (a clock step of the
//!   sender: NTP, a clock set by hand) the sample is a time jump: counted
//!   (`time_jumps`), named on stderr, and passed on as
//!   [`Acquired::AfterGap`]. Forward, the gap is what the time stamps imply,
//!   `round(Δt / T) − 1` samples (at least what the sequence says): the
//!   estimator reckons gaps from the time stamps, so both stages count the
//!   same, and a gap that long makes the filter re-anchor instead of bridging
//!   the step by prediction (the stderr line also says what the sequence
//!   numbers imply, to tell a clock step from a pause). Backward (by more
//!   than the rule allows; a smaller step back is rejected as before), the
//!   sample is accepted as a gap of what the sequence says, at least 1: the
//!   stream goes on in the new time base (rather than rejecting every sample
//!   until the time has caught up), flagged after a gap for the filter to
//!   re-anchor on.
//! - **rate**: the sender's sample period is measured as the median of
//!   `Δt / Δseq` over blocks of [`RATE_WINDOW`] steps of the stream (the
//!   median passes over the odd time jump or jittered stamp; time stamps
//!   coarser than the period can hide a small error). The first block of a
//!   stream is looked at after [`RATE_EARLY_STEPS`] steps already, with a
//!   tolerance of 20 % (a sender at twice or half the rate is caught within
//!   20 samples); every full block with 5 % ([`RATE_TOLERANCE`]). A period
//!   outside the tolerance is a **rate error**: counted (`rate_errors`),
//!   named on stderr once with both rates, shown by [`UdpSource::rate_error`]
//!   and the summary; from that sample on the stream's samples are dropped
//!   and counted (`wrong_rate`, reported missing in the next gap): the
//!   detector is blind rather than fed samples at a rate it does not model.
//!   The measurement goes on: a full block within 5 % (after the sender was
//!   set right, usually by a reboot) clears the error and samples flow again.
//!   The samples before the first look (20 at most) are passed on.
//!
//! The counts are [`UdpCounts`] ([`UdpSource::counts`]). The sender paces the
//! stream: a live source is published on arrival, never re-paced. The stream
//! ends with the datagram flagged end of stream (the sender's last sample, or
//! a sample-less end mark), when no datagram came for the idle timeout (which
//! runs from the first datagram: before it the source waits until stopped),
//! or when the stop flag is set.

use std::fmt;
use std::net::{SocketAddr, UdpSocket};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use config::udp::UdpScaling;
use frames::udp::{DecodeError, UdpDatagram};
use model::Sample;

use crate::{Acquired, Source};

mod rate;
mod sequence;
mod units;

use rate::RateMeter;
use sequence::Tracked;
pub use units::UNITS_AFTER_S;

/// The SI sample of a datagram: channels scaled by `scaling`, time as sent,
/// absent optional channels NaN; the position reference and leak flow are absent.
pub fn scaled_sample(scaling: &UdpScaling, d: &UdpDatagram) -> Sample {
    Sample {
        t_s: d.t_s,
        u_v: scaling.u.apply(d.u),
        x_m: scaling.x.apply(d.x),
        p1_pa: scaling.p1.apply(d.p1),
        p2_pa: scaling.p2.apply(d.p2),
        x_sp_m: scaling.x_sp.apply(d.x_sp),
        f_load_n: scaling.f_load.apply(d.f_load),
        ref_m: f64::NAN,
        q_leak_lpm: f64::NAN,
        temp_c: scaling.temp_c.apply(d.temp_c),
    }
}

/// What a UDP stream received, by outcome (since the source was opened).
///
/// Every datagram is counted once: `datagrams = samples + duplicated + late +
/// malformed + rejected + foreign + wrong_rate + end marks` (a sample-less
/// end-of-stream datagram is an end mark). `lost` counts sequence numbers
/// skipped by a jump forward (reported as gaps); a late datagram was counted
/// lost first, when the gap was published, so the datagrams that never arrived
/// are `lost - late` (plus the malformed ones whose sequence number could not
/// be read, if any). `reboots`, `time_jumps` and `rate_errors` count events,
/// not datagrams: the gaps of reboots and time jumps are in the `missing` of
/// the [`Acquired::AfterGap`] items (from the arrival clock and the time
/// stamps), not in `lost`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UdpCounts {
    /// Datagrams received.
    pub datagrams: u64,
    /// Samples passed on to the pipeline.
    pub samples: u64,
    /// Sequence numbers skipped by a jump forward, reported as gaps.
    pub lost: u64,
    /// Datagrams whose sequence number had been received already: dropped.
    pub duplicated: u64,
    /// Datagrams older than the newest received (reordered): dropped.
    pub late: u64,
    /// Datagrams that are not valid leakwatch datagrams: dropped.
    pub malformed: u64,
    /// Valid datagrams whose sample is out of its physical range or whose time
    /// does not increase: dropped and reported missing in the next gap.
    pub rejected: u64,
    /// Datagrams from an address other than the stream's sender (the
    /// configured `[udp] sender`, else the first one): dropped, not decoded.
    pub foreign: u64,
    /// Samples dropped while the sender's measured rate did not match the
    /// configured sample period (a rate error): reported missing in the next gap.
    pub wrong_rate: u64,
    /// Restarts of the sender (sequence number and time started again): each
    /// began a new stream after a gap.
    pub reboots: u64,
    /// Time stamps that jumped against the sequence numbers (a clock step of
    /// the sender): each reported as a gap.
    pub time_jumps: u64,
    /// Times the measured sample period was found not to match the configured one.
    pub rate_errors: u64,
}

impl fmt::Display for UdpCounts {
    /// `N datagrams: N samples, N lost, ...`; foreign, wrong-rate and the
    /// events (reboots, time jumps, rate errors) only when there were any.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} datagrams: {} samples, {} lost, {} duplicated, {} late (reordered), {} malformed, {} rejected",
            self.datagrams, self.samples, self.lost, self.duplicated, self.late, self.malformed, self.rejected
        )?;
        if self.foreign > 0 {
            write!(f, ", {} foreign (another sender)", self.foreign)?;
        }
        if self.wrong_rate > 0 {
            write!(f, ", {} dropped at a wrong rate", self.wrong_rate)?;
        }
        for (n, what) in [
            (self.reboots, "sender restarts (reboots)"),
            (self.time_jumps, "time jumps"),
            (self.rate_errors, "rate errors"),
        ] {
            if n > 0 {
                write!(f, "; {n} {what}")?;
            }
        }
        Ok(())
    }
}

/// Why a UDP stream ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UdpEnd {
    /// The sender flagged its last sample as the end of the stream.
    LastSample,
    /// A sample-less end-of-stream datagram came (or the flagged last sample
    /// was rejected or dropped at a wrong rate).
    EndMark,
    /// No datagram came for the idle timeout.
    IdleTimeout,
    /// The stop flag was set (a signal).
    Stopped,
    /// The socket failed (named on stderr).
    SocketError,
}

/// How often a blocked receive wakes to look at the stop flag and the idle timeout.
const POLL: Duration = Duration::from_millis(50);
/// Receive buffer requested from the kernel (capped by `net.core.rmem_max`), bytes.
pub const RECV_BUFFER_BYTES: usize = 8 << 20;
/// How many problems of each kind are named on stderr.
const NAMED: u64 = 10;
/// Sequence numbers behind the newest that are still told apart (duplicated
/// or late); a datagram further behind may start a new stream (a reboot).
pub const REORDER_WINDOW: u64 = 64;
/// Sample periods without a datagram of the stream after which a datagram
/// far behind in sequence and time is a reboot rather than a late one.
pub const RESTART_SILENCE_PERIODS: u64 = 20;
/// Steps (`Δt / Δseq` of consecutive samples) per block of the rate measurement.
pub const RATE_WINDOW: usize = 200;
/// Steps after which the first block of a stream is looked at (tolerance 20 %).
pub const RATE_EARLY_STEPS: usize = 20;
/// Largest relative difference of the measured from the configured sample
/// period over a full block (dimensionless, 5 %).
pub const RATE_TOLERANCE: f64 = 0.05;
/// Tolerance of the early look at a stream's first steps (dimensionless, 20 %).
const RATE_EARLY_TOLERANCE: f64 = 0.2;
/// A time step that differs from the sequence numbers by more than this many
/// periods (and by more than half the steps) is a time jump.
const TIME_JUMP_PERIODS: f64 = 10.0;

/// Options of a [`UdpSource`].
#[derive(Debug, Clone)]
pub struct UdpOptions {
    /// Raw to SI.
    pub scaling: UdpScaling,
    /// Physical ranges; samples outside are rejected (as CSV rows are).
    pub limits: dataset::Limits,
    /// The stream ends when no datagram came for this long (after the first one).
    pub idle_timeout: Duration,
    /// Set by a signal handler: the source ends at once (checked every 50 ms).
    pub stop: Option<&'static AtomicBool>,
    /// The sample period the sender must keep, s (the rig's, `[sim]
    /// sample_period_s`; the estimator models it); a measured period more
    /// than 5 % off is a rate error.
    pub sample_period_s: f64,
    /// The only address datagrams are taken from (`[udp] sender`); `None`: the
    /// first sender of a valid datagram.
    pub sender: Option<SocketAddr>,
}

impl Default for UdpOptions {
    /// SI senders, the default rig's limits at 1 kHz (period 1 ms), 5 s idle
    /// timeout, no stop flag, the first sender.
    fn default() -> Self {
        UdpOptions {
            scaling: UdpScaling::default(),
            limits: dataset::Limits::default(),
            idle_timeout: Duration::from_secs(5),
            stop: None,
            sample_period_s: 1e-3,
            sender: None,
        }
    }
}

/// A UDP sensor stream as a [`Source`] (see the module docs).
pub struct UdpSource {
    socket: UdpSocket,
    local: SocketAddr,
    opts: UdpOptions,
    recv_buffer_bytes: usize,
    buf: [u8; 2048],
    counts: UdpCounts,
    /// Newest sequence number received, and a bitmap of the 64 before it
    /// (bit k: `newest - k` was received).
    newest: Option<(u64, u64)>,
    /// The time of the datagram with the newest sequence number, s.
    newest_t: f64,
    /// Samples missing before the next one passed on.
    pending_missing: u64,
    /// Sequence number and time (s) of the stream's last sample that passed
    /// the checks (passed on, or dropped at a wrong rate).
    last: Option<(u64, f64)>,
    /// `CLOCK_MONOTONIC` of the last datagram's arrival, ns (0: none yet).
    arrival_mono_ns: u64,
    /// `CLOCK_MONOTONIC` of the arrival of the last datagram new to the
    /// stream (that advanced the newest sequence number), ns.
    stream_mono_ns: u64,
    /// The stream's sender: configured, else the first of a valid datagram.
    sender: Option<SocketAddr>,
    consecutive_late: u64,
    rate: RateMeter,
    /// The rate error while there is one (made once per error, not per datagram).
    rate_error: Option<String>,
    /// The largest pressure passed on, until the units are checked.
    reach: dataset::PressureReach,
    /// Whether the units were checked ([`UNITS_AFTER_S`]).
    units_checked: bool,
    end: Option<UdpEnd>,
}

impl UdpSource {
    /// Binds `addr` and asks for an 8 MiB receive buffer (the kernel grants up
    /// to `net.core.rmem_max`); the error names the address, or the sample
    /// period if it is not a positive number of seconds (up to 1 s).
    pub fn bind(addr: SocketAddr, opts: UdpOptions) -> Result<UdpSource, String> {
        if !(opts.sample_period_s > 0.0 && opts.sample_period_s <= 1.0) {
            return Err(format!(
                "UDP {addr}: sample period {} s: must be a number of seconds in (0, 1]",
                opts.sample_period_s
            ));
        }
        let socket = UdpSocket::bind(addr).map_err(|e| format!("cannot listen on UDP {addr}: {e}"))?;
        socket
            .set_read_timeout(Some(POLL))
            .map_err(|e| format!("UDP {addr}: {e}"))?;
        let local = socket.local_addr().map_err(|e| format!("UDP {addr}: {e}"))?;
        let recv_buffer_bytes = set_recv_buffer(&socket, RECV_BUFFER_BYTES);
        let sender = opts.sender;
        Ok(UdpSource {
            socket,
            local,
            opts,
            recv_buffer_bytes,
            buf: [0; 2048],
            counts: UdpCounts::default(),
            newest: None,
            newest_t: f64::NAN,
            pending_missing: 0,
            last: None,
            arrival_mono_ns: 0,
            stream_mono_ns: 0,
            sender,
            consecutive_late: 0,
            rate: RateMeter::new(),
            rate_error: None,
            reach: dataset::PressureReach::default(),
            units_checked: false,
            end: None,
        })
    }

    /// The address the source listens on (with the port the system chose for port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// The receive buffer the kernel granted, bytes.
    pub fn recv_buffer_bytes(&self) -> usize {
        self.recv_buffer_bytes
    }

    /// What was received so far, by outcome.
    pub fn counts(&self) -> UdpCounts {
        self.counts
    }

    /// Why the stream ended (`None` while it runs).
    pub fn end(&self) -> Option<UdpEnd> {
        self.end
    }

    /// The rate error while the sender's measured sample period does not
    /// match the configured one (its samples are dropped: the detector is
    /// blind), with both rates; `None` while the rate is right or not yet measured.
    pub fn rate_error(&self) -> Option<&str> {
        self.rate_error.as_deref()
    }

    /// The sender's sample period as last measured (median of a block of
    /// steps, module docs), s; `None` before the first look.
    pub fn measured_period_s(&self) -> Option<f64> {
        self.rate.measured_s
    }

    /// The stream's sender: the configured one, else the first that sent a
    /// valid datagram (`None` before it).
    pub fn sender(&self) -> Option<SocketAddr> {
        self.sender
    }

    /// The configured sample period in ns (at least 1).
    fn period_ns(&self) -> u64 {
        ((self.opts.sample_period_s * 1e9).round() as u64).max(1)
    }

    /// The item of one received datagram, or `None` to wait for the next one.
    fn on_datagram(&mut self, len: usize, from: SocketAddr) -> Option<Acquired> {
        self.counts.datagrams += 1;
        if self.is_foreign(from) {
            return None;
        }
        let d = match UdpDatagram::try_from(&self.buf[..len.min(self.buf.len())]) {
            Ok(d) => d,
            Err(e) => {
                self.malformed(e, from);
                return None;
            }
        };
        // a valid datagram: its address is the stream's from now on
        self.sender.get_or_insert(from);
        if !d.has_sample() {
            self.end = Some(UdpEnd::EndMark);
            return None;
        }
        if let Tracked::Dropped = self.track(d.seq, d.t_s, from) {
            return None;
        }
        let s = scaled_sample(&self.opts.scaling, &d);
        let problem = match self.opts.limits.check(&s) {
            Some((_, _, msg)) => Some(msg),
            None => {
                let last = self.last;
                match last {
                    Some((_, t)) if !self.time_step(d.seq, s.t_s) => {
                        Some(format!("time {} s does not increase (previous {t} s)", s.t_s))
                    }
                    _ => None,
                }
            }
        };
        if let Some(msg) = problem {
            self.counts.rejected += 1;
            self.pending_missing += 1;
            if self.counts.rejected <= NAMED {
                bus::say!("udp: datagram seq {} rejected: {msg}", d.seq);
            }
            if d.is_end_of_stream() {
                self.end = Some(UdpEnd::EndMark);
            }
            return None;
        }
        let rate_ok = self.rate_ok(d.seq, s.t_s);
        self.last = Some((d.seq, s.t_s));
        if !rate_ok {
            self.counts.wrong_rate += 1;
            self.pending_missing += 1;
            if d.is_end_of_stream() {
                self.end = Some(UdpEnd::EndMark);
            }
            return None;
        }
        self.counts.samples += 1;
        self.check_units(&s);
        if d.is_end_of_stream() {
            self.end = Some(UdpEnd::LastSample);
        }
        let missing = std::mem::take(&mut self.pending_missing);
        Some(if missing > 0 {
            Acquired::AfterGap { sample: s, missing }
        } else {
            Acquired::Sample(s)
        })
    }

    fn malformed(&mut self, e: DecodeError, from: SocketAddr) {
        self.counts.malformed += 1;
        if self.counts.malformed <= NAMED {
            bus::say!("udp: malformed datagram from {from} dropped: {e}");
        }
    }
}

impl Source for UdpSource {
    fn next_item(&mut self) -> Option<Acquired> {
        while self.end.is_none() {
            if self.opts.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
                self.end = Some(UdpEnd::Stopped);
                break;
            }
            match self.socket.recv_from(&mut self.buf) {
                Ok((len, from)) => {
                    self.arrival_mono_ns = bus::monotonic_ns();
                    if let Some(item) = self.on_datagram(len, from) {
                        return Some(item);
                    }
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) =>
                {
                    let idle_ns = self.opts.idle_timeout.as_nanos().min(u64::MAX as u128) as u64;
                    if self.arrival_mono_ns > 0
                        && bus::monotonic_ns().saturating_sub(self.arrival_mono_ns) >= idle_ns
                    {
                        self.end = Some(UdpEnd::IdleTimeout);
                    }
                }
                Err(e) => {
                    bus::say!("udp: receive on {} failed: {e}", self.local);
                    self.end = Some(UdpEnd::SocketError);
                }
            }
        }
        None
    }

    fn sample_period_s(&self) -> f64 {
        self.opts.sample_period_s
    }

    fn describe(&self) -> String {
        format!(
            "UDP stream on {} (LWUD v{}, {} Hz, {}, receive buffer {} KiB, idle timeout {} s{})",
            self.local,
            frames::udp::VERSION,
            1.0 / self.opts.sample_period_s,
            match self.opts.sender {
                Some(a) => format!("from {a} only"),
                None => "from the first sender".to_string(),
            },
            self.recv_buffer_bytes / 1024,
            self.opts.idle_timeout.as_secs_f64(),
            if self.opts.scaling.is_identity() {
                ", SI as sent"
            } else {
                ", scaled by [udp]"
            }
        )
    }

    fn is_live(&self) -> bool {
        true
    }

    fn ended(&self) -> bool {
        self.end.is_some()
    }

    fn arrival_mono_ns(&self) -> Option<u64> {
        (self.arrival_mono_ns > 0).then_some(self.arrival_mono_ns)
    }

    fn summary(&self) -> Option<String> {
        let end = match self.end {
            Some(UdpEnd::LastSample) => "the sender's last sample",
            Some(UdpEnd::EndMark) => "the sender's end mark",
            Some(UdpEnd::IdleTimeout) => "the idle timeout",
            Some(UdpEnd::Stopped) => "a signal",
            Some(UdpEnd::SocketError) => "a socket error",
            None => "not yet",
        };
        let rate = match &self.rate_error {
            Some(e) => format!("; RATE ERROR: {e}"),
            None => String::new(),
        };
        Some(format!("udp: {}; ended by {end}{rate}", self.counts))
    }
}

/// Asks for a receive buffer of `bytes` (SO_RCVBUF) and returns what the kernel granted.
fn set_recv_buffer(socket: &UdpSocket, bytes: usize) -> usize {
    let fd = socket.as_raw_fd();
    let want = bytes.min(i32::MAX as usize) as libc::c_int;
    let size = std::mem::size_of::<libc::c_int>() as libc::socklen_t;
    // SAFETY: fd is an open socket owned by `socket`; the option value is a c_int
    // of the length given.
    unsafe {
        libc::setsockopt(
            fd,
            libc::SOL_SOCKET,
            libc::SO_RCVBUF,
            &want as *const libc::c_int as *const libc::c_void,
            size,
        );
    }
    let mut got: libc::c_int = 0;
    let mut len = size;
    // SAFETY: as above; `got` and `len` are valid for writing.
    let ok = unsafe {
        libc::getsockopt(
            fd,
            libc::SOL_SOCKET,
            libc::SO_RCVBUF,
            &mut got as *mut libc::c_int as *mut libc::c_void,
            &mut len,
        )
    };
    if ok == 0 {
        got.max(0) as usize
    } else {
        0
    }
}
