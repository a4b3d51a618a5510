//! plot (placeholder).
