//! Every type the shaders read, in one place: the Rust twin of each WGSL struct or vertex
//! input, with named fields, and the vertex-attribute tables that bind them.
//!
//! The per-instance data is sylva-forest's [`Instance`], reinterpreted as it is: its vertex
//! attributes are built here from the struct's own field offsets (`offset_of!`), so the
//! layout cannot drift; the tests check every struct's size and field offsets against the
//! WGSL (naga's layouter) and every attribute's format against the shader input's type.
//!
//! Palettes stay in the lane layout of the sway step, one type on both sides:
//! [`sylva_forest::PaletteSlot`] (`Instance::palette`) says that element `e` of joint `j`
//! is at `base + (12 j + e) · stride` of [`sylva_forest::FrameData::palettes`]; `palette()`
//! in `common.wgsl` reads it from the instance's `vec2<u32>` slot (a GPU test checks the
//! WGSL reader against `PaletteSlot::read`).

use std::mem::{offset_of, size_of};

use bytemuck::{Pod, Zeroable};
use sylva_forest::{Camera, Instance, Lighting};

/// `Globals` in common.wgsl: camera, time, sun, sky and fog (uniform, 288 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct Globals {
    /// World → clip.
    pub view_proj: [[f32; 4]; 4],
    /// Clip → world.
    pub inv_view_proj: [[f32; 4]; 4],
    /// Eye, world m.
    pub eye: [f32; 3],
    /// Simulation time, s.
    pub time: f32,
    /// Unit direction towards the sun.
    pub sun_dir: [f32; 3],
    /// Fog density, per m.
    pub fog_density: f32,
    /// Sun colour.
    pub sun_colour: [f32; 3],
    /// Sun intensity.
    pub sun_intensity: f32,
    /// Ambient light from above.
    pub ambient_sky: [f32; 3],
    /// Padding.
    pub pad2: f32,
    /// Ambient light from below.
    pub ambient_ground: [f32; 3],
    /// Padding.
    pub pad3: f32,
    /// Sky at the zenith.
    pub sky_zenith: [f32; 3],
    /// Padding.
    pub pad4: f32,
    /// Sky at the horizon (where the aerial perspective fades to).
    pub sky_horizon: [f32; 3],
    /// Exposure multiplying the linear colour before the filmic tone map.
    pub exposure: f32,
    /// World → the near cascade's shadow-map clip space (all zero: no shadow map); while
    /// the far cascade is drawn, the far one's.
    pub sun_view_proj: [[f32; 4]; 4],
    /// Side of one shadow-map texel in its texture coordinates (0: no shadow map).
    pub shadow_texel: f32,
    /// Colour overlay of the tree passes (`Overlay` as f32: 0 off, 1 geometry level,
    /// 2 instance group).
    pub overlay: f32,
    /// Padding.
    pub pad6: f32,
    /// Padding.
    pub pad7: f32,
    /// World → the far cascade's shadow-map clip space (all zero: no far cascade).
    pub sun_view_proj_far: [[f32; 4]; 4],
}

/// Exposure before the filmic tone map (common.wgsl `finish`).
pub const EXPOSURE: f32 = 0.8;

impl Globals {
    /// The globals for `view_proj` (and its inverse), seen from `eye`, at `time`, under
    /// `light`.
    pub fn new(view_proj: [[f32; 4]; 4], eye: [f32; 3], time: f32, light: &Lighting) -> Globals {
        Globals {
            view_proj,
            inv_view_proj: sylva_core::mat4::invert(&view_proj),
            eye,
            time,
            fog_density: light.fog(0.0),
            sun_intensity: light.sun_intensity,
            sun_dir: light.sun_unit(),
            sun_colour: light.sun_colour,
            ambient_sky: light.ambient_sky,
            ambient_ground: light.ambient_ground,
            sky_zenith: light.sky_zenith,
            sky_horizon: light.sky_horizon,
            exposure: EXPOSURE,
            ..Zeroable::zeroed()
        }
    }

    /// The globals of a perspective `camera` for an image of `aspect` = width / height,
    /// its centre of projection moved `view_shift` of the half-width to the right
    /// (clip-space x += `view_shift` · w; see `Renderer::set_view_shift`).
    pub fn for_camera(
        camera: &Camera,
        aspect: f32,
        view_shift: f32,
        time: f32,
        light: &Lighting,
    ) -> Globals {
        let mut view_proj = camera.view_projection(aspect);
        for column in &mut view_proj {
            column[0] += view_shift * column[3];
        }
        Globals::new(view_proj, camera.eye, time, light)
    }
}

