//! The live outputs of a running rig, each its own process beside the pipeline
//! (it subscribes to the bus like the recorder and never slows the stages: it
//! drains its subscriptions every 20 ms, keeps the frames and estimates it
//! sends at a configured rate, and drops what a slow client cannot take):
//!
//! - [`view`]: the **live view**, Foxglove's WebSocket protocol
//!   (v1, subprotocol `foxglove.sdk.v1`, `foxglove.sdk.v1.1` or the earlier
//!   name `foxglove.websocket.v1`) served by the official `foxglove` crate
//!   (`leakwatch stage liveview`, `leakwatch run --live-view [PORT]`);
//! - [`gateway`]: the **fleet gateway**, which publishes a rig's events,
//!   health and decimated estimates on Zenoh under `leakwatch/<rig>/<topic>`
//!   (`leakwatch stage gateway`, `leakwatch run --zenoh`);
//! - [`layout`]: the live view's Foxglove layout, `docs/foxglove/leakwatch-layout.json`;
//! - [`watch`]: `leakwatch watch`, which subscribes to `leakwatch/**` on Zenoh
//!   and prints every rig's events as they happen;
//! - [`sign`]: the gateway's messages signed (HMAC-SHA256, `[zenoh] key_file`)
//!   and verified by `watch`.
//!
//! Both outputs send the same JSON messages, each with a JSON Schema
//! ([`json`]): SI units in the field names (`p1_pa`, `f_e_n`, `leak_ext1_lpm`),
//! codes as names (`"ext1"`, `"raised"`, `"healthy"`), NaN as `null`.

pub mod gateway;
pub mod json;
pub mod layout;
pub mod shell;
pub mod sign;
pub mod tap;
pub mod view;
pub mod watch;

pub use tap::{Decimator, LiveTopic, Sink, Tap, TapCounts};

/// CPU time this process has used (user + system), s; NaN if unknown.
pub fn cpu_time_s() -> f64 {
    // SAFETY: getrusage writes the zeroed struct it is given.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut ru) } != 0 {
        return f64::NAN;
    }
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    tv(ru.ru_utime) + tv(ru.ru_stime)
}
