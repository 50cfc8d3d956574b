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

use sylva_forest::{Instance, Lighting, PaletteSlot};
use sylva_tree::mesh::TreeModel;

use crate::gpu::{Gpu, RenderError};
use crate::layout::{FarSpecies, Globals, far_instance_layout};
use crate::shared::{
    GlobalsBinding, Mesh, PipelineSpec, buffer, globals_group, palette_buffer, pipeline,
    texture_entry, upload_mips,
};

/// Views baked around each tree, at each elevation: 22.5° apart, so a far tree is shown
/// from at most 11.25° off the direction it is seen from. A stand of 120 trees of scene B's
/// mix, 100–150 pixels tall at rest, read FLIP 0.039 against full detail with sixteen,
/// 0.042 with eight (full detail a quarter pixel aside: 0.022); twice the views doubled
/// the bake (4.2 to 9.8 s for B's five species on lavapipe), and neither twice the texels
/// a view (0.042) nor elevations 15° apart instead of 30° (0.041) helped as much
/// (docs/benchmarks.md, "Sixteen impostor views").
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
/// cards, card for card, on a third of its wood. The stand of `impostor_stand` (scene B's
/// mix, 100–150 pixels tall) reads the same FLIP against full detail baked from level 1
/// as from level 0 (0.0388 and 0.0387; as brightness within 0.1 %), and the bake of B's
/// five species takes about a fifth less time on lavapipe (6.4 s against 8.3, medians of
/// four; docs/benchmarks.md, "Baked from level 1").
pub const BAKE_FINEST: usize = 1;

