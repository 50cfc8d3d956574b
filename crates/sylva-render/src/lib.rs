//! The wgpu renderer: skinned branches, leaf-cluster billboards, ground, sky, one sun,
//! distance fog, 4× MSAA; one instanced draw per (species, LOD) bucket; headless capture.
//!
//! It reads [`sylva_forest::FrameData`] and the tree models, and never calls back into
//! the simulation. Shaders live in `src/shaders/*.wgsl`; `common.wgsl` is prepended to each
//! pipeline's file.
#![warn(missing_docs)]

mod gpu;
mod headless;
mod renderer;

pub use gpu::{Gpu, RenderError};
pub use headless::Headless;
pub use renderer::{Renderer, SHADERS, shader_source};
pub use wgpu;
