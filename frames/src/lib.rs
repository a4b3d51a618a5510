//! frames (placeholder).
