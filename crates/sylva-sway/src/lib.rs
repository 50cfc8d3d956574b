//! Quasi-physical tree animation (paper §4.2): damped angular springs on skeleton joints,
//! leaf-cluster sway and the animation LOD (active-joint budgets).
//!
//! Documented placeholder: the crate exports nothing until the spring model lands. It will
//! depend on `sylva-wind` (velocities, eq.-8 force) and `sylva-tree` (skeletons) only.
#![warn(missing_docs)]
