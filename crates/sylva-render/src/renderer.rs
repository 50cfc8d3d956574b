//! The frame: shared targets and per-frame buffers, the passes in order (the sun's shadow
//! map, then branches, leaves, impostors, ground and sky: nearest first, so the depth test
//! spares hidden fragments their shading), and the one-way upload of [`FrameData`]. Each
//! species' resources are built in `species`.

use sylva_forest::{Camera, Forest, FrameData, Instance, Lighting, Surround, Terrain};
use sylva_tree::mesh::TreeModel;

use crate::gpu::{Gpu, RenderError};
use crate::layout::Globals;
use crate::passes::branch::BranchPass;
use crate::passes::far::{BAKE_TARGETS, BakeContext, FarPass};
use crate::passes::ground::{Canopy, GroundPass, Woodland, mean_albedo};
use crate::passes::leaf::LeafPass;
use crate::passes::shadow::{SHADOW_SIZE, ShadowPass};
use crate::passes::sky::SkyPass;
use crate::passtimes::{PARTS, PassTimes, Stamp, pass_writes, stamp};
use crate::shared::{
    DEPTH, GlobalsBinding, Palettes, globals_group, globals_layout, instance_buffer,
    palettes_in_texture, pipeline_layout, texture_entry,
};
use crate::species::{SpeciesGpu, upload_species};

/// What the renderer draws a scene with: tree models (in the scene's species order, as
/// [`sylva_forest::Bucket::species`] indexes them), the terrain, how far the ground reaches
/// and the lighting.
#[derive(Debug, Clone)]
pub struct SceneAssets<'a> {
    /// Tree models per species.
    pub models: &'a [&'a TreeModel],
    /// Ground.
    pub terrain: &'a Terrain,
    /// Half side of the ground mesh, m.
    pub ground_extent: f32,
    /// Crowns the ground lies under: x, y and radius, m ([`Forest::crowns`]).
    pub crowns: &'a [[f32; 3]],
    /// Woodland painted on the ground around the forest ([`sylva_forest::Surround`]): where
    /// it starts, the width of its edge, the crowns' spacing and the species mix its colour
    /// is taken from; `None` for open ground.
    pub woodland: Option<Woodland>,
    /// Sun, sky and fog.
    pub lighting: Lighting,
}

/// The ground reaches this far beyond three forest radii, m.
const GROUND_MARGIN: f32 = 600.0;

/// Draws a forest's frames into a colour target of a given format and size.
#[derive(Debug)]
pub struct Renderer {
    format: wgpu::TextureFormat,
    samples: u32,
    width: u32,
    height: u32,
    sky: SkyPass,
    ground: GroundPass,
    branch: BranchPass,
    leaf: LeafPass,
    far: FarPass,
    shadow: ShadowPass,
    globals: wgpu::Buffer,
    globals_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    palettes: Palettes,
    instances: wgpu::Buffer,
    /// One bind group per palette window (one when all palettes fit one binding).
    windows: Vec<wgpu::BindGroup>,
    /// The same for the shadow pass (the map's placeholder in its place).
    shadow_windows: Vec<wgpu::BindGroup>,
    /// The same with the far cascade's globals (`globals_far`), for drawing that cascade.
    shadow_windows_far: Vec<wgpu::BindGroup>,
    /// The globals with the far cascade's sun matrix in `sun_view_proj`.
    globals_far: wgpu::Buffer,
    /// Offset (floats) of each palette window.
    window_offsets: Vec<u64>,
    /// Window of each instance of the frame.
    window_of: Vec<u32>,
    /// Instances as uploaded: palette indices relative to their window.
    staged: Vec<Instance>,
    /// Draws: (bucket, window, first instance, count).
    draws: Vec<(usize, usize, u32, u32)>,
    species: Vec<SpeciesGpu>,
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    lighting: Lighting,
    overlay: Overlay,
    /// Where the image's centre of projection lies, in clip-space x (see
    /// [`Renderer::set_view_shift`]).
    view_shift: f32,
    /// Timestamps between the passes, once [`Renderer::time_passes`] turned them on.
    timing: Option<PassTimes>,
}

