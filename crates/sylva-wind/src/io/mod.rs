//! File formats (placeholder)
