//! Why `leakwatch run` did not start, or ended on a failure.

use std::fmt;

/// Why a run did not start or did not end well; each step of
/// [`crate::run_pipeline`] has its own kind. The message names the argument,
/// file, stage or output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RunError {
    /// An argument, the config or an output path is wrong: nothing started.
    Invalid(String),
    /// The run could not start: the iceoryx2 prefix, the bus, the config for
    /// the stages, a stage process. What the start made is removed.
    Start(String),
    /// The watch could not go on (the terminal or pipe events are printed to closed).
    Watch(String),
    /// The run ended on a failure (a stage given up, a blocked restart); what
    /// was gathered is written, and the message says where.
    Failed(String),
    /// events.json or latency.json could not be written anywhere.
    Output(String),
}

impl RunError {
    /// The message, without the kind.
    pub fn message(&self) -> &str {
        match self {
            RunError::Invalid(m)
            | RunError::Start(m)
            | RunError::Watch(m)
            | RunError::Failed(m)
            | RunError::Output(m) => m,
        }
    }
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.message())
    }
}

impl std::error::Error for RunError {}

impl From<RunError> for String {
    fn from(e: RunError) -> String {
        e.message().to_string()
    }
}
