//! Far trees as impostors (`far.wgsl`): each species is rendered once, at start-up, from
//! [`VIEWS`] directions around it at each of [`ROWS`] elevations ([`bake_level`], rest
//! pose, orthographic, centred on the middle of its bounds) into an
//! atlas of albedo, tree-space normals and depth; a far tree is then one camera-facing quad
//! (two triangles) showing the nearest view, lit per pixel like the near trees and swayed by
//! its trunk-top joint. Each pixel finds the leaf it shows by following its line of sight
//! into the view's depth map (`surface_uv` in `far.wgsl`), so a view baked up to 11.25° round
//! or 15° above or below the line of sight still puts each clump of leaves where full detail
//! shows it. Seen from between two views, over the middle half of the step between
//! them, it shows both, cross-faded per pixel by a screen-space dither (`VIEW_BAND` in
//! `far.wgsl`), so a tree does not jump from one view to the next as the camera goes round
//! it or rises over it. The elevations matter to a camera over a forest: a tree 40° below
//! the horizon seen in a level view shows its side and its trunk below the crown, where
//! full detail shows the crown from above.
//!
//! The atlas keeps the crown's look at every distance: its mip chain averages colour
//! weighted by opacity (no dark fringes from the transparent background) and rescales each
//! level's alpha so the share of texels passing the alpha test stays that of level 0
//! (coverage-preserving alpha mips), so far crowns neither thin out nor darken.

use sylva_tree::mesh::TreeModel;

use crate::layout::{FarSpecies, far_instance_layout};
use crate::shared::{GlobalsBinding, PipelineSpec, pipeline, texture_entry};

mod atlas;
mod bake;
mod outline;
#[cfg(test)]
mod tests;

pub use atlas::{depth_mips, impostor_mips};
pub use outline::outline;

/// Views baked around each tree, at each elevation: 22.5° apart, so a far tree is shown
/// from at most 11.25° off the direction it is seen from. Fewer views show more error
/// against full detail; more double the start-up bake for less gain than they cost
/// (docs/decisions/0005-impostors.md).
pub const VIEWS: u32 = 16;
/// Elevations the views are baked at: 0, [`ROW_STEP_DEG`], 2·[`ROW_STEP_DEG`] … (rows of the
/// atlas).
pub const ROWS: u32 = 3;
/// Step between the baked elevations, degrees.
pub const ROW_STEP_DEG: f32 = 30.0;
/// Side of one view in the atlas, texels.
pub const VIEW_SIZE: u32 = 256;
/// Vectors of an impostor's outline per elevation row (`FarSpecies::outline`; far.wgsl's
/// `OUTLINE_LEN` for all rows): its sides and its top and bottom. See [`outline`].
pub const OUTLINE_PER_ROW: usize = 2;
/// Vectors of the outline for all rows.
pub const OUTLINE_LEN: usize = ROWS as usize * OUTLINE_PER_ROW;

/// Impostors are rendered from a level with at most this many triangles (see
/// [`bake_level`]).
pub const BAKE_TRIANGLES: usize = 300_000;
/// The finest level impostors are rendered from: level 1, which keeps full detail's leaf
/// cards, card for card, on a third of its wood: impostors baked from it look as those
/// baked from level 0 (the `impostor_stand` example measures both), for a shorter bake.
pub const BAKE_FINEST: usize = 1;

/// Sunlight's extinction in a crown per unit of leaf area density (m² of leaf per m³ of
/// the crown's ellipsoid), for an impostor's shade on its own leaves (`crown_light` in
/// far.wgsl, which leaves unshaded the outer layer full detail's shadow map leaves lit,
/// `SHADOW_BIAS_TEXELS`). Leaves facing every way give 0.5 in a crown filled evenly; full
/// detail's crowns are darker inside than that, their leaves on fewer, denser twigs than
/// the ellipsoid's volume suggests and their wood casting shadow too. Matched against full
/// detail in scenes B, C and D and in a stand seen from several sides
/// (`a_stand_drawn_as_impostors_keeps_the_brightness_of_full_detail_under_shadows` holds
/// the stand's brightness to full detail's; docs/decisions/0005-impostors.md).
pub const CROWN_EXTINCTION: f32 = 1.1;

