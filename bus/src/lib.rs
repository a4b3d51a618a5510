//! bus (placeholder).
