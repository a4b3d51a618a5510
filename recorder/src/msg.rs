// Over 600 lines: every message type with its schema and encoding, kept side by side so that a field changes in one place.
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

/// Consecutive sensor frames of the `frames` topic in columns
/// (`leakwatch_msgs/msg/SensorFrameBatch`): the log's lossless record of every
/// frame, written on the channel [`crate::FRAME_BATCHES_CHANNEL`]. Frame `i`
/// has sequence number `first_seq + i`; element `i` of every column is its
/// field (units as in [`SensorFrame`]: s, V, m, Pa, N, L/min, °C, ns). In the
/// message the columns `acq_mono_ns`, `t_s` and `u_v` are byte-shuffled
/// `uint8[]` ([`CdrWriter::shuffled_u64s`]: a rig's stream then takes 23 %
/// less), the others plain arrays.
///
/// The columns keep their capacity across [`SensorFrameBatch::clear`], so the
/// writer fills one batch after another without allocating.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SensorFrameBatch {
    /// Sequence number of the first frame (the others follow it by 1).
    pub first_seq: u64,
    /// When each frame was published, `CLOCK_MONOTONIC` ns.
    pub acq_mono_ns: Vec<u64>,
    /// Sample time of the source, s.
    pub t_s: Vec<f64>,
    /// Valve command, V.
    pub u_v: Vec<f64>,
    /// Rod position, m.
    pub x_m: Vec<f64>,
    /// Chamber-1 pressure, Pa.
    pub p1_pa: Vec<f64>,
    /// Chamber-2 pressure, Pa.
    pub p2_pa: Vec<f64>,
    /// Spool position, m (NaN = absent).
    pub x_sp_m: Vec<f64>,
    /// External load force, N (NaN = absent).
    pub f_load_n: Vec<f64>,
    /// Position reference, m (NaN = absent).
    pub ref_m: Vec<f64>,
    /// Leak flow, L/min (NaN = absent).
    pub q_leak_lpm: Vec<f64>,
    /// The frames' flag bits (`frames::sensor_flags`).
    pub flags: Vec<u32>,
    /// Oil temperature, °C (NaN = absent).
    pub temp_c: Vec<f64>,
}

impl SensorFrameBatch {
    /// An empty batch whose columns hold `capacity` frames without allocating.
    pub fn with_capacity(capacity: usize) -> Self {
        let f = || Vec::with_capacity(capacity);
        SensorFrameBatch {
            first_seq: 0,
            acq_mono_ns: Vec::with_capacity(capacity),
            t_s: f(),
            u_v: f(),
            x_m: f(),
            p1_pa: f(),
            p2_pa: f(),
            x_sp_m: f(),
            f_load_n: f(),
            ref_m: f(),
            q_leak_lpm: f(),
            flags: Vec::with_capacity(capacity),
            temp_c: f(),
        }
    }

    /// Frames held.
    pub fn len(&self) -> usize {
        self.acq_mono_ns.len()
    }

    /// Whether it holds no frame.
    pub fn is_empty(&self) -> bool {
        self.acq_mono_ns.is_empty()
    }

    /// Empties it, keeping the columns' capacity.
    pub fn clear(&mut self) {
        self.acq_mono_ns.clear();
        for c in [
            &mut self.t_s,
            &mut self.u_v,
            &mut self.x_m,
            &mut self.p1_pa,
            &mut self.p2_pa,
            &mut self.x_sp_m,
            &mut self.f_load_n,
            &mut self.ref_m,
            &mut self.q_leak_lpm,
            &mut self.temp_c,
        ] {
            c.clear();
        }
        self.flags.clear();
    }

    /// Whether `f` continues the batch: it is empty, or `f` is the frame after its last.
    pub fn continues_with(&self, f: &SensorFrame) -> bool {
        self.is_empty() || Some(f.seq) == self.first_seq.checked_add(self.len() as u64)
    }

    /// Appends `f`, which must continue the batch ([`SensorFrameBatch::continues_with`]);
    /// returns false (and holds nothing new) if it does not.
    pub fn push(&mut self, f: &SensorFrame) -> bool {
        if !self.continues_with(f) {
            return false;
        }
        if self.is_empty() {
            self.first_seq = f.seq;
        }
        self.acq_mono_ns.push(f.acq_mono_ns);
        self.t_s.push(f.t_s);
        self.u_v.push(f.u_v);
        self.x_m.push(f.x_m);
        self.p1_pa.push(f.p1_pa);
        self.p2_pa.push(f.p2_pa);
        self.x_sp_m.push(f.x_sp_m);
        self.f_load_n.push(f.f_load_n);
        self.ref_m.push(f.ref_m);
        self.q_leak_lpm.push(f.q_leak_lpm);
        self.flags.push(f.flags);
        self.temp_c.push(f.temp_c);
        true
    }

