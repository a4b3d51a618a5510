//! classifier (placeholder).
