//! The log's message encoding: every record as a ROS 2 message, serialised
//! as CDR (`message_encoding = "cdr"`) and described by its `.msg` definition
//! (`schema encoding = "ros2msg"`, the files in `leakwatch_msgs/msg/`).
//!
//! Why CDR with ros2msg schemas: Foxglove, rosbag2 (`ros2 bag info/play` of an
//! MCAP file) and Python's `mcap` + `mcap-ros2-support` decode it from the
//! schema stored in the file, with no code generation (no protoc); the
//! encoding is a fixed little-endian layout that is a few lines to write by
//! hand, so the recorder needs no new dependency.
//!
//! CDR as written here (XCDR1, little-endian): a 4-byte encapsulation header
//! `00 01 00 00`, then the fields in the order of the `.msg`, each aligned to
//! its own size (1, 4 or 8 bytes) counted from the end of the header; a nested
//! message is its fields in order; a fixed array has no length prefix; a
//! `string` is a `uint32` length (bytes + the closing NUL), the UTF-8 bytes and
//! a NUL. Floats are carried bit for bit (NaN = absent, the infinities).
//!
//! Named fields: the filter states are [`LEAK_STATE`] / [`THESIS_STATE`]
//! messages (`state.p1_pa`, `state.q_e1_m3_s`, ...), the measurement triples
//! `Measurement`, the leak flows `LeakFlows`; codes with names (event `kind`
//! and `phase`, health `status`, stats `stage`, gap `topic`) are strings, the
//! names of events.json (`ext1`, `raised`, `healthy`, ...); a code this version
//! does not name is written as its number and read back as one.

use std::borrow::Cow;

use frames::{
    code_name, code_of, event_kind, event_phase, health_status, stage, EstimateFrame, HealthFrame,
    LeakEventFrame, SensorFrame, StatsFrame, Topic,
};

use crate::GapRecord;

mod batch;

pub use batch::SensorFrameBatch;

/// The package of the leakwatch message types (`leakwatch_msgs/msg/SensorFrame`, ...).
pub const PACKAGE: &str = "leakwatch_msgs";

/// The CDR encapsulation header of a little-endian plain-CDR message.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// The separator between the definitions of a ros2msg schema and those of the
/// message types it uses (rosbag2's concatenated form).
macro_rules! dependency {
    ($name:literal) => {
        concat!(
            "\n================================================================================\nMSG: leakwatch_msgs/",
            $name,
            "\n",
            include_str!(concat!("../../leakwatch_msgs/msg/", $name, ".msg"))
        )
    };
}

/// `LeakState.msg`: the leak filter's first 11 states by name, SI units (the
/// 12th, the oil-stiffness scale θ, is the frame's `bulk_scale`).
pub const LEAK_STATE: &str = include_str!("../../leakwatch_msgs/msg/LeakState.msg");
/// `ThesisState.msg`: the thesis filter's 7 states by name, SI units.
pub const THESIS_STATE: &str = include_str!("../../leakwatch_msgs/msg/ThesisState.msg");

/// Appends a CDR message to a buffer: the encapsulation header first, then
/// one field per call, aligned as CDR requires.
pub struct CdrWriter<'a> {
    buf: &'a mut Vec<u8>,
}

impl<'a> CdrWriter<'a> {
    /// Clears `buf` and writes the little-endian encapsulation header.
    pub fn new(buf: &'a mut Vec<u8>) -> Self {
        buf.clear();
        buf.extend_from_slice(&CDR_LE_HEADER);
        CdrWriter { buf }
    }

