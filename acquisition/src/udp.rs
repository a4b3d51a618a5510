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

use frames::udp::{DecodeError, UdpDatagram};
use model::Sample;
use serde::{Deserialize, Serialize};

use crate::{Acquired, Source};

/// Linear scaling of one channel from what the sender sends to SI:
/// `SI = gain · raw + offset`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChannelScale {
    /// SI units per raw unit (e.g. Pa per count); negative for an inverted sensor.
    pub gain: f64,
    /// SI value at raw 0, in the channel's SI unit (V, m, Pa or N).
    pub offset: f64,
}

impl Default for ChannelScale {
    /// Gain 1, offset 0: the sender sends SI.
    fn default() -> Self {
        ChannelScale {
            gain: 1.0,
            offset: 0.0,
        }
    }
}

impl ChannelScale {
    /// The SI value of `raw` (NaN stays NaN).
    #[inline]
    pub fn apply(&self, raw: f64) -> f64 {
        self.gain * raw + self.offset
    }
}

/// The `[udp]` section of the configuration: the scaling of each channel of
/// the UDP stream from raw values to SI (`[udp.p1] gain = 250.0, offset =
/// -1.0e6` for a pressure sent in counts of 250 Pa from −1 MPa). The default,
/// gain 1 and offset 0 everywhere, means the sender already sends SI. The
/// sample time is never scaled (seconds).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UdpScaling {
    /// Valve command, to V.
    pub u: ChannelScale,
    /// Rod position, to m.
    pub x: ChannelScale,
    /// Chamber-1 pressure, to Pa.
    pub p1: ChannelScale,
    /// Chamber-2 pressure, to Pa.
    pub p2: ChannelScale,
    /// Spool position, to m.
    pub x_sp: ChannelScale,
    /// Load force, to N.
    pub f_load: ChannelScale,
}

/// Smallest and largest accepted |gain|, SI units per raw unit.
pub const GAIN_RANGE: (f64, f64) = (1e-12, 1e12);
/// Largest accepted |offset|, in the channel's SI unit.
pub const OFFSET_MAX: f64 = 1e9;

impl UdpScaling {
    /// Every channel with its name and SI unit.
    fn channels(&self) -> [(&'static str, &'static str, ChannelScale); 6] {
        [
            ("u", "V", self.u),
            ("x", "m", self.x),
            ("p1", "Pa", self.p1),
            ("p2", "Pa", self.p2),
            ("x_sp", "m", self.x_sp),
            ("f_load", "N", self.f_load),
        ]
    }

    /// Checks every gain (finite, |gain| from 1e-12 to 1e12) and offset
    /// (finite, |offset| ≤ 1e9 in the channel's unit); the error names the field.
    pub fn validate(&self) -> Result<(), String> {
        for (name, unit, c) in self.channels() {
            let g = c.gain.abs();
            if !(GAIN_RANGE.0..=GAIN_RANGE.1).contains(&g) {
                return Err(format!(
                    "[udp] {name}.gain = {:?}: must be a number of magnitude from {:e} to {:e} {unit} per raw unit \
                     (negative for an inverted sensor)",
                    c.gain, GAIN_RANGE.0, GAIN_RANGE.1
                ));
            }
            if !c.offset.is_finite() || c.offset.abs() > OFFSET_MAX {
                return Err(format!(
                    "[udp] {name}.offset = {:?}: must be a number from {:e} to {:e} {unit}",
                    c.offset, -OFFSET_MAX, OFFSET_MAX
                ));
            }
        }
        Ok(())
    }

    /// True if every channel passes through unchanged (gain 1, offset 0).
    pub fn is_identity(&self) -> bool {
        self.channels()
            .iter()
            .all(|(_, _, c)| *c == ChannelScale::default())
    }