/// Sunlight's extinction in a crown per unit of leaf area density (m² of leaf per m³ of
/// the crown's ellipsoid), for an impostor's shade on its own leaves (`crown_light` in
/// far.wgsl, which leaves unshaded the outer layer full detail's shadow map leaves lit,
/// `SHADOW_BIAS_TEXELS`). Leaves facing every way give 0.5 in a crown filled evenly; full
/// detail's crowns are darker inside than that, their leaves on fewer, denser twigs than
/// the ellipsoid's volume suggests and their wood casting shadow too. Matched against full
/// detail in scenes B, C and D at rest and B and C walking their paths (mean FLIP at rest
/// C 0.0754, D 0.0695 with 1.5; 0.0749, 0.0690 with 1.2; in motion C 0.0799 with 1.5,
/// 0.0803 with 1.2), and in a stand seen from several sides
/// (`a_stand_drawn_as_impostors_keeps_the_brightness_of_full_detail_under_shadows`: off by
/// 2.2 % at worst, 1.25 % on average). docs/benchmarks.md, "A crown's shade as full
/// detail's shadow map gives it".
pub const CROWN_EXTINCTION: f32 = 1.5;

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

    /// Bake `model`'s impostor: render its views, read them back, build the mip chains and
    /// upload them. `textures` is the species' bark and leaf bind group; `meshes` its
    /// branch and leaf meshes at [`bake_level`].
    pub fn bake(
        &self,
        gpu: &Gpu,
        ctx: &BakeContext<'_>,
        model: &TreeModel,
        textures: &wgpu::BindGroup,
        meshes: (Option<&Mesh>, Option<&Mesh>),
    ) -> Result<FarSpeciesGpu, RenderError> {
        let dev = &gpu.device;
        let level = &model.lods[bake_level(model)];
        // Bounds: horizontal radius about the trunk axis and height range, billboards
        // counted with their half diagonal.
        let (mut radius, mut z0, mut z1) = (0.1f32, f32::INFINITY, f32::NEG_INFINITY);
        for p in &level.branches.positions {
            radius = radius.max(p[0].hypot(p[1]));
            z0 = z0.min(p[2]);
            z1 = z1.max(p[2]);
        }
        for c in &level.clusters {
            let half = 0.71 * c.size;
            radius = radius.max(c.center[0].hypot(c.center[1]) + half);
            z0 = z0.min(c.center[2] - half);
            z1 = z1.max(c.center[2] + half);
        }
        if !z0.is_finite() {
            (z0, z1) = (0.0, 1.0);
        }
        // Every view is centred on the middle of the tree's bounds and covers them from any
        // elevation: the bounding cylinder seen from elevation e is 2·radius wide and
        // height·cos e + 2·radius·sin e tall, at most the hypotenuse below.
        let extent = (2.0 * radius).max((z1 - z0).hypot(2.0 * radius)) * 1.04;
        let center = 0.5 * (z0 + z1);
        let depth_range = radius.hypot(0.5 * (z1 - z0)) + 1.0;
        // Rest pose: identity palettes, one instance at the origin.
        let joints = model.tree.skeleton.len().max(1);
        let identity: Vec<f32> = (0..joints)
            .flat_map(|_| [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0])
            .collect();
        let palettes = palette_buffer(dev, (identity.len() * 4) as u64);
        gpu.queue.write_buffer(&palettes, 0, bytemuck::cast_slice(&identity));
        let instance = Instance {
            scale: 1.0,
            palette: PaletteSlot { base: 0, stride: 1 },
            fade: [0.0, 2.0],
            ..Default::default()
        };
        let instances =
            buffer(gpu, "bake instance", bytemuck::bytes_of(&instance), wgpu::BufferUsages::VERTEX);
        let light = Lighting::default();
        let groups: Vec<wgpu::BindGroup> = (0..ROWS * VIEWS)
            .map(|cell| {
                let (k, row) = (cell % VIEWS, cell / VIEWS);
                let a = std::f32::consts::TAU * k as f32 / VIEWS as f32;
                let (s, c) = a.sin_cos();
                let (se, ce) = (row as f32 * ROW_STEP_DEG).to_radians().sin_cos();
                // Looking along f (down by the elevation), right r, up u = r × f.
                let f = [c * ce, s * ce, -se];
                let r = [s, -c, 0.0];
                let u = [c * se, s * se, ce];
                let h = 0.5 * extent;
                let zs = 1.0 / (2.0 * depth_range);
                // Orthographic about (0, 0, center). Column-major: m[column][row].
                let view_proj = [
                    [r[0] / h, u[0] / h, f[0] * zs, 0.0],
                    [r[1] / h, u[1] / h, f[1] * zs, 0.0],
                    [r[2] / h, u[2] / h, f[2] * zs, 0.0],
                    [0.0, -center * u[2] / h, 0.5 - center * f[2] * zs, 1.0],
                ];
                // The projection is orthographic, but leaf cards turn towards the eye
                // point: placed far along the view, they turn as they do for a far viewer.
                // At the near plane's distance the cards off the axis turned sideways and
                // were seen foreshortened, and the baked crowns showed their bark between
                // thinned-out leaves.
                let eye = [-f[0] * FAR_EYE, -f[1] * FAR_EYE, center - f[2] * FAR_EYE];
                let g = Globals::new(view_proj, eye, 0.0, &light);
                let buf = buffer(
                    gpu,
                    "bake globals",
                    bytemuck::bytes_of(&g),
                    wgpu::BufferUsages::UNIFORM,
                );
                let with = GlobalsBinding { globals: &buf, ..ctx.globals };
                globals_group(dev, ctx.globals_layout, &with, &palettes)
            })
            .collect();
        let (w, h) = (VIEWS * VIEW_SIZE, ROWS * VIEW_SIZE);
        let target = |format, label| {
            dev.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let albedo_tex = target(BAKE_TARGETS[0], "impostor albedo");
        let normal_tex = target(BAKE_TARGETS[1], "impostor normals");
        let depth_tex = target(crate::shared::DEPTH, "impostor depth");
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let (av, nv, dv) = (view(&albedo_tex), view(&normal_tex), view(&depth_tex));
        let mut enc =
            dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("bake") });
        {
            let clear = |v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            // The depth is kept: it becomes the views' depth maps.
            let depth = wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("impostor bake"),
                color_attachments: &[clear(&av), clear(&nv)],
                depth_stencil_attachment: Some(depth),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(1, textures, &[]);
            pass.set_vertex_buffer(1, instances.slice(..));
            for (cell, group) in groups.iter().enumerate() {
                let (x, y) = ((cell as u32 % VIEWS) * VIEW_SIZE, (cell as u32 / VIEWS) * VIEW_SIZE);
                pass.set_viewport(x as f32, y as f32, VIEW_SIZE as f32, VIEW_SIZE as f32, 0.0, 1.0);
                pass.set_bind_group(0, group, &[]);
                for (pipeline, mesh) in [(ctx.branch, meshes.0), (ctx.leaf, meshes.1)] {
                    if let Some(mesh) = mesh {
                        pass.set_pipeline(pipeline);
                        mesh.draw(&mut pass, 0..1);
                    }
                }
            }
        }
        // Depth32Float reads back as four bytes a texel, as RGBA8 does.
        let read = read_back(gpu, enc, &[&albedo_tex, &normal_tex, &depth_tex], w, h)?;
        let (albedo, normal) = (&read[0], &read[1]);
        // The bake's depth is linear along each view (orthographic): 0 … 1 across
        // ±depth_range about the plane through the views' centre, nearest first.
        let depth: Vec<u8> = read[2]
            .chunks_exact(4)
            .map(|b| {
                let z = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                (z.clamp(0.0, 1.0) * 255.0).round() as u8
            })
            .collect();
        let (albedo_mips, normal_mips) = impostor_mips(albedo, normal, w, h, (VIEWS, ROWS));
        let depth_mips = depth_mips(&depth, albedo, w, h, VIEW_SIZE);
        let av = upload_mips(gpu, &albedo_mips, w, h, BAKE_TARGETS[0], "impostor albedo");
        let nv = upload_mips(gpu, &normal_mips, w, h, BAKE_TARGETS[1], "impostor normals");
        let dv = upload_mips(gpu, &depth_mips, w, h, DEPTH_MAP, "impostor depth");
        let sk = &model.tree.skeleton;
        let top = sk.trunk_top();
        let tip = sk.joints().get(top).map(|j| j.tip()).unwrap_or([0.0, 0.0, 1.0]);
        let params = FarSpecies {
            tip,
            extent,
            center,
            views: VIEWS,
            joint: top as u32,
            rows: ROWS,
            radius,
            height: z1 - z0,
            row_step: ROW_STEP_DEG.to_radians(),
            depth_range,
            crown: crown_ellipsoid(&level.clusters),
            outline: outline(albedo, w, h, VIEWS, ROWS, VIEW_SIZE)
                .try_into()
                .expect("an outline of OUTLINE_LEN edges"),
        };
        let uniform =
            buffer(gpu, "impostor", bytemuck::bytes_of(&params), wgpu::BufferUsages::UNIFORM);
        let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("impostor"),
            layout: &self.species_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&av),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&nv),
                },
                wgpu::BindGroupEntry { binding: 2, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&dv),
                },
            ],
        });
        Ok(FarSpeciesGpu {
            group,
            params,
            // The horizontal row: the atlas's first VIEW_SIZE rows of texels.
            albedo: albedo_mips
                .into_iter()
                .next()
                .map(|mut a| {
                    a.truncate((w * VIEW_SIZE * 4) as usize);
                    a
                })
                .unwrap_or_default(),
        })
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

