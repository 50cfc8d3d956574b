//! Pipelines, per-species GPU resources, per-frame uploads and the draw.

use bytemuck::{Pod, Zeroable};
use sylva_forest::{Camera, Forest, FrameData, Instance, Terrain};
use sylva_tree::mesh::TreeLod;
use sylva_tree::texture::Image;
use wgpu::util::DeviceExt;

use crate::gpu::Gpu;

const COMMON: &str = include_str!("shaders/common.wgsl");

/// Every pipeline shader: (file name, source). `common.wgsl` is prepended to each.
pub const SHADERS: [(&str, &str); 5] = [
    ("common.wgsl", COMMON),
    ("sky.wgsl", include_str!("shaders/sky.wgsl")),
    ("ground.wgsl", include_str!("shaders/ground.wgsl")),
    ("branch.wgsl", include_str!("shaders/branch.wgsl")),
    ("leaf.wgsl", include_str!("shaders/leaf.wgsl")),
];

/// The source the renderer compiles for shader file `name`: `common.wgsl` alone, or
/// prepended to the pipeline's file.
pub fn shader_source(name: &str) -> Option<String> {
    let (_, src) = SHADERS.iter().find(|(n, _)| *n == name)?;
    Some(if name == "common.wgsl" { src.to_string() } else { format!("{COMMON}\n{src}") })
}

/// Depth buffer format.
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    cam_right: [f32; 4],
    cam_up: [f32; 4],
    sun: [f32; 4],
    sky_zenith: [f32; 4],
    sky_horizon: [f32; 4],
    fog: [f32; 4],
    misc: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct BranchVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
    joints: [u32; 4],
    weights: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct LeafVertex {
    center: [f32; 3],
    hang: [f32; 3],
    corner: [f32; 2],
    params: [f32; 4],
    joint: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct GroundVertex {
    position: [f32; 3],
    normal: [f32; 3],
}

#[derive(Debug)]
struct Mesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

#[derive(Debug)]
struct SpeciesGpu {
    lods: Vec<(Option<Mesh>, Option<Mesh>)>,
    textures: wgpu::BindGroup,
}

/// Draws a forest's frames into a colour target of a given format and size.
#[derive(Debug)]
pub struct Renderer {
    format: wgpu::TextureFormat,
    samples: u32,
    width: u32,
    height: u32,
    sky: wgpu::RenderPipeline,
    ground: wgpu::RenderPipeline,
    branch: wgpu::RenderPipeline,
    leaf: wgpu::RenderPipeline,
    globals: wgpu::Buffer,
    globals_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    palettes: wgpu::Buffer,
    instances: wgpu::Buffer,
    globals_group: wgpu::BindGroup,
    species: Vec<SpeciesGpu>,
    ground_mesh: Mesh,
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    atlas_cells: u32,
}

fn upload_texture(gpu: &Gpu, img: &Image, label: &str) -> wgpu::TextureView {
    // Mip chain by 2×2 box filter (alpha too: an alpha test at 0.5 keeps the coverage).
    let mut levels = vec![img.rgba.clone()];
    let (mut w, mut h) = (img.width, img.height);
    while w > 4 && h > 4 {
        let prev = levels.last().map(Vec::as_slice).unwrap_or(&[]);
        let (nw, nh) = (w / 2, h / 2);
        let mut next = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                for c in 0..4 {
                    let at = |xx: u32, yy: u32| prev[((yy * w + xx) * 4 + c) as usize] as u32;
                    let s = at(2 * x, 2 * y)
                        + at(2 * x + 1, 2 * y)
                        + at(2 * x, 2 * y + 1)
                        + at(2 * x + 1, 2 * y + 1);
                    next[((y * nw + x) * 4 + c) as usize] = ((s + 2) / 4) as u8;
                }
            }
        }
        levels.push(next);
        w = nw;
        h = nh;
    }
    let data: Vec<u8> = levels.concat();
    let texture = gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: img.width, height: img.height, depth_or_array_layers: 1 },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8UnormSrgb,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &data,
    );
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

fn buffer(gpu: &Gpu, label: &str, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: data,
        usage,
    })
}

