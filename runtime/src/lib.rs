//! `leakwatch run`: start the four stage processes over iceoryx2, supervise
//! them, print events as they happen, and write events.json, latency.json and
//! the log (run.mcap) at the end.
//!
//! The stages (`acquisition`, `estimator`, `classifier`, `recorder`) are this
//! binary run as `leakwatch stage NAME`. A stage that exits is restarted with
//! backoff, the acquisition continuing its stream; a stage that makes no
//! progress is reported, and killed (so restarted) after 5 s. Every run gets
//! its own iceoryx2 prefix (`LEAKWATCH_IOX_PREFIX`), so runs and tests never
//! see each other.

mod args;
mod blocked;
mod clean;
mod error;
mod events;
mod figures;
mod launch;
mod notify;
mod outputs;
mod placement;
mod plan;
mod restart;
mod retention;
mod run_dir;
mod service;
mod stages;
mod summary;
mod supervision;
mod supervisor;
mod watchdog;

pub use args::RunArgs;
pub use clean::{clean, clean_all};
pub use error::RunError;
pub use stages::stage_main;
pub use supervisor::run_pipeline;

/// `leakwatch run`.
pub fn run(args: RunArgs) -> Result<(), String> {
    let o = run_pipeline(&args, false)?;
    summary::print(&args, &o)
}
