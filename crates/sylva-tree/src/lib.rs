//! Weber–Penn parametric trees in the paper's hybrid representation (paper §4.1).
//!
//! Planned content (see `ARCHITECTURE.md`): species parameters under the WP95 names, a
//! skeleton of rigid segments linked by joints (one index space shared by mesh, leaves and
//! animation), generalized-cylinder branch meshes, leaf-cluster billboards, a geometry LOD
//! chain and glTF 2.0 export. This crate is a documented placeholder until that work lands;
//! it deliberately exports nothing yet, so no other crate can depend on a half-made API.
#![warn(missing_docs)]
