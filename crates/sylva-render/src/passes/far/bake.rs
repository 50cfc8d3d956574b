//! The bake: a species rendered at rest from every view of the atlas, read back, its mip
//! chains built and uploaded with the parameters the shader places its quads with.

use sylva_forest::{Instance, Lighting, PaletteSlot};
use sylva_tree::mesh::TreeModel;

use super::atlas::{depth_mips, impostor_mips};
use super::outline::outline;
use super::*;
use crate::gpu::{Gpu, RenderError};
use crate::layout::{FarSpecies, Globals};
use crate::shared::{GlobalsBinding, Mesh, Palettes, buffer, globals_group, upload_mips};

/// Where a tree's views are taken: the bounds' horizontal radius about the trunk axis and
/// height range, the side every view covers, its centre height and the depth range.
struct Frame {
    radius: f32,
    z0: f32,
    z1: f32,
    extent: f32,
    center: f32,
    depth_range: f32,
}

impl Frame {
    fn of(level: &sylva_tree::mesh::TreeLod) -> Frame {
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
        Frame { radius, z0, z1, extent, center, depth_range }
    }
}

/// The atlas read back at level 0: albedo and normals (RGBA8) and depth (one byte a
/// texel), `w × h`.
struct Views {
    albedo: Vec<u8>,
    normal: Vec<u8>,
    depth: Vec<u8>,
}

impl FarPass {
    /// Bake `model`'s impostor: render its views, read them back, build the mip chains and
    /// upload them. `textures` is the species' bark and leaf bind group; `meshes` its
    /// branch and leaf meshes at [`bake_level`].
    pub async fn bake(
        &self,
        gpu: &Gpu,
        ctx: &BakeContext<'_>,
        model: &TreeModel,
        textures: &wgpu::BindGroup,
        meshes: (Option<&Mesh>, Option<&Mesh>),
    ) -> Result<FarSpeciesGpu, RenderError> {
        let level = &model.lods[bake_level(model)];
        let fr = Frame::of(level);
        let Frame { radius, z0, z1, extent, center, depth_range } = fr;
        let views = render_views(gpu, ctx, model, textures, meshes, &fr).await?;
        let (w, h) = (VIEWS * VIEW_SIZE, ROWS * VIEW_SIZE);
        let albedo = &views.albedo;
        let (albedo_mips, normal_mips) = impostor_mips(albedo, &views.normal, w, h, (VIEWS, ROWS));
        let depth_mips = depth_mips(&views.depth, albedo, w, h, VIEW_SIZE);
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
        let group = self.species_group(gpu, &params, (&av, &nv, &dv));
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

    /// Group 1 of the impostor pipeline for one species: its albedo, normals and depth
    /// views, and its parameters as a uniform.
    fn species_group(
        &self,
        gpu: &Gpu,
        params: &FarSpecies,
        (av, nv, dv): (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
    ) -> wgpu::BindGroup {
        let dev = &gpu.device;
        let uniform =
            buffer(gpu, "impostor", bytemuck::bytes_of(params), wgpu::BufferUsages::UNIFORM);
        dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("impostor"),
            layout: &self.species_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(av),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(nv),
                },
                wgpu::BindGroupEntry { binding: 2, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(dv),
                },
            ],
        })
    }
}