fn branch_mesh(gpu: &Gpu, lod: &TreeLod) -> Option<Mesh> {
    let b = &lod.branches;
    if b.indices.is_empty() {
        return None;
    }
    let verts: Vec<BranchVertex> = (0..b.positions.len())
        .map(|i| BranchVertex {
            position: b.positions[i],
            normal: b.normals[i],
            uv: b.uvs[i],
            joints: b.joints[i],
            weights: b.weights[i],
        })
        .collect();
    Some(Mesh {
        vertices: buffer(
            gpu,
            "branch vertices",
            bytemuck::cast_slice(&verts),
            wgpu::BufferUsages::VERTEX,
        ),
        indices: buffer(
            gpu,
            "branch indices",
            bytemuck::cast_slice(&b.indices),
            wgpu::BufferUsages::INDEX,
        ),
        count: b.indices.len() as u32,
    })
}

fn leaf_mesh(gpu: &Gpu, lod: &TreeLod) -> Option<Mesh> {
    if lod.clusters.is_empty() {
        return None;
    }
    let mut verts = Vec::with_capacity(4 * lod.clusters.len());
    let mut indices: Vec<u32> = Vec::with_capacity(6 * lod.clusters.len());
    for c in &lod.clusters {
        let first = verts.len() as u32;
        for corner in [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]] {
            verts.push(LeafVertex {
                center: c.center,
                hang: c.hang,
                corner,
                params: [c.size, c.roll, c.phase, c.atlas as f32],
                joint: c.joint,
            });
        }
        indices.extend_from_slice(&[first, first + 1, first + 2, first, first + 2, first + 3]);
    }
    Some(Mesh {
        vertices: buffer(
            gpu,
            "leaf vertices",
            bytemuck::cast_slice(&verts),
            wgpu::BufferUsages::VERTEX,
        ),
        indices: buffer(
            gpu,
            "leaf indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        ),
        count: indices.len() as u32,
    })
}

/// The terrain as a grid mesh reaching `extent` m from the origin.
fn ground_mesh(gpu: &Gpu, terrain: &Terrain, extent: f32) -> Mesh {
    let n = 192u32;
    let mut verts = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            // Denser near the centre, where the trees stand.
            let s = |k: u32| {
                let u = 2.0 * k as f32 / n as f32 - 1.0;
                extent * u * u.abs()
            };
            let (x, y) = (s(i), s(j));
            verts.push(GroundVertex {
                position: [x, y, terrain.height(x, y)],
                normal: terrain.normal(x, y),
            });
        }
    }
    let mut indices = Vec::with_capacity((n * n * 6) as usize);
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let b = a + n + 1;
            indices.extend_from_slice(&[a, a + 1, b + 1, a, b + 1, b]);
        }
    }
    Mesh {
        vertices: buffer(
            gpu,
            "ground vertices",
            bytemuck::cast_slice(&verts),
            wgpu::BufferUsages::VERTEX,
        ),
        indices: buffer(
            gpu,
            "ground indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        ),
        count: indices.len() as u32,
    }
}

const INSTANCE_ATTRS: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
    5 => Float32x4, 6 => Float32, 7 => Uint32, 8 => Float32x2, 9 => Uint32
];

fn instance_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Instance>() as u64,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &INSTANCE_ATTRS,
    }
}