/// Submit `enc` with copies of `textures` (RGBA8, `w × h`) and read them back, rows top
/// first.
fn read_back(
    gpu: &Gpu,
    mut enc: wgpu::CommandEncoder,
    textures: &[&wgpu::Texture],
    w: u32,
    h: u32,
) -> Result<Vec<Vec<u8>>, RenderError> {
    let padded = (w * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffers: Vec<wgpu::Buffer> = textures
        .iter()
        .map(|t| {
            let b = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bake readback"),
                size: (padded * h) as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            enc.copy_texture_to_buffer(
                t.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &b,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(padded),
                        rows_per_image: Some(h),
                    },
                },
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
            b
        })
        .collect();
    gpu.queue.submit([enc.finish()]);
    let mut out = Vec::with_capacity(buffers.len());
    for b in &buffers {
        let slice = b.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        rx.recv()
            .map_err(|e| RenderError::Readback(e.to_string()))?
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        let mut img = Vec::with_capacity((w * h * 4) as usize);
        {
            let data =
                slice.get_mapped_range().map_err(|e| RenderError::Readback(e.to_string()))?;
            for row in data.chunks(padded as usize) {
                img.extend_from_slice(&row[..(w * 4) as usize]);
            }
        }
        b.unmap();
        out.push(img);
    }
    Ok(out)
}

/// Mip chain of the views' depth map `depth` (one byte a texel, `w × h`, views `cell`
/// texels a side), down to 4 texels a side as [`impostor_mips`]'s: the mean depth of the
/// texels under each, weighted by the albedo's alpha as colour is (the depth of the leaves
/// a coarse texel shows, not of the background between them).
///
/// A texel over nothing takes the depth of the covered texels around it (pulled up a
/// pyramid of coverage-weighted means within its view, and pushed back down to the
/// texels without any): a line of sight followed into the map from a gap in the crown, or
/// from beside the trunk, reads the depth of what is next to it, and its steps land on
/// it. With one depth for every such texel (the covered texels' mean, the views' middle
/// plane) a trunk seen from above, whose foot lies metres behind that plane, was shown
/// twice where the views baked from above met its line of sight a little aside. A view
/// with nothing in it takes the covered texels' mean.
pub fn depth_mips(depth: &[u8], albedo: &[u8], w: u32, h: u32, cell: u32) -> Vec<Vec<u8>> {
    let n = (w * h) as usize;
    let mut raw: Vec<f32> = albedo.chunks(4).take(n).map(|p| p[3] as f32).collect();
    let covered: Vec<usize> = (0..n).filter(|&i| raw[i] >= 128.0).collect();
    let mean = covered.iter().map(|&i| depth[i] as f64).sum::<f64>() / covered.len().max(1) as f64;
    let fill = if covered.is_empty() { 128.0 } else { mean as f32 };
    // Pull: (depth, weight) of the covered texels under each texel, level by level, while a
    // texel stays within one view.
    let mut pull: Vec<(Vec<f32>, Vec<f32>, u32)> = vec![(
        (0..n).map(|i| if raw[i] >= 128.0 { depth[i] as f32 } else { 0.0 }).collect(),
        (0..n).map(|i| if raw[i] >= 128.0 { 1.0 } else { 0.0 }).collect(),
        w,
    )];
    let (mut cw, mut ch, mut side) = (w, h, 1u32);
    while 2 * side <= cell && cw % 2 == 0 && ch % 2 == 0 && cw > 1 && ch > 1 {
        let (nw, nh) = (cw / 2, ch / 2);
        let (d, wt, _) = pull.last().expect("level 0 is there");
        let mut nd = vec![0.0f32; (nw * nh) as usize];
        let mut nwt = vec![0.0f32; (nw * nh) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let o = (y * nw + x) as usize;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let t = ((2 * y + dy) * cw + 2 * x + dx) as usize;
                    nd[o] += d[t] * wt[t];
                    nwt[o] += wt[t];
                }
                if nwt[o] > 0.0 {
                    nd[o] /= nwt[o];
                }
            }
        }
        pull.push((nd, nwt, nw));
        (cw, ch, side) = (nw, nh, 2 * side);
    }
    // Push: from the coarsest level down, a texel without coverage takes its parent's.
    let mut parent: Option<(Vec<f32>, u32)> = None;
    for (mut d, wt, lw) in pull.into_iter().rev() {
        for (i, v) in d.iter_mut().enumerate() {
            if wt[i] > 0.0 {
                continue;
            }
            *v = match &parent {
                Some((p, pw)) => {
                    let (x, y) = (i as u32 % lw, i as u32 / lw);
                    p[((y / 2) * pw + x / 2) as usize]
                }
                None => fill,
            };
        }
        parent = Some((d, lw));
    }
    let (filled, _) = parent.expect("level 0 is there");
    let mut level: Vec<u8> = filled.iter().map(|v| v.round().clamp(0.0, 255.0) as u8).collect();
    let mut out = Vec::new();
    let (mut cw, mut ch) = (w, h);
    loop {
        out.push(level.clone());
        if cw <= 4 || ch <= 4 {
            break;
        }
        let (nw, nh) = (cw / 2, ch / 2);
        let mut next = vec![0u8; (nw * nh) as usize];
        let mut next_raw = vec![0.0f32; (nw * nh) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let texels = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .map(|(dx, dy)| ((2 * y + dy) * cw + 2 * x + dx) as usize);
                let weight: f32 = texels.iter().map(|&t| raw[t]).sum();
                let o = (y * nw + x) as usize;
                let sum: f32 = if weight > 0.0 {
                    texels.iter().map(|&t| raw[t] * level[t] as f32).sum::<f32>() / weight
                } else {
                    texels.iter().map(|&t| level[t] as f32).sum::<f32>() / 4.0
                };
                next[o] = sum.round() as u8;
                next_raw[o] = weight / 4.0;
            }
        }
        level = next;
        raw = next_raw;
        cw = nw;
        ch = nh;
    }
    out
}

