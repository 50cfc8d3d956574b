//! The wgpu renderer: skinned branches, leaf-cluster billboards, impostors for far trees,
//! ground, sky, one sun, distance fog, 4× MSAA; one instanced draw per (LOD, species)
//! bucket, levels cross-faded by a screen-space dither; headless capture.
//!
//! It reads [`sylva_forest::FrameData`] and the tree models, and never calls back into
//! the simulation. Each pass (`passes/`) keeps its pipeline and its `.wgsl` side by side;
//! `common.wgsl` is prepended to each; [`layout`] holds every type the shaders read.
//!
//! Three ways to draw: [`Headless`] renders offscreen and reads the image back (below);
//! [`Renderer::render`] draws onto a view of yours (a window's surface) and submits;
//! [`Renderer::encode`] and [`Renderer::encode_over`] record into your own command encoder,
//! the latter over your own colour and depth ([`DEPTH`]), so your objects and the trees
//! hide each other; [`Gpu::from_host`] puts the renderer on your device and queue.
//!
//! ```
//! use sylva_forest::{Forest, FrameData, SceneSpec};
//! use sylva_render::Headless;
//! let mut forest = Forest::new(&SceneSpec::builtin("small")?)?;
//! let camera = forest.default_camera();
//! let mut frame = FrameData::with_rows(48);
//! let mut gpu = Headless::new(&forest, 64, 48)?;     // any adapter; lavapipe without a GPU
//! forest.step(1.0 / 30.0);
//! forest.frame(&camera, 64.0 / 48.0, &mut frame);
//! let rgba = gpu.render(&frame, &camera)?;           // RGBA8, rows top first
//! assert_eq!(rgba.len(), 64 * 48 * 4);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod gpu;
mod headless;
pub mod layout;
mod oneshot;
pub mod passes;
mod passtimes;
mod renderer;
mod shared;
mod species;
// A thread waits on the GPU; on the web wgpu's handles stay on the page's thread.
#[cfg(not(target_arch = "wasm32"))]
mod timer;

pub use egui;
pub use gpu::{Gpu, RenderError};
pub use headless::{Headless, capture_texture, read_texture};
pub use passes::panel::{PanelFrame, PanelPass};
pub use passtimes::PARTS as PASS_PARTS;
pub use renderer::{Overlay, Renderer, SceneAssets};
pub use shared::{
    DEPTH, SHADER_PARTS, SHADERS, device_shader_source, host_depth_state, palettes_in_texture,
    shader_source,
};
#[cfg(not(target_arch = "wasm32"))]
pub use timer::GpuTimer;
pub use wgpu;
