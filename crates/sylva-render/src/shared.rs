//! What the passes share: meshes in GPU buffers, texture upload with mip chains, the bind
//! group layouts of the globals and of a species, and one render-pipeline builder.

use wgpu::util::DeviceExt;

use crate::gpu::Gpu;

/// Depth buffer format. Depth is not reversed: 0 at the near plane, 1 at the far one,
/// cleared to 1, nearer wins ([`host_depth_state`]).
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The depth state a host's own opaque pipeline needs to share a depth buffer with the
/// forest ([`Renderer::encode_over`](crate::Renderer::encode_over)): [`DEPTH`], written,
/// nearer (smaller) wins, as the forest's own opaque passes test.
pub fn host_depth_state() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

const COMMON: &str = include_str!("common.wgsl");

/// Every shader: (file name, source as on disk). `common.wgsl` is prepended to each
/// pass's file, and its [`SHADER_PARTS`] appended.
pub const SHADERS: [(&str, &str); 6] = [
    ("common.wgsl", COMMON),
    ("sky.wgsl", include_str!("passes/sky.wgsl")),
    ("ground.wgsl", include_str!("passes/ground.wgsl")),
    ("branch.wgsl", include_str!("passes/branch.wgsl")),
    ("leaf.wgsl", include_str!("passes/leaf.wgsl")),
    ("far.wgsl", include_str!("passes/far/far.wgsl")),
];

/// Shader files that are parts of another: (file name, the shader it is appended to,
/// source as on disk). The distant woodland is the ground's second half.
pub const SHADER_PARTS: [(&str, &str, &str); 1] =
    [("woodland.wgsl", "ground.wgsl", include_str!("passes/woodland.wgsl"))];

/// The source the renderer compiles for shader file `name`: `common.wgsl` alone, or
/// prepended to the pass's file with its parts appended.
pub fn shader_source(name: &str) -> Option<String> {
    let (_, src) = SHADERS.iter().find(|(n, _)| *n == name)?;
    if name == "common.wgsl" {
        return Some(src.to_string());
    }
    let mut out = format!("{COMMON}\n{src}");
    for (_, _, part) in SHADER_PARTS.iter().filter(|(_, host, _)| *host == name) {
        out.push('\n');
        out.push_str(part);
    }
    Some(out)
}

/// The palettes as `common.wgsl` declares them: a storage buffer.
pub const PALETTE_STORAGE: &str = "@group(0) @binding(1) var<storage, read> palettes: array<f32>;
fn palette_value(i: u32) -> f32 { return palettes[i]; }";

/// The same where palettes are a texture ([`palettes_in_texture`]): one float a texel,
/// [`PALETTE_ROW`] to a row, read with `textureLoad` (which WebGL2's vertex shaders have).
pub const PALETTE_TEXTURE: &str = "@group(0) @binding(1) var palettes: texture_2d<f32>;
fn palette_value(i: u32) -> f32 { return textureLoad(palettes, vec2<u32>(i % 2048u, i / 2048u), 0).x; }";

/// Floats per row of the palette texture (the `2048u` of [`PALETTE_TEXTURE`]).
pub const PALETTE_ROW: u32 = 2048;

/// Whether `dev` keeps the joint palettes in a texture: its vertex shaders cannot read
/// storage buffers (WebGL2, or a device asked for none). The images are the same.
pub fn palettes_in_texture(dev: &wgpu::Device) -> bool {
    dev.limits().max_storage_buffers_per_shader_stage == 0
}

/// The source compiled for shader file `name` on `dev`: [`shader_source`], with the
/// palettes declared as a texture where the device keeps them in one.
pub fn device_shader_source(dev: &wgpu::Device, name: &str) -> Option<String> {
    let src = shader_source(name)?;
    Some(if palettes_in_texture(dev) { src.replace(PALETTE_STORAGE, PALETTE_TEXTURE) } else { src })
}