/// Mip chains of the baked albedo and normals (`w × h`, RGBA8), down to 4 texels a side.
/// Colour and normals average weighted by the albedo's alpha (transparent texels take the
/// opaque mean, so filtering at an edge does not pull in black); each level's alpha is
/// rescaled so that the share of texels at or above 128 (the alpha test) equals level 0's,
/// in each of `tiles.0 × tiles.1` equal tiles (an atlas's cells or views) on its own, down
/// to tiles of one texel.
pub fn impostor_mips(
    albedo: &[u8],
    normal: &[u8],
    w: u32,
    h: u32,
    tiles: (u32, u32),
) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
    let n = (w * h) as usize;
    let opaque = |img: &[u8], i: usize| img[4 * i + 3] >= 128;
    let covered = (0..n).filter(|&i| opaque(albedo, i)).count();
    let (tx, ty) = (tiles.0.clamp(1, w.max(1)), tiles.1.clamp(1, h.max(1)));
    // Texel indices of tile t of a `lw × lh` level, row-major tiles.
    let tile = |t: u32, lw: u32, lh: u32| -> Vec<usize> {
        let (sw, sh) = ((lw / tx).max(1), (lh / ty).max(1));
        let (x0, y0) = ((t % tx) * sw, (t / tx) * sh);
        (y0..(y0 + sh).min(lh))
            .flat_map(|y| (x0..(x0 + sw).min(lw)).map(move |x| (y * lw + x) as usize))
            .collect()
    };
    // Level-0 coverage of each tile.
    let coverage: Vec<f64> = (0..tx * ty)
        .map(|t| {
            let texels = tile(t, w, h);
            let k = texels.iter().filter(|&&i| opaque(albedo, i)).count();
            k as f64 / texels.len().max(1) as f64
        })
        .collect();
    // Mean opaque colour and normal fill the transparent texels.
    let mut mean = [[0.0f64; 4]; 2];
    for i in (0..n).filter(|&i| opaque(albedo, i)) {
        for c in 0..4 {
            mean[0][c] += albedo[4 * i + c] as f64;
            mean[1][c] += normal[4 * i + c] as f64;
        }
    }
    let fill = |m: [f64; 4]| -> [u8; 4] {
        let k = covered.max(1) as f64;
        [(m[0] / k) as u8, (m[1] / k) as u8, (m[2] / k) as u8, (m[3] / k) as u8]
    };
    let (fa, fn_) = (fill(mean[0]), fill(mean[1]));
    let mut a0 = albedo.to_vec();
    let mut n0 = normal.to_vec();
    for i in (0..n).filter(|&i| !opaque(albedo, i)) {
        a0[4 * i..4 * i + 3].copy_from_slice(&fa[..3]);
        n0[4 * i..4 * i + 4].copy_from_slice(&fn_);
    }
    // Raw (box-filtered, unscaled) alpha per level, and the outputs.
    let mut raw: Vec<f32> = albedo.chunks(4).map(|p| p[3] as f32).collect();
    let (mut albedo_out, mut normal_out) = (vec![a0], vec![n0]);
    let (mut cw, mut ch) = (w, h);
    while cw > 4 && ch > 4 {
        let (nw, nh) = (cw / 2, ch / 2);
        let (pa, pn) = (&albedo_out[albedo_out.len() - 1], &normal_out[normal_out.len() - 1]);
        let mut next_raw = vec![0.0f32; (nw * nh) as usize];
        let mut na = vec![0u8; (nw * nh * 4) as usize];
        let mut nn = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let texels = [
                    (2 * x, 2 * y),
                    (2 * x + 1, 2 * y),
                    (2 * x, 2 * y + 1),
                    (2 * x + 1, 2 * y + 1),
                ]
                .map(|(xx, yy)| (yy * cw + xx) as usize);
                let weight: f32 = texels.iter().map(|&t| raw[t]).sum();
                let o = (y * nw + x) as usize;
                next_raw[o] = weight / 4.0;
                for c in 0..3 {
                    let avg = |img: &[u8]| {
                        if weight > 0.0 {
                            texels.iter().map(|&t| raw[t] * img[4 * t + c] as f32).sum::<f32>()
                                / weight
                        } else {
                            texels.iter().map(|&t| img[4 * t + c] as f32).sum::<f32>() / 4.0
                        }
                    };
                    na[4 * o + c] = avg(pa).round() as u8;
                    nn[4 * o + c] = avg(pn).round() as u8;
                }
                nn[4 * o + 3] =
                    (texels.iter().map(|&t| pn[4 * t + 3] as f32).sum::<f32>() / 4.0).round() as u8;
            }
        }
        // Alpha scale keeping each tile's alpha-tested coverage: the raw value at the
        // tile's coverage quantile maps to 128.
        for t in 0..tx * ty {
            // Rank by raw alpha (ties broken by a hash of the texel, so equal values do not
            // all pass or all fail together); the first `k` pass the test.
            let mut ranked = tile(t, nw, nh);
            let tie = |o: usize| (o as u32).wrapping_mul(0x9e37_79b9).rotate_left(13);
            ranked.sort_by(|&a, &b| next_raw[b].total_cmp(&next_raw[a]).then(tie(a).cmp(&tie(b))));
            let k =
                ((coverage[t as usize] * ranked.len() as f64).round() as usize).min(ranked.len());
            let at_quantile = if k > 0 { next_raw[ranked[k - 1]].max(1.0) } else { 255.0 };
            let scale = 128.0 / at_quantile;
            for (rank, &o) in ranked.iter().enumerate() {
                let a = (next_raw[o] * scale).round();
                na[4 * o + 3] = if rank < k { a.clamp(128.0, 255.0) } else { a.min(127.0) } as u8;
            }
        }
        raw = next_raw;
        albedo_out.push(na);
        normal_out.push(nn);
        cw = nw;
        ch = nh;
    }
    (albedo_out, normal_out)
}

