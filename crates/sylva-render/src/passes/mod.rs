//! The render passes, one module each with its pipeline, bind groups and `.wgsl` side by
//! side: the sun's shadow map, sky, ground, branches, leaves and far-tree impostors; and the
//! viewer's control panel drawn over them.

pub mod branch;
pub mod far;
pub mod ground;
pub mod leaf;
pub mod panel;
pub mod shadow;
pub mod sky;
