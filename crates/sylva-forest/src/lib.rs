//! The scene: a deterministic forest layout, the camera, and the per-frame driver that turns
//! wind into [`FrameData`] (paper §4.3, §5.2).
//!
//! GPU-free: the renderer reads [`FrameData`] (plain `Pod` arrays) and the tree models; it
//! never calls back into the simulation.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod camera;
pub mod clip;
pub mod driver;
mod groups;
mod lanes;
pub mod scene;
pub mod wind;

pub use camera::{Camera, Mat4, ShadowBox, ViewCone};
pub use driver::{
    Bucket, Forest, ForestError, FrameData, FrameStats, Instance, LodSettings, MAX_NEAR_POINTS,
    NEAR_REACH, REGROUP_FADE, REGROUP_TRAVEL, SHADOW_COARSER, SceneWind, SpeciesRuntime, TreeInfo,
    blend_levels, error_coordinate, hysteresis, level_thresholds, lod_cap, lod_coordinate,
    next_lod_state, past_cap_fraction, shadow_level, wind_field,
};
pub use scene::{
    BUILTIN_PATHS, CameraKey, FLY_IN, LOW_FLIGHT, Lighting, LodSpec, Placement, SCENES, SceneError,
    SceneSpec, SpeciesShare, Surround, SwayOverrides, Terrain, WALK, WindSource, camera_on_path,
    camera_path_from_toml, camera_path_to_toml, default_camera_path, layout, low_flight_path,
    walk_path,
};
pub use sylva_sway::PaletteSlot;