    /// Frame `i` (`None` past the end).
    pub fn frame(&self, i: usize) -> Option<SensorFrame> {
        Some(SensorFrame {
            seq: self.first_seq.checked_add(i as u64)?,
            acq_mono_ns: *self.acq_mono_ns.get(i)?,
            t_s: *self.t_s.get(i)?,
            u_v: *self.u_v.get(i)?,
            x_m: *self.x_m.get(i)?,
            p1_pa: *self.p1_pa.get(i)?,
            p2_pa: *self.p2_pa.get(i)?,
            x_sp_m: *self.x_sp_m.get(i)?,
            f_load_n: *self.f_load_n.get(i)?,
            ref_m: *self.ref_m.get(i)?,
            q_leak_lpm: *self.q_leak_lpm.get(i)?,
            flags: *self.flags.get(i)?,
            _pad: 0,
            temp_c: *self.temp_c.get(i)?,
        })
    }

    /// Every frame, in order.
    pub fn frames(&self) -> impl Iterator<Item = SensorFrame> + '_ {
        (0..self.len()).map_while(|i| self.frame(i))
    }

    /// Reads a CDR message's frames and appends them to `out` (no batch is
    /// built); returns how many. The error names the field: a column whose
    /// length differs from the others', an empty batch, or a sequence number
    /// that overflows.
    pub fn append_frames_from_cdr(data: &[u8], out: &mut Vec<SensorFrame>) -> Result<usize, String> {
        let b = SensorFrameBatch::from_cdr(data)?;
        out.reserve(b.len());
        out.extend(b.frames());
        Ok(b.len())
    }

    /// The sequence number of the last frame of a CDR message, reading only
    /// its first two fields (`None`: the message holds no frame).
    pub fn last_seq_from_cdr(data: &[u8]) -> Result<Option<u64>, String> {
        let mut r = CdrReader::new(data, Self::MSG_TYPE)?;
        let first = r.u64("first_seq")?;
        let n = r.shuffled_u64s("acq_mono_ns_shuffled")?.n as u64;
        Ok(n.checked_sub(1).and_then(|k| first.checked_add(k)))
    }
}

impl Message for SensorFrameBatch {
    const MSG_TYPE: &'static str = "leakwatch_msgs/msg/SensorFrameBatch";
    const DEFINITION: &'static str = include_str!("../../leakwatch_msgs/msg/SensorFrameBatch.msg");

    fn write_cdr(&self, w: &mut CdrWriter<'_>) {
        let n = self.len();
        w.u64(self.first_seq);
        w.shuffled_u64s(n, |i| self.acq_mono_ns[i]);
        w.shuffled_u64s(n, |i| self.t_s[i].to_bits());
        w.shuffled_u64s(n, |i| self.u_v[i].to_bits());
        for c in [
            &self.x_m,
            &self.p1_pa,
            &self.p2_pa,
            &self.x_sp_m,
            &self.f_load_n,
            &self.ref_m,
            &self.q_leak_lpm,
        ] {
            w.f64_seq(c);
        }
        w.u32_seq(&self.flags);
        w.f64_seq(&self.temp_c);
    }

    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, String> {
        let first_seq = r.u64("first_seq")?;
        let acq = r.shuffled_u64s("acq_mono_ns_shuffled")?;
        let n = acq.n;
        if n == 0 {
            return Err(format!("{}: a batch of no frame", Self::MSG_TYPE));
        }
        if first_seq.checked_add(n as u64 - 1).is_none() {
            return Err(format!(
                "{}.first_seq: {first_seq} + {n} frames overflows",
                Self::MSG_TYPE
            ));
        }
        let mut b = SensorFrameBatch::with_capacity(n);
        b.first_seq = first_seq;
        b.acq_mono_ns.extend((0..n).map(|i| acq.get(i)));
        for (field, out) in [("t_s_shuffled", &mut b.t_s), ("u_v_shuffled", &mut b.u_v)] {
            let column = r.shuffled_u64s(field)?;
            if column.n != n {
                return Err(format!(
                    "{}.{field}: {} values, the batch has {n} frames",
                    Self::MSG_TYPE,
                    column.n
                ));
            }
            out.extend((0..n).map(|i| f64::from_bits(column.get(i))));
        }
        let f64_column = |r: &mut CdrReader<'_>, field: &str, out: &mut Vec<f64>| {
            let len = r.seq_len(8, field)?;
            if len != n {
                return Err(format!(
                    "{}.{field}: {len} elements, the batch has {n} frames",
                    Self::MSG_TYPE
                ));
            }
            for _ in 0..n {
                out.push(r.f64(field)?);
            }
            Ok::<(), String>(())
        };
        f64_column(r, "x_m", &mut b.x_m)?;
        f64_column(r, "p1_pa", &mut b.p1_pa)?;
        f64_column(r, "p2_pa", &mut b.p2_pa)?;
        f64_column(r, "x_sp_m", &mut b.x_sp_m)?;
        f64_column(r, "f_load_n", &mut b.f_load_n)?;
        f64_column(r, "ref_m", &mut b.ref_m)?;
        f64_column(r, "q_leak_lpm", &mut b.q_leak_lpm)?;
        let len = r.seq_len(4, "flags")?;
        if len != n {
            return Err(format!(
                "{}.flags: {len} elements, the batch has {n} frames",
                Self::MSG_TYPE
            ));
        }
        for _ in 0..n {
            b.flags.push(r.u32("flags")?);
        }
        f64_column(r, "temp_c", &mut b.temp_c)?;
        Ok(b)
    }
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