/// Compile shader file `name` (with `common.wgsl`).
pub fn shader_module(dev: &wgpu::Device, name: &str) -> wgpu::ShaderModule {
    let src = device_shader_source(dev, name).unwrap_or_default();
    dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    })
}

/// An indexed mesh on the GPU.
#[derive(Debug)]
pub struct Mesh {
    /// Vertices.
    pub vertices: wgpu::Buffer,
    /// u32 indices.
    pub indices: wgpu::Buffer,
    /// Index count.
    pub count: u32,
}

impl Mesh {
    /// Upload `vertices` and `indices`.
    pub fn new<V: bytemuck::Pod>(gpu: &Gpu, label: &str, vertices: &[V], indices: &[u32]) -> Mesh {
        Mesh {
            vertices: buffer(
                gpu,
                label,
                bytemuck::cast_slice(vertices),
                wgpu::BufferUsages::VERTEX,
            ),
            indices: buffer(gpu, label, bytemuck::cast_slice(indices), wgpu::BufferUsages::INDEX),
            count: indices.len() as u32,
        }
    }

    /// Bind and draw `instances`.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, instances: std::ops::Range<u32>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.count, 0, instances);
    }
}

/// A buffer holding `data`.
pub fn buffer(gpu: &Gpu, label: &str, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: data,
        usage,
    })
}

/// A 2×2 box-filtered mip chain of an RGBA8 image, down to 4 texels a side.
pub fn box_mips(rgba: &[u8], width: u32, height: u32) -> Vec<Vec<u8>> {
    let mut levels = vec![rgba.to_vec()];
    let (mut w, mut h) = (width, height);
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
    levels
}

/// Upload a mip chain (level 0 first, each half the last) as a sampled texture.
pub fn upload_mips(
    gpu: &Gpu,
    levels: &[Vec<u8>],
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    label: &str,
) -> wgpu::TextureView {
    let data: Vec<u8> = levels.concat();
    let texture = gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &data,
    );
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// A bind-group layout entry for a filterable 2D texture seen by the fragment stage.
pub fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Group 0 of every pipeline: globals (uniform), palettes (storage, or a texture:
/// [`palettes_in_texture`]), linear sampler, the shadow map and its sampler.
pub fn globals_layout(dev: &wgpu::Device) -> wgpu::BindGroupLayout {
    let buffer_entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("globals"),
        entries: &[
            buffer_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT, wgpu::BufferBindingType::Uniform),
            if palettes_in_texture(dev) {
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                }
            } else {
                buffer_entry(
                    1,
                    wgpu::ShaderStages::VERTEX,
                    wgpu::BufferBindingType::Storage { read_only: true },
                )
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Depth,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 4,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                count: None,
            },
        ],
    })
}

/// What group 0 binds besides the palettes: the globals, the linear sampler, and the sun's
/// shadow map with its comparison sampler.
#[derive(Debug, Clone, Copy)]
pub struct GlobalsBinding<'a> {
    /// The `Globals` uniform buffer.
    pub globals: &'a wgpu::Buffer,
    /// Linear, repeating, mipmapped sampler.
    pub sampler: &'a wgpu::Sampler,
    /// Shadow map (a placeholder in passes that draw into the real one).
    pub shadow: &'a wgpu::TextureView,
    /// Comparison sampler of the shadow map.
    pub shadow_sampler: &'a wgpu::Sampler,
}

/// The bind group of [`globals_layout`].
pub fn globals_group(
    dev: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    with: &GlobalsBinding<'_>,
    palettes: &Palettes,
) -> wgpu::BindGroup {
    globals_window(dev, layout, with, palettes, 0, palettes.size())
}