/// A colour overlay of the tree passes, for looking at the LODs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Overlay {
    /// The trees as they are.
    #[default]
    Off,
    /// Each draw tinted by its geometry level: full detail white, then yellow, orange, red,
    /// magenta, blue; impostors cyan.
    Level,
    /// Each tree tinted by its instance group (trees sharing one simulation share a colour).
    Group,
}

impl Renderer {
    /// Build the passes for a colour target of `format` and `width × height` texels, and
    /// upload what `forest` is drawn with (see [`Renderer::new`]).
    pub fn for_forest(
        gpu: &Gpu,
        forest: &Forest,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Result<Renderer, RenderError> {
        pollster::block_on(Renderer::for_forest_async(gpu, forest, format, width, height))
    }

    /// [`Renderer::for_forest`] as a future, for the web (see [`Renderer::new_async`]).
    pub async fn for_forest_async(
        gpu: &Gpu,
        forest: &Forest,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Result<Renderer, RenderError> {
        let models: Vec<&TreeModel> = forest.species.iter().map(|s| &s.model).collect();
        let crowns = forest.crowns();
        let assets = SceneAssets {
            crowns: &crowns,
            models: &models,
            terrain: &forest.terrain,
            ground_extent: 3.0 * forest.radius + GROUND_MARGIN,
            woodland: (forest.spec.surround == Surround::Woodland).then(|| {
                let spacing = forest.spec.spacing;
                Woodland {
                    start: Surround::woodland_start(forest.radius, spacing),
                    ramp: Surround::woodland_ramp(spacing),
                    spacing,
                    shares: forest.spec.species.iter().map(|s| s.weight).collect(),
                }
            }),
            // The scene's fog, or the default scaled to the forest.
            lighting: Lighting {
                fog_density: Some(forest.spec.lighting.fog(forest.radius)),
                ..forest.spec.lighting
            },
        };
        Renderer::new_async(gpu, &assets, format, width, height).await
    }

    /// Build the passes for a colour target of `format` and `width × height` texels, and
    /// upload the scene's tree models (meshes per LOD, textures with mip chains, impostors
    /// rendered from each species) and ground.
    pub fn new(
        gpu: &Gpu,
        assets: &SceneAssets<'_>,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Result<Renderer, RenderError> {
        pollster::block_on(Renderer::new_async(gpu, assets, format, width, height))
    }

    /// [`Renderer::new`] as a future. The impostors are baked on the GPU and read back;
    /// natively the future is ready when first polled (the device is waited on), while on
    /// the web the read-back completes only as the page's event loop runs, so a page must
    /// await this (wasm-bindgen-futures) and not call [`Renderer::new`], which would wait
    /// for ever.
    pub async fn new_async(
        gpu: &Gpu,
        assets: &SceneAssets<'_>,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Result<Renderer, RenderError> {
        let dev = &gpu.device;
        let features = gpu.adapter.get_texture_format_features(format);
        let samples = if features.flags.sample_count_supported(4) { 4 } else { 1 };
        let globals_layout = globals_layout(dev);
        let species_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("species textures"),
            entries: &[texture_entry(0), texture_entry(1)],
        });
        let scene_layout = pipeline_layout(dev, "scene", &[&globals_layout]);
        let tree_layout = pipeline_layout(dev, "trees", &[&globals_layout, &species_layout]);
        let sky = SkyPass::new(dev, &scene_layout, format, samples);
        let branch = BranchPass::new(dev, &tree_layout, format, samples, &BAKE_TARGETS);
        let leaf = LeafPass::new(dev, &tree_layout, format, samples, &BAKE_TARGETS);
        let far = FarPass::new(dev, &globals_layout, format, samples);
        let shadow = ShadowPass::new(dev, &tree_layout);
        let sampler = dev.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Nearest,
            ..Default::default()
        });
        let uniform = |label| {
            dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<Globals>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (globals, globals_far) = (uniform("globals"), uniform("globals, far cascade"));
        let palettes = Palettes::new(dev, 48 * 1024);
        let instances = instance_buffer(dev, 1024);
        let (lit, unlit) = shadow.bindings(&globals, &sampler);
        let windows = vec![globals_group(dev, &globals_layout, &lit, &palettes)];
        let shadow_windows = vec![globals_group(dev, &globals_layout, &unlit, &palettes)];
        let far_unlit = GlobalsBinding { globals: &globals_far, ..unlit };
        let shadow_windows_far = vec![globals_group(dev, &globals_layout, &far_unlit, &palettes)];
        let bake = BakeContext {
            branch: &branch.bake,
            leaf: &leaf.bake,
            globals_layout: &globals_layout,
            globals: unlit,
        };
        let mut species = Vec::with_capacity(assets.models.len());
        for m in assets.models {
            species.push(upload_species(gpu, m, &species_layout, &far, &bake).await?);
        }
        // The woodland around the forest takes the colour of the forest's own impostors.
        let woodland = assets.woodland.as_ref().map(|w| {
            let colours: Vec<_> = species
                .iter()
                .zip(&w.shares)
                .map(|(sp, &share)| (mean_albedo(&sp.far.albedo), share))
                .collect();
            (w, Canopy::of(&colours))
        });
        let ground = GroundPass::new(
            gpu,
            &scene_layout,
            format,
            samples,
            assets.terrain,
            assets.ground_extent,
            assets.crowns,
            woodland,
        );
        let (msaa, depth) = targets(dev, format, samples, width, height);
        Ok(Renderer {
            format,
            samples,
            width,
            height,
            sky,
            ground,
            branch,
            leaf,
            far,
            shadow,
            globals,
            globals_layout,
            sampler,
            palettes,
            instances,
            windows,
            shadow_windows,
            shadow_windows_far,
            globals_far,
            window_offsets: vec![0],
            window_of: Vec::new(),
            staged: Vec::new(),
            draws: Vec::new(),
            species,
            msaa,
            depth,
            lighting: assets.lighting,
            overlay: Overlay::Off,
            view_shift: 0.0,
            timing: None,
        })
    }

    /// Time each part of every frame on the GPU from now on (the parts of
    /// [`PASS_PARTS`](crate::PASS_PARTS): shadows, trees, impostors, ground, sky), read
    /// with [`pass_times`](Self::pass_times). False, and nothing timed, where the device
    /// has no timestamps inside passes.
    pub fn time_passes(&mut self, gpu: &Gpu) -> bool {
        if self.timing.is_none() {
            self.timing = PassTimes::new(gpu);
        }
        self.timing.is_some()
    }

    /// Stop timing the passes (and forget the latest times).
    pub fn stop_timing_passes(&mut self) {
        self.timing = None;
    }

    /// The GPU's time (ms) in each part of the last frame rendered, in the order of
    /// [`PASS_PARTS`](crate::PASS_PARTS) (waits for that frame to finish); `None` unless
    /// [`time_passes`](Self::time_passes) turned timing on.
    pub fn pass_times(&self, gpu: &Gpu) -> Result<Option<[f64; PARTS.len()]>, RenderError> {
        Ok(self.timing.as_ref().map(|t| t.read(gpu)).transpose()?.flatten())
    }

    /// The same for the latest frame the GPU has finished and whose times were read back
    /// (when the device was last polled: the viewer's [`crate::GpuTimer`] polls as each
    /// frame finishes), without waiting; `None` before the first or when timing is off.
    pub fn latest_pass_times(&self) -> Option<[f64; PARTS.len()]> {
        self.timing.as_ref().and_then(|t| t.latest())
    }

    /// Targets for a host that draws its own objects before the forest
    /// ([`encode_over`](Self::encode_over)), made as the renderer makes its own: the
    /// multisampled colour target in [`format`](Self::format) (`None` at one sample: the
    /// host's colour target is drawn into directly) and the depth target
    /// ([`DEPTH`](crate::DEPTH)), both `width × height` at [`samples`](Self::samples).
    pub fn host_targets(
        &self,
        gpu: &Gpu,
        width: u32,
        height: u32,
    ) -> (Option<wgpu::TextureView>, wgpu::TextureView) {
        targets(&gpu.device, self.format(), self.samples(), width, height)
    }

    /// MSAA sample count in use.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The size of the image it draws, `(width, height)` pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The colour format it draws.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Move the camera's centre of projection `shift` of the image's half-width to the
    /// right (clip-space x, −1 … 1; 0 by default): a panel covering the left `p` pixels of
    /// a `w`-pixel window sets `p / w`, so the scene is centred in the part left free. The
    /// frustum is not narrowed: what moves off the right edge was inside the camera's
    /// field of view, and what comes in on the left lies under the panel.
    pub fn set_view_shift(&mut self, shift: f32) {
        self.view_shift = if shift.is_finite() { shift.clamp(-1.0, 1.0) } else { 0.0 };
    }

    /// Palette windows the last frame was bound through (1 when its palettes fit one
    /// storage binding).
    pub fn palette_windows(&self) -> usize {
        self.windows.len()
    }

    /// Sun, sky and fog in use.
    pub fn lighting(&self) -> Lighting {
        self.lighting
    }

    /// Tint the trees by their level or instance group (the viewer's overlay), or not.
    pub fn set_overlay(&mut self, overlay: Overlay) {
        self.overlay = overlay;
    }

    /// Change the sun, sky and fog.
    pub fn set_lighting(&mut self, lighting: Lighting) {
        self.lighting = lighting;
    }

    /// Level-0 albedo (RGBA8, sRGB) of species `i`'s impostor views, side by side, and the
    /// side of one view in texels.
    pub fn impostor_views(&self, i: usize) -> Option<(&[u8], u32)> {
        self.species.get(i).map(|s| (s.far.albedo.as_slice(), crate::passes::far::VIEW_SIZE))
    }

    /// Resize the internal targets.
    pub fn resize(&mut self, gpu: &Gpu, width: u32, height: u32) {
        if (width, height) != (self.width, self.height) && width > 0 && height > 0 {
            let (msaa, depth) = targets(&gpu.device, self.format, self.samples, width, height);
            self.msaa = msaa;
            self.depth = depth;
            self.width = width;
            self.height = height;
        }
    }

    /// Upload `frame` and draw it seen from `camera` into `target` (same format and size).
    /// Returns at once, the GPU still drawing: the index names the submission, to wait for
    /// it (the buffers it reads may be written again for the next frame meanwhile; the
    /// queue orders the writes after it). [`Renderer::encode`] and [`Renderer::encode_over`]
    /// record the same into an encoder of the caller's, submitting nothing.
    pub fn render(
        &mut self,
        gpu: &Gpu,
        frame: &FrameData,
        camera: &Camera,
        target: &wgpu::TextureView,
    ) -> wgpu::SubmissionIndex {
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        self.encode(gpu, &mut enc, frame, camera, target);
        if let Some(t) = &mut self.timing {
            t.resolve(&mut enc);
        }
        let index = gpu.queue.submit([enc.finish()]);
        if let Some(t) = &mut self.timing {
            t.submitted();
        }
        index
    }

    /// Record the frame into the caller's encoder `enc`, onto the renderer's own
    /// multisampled colour and depth targets (cleared), resolved into `target` (the
    /// renderer's format and size). Buffers are written through `gpu.queue`, ordered before
    /// the caller's next submission; nothing is submitted here.
    pub fn encode(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        frame: &FrameData,
        camera: &Camera,
        target: &wgpu::TextureView,
    ) {
        let (msaa, depth) = (self.msaa.take(), self.depth.clone());
        let (view, resolve) = match &msaa {
            Some(m) => (m, Some(target)),
            None => (target, None),
        };
        let attach = Attach { color: view, resolve, depth: &depth, load: false };
        self.record(gpu, enc, frame, camera, attach);
        self.msaa = msaa;
    }

    /// Record the frame into the caller's encoder `enc` over what the caller has drawn:
    /// `color` (the renderer's [`format`](Self::format), [`samples`](Self::samples) samples,
    /// its size) and `depth` (format [`DEPTH`], Depth32Float, the same samples) are loaded,
    /// not cleared, so the caller's objects and the forest hide each other by depth. The
    /// depth convention is the standard one: 0 at the near plane, 1 at the far plane,
    /// nearer passes `Less`; clear to 1.0. `resolve`, where given, receives the resolved
    /// image (with one sample, pass `None`). The sky fills only what is still at depth 1.
    /// Nothing is submitted; pass timing is not recorded on this path.
    pub fn encode_over(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        frame: &FrameData,
        camera: &Camera,
        (color, resolve): (&wgpu::TextureView, Option<&wgpu::TextureView>),
        depth: &wgpu::TextureView,
    ) {
        let timing = self.timing.take();
        self.record(gpu, enc, frame, camera, Attach { color, resolve, depth, load: true });
        self.timing = timing;
    }

    /// Write the frame's uniforms and buffers, then record the shadow map and the image.
    fn record(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        frame: &FrameData,
        camera: &Camera,
        attach: Attach<'_>,
    ) {
        let aspect = self.width as f32 / self.height as f32;
        let mut g =
            Globals::for_camera(camera, aspect, self.view_shift, frame.time as f32, &self.lighting);
        g.overlay = match self.overlay {
            Overlay::Off => 0.0,
            Overlay::Level => 1.0,
            Overlay::Group => 2.0,
        };
        let shadows = self.lighting.shadows;
        if shadows {
            let sun = self.lighting.sun_unit();
            g.sun_view_proj = ShadowPass::sun_matrix(camera, aspect, sun);
            g.sun_view_proj_far =
                ShadowPass::sun_matrix_reaching(camera, aspect, sun, ShadowPass::far_reach(camera));
            g.shadow_texel = 1.0 / SHADOW_SIZE as f32;
            let far = Globals { sun_view_proj: g.sun_view_proj_far, ..g };
            gpu.queue.write_buffer(&self.globals_far, 0, bytemuck::bytes_of(&far));
        }
        gpu.queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        self.upload(gpu, frame);
        if shadows {
            // The sun's shadow map: every tree casts into each cascade (those in view, and
            // those out of it whose shadow may fall in it: `Bucket::shadow_only`), into the
            // near one as drawn (meshes two levels coarser, and impostors), into the far one
            // as an impostor: its texels span metres, and it shades only beyond the near
            // one's reach, where the trees are small.
            let stamps = pass_writes(self.timing.as_ref(), Stamp::ShadowStart, Stamp::ShadowEnd);
            let mut pass = self.shadow.begin(enc, stamps);
            ShadowPass::viewport(&mut pass, 0);
            pass.set_vertex_buffer(1, self.instances.slice(..));
            let casters = [&self.shadow.branch, &self.shadow.leaf];
            self.draw_trees(&mut pass, frame, casters, Some(&self.shadow_windows));
            self.draw_impostors(&mut pass, frame, &self.shadow_windows, Casting::AsDrawn);
            ShadowPass::viewport(&mut pass, 1);
            self.draw_impostors(&mut pass, frame, &self.shadow_windows_far, Casting::Every);
        }
        {
            let Attach { color: view, resolve, depth, load } = attach;
            let depth_stencil = if load {
                wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }
            } else {
                crate::shared::depth_cleared(depth)
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("forest"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: resolve,
                    ops: wgpu::Operations {
                        load: if load {
                            wgpu::LoadOp::Load
                        } else {
                            wgpu::LoadOp::Clear(wgpu::Color::BLACK)
                        },
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(depth_stencil),
                // The pass's end stamp comes after its MSAA resolve.
                timestamp_writes: self.timing.as_ref().map(|t| t.end_of_pass(Stamp::ImageEnd)),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            // Nearest first, so the depth test rejects hidden fragments before they are
            // shaded: the trees (finest level and nearest tree first), the ground they
            // stand on, the sky behind everything.
            if !shadows {
                stamp(self.timing.as_ref(), &mut pass, Stamp::ShadowStart);
                stamp(self.timing.as_ref(), &mut pass, Stamp::ShadowEnd);
            }
            stamp(self.timing.as_ref(), &mut pass, Stamp::ImageStart);
            pass.set_vertex_buffer(1, self.instances.slice(..));
            self.draw_trees(&mut pass, frame, [&self.branch.draw, &self.leaf.draw], None);
            stamp(self.timing.as_ref(), &mut pass, Stamp::Trees);
            self.draw_impostors(&mut pass, frame, &self.windows, Casting::No);
            stamp(self.timing.as_ref(), &mut pass, Stamp::Impostors);
            pass.set_bind_group(0, &self.windows[0], &[]);
            self.ground.draw(&mut pass);
            stamp(self.timing.as_ref(), &mut pass, Stamp::Ground);
            self.sky.draw(&mut pass);
        }
    }
}

/// The image pass's attachments: colour (with its resolve target) and depth, cleared by the
/// renderer or loaded from what the caller drew (`load`).
struct Attach<'a> {
    color: &'a wgpu::TextureView,
    resolve: Option<&'a wgpu::TextureView>,
    depth: &'a wgpu::TextureView,
    load: bool,
}

