//! `leakwatch run`: start the four stage processes over iceoryx2, supervise
//! them, print events as they happen, and write events.json, latency.json and
//! the log (run.mcap) at the end.
//!
//! The stage binaries (`acquisition`, `estimator`, `classifier`, `recorder`)
//! are looked up next to the `leakwatch` binary; inside a Cargo workspace they
//! are built on first use. Every run gets its own iceoryx2 prefix
//! (`LEAKWATCH_IOX_PREFIX`), so runs and tests never see each other.

mod args;
mod events;
mod figures;
mod stages;
mod summary;
mod supervisor;

pub use args::RunArgs;
pub use stages::stage_main;
pub use supervisor::run_pipeline;

/// `leakwatch run`.
pub fn run(args: RunArgs) -> Result<(), String> {
    let o = run_pipeline(&args, false)?;
    summary::print(&args, &o)
}
