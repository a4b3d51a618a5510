//! bench (placeholder).