    fn align(&mut self, n: usize) {
        let off = (self.buf.len() - CDR_LE_HEADER.len()) % n;
        if off != 0 {
            self.buf.resize(self.buf.len() + n - off, 0);
        }
    }

    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `uint64`.
    pub fn u64(&mut self, v: u64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Consecutive `float64`s: a fixed array `float64[N]` or a message of N `float64` fields.
    pub fn f64s(&mut self, v: &[f64]) {
        for x in v {
            self.f64(*x);
        }
    }

    /// An unbounded array `uint32[]`: its length as a `uint32`, then the elements.
    pub fn u32_seq(&mut self, v: &[u32]) {
        self.u32(v.len() as u32);
        for x in v {
            self.u32(*x);
        }
    }

    /// An unbounded array `float64[]`: its length as a `uint32`, then the elements.
    pub fn f64_seq(&mut self, v: &[f64]) {
        self.u32(v.len() as u32);
        self.f64s(v);
    }

    /// `n` 8-byte values (`value(i)`: the bits of value `i`) as a byte-shuffled
    /// `uint8[]` of `8 n` bytes: byte `j` (little-endian) of value `i` is
    /// element `j n + i`, so the bytes that vary little lie side by side and
    /// compress.
    pub fn shuffled_u64s(&mut self, n: usize, value: impl Fn(usize) -> u64) {
        self.u32((8 * n) as u32);
        self.buf.reserve(8 * n);
        for j in 0..8 {
            for i in 0..n {
                self.buf.push((value(i) >> (8 * j)) as u8);
            }
        }
    }

    /// A `string` (a NUL in `s` would end it early for C readers: NULs are left out).
    pub fn string(&mut self, s: &str) {
        let s: Cow<'_, str> = if s.contains('\0') {
            Cow::Owned(s.replace('\0', ""))
        } else {
            Cow::Borrowed(s)
        };
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }
}

/// Reads a CDR message field by field; every error names the field and the byte.
pub struct CdrReader<'a> {
    data: &'a [u8],
    pos: usize,
    ty: &'static str,
}

impl<'a> CdrReader<'a> {
    /// A reader of `data` (a message of type `ty`, for errors); refuses anything
    /// but little-endian plain CDR.
    pub fn new(data: &'a [u8], ty: &'static str) -> Result<Self, String> {
        match data.get(..2) {
            Some([0x00, 0x01]) => Ok(CdrReader { data, pos: 4, ty }),
            Some(h) => Err(format!(
                "{ty}: CDR encapsulation {:02x} {:02x} is not little-endian plain CDR (00 01)",
                h[0], h[1]
            )),
            None => Err(format!("{ty}: {} bytes, no CDR header", data.len())),
        }
    }

