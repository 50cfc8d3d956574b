//! The scene: a deterministic forest layout, the camera, and the per-frame driver that turns
//! wind into [`FrameData`] (paper §4.3, §5.2).
//!
//! GPU-free: the renderer reads [`FrameData`] (plain `Pod` arrays) and the tree models; it
//! never calls back into the simulation.
//!
//! The flow: a [`SceneSpec`] (a built-in scene or a TOML file) → [`Forest::new`] (layout,
//! trees, simulations, wind) → per frame [`Forest::step`] (seconds of simulated time) and
//! [`Forest::frame`] for a [`Camera`] → [`FrameData`], which `sylva-render` draws or a
//! renderer of your own reads. World space is Z-up, in metres; time in seconds; wind in m/s.
//! The level functions behind the geometry LOD are in [`driver`].
//!
//! ```
//! use sylva_forest::{Forest, FrameData, SceneSpec};
//! let spec = SceneSpec::builtin("small")?;          // or SceneSpec::load("my-scene.toml")
//! let mut forest = Forest::new(&spec)?;
//! let camera = forest.default_camera();
//! let mut frame = FrameData::with_rows(768);         // one per view, for a 768-row image
//! forest.step(1.0 / 30.0);                           // s
//! forest.frame(&camera, 4.0 / 3.0, &mut frame);      // aspect = width / height
//! assert!(frame.stats.drawn > 0 && !frame.palettes.is_empty());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod camera;
pub mod canopy;
pub mod cells;
pub mod clip;
pub mod clock;
pub mod driver;
mod groups;
mod lanes;
pub mod occlusion;
pub mod scene;
pub mod wind;

pub use camera::{Camera, Mat4, Orbit, ShadowBox, ViewCone};
pub use driver::{
    Bucket, Forest, ForestError, FrameData, FrameStats, Instance, LodSettings, MAX_NEAR_POINTS,
    NEAR_REACH, REGROUP_FADE, REGROUP_TRAVEL, SceneWind, SpeciesRuntime, TreeInfo, wind_field,
    wind_field_over,
};
pub use scene::{
    BUILTIN_PATHS, CameraKey, FLY_IN, LOW_FLIGHT, Lighting, LodSpec, Placement, SCENES, SceneError,
    SceneSpec, SpeciesShare, Surround, SwayOverrides, Terrain, WALK, WindSource, camera_on_path,
    camera_path_from_toml, camera_path_to_toml, default_camera_path, layout, low_flight_path,
    walk_path,
};
pub use sylva_sway::PaletteSlot;