    /// The SI sample of a datagram: channels scaled, time as sent, absent
    /// optional channels NaN; the position reference and leak flow are absent.
    pub fn sample(&self, d: &UdpDatagram) -> Sample {
        Sample {
            t_s: d.t_s,
            u_v: self.u.apply(d.u),
            x_m: self.x.apply(d.x),
            p1_pa: self.p1.apply(d.p1),
            p2_pa: self.p2.apply(d.p2),
            x_sp_m: self.x_sp.apply(d.x_sp),
            f_load_n: self.f_load.apply(d.f_load),
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
        }
    }
}

/// Parses the listening address of a UDP stream, `IP:PORT` (e.g.
/// `0.0.0.0:5005` for every interface, `127.0.0.1:5005`, `[::1]:5005`), with
/// or without a `udp://` prefix. The error names the problem.
pub fn parse_udp_address(text: &str) -> Result<SocketAddr, String> {
    let addr = text.strip_prefix("udp://").unwrap_or(text);
    let parsed: SocketAddr = addr.parse().map_err(|_| {
        format!(
            "`{text}` is not a UDP listening address: expected IP:PORT such as 0.0.0.0:5005 (every interface) \
             or 127.0.0.1:5005 (IPv6: [::1]:5005); host names are not looked up"
        )
    })?;
    if parsed.port() == 0 {
        return Err(format!(
            "`{text}`: port 0 is not a fixed port, the sender could not find it; name a port from 1 to 65535"
        ));
    }
    Ok(parsed)
}

/// What a UDP stream received, by outcome (since the source was opened).
///
/// Every datagram is counted once: `datagrams = samples + duplicated + late +
/// malformed + rejected + end marks` (a sample-less end-of-stream datagram is
/// an end mark). `lost` counts sequence numbers skipped by a jump forward
/// (reported as gaps); a late datagram was counted lost first, when the gap
/// was published, so the datagrams that never arrived are `lost - late` (plus
/// the malformed ones whose sequence number could not be read, if any).
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
}

impl fmt::Display for UdpCounts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} datagrams: {} samples, {} lost, {} duplicated, {} late (reordered), {} malformed, {} rejected",
            self.datagrams, self.samples, self.lost, self.duplicated, self.late, self.malformed, self.rejected
        )
    }
}

/// Why a UDP stream ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UdpEnd {
    /// The sender flagged its last sample as the end of the stream.
    LastSample,
    /// A sample-less end-of-stream datagram came (or the flagged last sample was rejected).
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
}