/// Render every view of `model` at rest into the atlas and read it back.
async fn render_views(
    gpu: &Gpu,
    ctx: &BakeContext<'_>,
    model: &TreeModel,
    textures: &wgpu::BindGroup,
    meshes: (Option<&Mesh>, Option<&Mesh>),
    fr: &Frame,
) -> Result<Views, RenderError> {
    let dev = &gpu.device;
    // Rest pose: identity palettes, one instance at the origin.
    let joints = model.tree.skeleton.len().max(1);
    let identity: Vec<f32> = (0..joints)
        .flat_map(|_| [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0])
        .collect();
    let palettes = Palettes::new(dev, (identity.len() * 4) as u64);
    palettes.write(&gpu.queue, &identity);
    let instance = Instance {
        scale: 1.0,
        palette: PaletteSlot { base: 0, stride: 1 },
        fade: [0.0, 2.0],
        ..Default::default()
    };
    let instances =
        buffer(gpu, "bake instance", bytemuck::bytes_of(&instance), wgpu::BufferUsages::VERTEX);
    let groups = view_groups(gpu, ctx, fr, &palettes);
    let (w, h) = (VIEWS * VIEW_SIZE, ROWS * VIEW_SIZE);
    let target = |format, label| crate::headless::capture_texture(dev, (w, h), format, label);
    let albedo_tex = target(BAKE_TARGETS[0], "impostor albedo");
    let normal_tex = target(BAKE_TARGETS[1], "impostor normals");
    let depth_tex = depth_target(dev, w, h, "impostor depth");
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
    // Depth32Float reads back as four bytes a texel, as RGBA8 does; where a depth texture
    // cannot be copied (WebGL2) its values are drawn into an RGBA8 target's red first (the
    // eight bits the depth map keeps).
    let copies_depth = gpu
        .adapter
        .get_downlevel_capabilities()
        .flags
        .contains(wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
    let depth_read =
        if copies_depth { depth_tex } else { depth_as_colour(gpu, &mut enc, &dv, w, h) };
    let read = read_back(gpu, enc, &[&albedo_tex, &normal_tex, &depth_read], w, h).await?;
    // The bake's depth is linear along each view (orthographic): 0 … 1 across
    // ±depth_range about the plane through the views' centre, nearest first.
    let depth = depth_bytes(&read[2], copies_depth);
    let mut read = read;
    let normal = read.swap_remove(1);
    let albedo = read.swap_remove(0);
    Ok(Views { albedo, normal, depth })
}

/// A `w × h` depth target that can be read back: copied, or drawn by [`depth_as_colour`].
fn depth_target(dev: &wgpu::Device, w: u32, h: u32, label: &str) -> wgpu::Texture {
    dev.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: crate::shared::DEPTH,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// The depth map's bytes from what was read back: Depth32Float texels (`copied`), or the
/// red of an RGBA8 target [`depth_as_colour`] drew.
fn depth_bytes(read: &[u8], copied: bool) -> Vec<u8> {
    read.chunks_exact(4)
        .map(|b| {
            if copied {
                let z = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                (z.clamp(0.0, 1.0) * 255.0).round() as u8
            } else {
                b[0]
            }
        })
        .collect()
}

/// Draws a depth texture's values into a colour target (`Rgba8Unorm`, the depth in red:
/// the eight bits the depth map keeps), for devices that cannot copy depth textures to
/// buffers (WebGL2, whose float colour targets need an extension besides). The depth is
/// bound as an unfilterable float texture (GLSL has no `textureLoad` of a depth texture)
/// and sampled at texel centres through a nearest sampler: in WebGL a float depth texture
/// read without a nearest sampler is incomplete and reads as 0.
const DEPTH_AS_COLOUR: &str = "
@group(0) @binding(0) var depth: texture_2d<f32>;
@group(0) @binding(1) var nearest: sampler;
@vertex fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
}
@fragment fn fs_main(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(depth));
    return vec4<f32>(textureSampleLevel(depth, nearest, at.xy / size, 0.0).x, 0.0, 0.0, 1.0);
}";