/// `BranchIn` in branch.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct BranchVertex {
    /// Rest position, tree space, m.
    pub position: [f32; 3],
    /// Unit normal, tree space.
    pub normal: [f32; 3],
    /// Bark texture coordinates.
    pub uv: [f32; 2],
    /// Up to four joints.
    pub joints: [u32; 4],
    /// Their weights (sum 1).
    pub weights: [f32; 4],
}

/// `LeafIn` in leaf.wgsl: one corner of a leaf-cluster billboard.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct LeafVertex {
    /// Card centre (rest pose, tree space), m.
    pub center: [f32; 3],
    /// Hanging point, m.
    pub hang: [f32; 3],
    /// Corner, ±0.5 each.
    pub corner: [f32; 2],
    /// The card's right edge direction times its side (rest pose, tree space), m.
    pub right: [f32; 3],
    /// The card's up direction (out of the branch) times its side, m.
    pub up: [f32; 3],
    /// 1 at the crown's surface … 0 at its centre.
    pub exposure: f32,
    /// Flutter phase offset, rad.
    pub phase: f32,
    /// Joint it hangs on.
    pub joint: u32,
    /// Top-left of its atlas cell, texture coordinates.
    pub uv_origin: [f32; 2],
    /// Side of its atlas cell, texture coordinates.
    pub uv_size: f32,
}

/// `GroundIn` in ground.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct GroundVertex {
    /// World position, m.
    pub position: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// Sky the ground sees past the crowns above it (1: open ground).
    pub open: f32,
    /// Share of distant woodland painted here (0: grass and soil, 1: canopy).
    pub woodland: f32,
    /// Spacing of the painted woodland's crowns, m.
    pub crown_spacing: f32,
    /// Mean linear albedo of the painted woodland's crowns.
    pub canopy: [f32; 3],
    /// Where the painted woodland's crowns start to stand, m from the forest's centre, and
    /// the width over which they thicken to full ([`crate::passes::ground::Woodland`]'s
    /// `start` and `ramp`).
    pub woodland_edge: [f32; 2],
    /// The darker crowns of the painted woodland: their linear albedo, and their share of
    /// the crowns (0: one colour). The forest's darker species (conifers, in the built-in
    /// mixes) seen among the lighter ones; the rest take the colour that keeps `canopy`
    /// the mean.
    pub canopy_dark: [f32; 4],
}

/// `FarSpecies` in far.wgsl: one species' impostor (uniform).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct FarSpecies {
    /// Trunk-top point (rest, tree space), m.
    pub tip: [f32; 3],
    /// Side of the square each view covers, m.
    pub extent: f32,
    /// Height of the point every view is centred on, tree space, m.
    pub center: f32,
    /// Views around the tree.
    pub views: u32,
    /// The trunk-top joint, whose palette sways the quad.
    pub joint: u32,
    /// Elevations baked (rows of the atlas), [`crate::passes::far::ROW_STEP_DEG`] apart.
    pub rows: u32,
    /// Radius of the tree's bounds about the trunk axis, m.
    pub radius: f32,
    /// Height of the tree's bounds, m.
    pub height: f32,
    /// Step between the baked elevations, rad.
    pub row_step: f32,
    /// Half the depth range the views' depth maps span about the plane through the
    /// views' centre, m: a depth texel of `z` (0 … 1) lies `(2z − 1)·depth_range` behind
    /// that plane along its view.
    pub depth_range: f32,
    /// The crown as an ellipsoid about the trunk axis, tree space: its centre's height,
    /// horizontal and vertical radii (m), and the light's extinction in it (1/m).
    pub crown: [f32; 4],
    /// The trapezoid the impostor is drawn as, per elevation row
    /// ([`crate::passes::far::outline`]), in a cell's units: its sides `x = a + s·y` as
    /// `[a_left, s_left, a_right, s_right]`, then `[y_top, y_bottom, 0, 0]`.
    pub outline: [[f32; 4]; crate::passes::far::OUTLINE_LEN],
}

macro_rules! attr {
    ($t:ty, $field:ident, $format:ident, $loc:expr) => {
        wgpu::VertexAttribute {
            format: wgpu::VertexFormat::$format,
            offset: offset_of!($t, $field) as u64,
            shader_location: $loc,
        }
    };
}