impl Default for UdpOptions {
    /// SI senders, the default rig's limits at 1 kHz, 5 s idle timeout, no stop flag.
    fn default() -> Self {
        UdpOptions {
            scaling: UdpScaling::default(),
            limits: dataset::Limits::default(),
            idle_timeout: Duration::from_secs(5),
            stop: None,
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
    /// Samples missing before the next one passed on.
    pending_missing: u64,
    last_t: Option<f64>,
    /// `CLOCK_MONOTONIC` of the last datagram's arrival, ns (0: none yet).
    arrival_mono_ns: u64,
    sender: Option<SocketAddr>,
    second_sender_seen: bool,
    consecutive_late: u64,
    end: Option<UdpEnd>,
}

impl UdpSource {
    /// Binds `addr` and asks for an 8 MiB receive buffer (the kernel grants up
    /// to `net.core.rmem_max`); the error names the address.
    pub fn bind(addr: SocketAddr, opts: UdpOptions) -> Result<UdpSource, String> {
        let socket = UdpSocket::bind(addr).map_err(|e| format!("cannot listen on UDP {addr}: {e}"))?;
        socket
            .set_read_timeout(Some(POLL))
            .map_err(|e| format!("UDP {addr}: {e}"))?;
        let local = socket.local_addr().map_err(|e| format!("UDP {addr}: {e}"))?;
        let recv_buffer_bytes = set_recv_buffer(&socket, RECV_BUFFER_BYTES);
        Ok(UdpSource {
            socket,
            local,
            opts,
            recv_buffer_bytes,
            buf: [0; 2048],
            counts: UdpCounts::default(),
            newest: None,
            pending_missing: 0,
            last_t: None,
            arrival_mono_ns: 0,
            sender: None,
            second_sender_seen: false,
            consecutive_late: 0,
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

    /// Follows the sequence number of a valid datagram; false if it is to be
    /// dropped (duplicated or late).
    fn track(&mut self, seq: u64, from: SocketAddr) -> bool {
        let Some((newest, seen)) = self.newest else {
            self.newest = Some((seq, 1));
            return true;
        };
        if seq > newest {
            let jump = seq - newest;
            let lost = jump - 1;
            self.counts.lost += lost;
            self.pending_missing += lost;
            let seen = if jump >= 64 { 1 } else { (seen << jump) | 1 };
            self.newest = Some((seq, seen));
            self.consecutive_late = 0;
            return true;
        }
        let age = newest - seq;
        if age < 64 && seen & (1 << age) != 0 {
            self.counts.duplicated += 1;
            if self.counts.duplicated <= NAMED {
                eprintln!("udp: duplicated datagram seq {seq} from {from} dropped");
            }
            return false;
        }
        if age < 64 {
            self.newest = Some((newest, seen | (1 << age)));
        }
        self.counts.late += 1;
        self.consecutive_late += 1;
        if self.counts.late <= NAMED {
            eprintln!("udp: late datagram seq {seq} from {from} (newest {newest}) dropped: reordered");
        }
        if self.consecutive_late == 1000 {
            eprintln!(
                "udp: 1000 late datagrams in a row (seq {seq}, newest {newest}): did the sender restart its \
                 sequence? Restart the receiver with it"
            );
        }
        false
    }

    /// The item of one received datagram, or `None` to wait for the next one.
    fn on_datagram(&mut self, len: usize, from: SocketAddr) -> Option<Acquired> {
        self.counts.datagrams += 1;
        match self.sender {
            None => self.sender = Some(from),
            Some(first) if first != from && !self.second_sender_seen => {
                self.second_sender_seen = true;
                eprintln!(
                    "udp: warning: datagrams from a second sender {from} (the stream is from {first}); \
                     their sequence numbers mix with the stream's"
                );
            }
            Some(_) => {}
        }
        let d = match UdpDatagram::try_from(&self.buf[..len.min(self.buf.len())]) {
            Ok(d) => d,
            Err(e) => {
                self.malformed(e, from);
                return None;
            }
        };
        if !d.has_sample() {
            self.end = Some(UdpEnd::EndMark);
            return None;
        }
        if !self.track(d.seq, from) {
            return None;
        }
        let s = self.opts.scaling.sample(&d);
        let problem = match self.opts.limits.check(&s) {
            Some((_, _, msg)) => Some(msg),
            None => match self.last_t {
                Some(t) if s.t_s <= t => Some(format!("time {} s does not increase (previous {t} s)", s.t_s)),
                _ => None,
            },
        };
        if let Some(msg) = problem {
            self.counts.rejected += 1;
            self.pending_missing += 1;
            if self.counts.rejected <= NAMED {
                eprintln!("udp: datagram seq {} rejected: {msg}", d.seq);
            }
            if d.is_end_of_stream() {
                self.end = Some(UdpEnd::EndMark);
            }
            return None;
        }
        self.last_t = Some(s.t_s);
        self.counts.samples += 1;
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
            eprintln!("udp: malformed datagram from {from} dropped: {e}");
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
                    eprintln!("udp: receive on {} failed: {e}", self.local);
                    self.end = Some(UdpEnd::SocketError);
                }
            }
        }
        None
    }

    fn sample_period_s(&self) -> f64 {
        self.opts.limits.sample_period_s.unwrap_or(1e-3)
    }

    fn describe(&self) -> String {
        format!(
            "UDP stream on {} (LWUD v{}, receive buffer {} KiB, idle timeout {} s{})",
            self.local,
            frames::udp::VERSION,
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
        Some(format!("udp: {}; ended by {end}", self.counts))
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