/// The crown of leaf `clusters` as an ellipsoid about the trunk axis: centre height,
/// horizontal and vertical radii (those of a uniformly filled ellipsoid with the clusters'
/// area-weighted second moments), and the sunlight's extinction through it,
/// [`CROWN_EXTINCTION`] × leaf area / volume, 1/m; zeros without leaves.
pub fn crown_ellipsoid(clusters: &[sylva_tree::mesh::LeafCluster]) -> [f32; 4] {
    let total: f32 = clusters.iter().map(|c| c.leaf_area).sum();
    if total <= 0.0 {
        return [0.0; 4];
    }
    let z = clusters.iter().map(|c| c.leaf_area * c.center[2]).sum::<f32>() / total;
    let (mut h2, mut v2) = (0.0f32, 0.0f32);
    for c in clusters {
        let w = c.leaf_area / total;
        h2 += w * (c.center[0] * c.center[0] + c.center[1] * c.center[1]);
        v2 += w * (c.center[2] - z) * (c.center[2] - z);
    }
    let (a, b) = ((2.5 * h2).sqrt().max(0.1), (5.0 * v2).sqrt().max(0.1));
    let volume = 4.0 / 3.0 * std::f32::consts::PI * a * a * b;
    [z, a, b, CROWN_EXTINCTION * total / volume]
}

/// The level of `model` its impostor is rendered from: the finest with at most
/// [`BAKE_TRIANGLES`] triangles, and not finer than [`BAKE_FINEST`] (nor past the chain's
/// last level).
pub fn bake_level(model: &TreeModel) -> usize {
    let last = model.lods.len().saturating_sub(1);
    let within = model.lods.iter().position(|l| l.triangles() <= BAKE_TRIANGLES);
    within.unwrap_or(last).max(BAKE_FINEST).min(last)
}
/// Distance of the bake's eye point from the tree, m: the views are orthographic, and what
/// turns towards the eye (leaf cards) must turn as for a viewer far away.
const FAR_EYE: f32 = 1.0e4;
/// Formats of the bake targets: albedo (sRGB) and normals (linear).
pub const BAKE_TARGETS: [wgpu::TextureFormat; 2] =
    [wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::TextureFormat::Rgba8Unorm];
/// Format of the views' depth maps: 256 steps across the tree's depth (about 9 cm for a
/// 20 m tree), filtered like the albedo.
const DEPTH_MAP: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// The impostor pass.
#[derive(Debug)]
pub struct FarPass {
    pipeline: wgpu::RenderPipeline,
    /// Impostors into the sun's shadow map: the quad turned to the sun, alpha-tested.
    shadow: wgpu::RenderPipeline,
    /// Group 1 of the pipeline: albedo, normals, [`FarSpecies`].
    pub species_layout: wgpu::BindGroupLayout,
}

/// One species' impostor on the GPU.
#[derive(Debug)]
pub struct FarSpeciesGpu {
    group: wgpu::BindGroup,
    /// What the shader places the quad with.
    pub params: FarSpecies,
    /// The horizontal views, level 0: albedo RGBA8 (sRGB), `VIEWS·VIEW_SIZE × VIEW_SIZE`.
    pub albedo: Vec<u8>,
}

/// What the bake needs of the renderer: the tree pipelines, their bind group layouts and
/// the sampler.
#[derive(Debug)]
pub struct BakeContext<'a> {
    /// Branch bake pipeline.
    pub branch: &'a wgpu::RenderPipeline,
    /// Leaf bake pipeline.
    pub leaf: &'a wgpu::RenderPipeline,
    /// Group 0 layout.
    pub globals_layout: &'a wgpu::BindGroupLayout,
    /// Samplers and the shadow map's placeholder (the bake is unshadowed); its `globals`
    /// buffer is replaced by each view's.
    pub globals: GlobalsBinding<'a>,
}

impl FarPass {
    /// The pipeline; `globals_layout` is group 0.
    pub fn new(
        dev: &wgpu::Device,
        globals_layout: &wgpu::BindGroupLayout,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> FarPass {
        let species_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("impostor"),
            entries: &[
                texture_entry(0),
                texture_entry(1),
                texture_entry(3),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let layout =
            crate::shared::pipeline_layout(dev, "impostors", &[globals_layout, &species_layout]);
        let buffers = [Some(far_instance_layout())];
        let spec = PipelineSpec {
            shader: "far.wgsl",
            fragment: "fs_main",
            layout: &layout,
            buffers: &buffers,
            depth: true,
            cull: None,
            samples,
            targets: &[format],
            shadow: false,
            strip: true,
            coverage: true,
        };
        let shadow =
            PipelineSpec { fragment: "fs_shadow", samples: 1, targets: &[], shadow: true, ..spec };
        FarPass { pipeline: pipeline(dev, &spec), shadow: pipeline(dev, &shadow), species_layout }
    }

    /// Bind the pipeline (globals at group 0 and the instance buffer at slot 0 are the
    /// caller's).
    pub fn begin(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
    }

    /// Bind the shadow-map pipeline instead (same bindings as [`FarPass::begin`]).
    pub fn begin_shadow(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.shadow);
    }

    /// Draw `instances` of one species' impostor.
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        species: &FarSpeciesGpu,
        instances: std::ops::Range<u32>,
    ) {
        pass.set_bind_group(1, &species.group, &[]);
        pass.draw(0..4, instances);
    }
}