impl Renderer {
    /// Build pipelines and upload `forest`'s tree models, textures and ground, for a colour
    /// target of `format` and `width × height` texels.
    pub fn new(
        gpu: &Gpu,
        forest: &Forest,
        format: wgpu::TextureFormat,
        width: u32,
        height: u32,
    ) -> Renderer {
        let dev = &gpu.device;
        let features = gpu.adapter.get_texture_format_features(format);
        let samples = if features.flags.sample_count_supported(4) { 4 } else { 1 };
        let globals_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let tex_entry = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let species_layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("species textures"),
            entries: &[tex_entry(0), tex_entry(1)],
        });
        let scene_layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&globals_layout)],
            immediate_size: 0,
        });
        let tree_layout = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("trees"),
            bind_group_layouts: &[Some(&globals_layout), Some(&species_layout)],
            immediate_size: 0,
        });
        let module = |name: &str| {
            let src = shader_source(name).unwrap_or_default();
            dev.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(src.into()),
            })
        };
        let pipeline = |name: &str,
                        layout: &wgpu::PipelineLayout,
                        buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                        depth: bool,
                        cull: Option<wgpu::Face>| {
            let m = module(name);
            dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(name),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &m,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: cull,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(depth),
                    depth_compare: Some(if depth {
                        wgpu::CompareFunction::Less
                    } else {
                        wgpu::CompareFunction::Always
                    }),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: samples,
                    mask: !0,
                    alpha_to_coverage_enabled: false,
                },
                fragment: Some(wgpu::FragmentState {
                    module: &m,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let ground_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3];
        let branch_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32x4, 4 => Float32x4];
        let leaf_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4, 4 => Uint32];
        let sky = pipeline("sky.wgsl", &scene_layout, &[], false, None);
        let ground = pipeline(
            "ground.wgsl",
            &scene_layout,
            &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<GroundVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &ground_attrs,
            })],
            true,
            Some(wgpu::Face::Back),
        );
        let branch = pipeline(
            "branch.wgsl",
            &tree_layout,
            &[
                Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<BranchVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &branch_attrs,
                }),
                Some(instance_layout()),
            ],
            true,
            Some(wgpu::Face::Back),
        );
        let leaf = pipeline(
            "leaf.wgsl",
            &tree_layout,
            &[
                Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<LeafVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &leaf_attrs,
                }),
                Some(instance_layout()),
            ],
            true,
            None,
        );
        let sampler = dev.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let globals = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let palettes = storage(dev, 48 * 1024);
        let instances = instance_buffer(dev, 1024);
        let globals_group = globals_bind_group(dev, &globals_layout, &globals, &palettes, &sampler);
        let mut atlas_cells = 2;
        let species = forest
            .species
            .iter()
            .map(|s| {
                let m = &s.model;
                atlas_cells = m.leaves.cells;
                let bark = upload_texture(gpu, &m.bark, "bark");
                let leaves = upload_texture(gpu, &m.leaves.image, "leaf atlas");
                let textures = dev.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("species textures"),
                    layout: &species_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: wgpu::BindingResource::TextureView(&bark),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(&leaves),
                        },
                    ],
                });
                SpeciesGpu {
                    lods: m.lods.iter().map(|l| (branch_mesh(gpu, l), leaf_mesh(gpu, l))).collect(),
                    textures,
                }
            })
            .collect();
        let ground_mesh = ground_mesh(gpu, &forest.terrain, 3.0 * forest.radius + 600.0);
        let (msaa, depth) = targets(dev, format, samples, width, height);
        Renderer {
            format,
            samples,
            width,
            height,
            sky,
            ground,
            branch,
            leaf,
            globals,
            globals_layout,
            sampler,
            palettes,
            instances,
            globals_group,
            species,
            ground_mesh,
            msaa,
            depth,
            atlas_cells,
        }
    }

    /// MSAA sample count in use.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The colour format it draws.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
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
    pub fn render(
        &mut self,
        gpu: &Gpu,
        frame: &FrameData,
        camera: &Camera,
        target: &wgpu::TextureView,
    ) {
        let dev = &gpu.device;
        let aspect = self.width as f32 / self.height as f32;
        let vp = camera.view_projection(aspect);
        let inv = invert(&vp);
        let view = camera.view();
        let right = [view[0][0], view[1][0], view[2][0], 0.0];
        let up = [view[0][1], view[1][1], view[2][1], 0.0];
        let sun = normalize([-0.35, -0.55, 0.75]);
        let horizon = [0.62, 0.72, 0.82, 1.0];
        let g = Globals {
            view_proj: vp,
            inv_view_proj: inv,
            eye: [camera.eye[0], camera.eye[1], camera.eye[2], 1.0],
            cam_right: right,
            cam_up: up,
            sun: [sun[0], sun[1], sun[2], 1.1],
            sky_zenith: [0.18, 0.36, 0.72, 1.0],
            sky_horizon: horizon,
            fog: [horizon[0], horizon[1], horizon[2], 0.0011],
            misc: [frame.time as f32, self.atlas_cells as f32, 0.0, 0.0],
        };
        gpu.queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&g));
        // Grow the per-frame buffers to the next power of two.
        let pal_bytes = (frame.palettes.len().max(12) * 4) as u64;
        if pal_bytes > self.palettes.size() {
            self.palettes = storage(dev, pal_bytes.next_power_of_two());
            self.globals_group = globals_bind_group(
                dev,
                &self.globals_layout,
                &self.globals,
                &self.palettes,
                &self.sampler,
            );
        }
        let inst_bytes = (frame.instances.len().max(1) * std::mem::size_of::<Instance>()) as u64;
        if inst_bytes > self.instances.size() {
            self.instances = instance_buffer(dev, inst_bytes.next_power_of_two());
        }
        if !frame.palettes.is_empty() {
            gpu.queue.write_buffer(&self.palettes, 0, bytemuck::cast_slice(&frame.palettes));
        }
        if !frame.instances.is_empty() {
            gpu.queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&frame.instances));
        }
        let mut enc =
            dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        {
            let (view, resolve) = match &self.msaa {
                Some(m) => (m, Some(target)),
                None => (target, None),
            };
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("forest"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: resolve,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.globals_group, &[]);
            pass.set_pipeline(&self.sky);
            pass.draw(0..3, 0..1);
            pass.set_pipeline(&self.ground);
            pass.set_vertex_buffer(0, self.ground_mesh.vertices.slice(..));
            pass.set_index_buffer(self.ground_mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.ground_mesh.count, 0, 0..1);
            pass.set_vertex_buffer(1, self.instances.slice(..));
            for (pipeline, leaves) in [(&self.branch, false), (&self.leaf, true)] {
                pass.set_pipeline(pipeline);
                for b in &frame.buckets {
                    let Some(sp) = self.species.get(b.species as usize) else { continue };
                    let Some((branch, leaf)) = sp.lods.get(b.lod as usize) else { continue };
                    let Some(mesh) = (if leaves { leaf } else { branch }) else { continue };
                    pass.set_bind_group(1, &sp.textures, &[]);
                    pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                    pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..mesh.count, 0, b.first..b.first + b.count);
                }
            }
        }
        gpu.queue.submit([enc.finish()]);
    }
}