/// Which trees [`Renderer::draw_impostors`] draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Casting {
    /// The impostors, into the image.
    No,
    /// The impostors, into the shadow map.
    AsDrawn,
    /// Every tree as its impostor, into the shadow map.
    Every,
}

impl Renderer {
    /// Draw the impostors (buckets one past their species' last mesh level) through
    /// `windows`: the frame's, or (casting) a cascade's, into the shadow map, turned to
    /// the sun.
    fn draw_impostors(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameData,
        windows: &[wgpu::BindGroup],
        casting: Casting,
    ) {
        pass.set_vertex_buffer(0, self.instances.slice(..));
        if casting == Casting::No {
            self.far.begin(pass)
        } else {
            self.far.begin_shadow(pass)
        }
        for &(bucket, window, first, count) in &self.draws {
            let b = &frame.buckets[bucket];
            let Some(sp) = self.species.get(b.species as usize) else { continue };
            if b.shadow_only && casting == Casting::No {
                continue;
            }
            if b.lod as usize == sp.lods.len() || casting == Casting::Every {
                pass.set_bind_group(0, &windows[window], &[]);
                self.far.draw(pass, &sp.far, first..first + count);
            }
        }
    }

    /// Draw every tree drawn as a mesh (not the impostors) with `pipelines` (branches,
    /// leaves), bound through the frame's palette windows. `shadow`: into the shadow map,
    /// through the shadow pass's windows and at its bucket's `shadow_lod`, no finer than the
    /// tree is drawn at (its joints are a prefix of the drawn level's, so its palettes are
    /// there): a shadow-map texel spans a decimetre or more, and the coarser levels keep
    /// the crown's outline and leaf area, so the finer ones add cost, not shade.
    fn draw_trees(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        frame: &FrameData,
        pipelines: [&wgpu::RenderPipeline; 2],
        shadow: Option<&Vec<wgpu::BindGroup>>,
    ) {
        let windows = shadow.unwrap_or(&self.windows);
        for (pipeline, leaves) in [(pipelines[0], false), (pipelines[1], true)] {
            pass.set_pipeline(pipeline);
            for &(bucket, window, first, count) in &self.draws {
                let b = &frame.buckets[bucket];
                let Some(sp) = self.species.get(b.species as usize) else { continue };
                if b.shadow_only && shadow.is_none() {
                    continue;
                }
                let level = if shadow.is_some() { b.shadow_lod as usize } else { b.lod as usize };
                if b.lod as usize >= sp.lods.len() {
                    continue;
                }
                let Some((branch, leaf)) = sp.lods.get(level) else { continue };
                let Some(mesh) = (if leaves { leaf } else { branch }) else { continue };
                pass.set_bind_group(0, &windows[window], &[]);
                pass.set_bind_group(1, &sp.textures, &[]);
                mesh.draw(pass, first..first + count);
            }
        }
    }

