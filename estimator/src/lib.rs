//! estimator (placeholder).
