//! calibrate (placeholder).