    fn take(&mut self, n: usize, field: &str) -> Result<&'a [u8], String> {
        let off = (self.pos - CDR_LE_HEADER.len()) % n.min(8);
        if off != 0 {
            self.pos += n.min(8) - off;
        }
        match self.data.get(self.pos..self.pos + n) {
            Some(b) => {
                self.pos += n;
                Ok(b)
            }
            None => Err(format!(
                "{}.{field}: the message ends at byte {}, before the field",
                self.ty,
                self.data.len()
            )),
        }
    }

    /// A `uint32`.
    pub fn u32(&mut self, field: &str) -> Result<u32, String> {
        let b = self.take(4, field)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A `uint64`.
    pub fn u64(&mut self, field: &str) -> Result<u64, String> {
        let b = self.take(8, field)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }

    /// A `float64`.
    pub fn f64(&mut self, field: &str) -> Result<f64, String> {
        self.u64(field).map(f64::from_bits)
    }

    /// A `float64` a later version appended: NaN (absent) when the message
    /// ends before it (a log of an earlier version).
    pub fn f64_added(&mut self, field: &str) -> Result<f64, String> {
        self.f64s_added::<1>(field).map(|[v]| v)
    }

    /// `N` consecutive `float64`s.
    pub fn f64s<const N: usize>(&mut self, field: &str) -> Result<[f64; N], String> {
        let mut out = [0.0; N];
        for x in &mut out {
            *x = self.f64(field)?;
        }
        Ok(out)
    }

    /// `N` consecutive `float64`s that a later version appended: all NaN
    /// ("absent") when the message ends before them (one of an earlier version).
    pub fn f64s_added<const N: usize>(&mut self, field: &str) -> Result<[f64; N], String> {
        if self.pos >= self.data.len() {
            return Ok([f64::NAN; N]);
        }
        self.f64s(field)
    }

    /// The length of an unbounded array of `elem_bytes`-byte elements, checked
    /// to fit in the rest of the message (so nothing is allocated for a length
    /// the data do not hold).
    pub fn seq_len(&mut self, elem_bytes: usize, field: &str) -> Result<usize, String> {
        let n = self.u32(field)? as usize;
        let left = self.data.len().saturating_sub(self.pos);
        if n.saturating_mul(elem_bytes) > left {
            return Err(format!(
                "{}.{field}: an array of {n} elements at byte {} runs past the message's {} bytes",
                self.ty,
                self.pos,
                self.data.len()
            ));
        }
        Ok(n)
    }

    /// A byte-shuffled `uint8[]` of 8-byte values ([`CdrWriter::shuffled_u64s`]):
    /// their count and an accessor of value `i`'s bits; an array whose length
    /// is not a multiple of 8 is an error naming the field.
    pub fn shuffled_u64s(&mut self, field: &str) -> Result<Shuffled<'a>, String> {
        let len = self.seq_len(1, field)?;
        if len % 8 != 0 {
            return Err(format!(
                "{}.{field}: {len} bytes, not a whole number of 8-byte values",
                self.ty
            ));
        }
        let bytes = &self.data[self.pos..self.pos + len];
        self.pos += len;
        Ok(Shuffled { bytes, n: len / 8 })
    }

    /// A `string`.
    pub fn string(&mut self, field: &str) -> Result<&'a str, String> {
        let len = self.u32(field)? as usize;
        let end = self.pos.checked_add(len).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(format!(
                "{}.{field}: a string of {len} bytes at byte {} runs past the message's {} bytes",
                self.ty,
                self.pos,
                self.data.len()
            ));
        };
        let bytes = &self.data[self.pos..end];
        self.pos = end;
        // the length counts the closing NUL; tolerate a writer that left it out
        let bytes = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        std::str::from_utf8(bytes).map_err(|e| format!("{}.{field}: not UTF-8: {e}", self.ty))
    }

    /// A NUL-padded text field of `N` bytes from a `string` (cut to `N` bytes at
    /// a character boundary, as the frames hold it).
    pub fn text<const N: usize>(&mut self, field: &str) -> Result<[u8; N], String> {
        self.string(field).map(frames::text_bytes)
    }

    /// A code from a `string` holding its name in `names` (or its number).
    pub fn code(&mut self, names: &[(u32, &'static str)], field: &str) -> Result<u32, String> {
        let s = self.string(field)?;
        code_of(names, s).ok_or_else(|| format!("{}.{field}: unknown name {s:?}", self.ty))
    }
}

/// A byte-shuffled array of 8-byte values as read ([`CdrReader::shuffled_u64s`]).
pub struct Shuffled<'a> {
    bytes: &'a [u8],
    /// Values held.
    pub n: usize,
}

impl Shuffled<'_> {
    /// The bits of value `i` (`i < n`).
    pub fn get(&self, i: usize) -> u64 {
        (0..8).fold(0u64, |v, j| v | u64::from(self.bytes[j * self.n + i]) << (8 * j))
    }
}

