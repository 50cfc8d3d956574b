//! Weber–Penn parametric trees in the paper's hybrid representation (paper §4.1).
//!
//! Today this crate holds the [`Skeleton`]: the joint hierarchy that the branch mesh, the
//! leaf clusters and the animation share. Species parameters, generation, meshes, leaves,
//! the geometry LOD chain and glTF export are still to come (see `ARCHITECTURE.md`).
#![warn(missing_docs)]

pub mod skeleton;

pub use skeleton::{Joint, NO_PARENT, Skeleton, SkeletonError};
