//! [`LeakEventFrame`]: a leak or fault event from the classifier, and its
//! NUL-padded text fields (detector name, channel, detail).

use iceoryx2::prelude::*;

use crate::{Frame, Topic};

/// Length of [`LeakEventFrame::detector`], bytes.
pub const DETECTOR_NAME_LEN: usize = 16;
/// Length of [`LeakEventFrame::channel`], bytes.
pub const CHANNEL_NAME_LEN: usize = 8;
/// Length of [`LeakEventFrame::detail`], bytes (UTF-8): room for the longest
/// details the classifier writes (a slowly growing leak's 280 bytes, a drifting
/// offset's 326, every number at its widest; tests in classifier/src/wire.rs);
/// a longer text is cut at a word boundary and ends in `…` (see [`detail_bytes`]).
pub const DETAIL_LEN: usize = 384;

/// A leak or fault event from the classifier (raised, updated, cleared).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("leakwatch.LeakEventFrame.v3")]
pub struct LeakEventFrame {
    /// Sequence number of the estimate that triggered the event.
    pub seq: u64,
    /// `CLOCK_MONOTONIC` when that sample was acquired, ns.
    pub acq_mono_ns: u64,
    /// `CLOCK_MONOTONIC` when the classifier decided, ns.
    pub cls_done_mono_ns: u64,
    /// Identifier of the event, the same for its raised, updated and cleared frames.
    pub event_id: u64,
    /// One of [`event_kind`](crate::event_kind).
    pub kind: u32,
    /// One of [`event_phase`](crate::event_phase).
    pub phase: u32,
    /// Sample time of the decision, s.
    pub t_detect_s: f64,
    /// Estimated onset time, s (NaN = unknown).
    pub t_onset_s: f64,
    /// Estimated leak flow, L/min (NaN for non-leak events).
    pub size_lpm: f64,
    /// One standard deviation of [`Self::size_lpm`], L/min.
    pub size_lpm_sigma: f64,
    /// Confidence of the decision, 0..1.
    pub confidence: f64,
    /// Name of the detector, ASCII, NUL-padded (see [`detector_name`]).
    pub detector: [u8; DETECTOR_NAME_LEN],
    /// The same leak at the nominal pressure drop p_s/2, L/min (NaN if not sized).
    pub size_nominal_lpm: f64,
    /// Leak coefficient of the square-root law q = k·√Δp, m³/(s·√Pa) (NaN if not sized).
    pub coefficient_m3_s_sqrt_pa: f64,
    /// Decision statistic, in healthy spreads (NaN where not applicable).
    pub statistic: f64,
    /// Threshold of the statistic, in healthy spreads (NaN where not applicable).
    pub threshold: f64,
    /// Sensor events: the channel (`x`, `p1`, `p2`), ASCII, NUL-padded; empty otherwise.
    pub channel: [u8; CHANNEL_NAME_LEN],
    /// Human-readable detail, UTF-8, NUL-padded, at most [`DETAIL_LEN`] bytes
    /// (a longer one cut at a word boundary with `…`, see [`detail_bytes`]).
    pub detail: [u8; DETAIL_LEN],
}

impl Frame for LeakEventFrame {
    const TOPIC: Topic = Topic::Events;
    /// Events are sparse and their `seq` is the triggering estimate's: no sequence to check.
    fn seq(&self) -> Option<u64> {
        None
    }
    fn acq_mono_ns(&self) -> Option<u64> {
        Some(self.acq_mono_ns)
    }
}

/// All-zero integers, NaN floats ("absent"), empty detector name.
impl Default for LeakEventFrame {
    fn default() -> Self {
        LeakEventFrame {
            seq: 0,
            acq_mono_ns: 0,
            cls_done_mono_ns: 0,
            event_id: 0,
            kind: 0,
            phase: 0,
            t_detect_s: f64::NAN,
            t_onset_s: f64::NAN,
            size_lpm: f64::NAN,
            size_lpm_sigma: f64::NAN,
            confidence: f64::NAN,
            detector: [0; DETECTOR_NAME_LEN],
            size_nominal_lpm: f64::NAN,
            coefficient_m3_s_sqrt_pa: f64::NAN,
            statistic: f64::NAN,
            threshold: f64::NAN,
            channel: [0; CHANNEL_NAME_LEN],
            detail: [0; DETAIL_LEN],
        }
    }
}

/// The detector name as a NUL-padded ASCII field: non-ASCII bytes become `?`
/// and a name longer than [`DETECTOR_NAME_LEN`] bytes is cut.
pub fn detector_bytes(name: &str) -> [u8; DETECTOR_NAME_LEN] {
    let mut out = [0u8; DETECTOR_NAME_LEN];
    for (o, b) in out.iter_mut().zip(name.bytes()) {
        *o = if b.is_ascii() && b != 0 { b } else { b'?' };
    }
    out
}

/// The detector name of a NUL-padded field: the bytes before the first NUL
/// (non-UTF-8 content gives `"?"`).
pub fn detector_name(field: &[u8; DETECTOR_NAME_LEN]) -> &str {
    text(field)
}

/// A UTF-8 text as a NUL-padded field of `N` bytes: cut at the last character
/// boundary that fits, NUL characters left out.
pub fn text_bytes<const N: usize>(text: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut n = 0;
    for c in text.chars().filter(|c| *c != '\0') {
        let len = c.len_utf8();
        if n + len > N {
            break;
        }
        c.encode_utf8(&mut out[n..n + len]);
        n += len;
    }
    out
}

/// The ellipsis that ends a detail cut by [`detail_bytes`] (3 bytes of UTF-8).
pub const ELLIPSIS: &str = "…";

/// A detail as the NUL-padded field [`LeakEventFrame::detail`]: whole if it
/// fits in [`DETAIL_LEN`] bytes; else cut before the last space that leaves
/// room for [`ELLIPSIS`] (never inside a word, a number or a unit), or, in a
/// text without a space in its last 64 bytes, at a character boundary, and
/// ended with [`ELLIPSIS`]. NUL characters are left out.
pub fn detail_bytes(detail: &str) -> [u8; DETAIL_LEN] {
    let clean: String = detail.chars().filter(|c| *c != '\0').collect();
    if clean.len() <= DETAIL_LEN {
        return text_bytes(&clean);
    }
    let room = DETAIL_LEN - ELLIPSIS.len();
    // the last character boundary at or before `room`
    let mut end = room;
    while !clean.is_char_boundary(end) {
        end -= 1;
    }
    // back to the last space, unless that throws away more than 64 bytes
    if let Some(space) = clean[..end].rfind(' ').filter(|s| end - *s <= 64) {
        end = space;
    }
    let cut = format!(
        "{}{ELLIPSIS}",
        clean[..end].trim_end_matches([' ', ',', ';', ':'])
    );
    text_bytes(&cut)
}

/// The text of a NUL-padded field: the bytes before the first NUL (non-UTF-8
/// content gives `"?"`).
pub fn text<const N: usize>(field: &[u8; N]) -> &str {
    let end = field.iter().position(|&b| b == 0).unwrap_or(N);
    core::str::from_utf8(&field[..end]).unwrap_or("?")
}