/// A record type of the log as a ROS 2 message in CDR.
///
/// The messages are read leniently at the end: bytes after the last known
/// field are ignored, so a later version may append fields.
pub trait Message: Sized {
    /// The ros2msg type name, the MCAP schema name (`leakwatch_msgs/msg/SensorFrame`).
    const MSG_TYPE: &'static str;
    /// The MCAP schema data: the `.msg` definition followed by those of the
    /// message types it uses, in rosbag2's concatenated form.
    const DEFINITION: &'static str;
    /// Writes the fields (after the header) into `w`.
    fn write_cdr(&self, w: &mut CdrWriter<'_>);
    /// Reads the fields; the error names the field.
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, String>;

    /// The CDR message (header included), written into `buf` (cleared first).
    fn to_cdr(&self, buf: &mut Vec<u8>) {
        let mut w = CdrWriter::new(buf);
        self.write_cdr(&mut w);
    }

    /// The record of a CDR message; the error names the field.
    fn from_cdr(data: &[u8]) -> Result<Self, String> {
        let mut r = CdrReader::new(data, Self::MSG_TYPE)?;
        Self::read_cdr(&mut r)
    }
}

/// Writes and reads a record type's fields in the order listed, each with its
/// codec: `u32`, `u64`, `f64`, `f64_added` (a `float64` a later version
/// appended: NaN when an earlier version's message ends before it), `f64s` (a
/// fixed array; `f64s_added`: one a later version appended, NaN in a message of
/// an earlier one), `text` (a fixed byte
/// buffer as a string), `code(NAMES)` (a code as its name) or `zero` (padding,
/// not on the wire, read as 0). Reading builds the struct literally, so a field
/// added to the type and not listed here does not compile.
macro_rules! cdr_fields {
    ($ty:ident { $($field:ident: $codec:ident $(($names:expr))?),* $(,)? }) => {
        fn write_cdr(&self, w: &mut CdrWriter<'_>) {
            $( cdr_fields!(@write w, self.$field, $codec $(($names))?); )*
        }

        fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, String> {
            Ok($ty {
                $( $field: cdr_fields!(@read r, stringify!($field), $codec $(($names))?), )*
            })
        }
    };
    (@write $w:ident, $v:expr, u32) => { $w.u32($v) };
    (@write $w:ident, $v:expr, u64) => { $w.u64($v) };
    (@write $w:ident, $v:expr, f64) => { $w.f64($v) };
    (@write $w:ident, $v:expr, f64_added) => { $w.f64($v) };
    (@write $w:ident, $v:expr, f64s) => { $w.f64s(&$v) };
    (@write $w:ident, $v:expr, f64s_added) => { $w.f64s(&$v) };
    (@write $w:ident, $v:expr, text) => { $w.string(frames::text(&$v)) };
    (@write $w:ident, $v:expr, code($names:expr)) => { $w.string(&code_name(&$names, $v)) };
    (@write $w:ident, $v:expr, zero) => { let _ = $v; };
    (@read $r:ident, $name:expr, u32) => { $r.u32($name)? };
    (@read $r:ident, $name:expr, u64) => { $r.u64($name)? };
    (@read $r:ident, $name:expr, f64) => { $r.f64($name)? };
    (@read $r:ident, $name:expr, f64_added) => { $r.f64_added($name)? };
    (@read $r:ident, $name:expr, f64s) => { $r.f64s($name)? };
    (@read $r:ident, $name:expr, f64s_added) => { $r.f64s_added($name)? };
    (@read $r:ident, $name:expr, text) => { $r.text($name)? };
    (@read $r:ident, $name:expr, code($names:expr)) => { $r.code(&$names, $name)? };
    (@read $r:ident, $name:expr, zero) => { Default::default() };
}

impl Message for SensorFrame {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/SensorFrame";
    const DEFINITION: &'static str = include_str!("../../leakwatch_msgs/msg/SensorFrame.msg");

    cdr_fields!(SensorFrame {
        seq: u64,
        acq_mono_ns: u64,
        t_s: f64,
        u_v: f64,
        x_m: f64,
        p1_pa: f64,
        p2_pa: f64,
        x_sp_m: f64,
        f_load_n: f64,
        ref_m: f64,
        q_leak_lpm: f64,
        flags: u32,
        _pad: zero,
        temp_c: f64_added,
    });
}

impl Message for EstimateFrame {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/EstimateFrame";
    const DEFINITION: &'static str = concat!(
        include_str!("../../leakwatch_msgs/msg/EstimateFrame.msg"),
        dependency!("LeakState"),
        dependency!("Measurement"),
        dependency!("Pressures"),
        dependency!("ThesisState"),
        dependency!("LeakFlows"),
    );