/// Record a pass that draws `depth`'s values (a `w × h` depth view) into a new
/// `Rgba8Unorm` texture, and return it (see [`DEPTH_AS_COLOUR`]).
fn depth_as_colour(
    gpu: &Gpu,
    enc: &mut wgpu::CommandEncoder,
    depth: &wgpu::TextureView,
    w: u32,
    h: u32,
) -> wgpu::Texture {
    let dev = &gpu.device;
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let out = crate::headless::capture_texture(dev, (w, h), format, "impostor depth as colour");
    let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("depth as colour"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::NonFiltering),
                count: None,
            },
        ],
    });
    let nearest = dev.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("depth as colour"),
        ..Default::default()
    });
    let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("depth as colour"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(depth),
            },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&nearest) },
        ],
    });
    let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("depth as colour"),
        source: wgpu::ShaderSource::Wgsl(DEPTH_AS_COLOUR.into()),
    });
    let pipeline_layout = crate::shared::pipeline_layout(dev, "depth as colour", &[&layout]);
    let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("depth as colour"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    });
    let view = out.create_view(&wgpu::TextureViewDescriptor::default());
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("depth as colour"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(&pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.draw(0..3, 0..1);
    drop(pass);
    out
}

/// Per view of the atlas, group 0: an orthographic camera about the tree's centre looking
/// along the view, with the rest-pose `palettes`.
fn view_groups(
    gpu: &Gpu,
    ctx: &BakeContext<'_>,
    fr: &Frame,
    palettes: &Palettes,
) -> Vec<wgpu::BindGroup> {
    let dev = &gpu.device;
    let (extent, center, depth_range) = (fr.extent, fr.center, fr.depth_range);
    let light = Lighting::default();
    (0..ROWS * VIEWS)
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
            let buf =
                buffer(gpu, "bake globals", bytemuck::bytes_of(&g), wgpu::BufferUsages::UNIFORM);
            let with = GlobalsBinding { globals: &buf, ..ctx.globals };
            globals_group(dev, ctx.globals_layout, &with, palettes)
        })
        .collect()
}

/// Submit `enc` with copies of `textures` (RGBA8, `w × h`) and read them back, rows top
/// first.
pub(super) async fn read_back(
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
    let mut read = Vec::with_capacity(buffers.len());
    for b in &buffers {
        read.push(crate::headless::map_rows_async(gpu, b, w, padded).await?);
    }
    Ok(read)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bake's depth drawn into a colour target (WebGL2's path) reads back as the depth
    /// texture copied directly does, texel for texel: a ramp across x and down y.
    #[test]
    fn depth_drawn_as_colour_reads_back_as_the_depth_copied() {
        let gpu = Gpu::headless().expect("adapter");
        let dev = &gpu.device;
        let (w, h) = (64u32, 32u32);
        let depth = depth_target(dev, w, h, "ramp");
        let dv = depth.create_view(&wgpu::TextureViewDescriptor::default());
        // The pass's vertex stage, and a fragment stage writing a ramp into the depth.
        let vertex: String = DEPTH_AS_COLOUR
            .split("@fragment")
            .next()
            .unwrap_or_default()
            .lines()
            .filter(|l| !l.starts_with("@group"))
            .collect::<Vec<_>>()
            .join("\n");
        let ramp = format!(
            "{vertex}
            @fragment fn fs_main(@builtin(position) at: vec4<f32>) -> @builtin(frag_depth) f32 {{
                return at.x / 128.0 + at.y / 64.0;
            }}"
        );
        let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ramp"),
            source: wgpu::ShaderSource::Wgsl(ramp.into()),
        });
        let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("ramp"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                depth_compare: Some(wgpu::CompareFunction::Always),
                ..crate::shared::host_depth_state()
            }),
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("ramp"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &dv,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.draw(0..3, 0..1);
        }
        let colour = depth_as_colour(&gpu, &mut enc, &dv, w, h);
        let read =
            pollster::block_on(read_back(&gpu, enc, &[&depth, &colour], w, h)).expect("read back");
        let value = |bytes: &[u8], x: u32, y: u32| {
            let i = (4 * (y * w + x)) as usize;
            f32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]])
        };
        let corner = value(&read[0], w - 1, h - 1);
        assert!((corner - (63.5 / 128.0 + 31.5 / 64.0)).abs() < 1e-3, "the ramp: {corner}");
        let (copied, drawn) = (depth_bytes(&read[0], true), depth_bytes(&read[1], false));
        assert!(copied.iter().collect::<std::collections::BTreeSet<_>>().len() > 50, "a ramp");
        // The GPU's conversion to eight bits may round a value half-way the other way.
        let off: Vec<_> = copied
            .iter()
            .zip(&drawn)
            .filter(|(a, b)| a != b)
            .map(|(a, b)| a.abs_diff(*b))
            .collect();
        assert!(off.iter().all(|&d| d <= 1), "depth drawn as colour is off by {off:?}");
        assert!(off.len() * 100 <= copied.len(), "{} of {} texels differ", off.len(), copied.len());
    }
}
