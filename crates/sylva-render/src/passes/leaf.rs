//! Leaves: the LOD's leaf-cluster cards, oriented out of the crown and turned part way
//! towards the viewer (or the sun, in the shadow pass), swung about their hanging
//! point and skinned to their joint, alpha-tested against the species' leaf atlas
//! (`leaf.wgsl`). A second pipeline (`fs_bake`) writes albedo and normals for the impostor
//! atlas.

use sylva_tree::mesh::TreeLod;

use crate::gpu::Gpu;
use crate::layout::{LEAF_ATTRIBUTES, LeafVertex, instance_layout, vertex_layout};
use crate::shared::{Mesh, PipelineSpec, draw_and_bake};

/// The leaf pass: a pipeline for the frame and one for the impostor bake.
#[derive(Debug)]
pub struct LeafPass {
    /// Lit, fogged, dithered for cross-fades.
    pub draw: wgpu::RenderPipeline,
    /// Albedo and normal into the impostor atlas (two targets, no MSAA).
    pub bake: wgpu::RenderPipeline,
}

impl LeafPass {
    /// Pipelines; `layout` holds the globals and a species' textures.
    pub fn new(
        dev: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        format: wgpu::TextureFormat,
        samples: u32,
        bake_targets: &[wgpu::TextureFormat],
    ) -> LeafPass {
        let buffers =
            [Some(vertex_layout::<LeafVertex>(&LEAF_ATTRIBUTES)), Some(instance_layout())];
        let spec = PipelineSpec {
            shader: "leaf.wgsl",
            fragment: "fs_main",
            layout,
            buffers: &buffers,
            depth: true,
            cull: None,
            samples,
            targets: &[format],
            shadow: false,
            strip: false,
            coverage: true,
        };
        let (draw, bake) = draw_and_bake(dev, &spec, bake_targets);
        LeafPass { draw, bake }
    }
}

/// The leaf cards of `lod` on the GPU (none without clusters); `cells` atlas cells a side.
pub fn mesh(gpu: &Gpu, lod: &TreeLod, cells: u32) -> Option<Mesh> {
    if lod.clusters.is_empty() {
        return None;
    }
    let cells = cells.max(1);
    let uv_size = 1.0 / cells as f32;
    let mut verts = Vec::with_capacity(4 * lod.clusters.len());
    let mut indices: Vec<u32> = Vec::with_capacity(6 * lod.clusters.len());
    // Outer clusters first: whichever side the crown is seen from, its surface is then
    // drawn before the clusters it hides, which the depth test rejects before shading.
    let mut order: Vec<&_> = lod.clusters.iter().collect();
    order.sort_by(|a, b| b.exposure.total_cmp(&a.exposure));
    for c in order {
        let first = verts.len() as u32;
        let cell = c.atlas % (cells * cells);
        let uv_origin = [(cell % cells) as f32 * uv_size, (cell / cells) as f32 * uv_size];
        let (right, up) = c.axes();
        let side = |v: [f32; 3]| [v[0] * c.size, v[1] * c.size, v[2] * c.size];
        for corner in [[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]] {
            verts.push(LeafVertex {
                center: c.center,
                hang: c.hang,
                corner,
                right: side(right),
                up: side(up),
                exposure: c.exposure,
                phase: c.phase,
                joint: c.joint,
                uv_origin,
                uv_size,
            });
        }
        indices.extend_from_slice(&[first, first + 1, first + 2, first, first + 2, first + 3]);
    }
    Some(Mesh::new(gpu, "leaves", &verts, &indices))
}
