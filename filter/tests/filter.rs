//! The estimator against the simulated rig and against textbook properties.

#[path = "filter/command_timing.rs"]
mod command_timing;
#[path = "filter/consistency.rs"]
mod consistency;
#[path = "filter/convergence.rs"]
mod convergence;
#[path = "filter/oil.rs"]
mod oil;
#[path = "filter/samples.rs"]
mod samples;
