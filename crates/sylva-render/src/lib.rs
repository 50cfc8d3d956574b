//! The wgpu renderer: skinned branches, leaf billboards, ground and sky, instancing and LOD
//! cross-fade, headless capture.
//!
//! Documented placeholder: exports nothing yet. It will read `FrameData` from `sylva-forest`
//! and never call back into the simulation.
#![warn(missing_docs)]
