//! [`SensorFrame`]: one rig sample as published by the acquisition, and its
//! conversions from and to [`model::Sample`].

use iceoryx2::prelude::*;

use crate::{impl_sequenced_frame, sensor_flags, Topic};

/// One rig sample as published by the acquisition process (1 kHz).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.SensorFrame.v2")]
pub struct SensorFrame {
    /// Sequence number, 0 for the first frame of a stream, +1 per frame.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when the frame was published, ns.
    pub acq_mono_ns: u64,
    /// Sample time of the source, s.
    pub t_s: f64,
    /// Valve command applied from this sample to the next, V.
    pub u_v: f64,
    /// Measured rod position, m.
    pub x_m: f64,
    /// Measured chamber-1 pressure, Pa.
    pub p1_pa: f64,
    /// Measured chamber-2 pressure, Pa.
    pub p2_pa: f64,
    /// Measured spool position, m (NaN = channel absent).
    pub x_sp_m: f64,
    /// Measured external load force, N (NaN = channel absent).
    pub f_load_n: f64,
    /// Position reference of the controller, m (NaN = open loop or absent).
    pub ref_m: f64,
    /// Leak flow (flow meter or simulator truth), L/min (NaN = channel absent).
    pub q_leak_lpm: f64,
    /// Bit set of [`sensor_flags`].
    pub flags: u32,
    /// Explicit padding, always 0.
    pub _pad: u32,
    /// Oil temperature, °C (NaN = channel absent).
    pub temp_c: f64,
}

impl_sequenced_frame!(SensorFrame, Topic::Frames, sensor_flags::END_OF_STREAM);

/// All-zero integers, NaN floats ("absent"), empty detector name.
impl Default for SensorFrame {
    fn default() -> Self {
        SensorFrame {
            seq: 0,
            acq_mono_ns: 0,
            t_s: f64::NAN,
            u_v: f64::NAN,
            x_m: f64::NAN,
            p1_pa: f64::NAN,
            p2_pa: f64::NAN,
            x_sp_m: f64::NAN,
            f_load_n: f64::NAN,
            ref_m: f64::NAN,
            q_leak_lpm: f64::NAN,
            flags: 0,
            _pad: 0,
            temp_c: f64::NAN,
        }
    }
}

/// The sample a sensor frame carries (sequence, clock and flags stay on the wire).
impl From<&SensorFrame> for model::Sample {
    fn from(f: &SensorFrame) -> Self {
        model::Sample {
            t_s: f.t_s,
            u_v: f.u_v,
            x_m: f.x_m,
            p1_pa: f.p1_pa,
            p2_pa: f.p2_pa,
            x_sp_m: f.x_sp_m,
            f_load_n: f.f_load_n,
            ref_m: f.ref_m,
            q_leak_lpm: f.q_leak_lpm,
            temp_c: f.temp_c,
        }
    }
}

/// A sensor frame carrying `s`, with sequence 0, clock 0 and no flags (the
/// publisher sets those).
impl From<&model::Sample> for SensorFrame {
    fn from(s: &model::Sample) -> Self {
        SensorFrame {
            seq: 0,
            acq_mono_ns: 0,
            t_s: s.t_s,
            u_v: s.u_v,
            x_m: s.x_m,
            p1_pa: s.p1_pa,
            p2_pa: s.p2_pa,
            x_sp_m: s.x_sp_m,
            f_load_n: s.f_load_n,
            ref_m: s.ref_m,
            q_leak_lpm: s.q_leak_lpm,
            flags: 0,
            _pad: 0,
            temp_c: s.temp_c,
        }
    }
}
