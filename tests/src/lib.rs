//! End-to-end and workspace tests live in tests/tests/ (`pure_crates.rs`: the
//! pure crates depend on no process machinery).

#![forbid(unsafe_code)]
