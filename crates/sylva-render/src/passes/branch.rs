//! Branches: the LOD meshes of generalized cylinders, skinned in the vertex shader from the
//! palette storage buffer (up to four joints per vertex), bark-textured (`branch.wgsl`).
//! A second pipeline (`fs_bake`) writes albedo and normals for the impostor atlas.

use sylva_tree::mesh::TreeLod;

use crate::gpu::Gpu;
use crate::layout::{BRANCH_ATTRIBUTES, BranchVertex, instance_layout, vertex_layout};
use crate::shared::{Mesh, PipelineSpec, draw_and_bake};

/// The branch pass: a pipeline for the frame and one for the impostor bake.
#[derive(Debug)]
pub struct BranchPass {
    /// Lit, fogged, dithered for cross-fades.
    pub draw: wgpu::RenderPipeline,
    /// Albedo and normal into the impostor atlas (two targets, no MSAA).
    pub bake: wgpu::RenderPipeline,
}

impl BranchPass {
    /// Pipelines; `layout` holds the globals and a species' textures.
    pub fn new(
        dev: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        format: wgpu::TextureFormat,
        samples: u32,
        bake_targets: &[wgpu::TextureFormat],
    ) -> BranchPass {
        let buffers =
            [Some(vertex_layout::<BranchVertex>(&BRANCH_ATTRIBUTES)), Some(instance_layout())];
        let spec = PipelineSpec {
            shader: "branch.wgsl",
            fragment: "fs_main",
            layout,
            buffers: &buffers,
            depth: true,
            cull: Some(wgpu::Face::Back),
            samples,
            targets: &[format],
            shadow: false,
            strip: false,
            coverage: false,
        };
        let (draw, bake) = draw_and_bake(dev, &spec, bake_targets);
        BranchPass { draw, bake }
    }
}

/// The branch mesh of `lod` on the GPU (none when it has no triangles).
pub fn mesh(gpu: &Gpu, lod: &TreeLod) -> Option<Mesh> {
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
    Some(Mesh::new(gpu, "branches", &verts, &b.indices))
}