/// The trapezoid an impostor is drawn as, from its views' coverage (`albedo`, RGBA8,
/// `w × h`, `views × rows` cells of `cell` texels a side), in a cell's coordinates (x across
/// 0 … 1, y down 0 … 1): for each elevation row `r`, the smallest trapezoid with horizontal
/// top and bottom that holds every texel any view of row `r` or `r + 1` covers (an
/// instance between the two shows either), as its left and right sides `x = a + s·y`,
/// `[a_left, s_left, a_right, s_right]`, then `[y_top, y_bottom, 0, 0]`. Still two
/// triangles a tree, as the square of the cells was, but a conifer's is nearly a triangle
/// and every tree's ends where its crown and trunk end. The shader clamps it to the square
/// it replaces and does not widen it (what a coarse mip's texel spreads past the outline
/// shows in a few hundred pixels of scene D's frame, each by a few levels: far.wgsl).
pub fn outline(albedo: &[u8], w: u32, h: u32, views: u32, rows: u32, cell: u32) -> Vec<[f32; 4]> {
    let (views, rows, cell) = (views.max(1), rows.max(1), cell.max(1));
    // Per row and texel row of a cell: the covered columns' range over all the row's views.
    let mut spans = vec![None::<(u32, u32)>; (rows * cell) as usize];
    for r in 0..rows {
        for y in 0..cell {
            let ty = r * cell + y;
            if ty >= h {
                continue;
            }
            let span = &mut spans[ty as usize];
            for k in 0..views {
                for x in 0..cell {
                    let tx = k * cell + x;
                    if tx >= w || albedo[((ty * w + tx) * 4 + 3) as usize] == 0 {
                        continue;
                    }
                    *span = Some(span.map_or((x, x), |(a, b)| (a.min(x), b.max(x))));
                }
            }
        }
    }
    let mut out = Vec::with_capacity(rows as usize * OUTLINE_PER_ROW);
    for r in 0..rows {
        // The texel rows covered in row r or the next, with their covered range (texel
        // edges, in a cell's units): (y top, y bottom, x left, x right).
        let pair = [r, (r + 1).min(rows - 1)];
        let covered: Vec<[f32; 4]> = (0..cell)
            .filter_map(|y| {
                let both = pair.map(|r| spans[(r * cell + y) as usize]);
                let (a, b) =
                    both.into_iter().flatten().reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
                let c = cell as f32;
                Some([y as f32 / c, (y + 1) as f32 / c, a as f32 / c, (b + 1) as f32 / c])
            })
            .collect();
        let (Some(first), Some(last)) = (covered.first(), covered.last()) else {
            // Nothing covered: the whole cell.
            out.extend([[0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 0.0]]);
            continue;
        };
        let (top, bottom) = (first[0], last[1]);
        let mid = 0.5 * (top + bottom);
        // Each side: of the slopes tried, the one whose line, moved out to the last covered
        // texel, lies innermost at mid-height (the trapezoid's area is its height times
        // its width there). A texel row is held where its top and bottom corners are.
        let side = |left: bool| {
            (-200..=200)
                .map(|i| {
                    let slope = i as f32 * 0.01;
                    let offsets = covered.iter().flat_map(|c| {
                        let x = if left { c[2] } else { c[3] };
                        [x - slope * c[0], x - slope * c[1]]
                    });
                    let a = if left {
                        offsets.fold(f32::INFINITY, f32::min)
                    } else {
                        offsets.fold(f32::NEG_INFINITY, f32::max)
                    };
                    (a, slope)
                })
                .max_by(|p, q| {
                    let at = |(a, s): (f32, f32)| if left { a + s * mid } else { -(a + s * mid) };
                    at(*p).total_cmp(&at(*q))
                })
                .unwrap_or((0.0, 0.0))
        };
        let (l, rt) = (side(true), side(false));
        out.extend([[l.0, l.1, rt.0, rt.1], [top, bottom, 0.0, 0.0]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether texel (x, y) of a `cell`-texel cell lies within row `r`'s trapezoid of
    /// `outline` (its four corners inside, to rounding).
    fn inside(outline: &[[f32; 4]], r: usize, x: u32, y: u32, cell: u32) -> bool {
        let ([al, sl, ar, sr], [top, bottom, _, _]) = (outline[2 * r], outline[2 * r + 1]);
        let c = cell as f32;
        let eps = 1e-4;
        [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].iter().all(|&(px, py)| {
            let (px, py) = (px as f32 / c, py as f32 / c);
            py >= top - eps
                && py <= bottom + eps
                && px >= al + sl * py - eps
                && px <= ar + sr * py + eps
        })
    }

    #[test]
    fn an_impostor_outline_holds_every_covered_texel_of_its_rows_and_hugs_a_cone() {
        // Two views a row, three rows of 64-texel cells. Row 0 shows a cone (a conifer
        // from the side: apex at the top, 40 texels wide at its foot) on a two-texel trunk;
        // row 1 the same cone shifted 6 texels right in its second view (a view baked from
        // a turned direction); row 2 a disc (the crown from above). Each row's trapezoid
        // must hold every texel its own row and the next cover, and the side view's must be
        // about the cone's area, not the square's.
        let (views, rows, cell) = (2u32, 3u32, 64u32);
        let (w, h) = (views * cell, rows * cell);
        let mut albedo = vec![0u8; (w * h * 4) as usize];
        let mut cover = |k: u32, r: u32, x: u32, y: u32| {
            let i = (((r * cell + y) * w + k * cell + x) * 4 + 3) as usize;
            albedo[i] = 200;
        };
        let cone = |x: i32, y: i32, shift: i32| {
            // Apex at (32, 8), foot at y = 48, half-width 20 there; trunk below to 60.
            let x = x - shift;
            (8..48).contains(&y) && (x - 32).abs() * 40 <= 20 * (y - 8)
                || (48..60).contains(&y) && (31..33).contains(&x)
        };
        for y in 0..cell {
            for x in 0..cell {
                let (xi, yi) = (x as i32, y as i32);
                for k in 0..views {
                    if cone(xi, yi, 0) {
                        cover(k, 0, x, y);
                    }
                    if cone(xi, yi, if k == 1 { 6 } else { 0 }) {
                        cover(k, 1, x, y);
                    }
                    if (xi - 32).pow(2) + (yi - 30).pow(2) <= 18 * 18 {
                        cover(k, 2, x, y);
                    }
                }
            }
        }
        let o = outline(&albedo, w, h, views, rows, cell);
        assert_eq!(o.len(), rows as usize * OUTLINE_PER_ROW);
        for r in 0..rows {
            for shown in [r, (r + 1).min(rows - 1)] {
                for k in 0..views {
                    for y in 0..cell {
                        for x in 0..cell {
                            let i = (((shown * cell + y) * w + k * cell + x) * 4 + 3) as usize;
                            if albedo[i] > 0 {
                                assert!(
                                    inside(&o, r as usize, x, y, cell),
                                    "row {r}'s outline misses texel ({x}, {y}) of row {shown}"
                                );
                            }
                        }
                    }
                }
            }
        }
        let area = |o: &[[f32; 4]], r: usize| {
            let ([al, sl, ar, sr], [top, bottom, _, _]) = (o[2 * r], o[2 * r + 1]);
            let mid = 0.5 * (top + bottom);
            (bottom - top) * (ar + sr * mid - (al + sl * mid))
        };
        let texel = 1.0 / cell as f32;
        // Row 2 alone (the disc, 37 texels across): its bounding box, no more.
        let disc_box = (37.0 * texel) * (37.0 * texel);
        assert!((area(&o, 2) / disc_box - 1.0).abs() < 0.05, "disc {} box {disc_box}", area(&o, 2));
        // Rows 0 and 1: the two cones on their trunk. The trapezoid through the apexes and
        // the feet's corners, extended down to the trunk's end (6 … 64 at y = 60, 6 texels
        // wide at the top: 0.41 of the cell), not the box around them (46 × 52: 0.58).
        assert!(area(&o, 0) < 0.43, "the cones' outline: {}", area(&o, 0));
        // A cone alone, apex up: half its box, which the square of the cells draws whole.
        let mut albedo = vec![0u8; (w * h * 4) as usize];
        for r in 0..rows {
            for y in 0..cell {
                for x in 0..cell {
                    if (8..48).contains(&(y as i32)) && cone(x as i32, y as i32, 0) {
                        let i = (((r * cell + y) * w + x) * 4 + 3) as usize;
                        albedo[i] = 255;
                    }
                }
            }
        }
        let o = outline(&albedo, w, h, views, rows, cell);
        let cone_box = 41.0 * 40.0 * texel * texel;
        for r in 0..rows as usize {
            assert!(area(&o, r) < 0.56 * cone_box, "row {r}: {} for a box {cone_box}", area(&o, r));
        }
    }

    #[test]
    fn an_impostor_with_nothing_baked_is_drawn_over_its_whole_cell() {
        let (w, h) = (2 * 8, 3 * 8);
        let o = outline(&vec![0u8; (w * h * 4) as usize], w, h, 2, 3, 8);
        for r in 0..3 {
            assert!(inside(&o, r, 0, 0, 8) && inside(&o, r, 7, 7, 8), "row {r}: {o:?}");
        }
    }

    #[test]
    fn impostors_are_baked_from_level_one_with_every_leaf_card_of_full_detail() {
        // Every preset's impostor is rendered from level 1 (each preset's level 1 is within
        // BAKE_TRIANGLES), which has full detail's leaf cards on less wood: only the wood is
        // thinned, not the foliage the impostor mostly shows. Full detail itself is within
        // the cap for most presets, so it is BAKE_FINEST, not the cap, that picks level 1.
        let mut full_within_cap = 0;
        for (name, _) in sylva_tree::species::PRESETS {
            let species = sylva_tree::species::Species::preset(name).expect("preset");
            let model = species.model(1, sylva_tree::mesh::LOD_LEVELS).expect("model");
            let (full, baked) = (&model.lods[0], &model.lods[bake_level(&model)]);
            assert_eq!(bake_level(&model), 1, "{name}");
            assert!(baked.triangles() <= BAKE_TRIANGLES, "{name}: {}", baked.triangles());
            assert_eq!(baked.clusters.len(), full.clusters.len(), "{name}: leaf cards");
            assert!(baked.triangles() < full.triangles(), "{name}: less wood");
            full_within_cap += usize::from(full.triangles() <= BAKE_TRIANGLES);
        }
        assert!(full_within_cap > 0);
    }

    #[test]
    fn the_crown_ellipsoid_of_clusters_filling_one_gives_back_its_radii_and_leaf_density() {
        // Clusters of 0.05 m² each on a 0.25 m lattice filling an ellipsoid of radii 3 m
        // across and 4 m up about (0, 0, 8): leaf area density 0.05 / 0.25³
        // = 3.2 m²/m³. The moments of a uniformly filled ellipsoid give its radii back (to
        // the lattice's step), and the extinction is CROWN_EXTINCTION times the density.
        let (a, b, z0, step, area) = (3.0f32, 4.0f32, 8.0f32, 0.25f32, 0.05f32);
        let mut clusters = Vec::new();
        let n = (b / step) as i32 + 1;
        for i in -n..=n {
            for j in -n..=n {
                for k in -n..=n {
                    let p = [i as f32 * step, j as f32 * step, k as f32 * step];
                    if (p[0] * p[0] + p[1] * p[1]) / (a * a) + p[2] * p[2] / (b * b) <= 1.0 {
                        clusters.push(sylva_tree::mesh::LeafCluster {
                            joint: 0,
                            hang: [0.0; 3],
                            center: [p[0], p[1], p[2] + z0],
                            size: 0.3,
                            roll: 0.0,
                            atlas: 0,
                            phase: 0.0,
                            leaf_area: area,
                            normal: [0.0, 0.0, 1.0],
                            exposure: 1.0,
                        });
                    }
                }
            }
        }
        let [z, ra, rb, extinction] = crown_ellipsoid(&clusters);
        assert!((z - z0).abs() < 1e-3, "centre {z}");
        assert!((ra - a).abs() < 0.1 && (rb - b).abs() < 0.1, "radii {ra}, {rb}");
        let density = area / (step * step * step);
        assert!(
            (extinction / (CROWN_EXTINCTION * density) - 1.0).abs() < 0.05,
            "extinction {extinction} for density {density}"
        );
        assert_eq!(crown_ellipsoid(&[]), [0.0; 4], "no leaves, no shade");
    }

    #[test]
    fn a_coarse_depth_texel_holds_the_depth_of_the_leaves_under_it_not_of_the_background() {
        // An 8 × 8 view: a leaf at depth 60 covering one texel of each 2 × 2 block in the
        // left half, one at depth 200 in the top right quarter, nothing else (depth 255,
        // the bake's cleared far plane). A plain mean would pull every coarse texel towards
        // the far plane; weighted by coverage each holds its leaves' depth. Texels over
        // nothing hold the depth of the leaves next to them (the empty quarter, next to
        // nothing within its 4 × 4 block, the covered texels' mean).
        let (w, h) = (8u32, 8u32);
        let mut albedo = vec![0u8; (w * h * 4) as usize];
        let mut depth = vec![255u8; (w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let leaf = if x < 4 && x % 2 == 0 && y % 2 == 0 {
                    60
                } else if x >= 4 && y < 4 {
                    200
                } else {
                    continue;
                };
                albedo[4 * i + 3] = 255;
                depth[i] = leaf;
            }
        }
        let mips = depth_mips(&depth, &albedo, w, h, 8);
        assert_eq!(mips.len(), 2, "8 × 8 and 4 × 4, as impostor_mips stops");
        let covered = 8 + 16;
        let mean = ((8 * 60 + 16 * 200) as f64 / covered as f64).round() as u8;
        assert_eq!(mips[0][(7 * w + 7) as usize], mean, "an empty quarter takes the covered mean");
        assert_eq!(mips[0][0], 60);
        assert_eq!(mips[0][(w + 1) as usize], 60, "a gap between the near leaves takes theirs");
        assert_eq!(mips[0][(5 * w + 3) as usize], 60, "and lower down");
        let l1 = &mips[1];
        for y in 0..4u32 {
            for x in 0..4u32 {
                let want = match (x < 2, y < 2) {
                    (true, _) => 60,
                    (false, true) => 200,
                    (false, false) => mean,
                };
                assert_eq!(l1[(y * 4 + x) as usize], want, "level 1 texel ({x}, {y})");
            }
        }
    }

    #[test]
    fn a_texel_over_nothing_takes_the_depth_of_what_is_beside_it_in_its_own_view() {
        // Two 16 × 16 views side by side. The left one holds a vertical trunk two texels wide
        // at depth 220 (a foot seen from above, behind the views' middle) and a leaf at
        // depth 20 in its top left corner; the right one a single leaf at depth 100. Beside
        // the trunk the map must read the trunk's depth, so that a line of sight followed
        // into it from just beside the trunk lands on the trunk and not a view's width
        // away; the right view's empty texels must read its own leaf's depth, not the left
        // view's.
        let (w, h, cell) = (32u32, 16u32, 16u32);
        let mut albedo = vec![0u8; (w * h * 4) as usize];
        let mut depth = vec![255u8; (w * h) as usize];
        let mut put = |x: u32, y: u32, d: u8| {
            let i = (y * w + x) as usize;
            albedo[4 * i + 3] = 255;
            depth[i] = d;
        };
        for y in 8..16 {
            put(7, y, 220);
            put(8, y, 220);
        }
        put(0, 0, 20);
        put(24, 4, 100);
        let mips = depth_mips(&depth, &albedo, w, h, cell);
        let at = |x: u32, y: u32| mips[0][(y * w + x) as usize];
        for y in 8..16 {
            for x in [5, 6, 9, 10] {
                assert_eq!(at(x, y), 220, "texel ({x}, {y}) beside the trunk");
            }
        }
        assert_eq!(at(1, 1), 20, "beside the corner leaf");
        for (x, y) in [(16, 0), (31, 15), (20, 10)] {
            assert_eq!(at(x, y), 100, "texel ({x}, {y}) of the right view");
        }
        // The covered texels keep their own depth.
        assert_eq!((at(7, 12), at(0, 0), at(24, 4)), (220, 20, 100));
    }

    #[test]
    fn alpha_mips_keep_the_crown_from_thinning_out_and_within_its_silhouette() {
        // Left half: isolated opaque texels (thin leaves) at 25 % density; right half empty.
        // A plain box filter turns them into alpha 64: every texel fails the alpha test.
        let (w, h) = (64u32, 64u32);
        let mut albedo = vec![0u8; (w * h * 4) as usize];
        for y in 0..h {
            for x in 0..w / 2 {
                if x % 2 == 0 && y % 2 == 0 {
                    let i = ((y * w + x) * 4) as usize;
                    albedo[i..i + 4].copy_from_slice(&[40, 120, 30, 255]);
                }
            }
        }
        let normal = vec![128u8; albedo.len()];
        let (mips, normals) = impostor_mips(&albedo, &normal, w, h, (1, 1));
        assert_eq!(mips.len(), normals.len());
        assert!(mips.len() >= 4);
        let share = |m: &[u8], pred: &dyn Fn(&[u8]) -> bool| {
            m.chunks(4).filter(|p| pred(p)).count() as f64 / (m.len() / 4) as f64
        };
        let level0 = share(&mips[0], &|p| p[3] >= 128);
        assert!((level0 - 0.125).abs() < 1e-9);
        for (l, m) in mips.iter().enumerate().skip(1) {
            let pass = share(m, &|p| p[3] >= 128);
            let silhouette = share(m, &|p| p[3] > 0);
            assert!(pass >= level0 - 0.01, "level {l}: {pass:.3} pass, level 0 {level0:.3}");
            assert!(pass <= silhouette + 1e-9, "level {l}: {pass:.3} pass outside the silhouette");
            // Colour is the leaves' colour, not darkened by the transparent background.
            for p in m.chunks(4).filter(|p| p[3] >= 128) {
                assert!((p[1] as i32 - 120).abs() <= 2, "level {l}: green {}", p[1]);
            }
        }
        let plain = crate::shared::box_mips(&albedo, w, h);
        assert_eq!(share(&plain[1], &|p| p[3] >= 128), 0.0, "the case a plain box filter loses");
    }

    #[test]
    fn every_leaf_cell_keeps_its_coverage_within_ten_percent_at_every_mip_level() {
        // A crown seen from farther away samples coarser mips of the leaf atlas: what passes
        // the alpha test must stay the same share of each cluster, or far crowns thin out
        // (plain box filter) or fatten.
        for (name, _) in sylva_tree::PRESETS {
            let sp = sylva_tree::Species::preset(name).expect("preset");
            let atlas = sylva_tree::texture::leaf_atlas(&sp, 1, sylva_tree::mesh::ATLAS_SIZE);
            let (w, h) = (atlas.image.width, atlas.image.height);
            let normal = vec![128u8; atlas.image.rgba.len()];
            let (mips, _) =
                impostor_mips(&atlas.image.rgba, &normal, w, h, (atlas.cells, atlas.cells));
            let cells = atlas.cells;
            for (l, m) in mips.iter().enumerate() {
                let (lw, lh) = ((w >> l).max(1), (h >> l).max(1));
                let side = lw / cells;
                // Below 8 texels a cell, one texel is more than 10 % of a cluster's leaves.
                if side < 8 {
                    break;
                }
                for c in 0..cells * cells {
                    let (cx, cy) = (c % cells, c / cells);
                    let mut pass = 0usize;
                    for y in cy * side..(cy + 1) * side {
                        for x in cx * side..(cx + 1) * side {
                            pass += usize::from(m[((y * lw + x) * 4 + 3) as usize] >= 128);
                        }
                    }
                    let cov = pass as f32 / (side * side) as f32;
                    let want = atlas.coverage[c as usize];
                    assert!(
                        (cov / want - 1.0).abs() < 0.10,
                        "{name} cell {c} mip {l} ({lw}x{lh}): coverage {cov:.3} vs {want:.3}"
                    );
                }
            }
        }
    }
}
