//! Ground: the terrain as a grid mesh, denser near the centre where the trees stand, and a
//! flat skirt around it out to the horizon;
//! grass and soil mixed by value noise, lit and fogged (`ground.wgsl`).

use sylva_forest::Terrain;

use crate::gpu::Gpu;
use crate::layout::{GROUND_ATTRIBUTES, GroundVertex, vertex_layout};
use crate::shared::{Mesh, PipelineSpec, pipeline};

/// The ground pass.
#[derive(Debug)]
pub struct GroundPass {
    pipeline: wgpu::RenderPipeline,
    mesh: Mesh,
}

/// Grid cells per side of the ground mesh.
const CELLS: u32 = 192;
/// The skirt around the grid reaches this many times its half side.
const HORIZON: f32 = 8.0;

impl GroundPass {
    /// Pipeline and mesh of `terrain` reaching `extent` m from the origin.
    pub fn new(
        gpu: &Gpu,
        layout: &wgpu::PipelineLayout,
        format: wgpu::TextureFormat,
        samples: u32,
        terrain: &Terrain,
        extent: f32,
    ) -> GroundPass {
        let spec = PipelineSpec {
            shader: "ground.wgsl",
            fragment: "fs_main",
            layout,
            buffers: &[Some(vertex_layout::<GroundVertex>(&GROUND_ATTRIBUTES))],
            depth: true,
            cull: Some(wgpu::Face::Back),
            samples,
            targets: &[format],
            shadow: false,
        };
        GroundPass {
            pipeline: pipeline(&gpu.device, &spec),
            mesh: ground_mesh(gpu, terrain, extent),
        }
    }

    /// Draw (globals bound at group 0).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        self.mesh.draw(pass, 0..1);
    }
}

fn ground_mesh(gpu: &Gpu, terrain: &Terrain, extent: f32) -> Mesh {
    let n = CELLS;
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
    let mut indices = Vec::with_capacity((n * n * 6 + 4 * n * 6) as usize);
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let b = a + n + 1;
            indices.extend_from_slice(&[a, a + 1, b + 1, a, b + 1, b]);
        }
    }
    // A skirt from the grid's edge out to HORIZON × extent at the edge's height: the ground
    // reaches the horizon, where the aerial perspective has turned it into the sky.
    let edge: Vec<u32> = (0..n)
        .chain((0..n).map(|j| j * (n + 1) + n))
        .chain((0..n).map(|i| n * (n + 1) + n - i))
        .chain((0..n).map(|j| (n - j) * (n + 1)))
        .collect();
    let first_far = verts.len() as u32;
    for &e in &edge {
        let p = verts[e as usize].position;
        verts.push(GroundVertex {
            position: [p[0] * HORIZON, p[1] * HORIZON, p[2]],
            normal: [0.0, 0.0, 1.0],
        });
    }
    let m = edge.len() as u32;
    for k in 0..m {
        let (a, b) = (edge[k as usize], edge[((k + 1) % m) as usize]);
        let (fa, fb) = (first_far + k, first_far + (k + 1) % m);
        indices.extend_from_slice(&[a, fa, fb, a, fb, b]);
    }
    Mesh::new(gpu, "ground", &verts, &indices)
}
