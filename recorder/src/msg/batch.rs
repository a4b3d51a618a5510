//! The frame batch (`leakwatch_msgs/msg/SensorFrameBatch`): consecutive sensor
//! frames in columns, with its CDR encoding.

use frames::SensorFrame;

use super::{CdrReader, CdrWriter, Message};

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
    const DEFINITION: &'static str = include_str!("../../../leakwatch_msgs/msg/SensorFrameBatch.msg");

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
