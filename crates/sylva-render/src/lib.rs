//! The wgpu renderer: skinned branches, leaf-cluster billboards, impostors for far trees,
//! ground, sky, one sun, distance fog, 4× MSAA; one instanced draw per (LOD, species)
//! bucket, levels cross-faded by a screen-space dither; headless capture.
//!
//! It reads [`sylva_forest::FrameData`] and the tree models, and never calls back into
//! the simulation. Each pass (`passes/`) keeps its pipeline and its `.wgsl` side by side;
//! `common.wgsl` is prepended to each; [`layout`] holds every type the shaders read.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod gpu;
mod headless;
pub mod layout;
pub mod passes;
mod passtimes;
mod renderer;
mod shared;
mod timer;

pub use egui;
pub use gpu::{Gpu, RenderError};
pub use headless::Headless;
pub use passes::panel::{PanelFrame, PanelPass};
pub use passtimes::PARTS as PASS_PARTS;
pub use renderer::{Overlay, Renderer, SceneAssets};
pub use shared::{DEPTH, SHADER_PARTS, SHADERS, shader_source};
pub use timer::GpuTimer;
pub use wgpu;