/// `InstanceIn` in common.wgsl, read from [`Instance`] as sylva-forest lays it out.
pub const INSTANCE_ATTRIBUTES: [wgpu::VertexAttribute; 6] = [
    // position (vec3) followed by yaw: read together as `base`.
    attr!(Instance, position, Float32x4, 5),
    attr!(Instance, scale, Float32, 6),
    // The palette slot (base, stride): `PaletteSlot`, as one vec2<u32>.
    attr!(Instance, palette, Uint32x2, 7),
    // leaf_phase and leaf_amplitude: read together as `leaf`.
    attr!(Instance, leaf_phase, Float32x2, 8),
    attr!(Instance, fade, Float32x2, 10),
    attr!(Instance, tag, Uint32, 9),
];

/// The impostors' instance attributes: [`INSTANCE_ATTRIBUTES`] and `LeanIn` in far.wgsl,
/// the crown's lean and how it turns the leaves (`Instance::lean` and `Instance::tilt`,
/// two half floats each), and how much wider the impostor is drawn (`Instance::spread`).
pub const FAR_INSTANCE_ATTRIBUTES: [wgpu::VertexAttribute; 9] = {
    let mut all = [attr!(Instance, lean, Float16x2, 11); 9];
    all[7] = attr!(Instance, tilt, Float16x2, 12);
    all[8] = attr!(Instance, spread, Float32, 13);
    let mut i = 0;
    while i < INSTANCE_ATTRIBUTES.len() {
        all[i] = INSTANCE_ATTRIBUTES[i];
        i += 1;
    }
    all
};

/// `BranchIn`.
pub const BRANCH_ATTRIBUTES: [wgpu::VertexAttribute; 5] = [
    attr!(BranchVertex, position, Float32x3, 0),
    attr!(BranchVertex, normal, Float32x3, 1),
    attr!(BranchVertex, uv, Float32x2, 2),
    attr!(BranchVertex, joints, Uint32x4, 3),
    attr!(BranchVertex, weights, Float32x4, 4),
];

/// `LeafIn`.
pub const LEAF_ATTRIBUTES: [wgpu::VertexAttribute; 10] = [
    attr!(LeafVertex, center, Float32x3, 0),
    attr!(LeafVertex, hang, Float32x3, 1),
    attr!(LeafVertex, corner, Float32x2, 2),
    attr!(LeafVertex, right, Float32x3, 3),
    attr!(LeafVertex, up, Float32x3, 4),
    attr!(LeafVertex, exposure, Float32, 15),
    attr!(LeafVertex, phase, Float32, 11),
    attr!(LeafVertex, joint, Uint32, 12),
    attr!(LeafVertex, uv_origin, Float32x2, 13),
    attr!(LeafVertex, uv_size, Float32, 14),
];

/// `GroundIn`.
pub const GROUND_ATTRIBUTES: [wgpu::VertexAttribute; 8] = [
    attr!(GroundVertex, position, Float32x3, 0),
    attr!(GroundVertex, normal, Float32x3, 1),
    attr!(GroundVertex, open, Float32, 2),
    attr!(GroundVertex, woodland, Float32, 3),
    attr!(GroundVertex, crown_spacing, Float32, 4),
    attr!(GroundVertex, canopy, Float32x3, 5),
    attr!(GroundVertex, woodland_edge, Float32x2, 6),
    attr!(GroundVertex, canopy_dark, Float32x4, 7),
];

/// The per-instance buffer layout of the mesh pipelines.
pub fn instance_layout() -> wgpu::VertexBufferLayout<'static> {
    instances_read_as(&INSTANCE_ATTRIBUTES)
}

/// The per-instance buffer layout of the impostors' pipelines, which read the lean too.
pub fn far_instance_layout() -> wgpu::VertexBufferLayout<'static> {
    instances_read_as(&FAR_INSTANCE_ATTRIBUTES)
}

fn instances_read_as(
    attributes: &'static [wgpu::VertexAttribute],
) -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: size_of::<Instance>() as u64,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes,
    }
}

/// A per-vertex buffer layout of `T` with `attributes`.
pub fn vertex_layout<T>(
    attributes: &'static [wgpu::VertexAttribute],
) -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: size_of::<T>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes,
    }
}
