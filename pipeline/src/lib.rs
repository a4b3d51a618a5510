//! The in-process pipeline: each sample through the estimator stage (the leak
//! filter, and the thesis filter where something reads it) to the detectors,
//! and the offline runs built on it.
//!
//! Replay, batch, the demonstration, commissioning and every benchmark build
//! their chain from [`ChainSettings`] ([`chain`]), so none can drift from
//! another. The live pipeline runs the same two stages in their own processes
//! (`estimator`, `classifier`).
//!
//! - [`replay`]: a CSV recording through the chain into estimates, events and
//!   a summary; [`replay_cmd`] picks one file or a batch ([`batch`]: files on
//!   worker threads), [`estimates_out`] writes the estimates file.
//! - [`simulate`]: the rig simulator from a config, to CSV; [`demo`]: a
//!   simulated leak through the chain, printed.
//! - [`commission`]: a healthy recording into a commissioned config.
//! - [`commission_report`], [`calibrate_report`], `replay::report`: the HTML
//!   reports of commission, calibrate and replay, built of [`html`]'s pieces.
//! - [`logs`]: MCAP logs exported, repaired, described, replayed.
//! - [`model_file`]: the model.toml `calibrate` writes, read and written.
//! - [`out`]: every file and standard-output write; [`status`]: the exit
//!   status of a command that ran but could not do all it should.

#![forbid(unsafe_code)]

pub mod batch;
pub mod calibrate_report;
pub mod calibration;
pub mod chain;
pub mod commission;
pub mod commission_report;
pub mod demo;
pub mod estimates_out;
pub mod html;
pub mod logs;
pub mod model_file;
pub mod out;
pub mod replay;
pub mod replay_cmd;
pub mod simulate;
pub mod status;

pub use chain::{Chain, ChainSettings};
