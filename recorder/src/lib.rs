//! recorder (placeholder).
