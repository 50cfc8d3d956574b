//! Ground: the terrain as a grid mesh, denser near the centre where the trees stand, and a
//! flat skirt around it out to the horizon;
//! grass and soil mixed by value noise, lit and fogged (`ground.wgsl`). Each vertex carries
//! how much sky it sees past the crowns above it ([`open_sky`]), so the forest floor is
//! darker than the clearing.

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
        crowns: &[[f32; 3]],
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
            strip: false,
        };
        GroundPass {
            pipeline: pipeline(&gpu.device, &spec),
            mesh: ground_mesh(gpu, terrain, extent, crowns),
        }
    }

    /// Draw (globals bound at group 0).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        self.mesh.draw(pass, 0..1);
    }
}

/// Share of the sky a crown of radius R hides from the ground below its centre; it falls
/// smoothly to nothing at 1.3 R.
const CROWN_OCCLUSION: f32 = 0.45;

/// Sky seen from ground point (x, y) past `crowns` (x, y, radius; looked up through `grid`):
/// the product over crowns of 1 − CROWN_OCCLUSION · s(d / 1.3 R), s falling from 1 at the
/// centre to 0 at the edge (smoothstep).
pub fn open_sky(x: f32, y: f32, crowns: &[[f32; 3]], grid: &CrownGrid) -> f32 {
    let mut open = 1.0;
    grid.near(x, y, |k| {
        let [cx, cy, r] = crowns[k];
        let reach = 1.3 * r.max(1e-3);
        let d = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt() / reach;
        if d < 1.0 {
            let s = 1.0 - d * d * (3.0 - 2.0 * d);
            open *= 1.0 - CROWN_OCCLUSION * s;
        }
    });
    open
}

/// Crowns binned on a square grid of cells as wide as the widest crown's reach.
#[derive(Debug)]
pub struct CrownGrid {
    cell: f32,
    origin: [f32; 2],
    side: usize,
    bins: Vec<Vec<u32>>,
}

impl CrownGrid {
    /// Bin `crowns` (x, y, radius).
    pub fn new(crowns: &[[f32; 3]]) -> CrownGrid {
        let cell = crowns.iter().map(|c| 1.3 * c[2]).fold(1.0f32, f32::max);
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for c in crowns {
            for i in 0..2 {
                lo[i] = lo[i].min(c[i]);
                hi[i] = hi[i].max(c[i]);
            }
        }
        if crowns.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let side = (((hi[0] - lo[0]).max(hi[1] - lo[1]) / cell) as usize + 1).min(4096);
        let cell = cell.max((hi[0] - lo[0]).max(hi[1] - lo[1]) / side as f32);
        let mut grid = CrownGrid { cell, origin: lo, side, bins: vec![Vec::new(); side * side] };
        for (k, c) in crowns.iter().enumerate() {
            if let Some(b) = grid.bin(c[0], c[1]) {
                grid.bins[b].push(k as u32);
            }
        }
        grid
    }

    fn index(&self, v: f32, axis: usize) -> isize {
        ((v - self.origin[axis]) / self.cell).floor() as isize
    }

    fn bin(&self, x: f32, y: f32) -> Option<usize> {
        let (i, j) = (self.index(x, 0), self.index(y, 1));
        let n = self.side as isize;
        (i >= 0 && j >= 0 && i < n && j < n).then(|| (j * n + i) as usize)
    }

    /// Call `f` with every crown binned in the cells next to (x, y).
    fn near(&self, x: f32, y: f32, mut f: impl FnMut(usize)) {
        let (i, j, n) = (self.index(x, 0), self.index(y, 1), self.side as isize);
        for b in (j - 1).max(0)..=(j + 1).min(n - 1) {
            for a in (i - 1).max(0)..=(i + 1).min(n - 1) {
                for &k in &self.bins[(b * n + a) as usize] {
                    f(k as usize);
                }
            }
        }
    }
}

fn ground_mesh(gpu: &Gpu, terrain: &Terrain, extent: f32, crowns: &[[f32; 3]]) -> Mesh {
    let n = CELLS;
    let grid = CrownGrid::new(crowns);
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
                open: open_sky(x, y, crowns, &grid),
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
            open: 1.0,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_under_crowns_sees_less_sky_than_the_clearing() {
        let crowns = [[0.0, 0.0, 4.0], [3.0, 0.0, 4.0], [40.0, 40.0, 2.0]];
        let grid = CrownGrid::new(&crowns);
        let open = |x, y| open_sky(x, y, &crowns, &grid);
        // In the clearing: the whole sky.
        assert_eq!(open(-20.0, 30.0), 1.0);
        // Under a lone crown's centre: CROWN_OCCLUSION of it hidden.
        assert!((open(40.0, 40.0) - (1.0 - CROWN_OCCLUSION)).abs() < 1e-6);
        // Darker towards the centre, open again past 1.3 R.
        assert!(open(40.0, 41.0) > open(40.0, 40.0) && open(40.0, 41.0) < 1.0);
        assert_eq!(open(40.0, 42.7), 1.0);
        // Where two crowns overlap each hides its share of what the other leaves.
        let (a, b) = (open_sky(1.5, 0.0, &crowns[..1], &CrownGrid::new(&crowns[..1])), {
            let one = [crowns[1]];
            open_sky(1.5, 0.0, &one, &CrownGrid::new(&one))
        });
        assert!((open(1.5, 0.0) - a * b).abs() < 1e-6 && open(1.5, 0.0) < a.min(b));
    }
}