/// The bind group of [`globals_layout`] with the palettes bound from byte `offset`,
/// `size` bytes (a window within the device's storage-binding limit; a texture is bound
/// whole).
pub fn globals_window(
    dev: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    with: &GlobalsBinding<'_>,
    palettes: &Palettes,
    offset: u64,
    size: u64,
) -> wgpu::BindGroup {
    let window = match palettes {
        Palettes::Buffer(buffer) => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset,
            size: wgpu::BufferSize::new(size),
        }),
        Palettes::Texture { view, .. } => wgpu::BindingResource::TextureView(view),
    };
    dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("globals"),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: with.globals.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: window },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::Sampler(with.sampler),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(with.shadow),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(with.shadow_sampler),
            },
        ],
    })
}

/// The joint palettes on the GPU: a storage buffer, or where the device's vertex shaders
/// cannot read one ([`palettes_in_texture`]), an `R32Float` texture of [`PALETTE_ROW`]
/// floats a row.
#[derive(Debug)]
pub enum Palettes {
    /// A storage buffer.
    Buffer(wgpu::Buffer),
    /// A texture and its view.
    Texture {
        /// The texture.
        texture: wgpu::Texture,
        /// Its view, as bound.
        view: wgpu::TextureView,
    },
}

impl Palettes {
    /// Room for at least `size` bytes of palettes (a texture: whole rows, at most the
    /// device's largest texture).
    pub fn new(dev: &wgpu::Device, size: u64) -> Palettes {
        if !palettes_in_texture(dev) {
            return Palettes::Buffer(dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("palettes"),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        let floats = size.div_ceil(4).max(1);
        let max_rows = dev.limits().max_texture_dimension_2d;
        let rows = (floats.div_ceil(u64::from(PALETTE_ROW)) as u32).clamp(1, max_rows);
        let texture = dev.create_texture(&wgpu::TextureDescriptor {
            label: Some("palettes"),
            size: wgpu::Extent3d { width: PALETTE_ROW, height: rows, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Palettes::Texture { texture, view }
    }

    /// Bytes held.
    pub fn size(&self) -> u64 {
        match self {
            Palettes::Buffer(b) => b.size(),
            Palettes::Texture { texture, .. } => {
                4 * u64::from(texture.width()) * u64::from(texture.height())
            }
        }
    }

    /// Write `data` from the first float on (it must fit: [`Palettes::size`]).
    pub fn write(&self, queue: &wgpu::Queue, data: &[f32]) {
        match self {
            Palettes::Buffer(b) => queue.write_buffer(b, 0, bytemuck::cast_slice(data)),
            Palettes::Texture { texture, .. } => {
                let row = PALETTE_ROW as usize;
                let (whole, rest) = (data.len() / row, data.len() % row);
                let put = |y: usize, floats: &[f32], rows: usize| {
                    queue.write_texture(
                        wgpu::TexelCopyTextureInfo {
                            texture,
                            mip_level: 0,
                            origin: wgpu::Origin3d { x: 0, y: y as u32, z: 0 },
                            aspect: wgpu::TextureAspect::All,
                        },
                        bytemuck::cast_slice(floats),
                        wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(4 * PALETTE_ROW),
                            rows_per_image: None,
                        },
                        wgpu::Extent3d {
                            width: (floats.len() / rows) as u32,
                            height: rows as u32,
                            depth_or_array_layers: 1,
                        },
                    );
                };
                if whole > 0 {
                    put(0, &data[..whole * row], whole);
                }
                if rest > 0 {
                    put(whole, &data[whole * row..], 1);
                }
            }
        }
    }
}

/// A vertex buffer of `size` bytes for instances.
pub fn instance_buffer(dev: &wgpu::Device, size: u64) -> wgpu::Buffer {
    dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("instances"),
        size,
        usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// How a pass's pipeline is built.
#[derive(Debug, Clone, Copy)]
pub struct PipelineSpec<'a> {
    /// Shader file (see [`SHADERS`]).
    pub shader: &'a str,
    /// Fragment entry point.
    pub fragment: &'a str,
    /// Bind group layouts.
    pub layout: &'a wgpu::PipelineLayout,
    /// Vertex buffers.
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    /// Depth test (less) and write; else tested (less or equal) without writing: the sky,
    /// at the far plane, drawn last, shades only the pixels nothing else covers.
    pub depth: bool,
    /// Back-face culling.
    pub cull: Option<wgpu::Face>,
    /// MSAA samples.
    pub samples: u32,
    /// Colour targets.
    pub targets: &'a [wgpu::TextureFormat],
    /// A shadow-pass pipeline: `SHADOW` overridden to true, depth biased against acne, no
    /// colour targets (and no fragment stage when `fragment` is empty).
    pub shadow: bool,
    /// One triangle strip per instance (a quad in four vertices rather than six) instead
    /// of a triangle list.
    pub strip: bool,
    /// Alpha to coverage (`COVERAGE` overridden to true) where there are several samples
    /// and colour targets; the colour's alpha then only chooses samples and is not written.
    pub coverage: bool,
}

/// Build the render pipeline `spec` describes (entry points `vs_main` and `spec.fragment`).
pub fn pipeline(dev: &wgpu::Device, spec: &PipelineSpec<'_>) -> wgpu::RenderPipeline {
    let module = shader_module(dev, spec.shader);
    let coverage = spec.coverage && spec.samples > 1 && !spec.shadow && !spec.targets.is_empty();
    let write_mask = if coverage { wgpu::ColorWrites::COLOR } else { wgpu::ColorWrites::ALL };
    let targets: Vec<Option<wgpu::ColorTargetState>> = spec
        .targets
        .iter()
        .map(|&format| Some(wgpu::ColorTargetState { format, blend: None, write_mask }))
        .collect();
    let mut constants: Vec<(&str, f64)> = Vec::new();
    if spec.shadow {
        constants.push(("SHADOW", 1.0));
    }
    if coverage {
        constants.push(("COVERAGE", 1.0));
    }
    let options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
    let bias = if spec.shadow {
        wgpu::DepthBiasState { constant: 2, slope_scale: 2.0, clamp: 0.0 }
    } else {
        Default::default()
    };
    dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.shader),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: options.clone(),
            buffers: spec.buffers,
        },
        primitive: wgpu::PrimitiveState {
            topology: if spec.strip {
                wgpu::PrimitiveTopology::TriangleStrip
            } else {
                wgpu::PrimitiveTopology::TriangleList
            },
            front_face: wgpu::FrontFace::Ccw,
            cull_mode: spec.cull,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(spec.depth),
            depth_compare: Some(if spec.depth {
                wgpu::CompareFunction::Less
            } else {
                wgpu::CompareFunction::LessEqual
            }),
            stencil: Default::default(),
            bias,
        }),
        multisample: wgpu::MultisampleState {
            count: spec.samples,
            mask: !0,
            alpha_to_coverage_enabled: coverage,
        },
        fragment: (!spec.fragment.is_empty()).then(|| wgpu::FragmentState {
            module: &module,
            entry_point: Some(spec.fragment),
            compilation_options: options.clone(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A tree pass's two pipelines from one `spec`: the frame's (`fs_main`, as `spec` says)
/// and the impostor bake's (`fs_bake`, no MSAA, into `bake_targets`).
pub fn draw_and_bake(
    dev: &wgpu::Device,
    spec: &PipelineSpec<'_>,
    bake_targets: &[wgpu::TextureFormat],
) -> (wgpu::RenderPipeline, wgpu::RenderPipeline) {
    let bake = PipelineSpec { fragment: "fs_bake", samples: 1, targets: bake_targets, ..*spec };
    (pipeline(dev, spec), pipeline(dev, &bake))
}

/// A depth attachment cleared to the far plane and discarded after the pass.
pub fn depth_cleared(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Discard,
        }),
        stencil_ops: None,
    }
}

/// A pipeline layout of `groups`.
pub fn pipeline_layout(
    dev: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|g| Some(*g)).collect();
    dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}