    cdr_fields!(EstimateFrame {
        seq: u64,
        acq_mono_ns: u64,
        est_recv_mono_ns: u64,
        est_done_mono_ns: u64,
        t_s: f64,
        n_states: u32,
        flags: u32,
        state: f64s,
        state_sigma: f64s,
        residual: f64s,
        innovation: f64s,
        innovation_sigma: f64s,
        measured: f64s,
        u_v: f64,
        nis: f64,
        mae_pa: f64s,
        th_flags: u32,
        _pad: zero,
        th_state: f64s,
        th_residual: f64s,
        th_innovation: f64s,
        th_mae_pa: f64s,
        th_nis: f64,
        bulk_scale: f64_added,
        bulk_scale_sigma: f64_added,
        oil_temp_c: f64_added,
        oil_temp_sigma_k: f64_added,
        laminar_factor_sigma: f64_added,
        null_leakage_band_lpm: f64_added,
        offset_response_p1_lpm_per_mpa: f64s_added,
        offset_response_p2_lpm_per_mpa: f64s_added,
        span_response_p1_lpm: f64s_added,
        span_response_p2_lpm: f64s_added,
        offset_response_x_lpm_per_mm: f64s_added,
        delay_response_p1_lpm_per_ms: f64s_added,
        delay_response_p2_lpm_per_ms: f64s_added,
    });
}

impl Message for LeakEventFrame {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/LeakEventFrame";
    const DEFINITION: &'static str = include_str!("../../leakwatch_msgs/msg/LeakEventFrame.msg");

    cdr_fields!(LeakEventFrame {
        seq: u64,
        acq_mono_ns: u64,
        cls_done_mono_ns: u64,
        event_id: u64,
        kind: code(event_kind::NAMES),
        phase: code(event_phase::NAMES),
        t_detect_s: f64,
        t_onset_s: f64,
        size_lpm: f64,
        size_lpm_sigma: f64,
        confidence: f64,
        detector: text,
        size_nominal_lpm: f64,
        coefficient_m3_s_sqrt_pa: f64,
        statistic: f64,
        threshold: f64,
        channel: text,
        detail: text,
    });
}

impl Message for HealthFrame {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/HealthFrame";
    const DEFINITION: &'static str = concat!(
        include_str!("../../leakwatch_msgs/msg/HealthFrame.msg"),
        dependency!("LeakFlows")
    );

    cdr_fields!(HealthFrame {
        seq: u64,
        mono_ns: u64,
        t_s: f64,
        status: code(health_status::NAMES),
        active_events: u32,
        leak_flow_lpm: f64s,
        leak_flow_sigma_lpm: f64s,
        leak_threshold_lpm: f64s_added,
    });
}

impl Message for StatsFrame {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/StatsFrame";
    const DEFINITION: &'static str = include_str!("../../leakwatch_msgs/msg/StatsFrame.msg");

    cdr_fields!(StatsFrame {
        mono_ns: u64,
        pid: u32,
        stage: code(stage::NAMES),
        frames_in: u64,
        frames_out: u64,
        seq_gaps: u64,
        deadline_misses: u64,
        proc_ns_p50: u64,
        proc_ns_p99: u64,
        proc_ns_max: u64,
        lat_ns_p50: u64,
        lat_ns_p99: u64,
        lat_ns_max: u64,
        cpu_fraction: f64,
        rss_bytes: u64,
    });
}

/// The topic of a gap record by its name.
pub(crate) fn topic_of(name: &str) -> Option<Topic> {
    Topic::ALL.into_iter().find(|t| t.as_str() == name)
}

impl Message for GapRecord {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/Gap";
    const DEFINITION: &'static str = include_str!("../../leakwatch_msgs/msg/Gap.msg");

    fn write_cdr(&self, w: &mut CdrWriter<'_>) {
        let GapRecord {
            topic,
            expected_seq,
            got_seq,
            missing,
            recv_mono_ns,
        } = *self;
        w.string(topic.as_str());
        w.u64(expected_seq);
        w.u64(got_seq);
        w.u64(missing);
        w.u64(recv_mono_ns);
    }

    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, String> {
        let name = r.string("topic")?;
        let topic =
            topic_of(name).ok_or_else(|| format!("{}.topic: unknown topic {name:?}", Self::MSG_TYPE))?;
        Ok(GapRecord {
            topic,
            expected_seq: r.u64("expected_seq")?,
            got_seq: r.u64("got_seq")?,
            missing: r.u64("missing")?,
            recv_mono_ns: r.u64("recv_mono_ns")?,
        })
    }
}