    /// Copy `frame`'s palettes and instances to the GPU. Palettes beyond what one storage
    /// binding may hold (`max_storage_buffer_binding_size`) are bound through windows:
    /// instances in order of their first palette value, a window opens (aligned down to
    /// the device's offset alignment) at the first instance whose palette reads do not fit
    /// the current one; each instance's palette index is made relative to its window, and
    /// each bucket is drawn once per window it uses. One lane group's palettes must fit one
    /// binding (16 willows at full detail take 61 MB; devices bind at least 128 MB).
    fn upload(&mut self, gpu: &Gpu, frame: &FrameData) {
        let dev = &gpu.device;
        let limits = dev.limits();
        // A palette texture is bound whole: one window.
        let max_binding = if palettes_in_texture(dev) {
            u64::MAX
        } else {
            limits.max_storage_buffer_binding_size.min(limits.max_buffer_size)
        };
        let pal_bytes = (frame.palettes.len().max(12) * 4) as u64;
        // Grow the per-frame buffers to the next power of two (within the device's limit).
        let grown = pal_bytes > self.palettes.size();
        if grown {
            let size = pal_bytes.next_power_of_two().min(limits.max_buffer_size);
            self.palettes = Palettes::new(dev, size);
        }
        let floats = (self.palettes.size() / 4) as usize;
        let fits = self.palettes.size() <= max_binding;
        // Window of each instance (floats offset of each window).
        self.window_of.clear();
        self.window_of.resize(frame.instances.len(), 0);
        let mut offsets = vec![0u64];
        if !fits {
            let align = ((limits.min_storage_buffer_offset_alignment as u64).max(4) / 4) as usize;
            let span = (max_binding / 4) as usize;
            let mut order: Vec<(usize, usize, usize)> = Vec::with_capacity(frame.instances.len());
            for b in &frame.buckets {
                // A tree cast only into the shadow map reads the joints of its cast level.
                let reads = self.species.get(b.species as usize).map_or(1, |s| {
                    let chain = s.lods.len() as u32;
                    if b.shadow_only && b.lod < chain {
                        s.reads(b.shadow_lod)
                    } else {
                        s.reads(b.lod)
                    }
                });
                for k in b.first as usize..(b.first + b.count) as usize {
                    let i = &frame.instances[k];
                    let start = i.palette.base as usize;
                    let end = i.palette.end(reads).max(start + 1) - 1;
                    order.push((start, end, k));
                }
            }
            order.sort_unstable();
            offsets.clear();
            for (start, end, k) in order {
                let open = offsets.last().map(|&o| end < o as usize + span).unwrap_or(false);
                if !open {
                    offsets.push((start / align * align) as u64);
                }
                self.window_of[k] = (offsets.len() - 1) as u32;
            }
            if offsets.is_empty() {
                offsets.push(0);
            }
        }
        if grown || offsets != self.window_offsets {
            self.windows.clear();
            self.shadow_windows.clear();
            self.shadow_windows_far.clear();
            let (lit, unlit) = self.shadow.bindings(&self.globals, &self.sampler);
            let far_unlit = GlobalsBinding { globals: &self.globals_far, ..unlit };
            for &o in &offsets {
                let offset = 4 * o;
                let size = (self.palettes.size() - offset).min(max_binding);
                for (with, to) in [
                    (&lit, &mut self.windows),
                    (&unlit, &mut self.shadow_windows),
                    (&far_unlit, &mut self.shadow_windows_far),
                ] {
                    to.push(crate::shared::globals_window(
                        dev,
                        &self.globals_layout,
                        with,
                        &self.palettes,
                        offset,
                        size,
                    ));
                }
            }
            self.window_offsets = offsets;
        }
        self.staged.clear();
        self.draws.clear();
        for (bi, b) in frame.buckets.iter().enumerate() {
            let range = b.first as usize..(b.first + b.count) as usize;
            let mut w = 0;
            loop {
                let first = self.staged.len() as u32;
                let mut next = u32::MAX;
                for k in range.clone() {
                    let wk = self.window_of[k];
                    let inst = &frame.instances[k];
                    if wk == w && (inst.palette.base as usize) < floats {
                        let mut palette = inst.palette;
                        palette.base -= self.window_offsets[w as usize] as u32;
                        self.staged.push(Instance { palette, ..*inst });
                    } else if wk > w {
                        next = next.min(wk);
                    }
                }
                let count = self.staged.len() as u32 - first;
                if count > 0 {
                    self.draws.push((bi, w as usize, first, count));
                }
                if next == u32::MAX {
                    break;
                }
                w = next;
            }
        }
        let inst_bytes = (self.staged.len().max(1) * std::mem::size_of::<Instance>()) as u64;
        if inst_bytes > self.instances.size() {
            self.instances = instance_buffer(dev, inst_bytes.next_power_of_two());
        }
        let n = frame.palettes.len().min(floats);
        if n > 0 {
            self.palettes.write(&gpu.queue, &frame.palettes[..n]);
        }
        if !self.staged.is_empty() {
            gpu.queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&self.staged));
        }
    }
}

/// A multisampled colour target of `format` (none with one sample) and a depth target
/// ([`DEPTH`]), `samples` samples, `width × height`.
pub(crate) fn targets(
    dev: &wgpu::Device,
    format: wgpu::TextureFormat,
    samples: u32,
    width: u32,
    height: u32,
) -> (Option<wgpu::TextureView>, wgpu::TextureView) {
    let make = |format, label| {
        dev.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&wgpu::TextureViewDescriptor::default())
    };
    let msaa = (samples > 1).then(|| make(format, "msaa colour"));
    (msaa, make(DEPTH, "depth"))
}
