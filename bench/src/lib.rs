//! Benchmark harnesses run from `leakwatch bench ...` (docs/performance.md). They
//! print tables and return JSON-ready results; they are never timed assertions.

#![forbid(unsafe_code)]

pub mod alarms;
pub mod commands;
pub mod detection;
pub mod detection_data;
pub mod identification;
pub mod replay;
pub mod speed;
pub mod stats;
pub mod thesis;
pub mod truth_flow;
pub mod work;