fn storage(dev: &wgpu::Device, size: u64) -> wgpu::Buffer {
    dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("palettes"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn instance_buffer(dev: &wgpu::Device, size: u64) -> wgpu::Buffer {
    dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("instances"),
        size,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn globals_bind_group(
    dev: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    globals: &wgpu::Buffer,
    palettes: &wgpu::Buffer,
    sampler: &wgpu::Sampler,
) -> wgpu::BindGroup {
    dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("globals"),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: globals.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: palettes.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(sampler) },
        ],
    })
}

fn targets(
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

fn normalize(a: [f32; 3]) -> [f32; 3] {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

/// Inverse of a column-major 4×4 matrix (Gauss–Jordan with partial pivoting, in f64);
/// the identity for a singular one.
fn invert(m: &[[f32; 4]; 4]) -> [[f32; 4]; 4] {
    // a[row][col], augmented with the identity.
    let mut a = [[0.0f64; 8]; 4];
    for r in 0..4 {
        for c in 0..4 {
            a[r][c] = m[c][r] as f64;
        }
        a[r][4 + r] = 1.0;
    }
    let mut out = [[0.0f32; 4]; 4];
    for col in 0..4 {
        let pivot =
            (col..4).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs())).unwrap_or(col);
        if a[pivot][col].abs() < 1e-30 {
            for (i, row) in out.iter_mut().enumerate() {
                row[i] = 1.0;
            }
            return out;
        }
        a.swap(col, pivot);
        let p = a[col][col];
        for v in &mut a[col] {
            *v /= p;
        }
        for r in 0..4 {
            if r != col {
                let f = a[r][col];
                let pivot_row = a[col];
                for (v, pv) in a[r].iter_mut().zip(pivot_row) {
                    *v -= f * pv;
                }
            }
        }
    }
    for r in 0..4 {
        for c in 0..4 {
            out[c][r] = a[r][4 + c] as f32;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_matrix_is_identity() {
        let cam = Camera {
            eye: [3.0, -20.0, 5.0],
            target: [0.0, 0.0, 4.0],
            fov_deg: 50.0,
            near: 0.5,
            far: 500.0,
        };
        let m = cam.view_projection(1.33);
        let p = sylva_forest::camera::mul(&invert(&m), &m);
        for c in 0..4 {
            for r in 0..4 {
                let want = if c == r { 1.0 } else { 0.0 };
                assert!((p[c][r] - want).abs() < 1e-3, "({c},{r}) = {}", p[c][r]);
            }
        }
    }
}
