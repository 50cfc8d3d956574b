//! The forest scene (paper §4.3, §5.2): layout, camera, the three LOD policies, instance
//! groups and the per-frame driver that produces `FrameData` (plain Pod arrays).
//!
//! Documented placeholder: exports nothing yet. Architecture invariant: this crate never
//! depends on a GPU or windowing crate.
#![warn(missing_docs)]
