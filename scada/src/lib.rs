//! The OPC UA output of a running rig, for a plant's SCADA: `leakwatch stage
//! opcua` (started by `leakwatch run --opcua` or `[opcua] enabled`), a
//! process beside the pipeline like the live outputs, that subscribes to the
//! rig's estimates, health and events and serves them read-only with the
//! `async-opcua` server:
//!
//! - [`state`]: the rig's state variables (running, armed, watched, blind
//!   since, the active alarm's kind, size, onset and confidence, the smallest
//!   detectable leaks, the oil's temperature, sensor faults), kept from the bus;
//! - [`space`]: the address space, `Objects/Leakwatch/<rig>/<Variable>`;
//! - [`event`]: `LeakwatchEventType`, the OPC UA event of every leak and
//!   sensor event (raised, updated, cleared);
//! - [`server`]: endpoints and security of `[opcua]`;
//! - [`shell`]: the process.
//!
//! docs/opcua.md has the address space's table and how to connect.

pub mod event;
pub mod server;
pub mod shell;
pub mod space;
pub mod state;
