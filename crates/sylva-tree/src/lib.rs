//! Weber–Penn parametric trees in the paper's hybrid representation (paper §4.1).
//!
//! From a [`Species`] (Weber & Penn's full parameter set under their names, TOML species
//! files whose errors name the key and line, six shipped presets) and a seed:
//! [`Species::generate`] grows the [`Skeleton`] — the joint hierarchy that the branch mesh,
//! the leaf clusters and the animation share — and [`Species::model`] adds the
//! [`mesh`] (skinned branch meshes and leaf-cluster billboards at every level of the
//! geometry LOD chain) and the procedural [`texture`]s; [`gltf`] writes it all as `.glb`.
//! See `ARCHITECTURE.md`.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod generate;
pub mod gltf;
pub mod lod_error;
pub mod mesh;
pub mod order;
pub mod skeleton;
pub mod species;
pub mod texture;

/// Fraction of a tree's height at which the one wind velocity that drives its simulation is
/// read (an instance group's sample point, `tree animate`'s wind, the viewer's probe):
/// within the crown, where most of the tree's drag acts. Kept as `f64` so that the `f32`
/// uses (`as f32`) and the `f64` uses read exactly the literal 0.7.
pub const WIND_SAMPLE_HEIGHT: f64 = 0.7;

pub use generate::{Tree, TreeStats, shape_ratio};
pub use mesh::{BranchMesh, LeafCluster, TreeLod, TreeModel};
pub use order::{LodOrder, lod_order};
pub use skeleton::{Joint, NO_PARENT, Skeleton, SkeletonError};
pub use species::{LevelParams, PARAMS, PRESETS, Species, SpeciesError};
pub use texture::{Image, LeafAtlas};
