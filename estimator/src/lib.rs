//! The `estimator` process crate: the EKF core is the pure [`filter`] crate;
//! this crate adds the process around it ([`shell`]: iceoryx2, command line, config file)
//! and the estimator's side of the wire ([`wire`]).

#![forbid(unsafe_code)]

pub mod shell;
pub mod wire;
