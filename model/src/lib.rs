//! Physics of a servovalve-driven hydraulic cylinder (docs/model.md), double-rod
//! or single-rod: parameters (also from a rig's datasheet), valve, chambers, friction, leakage laws and load; the
//! continuous dynamics; the simulated rig (RK4 with sub-steps, sensors,
//! seeded noise, leak and sensor fault schedules); and the scenarios of the thesis.
//!
//! All quantities are SI (m, s, Pa, m³/s, N, V) unless a name says otherwise.

#![forbid(unsafe_code)]

pub mod datasheet;
pub mod dynamics;
pub mod fault;
pub mod friction;
pub mod instance;
pub mod leakage;
pub mod params;
pub mod process;
pub mod rigs;
pub mod rng;
pub mod sample;
pub mod scenario;
pub mod sensor_fault;
pub mod sensors;
pub mod sim;
pub mod units;

pub use datasheet::Datasheet;
pub use dynamics::{LeakSet, State};
pub use fault::{Fault, FaultSchedule};
pub use leakage::{LeakLaw, LeakPath};
pub use params::{ActuatorParams, FrictionPreset};
pub use sample::Sample;
pub use scenario::Scenario;
pub use sensor_fault::{SensorFault, SensorFaultSchedule};
pub use sensors::SensorParams;
pub use sim::{OilWarmUp, SimSettings, Simulator};
