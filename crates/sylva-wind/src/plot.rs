//! Plot
