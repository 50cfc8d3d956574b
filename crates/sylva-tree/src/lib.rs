//! Weber–Penn parametric trees in the paper's hybrid representation (paper §4.1).
//!
//! Today this crate holds the [`Species`] parameters (Weber & Penn's full set under their
//! names, TOML species files, validation naming the key and line, six shipped presets) and
//! the [`Skeleton`]: the joint hierarchy that the branch mesh, the leaf clusters and the
//! animation share. Generation, meshes, leaves, the geometry LOD chain and glTF export are
//! still to come (see `ARCHITECTURE.md`).
#![warn(missing_docs)]

pub mod generate;
pub mod gltf;
pub mod mesh;
pub mod skeleton;
pub mod species;
pub mod texture;

pub use generate::{Tree, TreeStats, shape_ratio};
pub use mesh::{BranchMesh, LeafCluster, TreeLod, TreeModel};
pub use skeleton::{Joint, NO_PARENT, Skeleton, SkeletonError};
pub use species::{LevelParams, PARAMS, PRESETS, Species, SpeciesError};
pub use texture::{Image, LeafAtlas};
