//! The wire types of leakwatch: every value that crosses a process boundary
//! over iceoryx2 shared memory, and the names of the services that carry them.
//!
//! Every frame is `#[repr(C)]`, fixed size, 8-byte aligned, with no implicit
//! padding (padding is an explicit `_pad` field, always 0), and carries a
//! versioned iceoryx2 type name `leakwatch.<Name>.v1`. iceoryx2 checks only the
//! type name, size and alignment when two processes open a service, so any
//! change of layout must bump the version in the type name. The byte layout of
//! every type (for the Python bindings' `ctypes.Structure`) is tabled in
//! `frames/README.md` and checked by the tests of this crate.
//!
//! Units: SI throughout (s, m, m/s, Pa, N, V, m³/s), except where a field name
//! says otherwise (`_lpm` = L/min, `_ns` = nanoseconds). Times named
//! `*_mono_ns` are `CLOCK_MONOTONIC` nanoseconds of the host; `t_s` is the
//! sample time of the source. A float that is `NaN` means "absent".
//!
//! [`udp`] is the other wire format: the little-endian datagrams in which a
//! DAQ board or PLC sends rig samples to the acquisition stage.

#![forbid(unsafe_code)]

use core::fmt;

use iceoryx2::prelude::*;

pub mod udp;

mod codes;
mod estimate;
mod event;
mod fields;
mod health;
mod sensor;
mod service;
mod stats;

pub use codes::{
    code_name, code_of, estimate_flags, event_kind, event_phase, health_status, sensor_flags, stage,
};
pub use estimate::{EstimateFrame, MAX_STATES, THESIS_STATES};
pub use event::{
    detail_bytes, detector_bytes, detector_name, text, text_bytes, LeakEventFrame, CHANNEL_NAME_LEN,
    DETAIL_LEN, DETECTOR_NAME_LEN, ELLIPSIS,
};
pub use health::HealthFrame;
pub use sensor::SensorFrame;
pub use service::{service_name, wake_service_name, RigId, RigIdError, Topic, RIG_ID_MAX_LEN};
pub use stats::StatsFrame;

/// A frame type with its topic: what the `bus` and `recorder` crates need to
/// know about every wire type.
pub trait Frame: fmt::Debug + Copy + Send + ZeroCopySend + Default + 'static {
    /// The topic that carries this type.
    const TOPIC: Topic;
    /// The sequence number, if the type carries one.
    fn seq(&self) -> Option<u64>;
    /// The acquisition time (`CLOCK_MONOTONIC`, ns), if the type carries one.
    fn acq_mono_ns(&self) -> Option<u64>;
    /// True if this is the last frame of its stream (types without the flag: false).
    fn is_end_of_stream(&self) -> bool {
        false
    }
    /// Marks this frame as the last of its stream (types without the flag: no-op).
    fn mark_end_of_stream(&mut self) {}
}

/// [`Frame`] for a type whose `seq` and `acq_mono_ns` fields are its sequence
/// number and acquisition time and whose `flags` carry an end-of-stream bit.
macro_rules! impl_sequenced_frame {
    ($ty:ty, $topic:expr, $end_of_stream:path) => {
        impl $crate::Frame for $ty {
            const TOPIC: $crate::Topic = $topic;
            fn seq(&self) -> Option<u64> {
                Some(self.seq)
            }
            fn acq_mono_ns(&self) -> Option<u64> {
                Some(self.acq_mono_ns)
            }
            fn is_end_of_stream(&self) -> bool {
                self.flags & $end_of_stream != 0
            }
            fn mark_end_of_stream(&mut self) {
                self.flags |= $end_of_stream;
            }
        }
    };
}
use impl_sequenced_frame;

// Compile-time layout checks (the offsets are checked in tests/layout.rs).
const _: () = assert!(core::mem::size_of::<SensorFrame>() == 104);
const _: () = assert!(core::mem::size_of::<EstimateFrame>() == 704);
const _: () = assert!(core::mem::size_of::<LeakEventFrame>() == 520);
const _: () = assert!(core::mem::size_of::<HealthFrame>() == 104);
const _: () = assert!(core::mem::size_of::<StatsFrame>() == 112);
