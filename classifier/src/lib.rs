//! The `classifier` process crate: the detectors are the pure [`detect`]
//! crate; this crate adds the process around them ([`shell`]: iceoryx2, command line, config file;
//! [`node`]: its work on each estimate), the estimator and classifier fused in
//! one process ([`fused`]) and the classifier's side of the wire ([`wire`]).

#![forbid(unsafe_code)]

pub mod fused;
pub mod node;
pub mod shell;
pub mod wire;
