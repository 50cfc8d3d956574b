//! Ground: the terrain as a grid mesh, denser near the centre where the trees stand, and a
//! flat skirt around it out to the horizon;
//! grass and soil mixed by value noise, lit and fogged (`ground.wgsl`). Each vertex carries
//! how much sky it sees past the crowns above it ([`open_sky`]), so the forest floor is
//! darker than the clearing, and how much distant woodland is drawn on it ([`Woodland`]):
//! sunlit crowns at the scene's spacing, met along the view ray in the fragment shader so
//! that they stand up and hide one another, spheroids and the forest's darker species as
//! darker cones ([`Canopy`]), near crowns broken into leaf clumps, faded to their mean
//! colour where a crown is smaller than a few pixels or lost in the haze.

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
        woodland: Option<(&Woodland, Canopy)>,
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
            coverage: false,
        };
        GroundPass {
            pipeline: pipeline(&gpu.device, &spec),
            mesh: ground_mesh(gpu, terrain, extent, crowns, woodland),
        }
    }

    /// Draw (globals bound at group 0).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        self.mesh.draw(pass, 0..1);
    }
}

/// Woodland painted on the ground around a forest (`sylva_forest::Surround::Woodland`).
#[derive(Debug, Clone, PartialEq)]
pub struct Woodland {
    /// Distance from the forest's centre where it starts, m.
    pub start: f32,
    /// Width over which it thickens from nothing to full, m.
    pub ramp: f32,
    /// Spacing of its crowns, m.
    pub spacing: f32,
    /// Share of each species of the scene (in its species order) in the woodland's colour:
    /// the crowns take the mean albedo of the forest's own impostors, weighted by these.
    pub shares: Vec<f32>,
}

/// What a painted conifer (a cone, as ground.wgsl draws the darker crowns) shows of
/// itself in a canopy seen at a glancing angle, against a broadleaf's spheroid of the same
/// radius: its upper side is narrower. The shader gives the lighter crowns the albedo
/// that keeps the mean over what the crowns show (`CONE_SHOWN` in ground.wgsl, the same
/// value); set from the woodland's mean brightness in a low view over it, which this keeps
/// within about 3 % of the spheroids' (docs/decisions/0008-lighting-and-surround.md).
pub const CONE_SHOWN: f32 = 0.6;

/// The painted woodland's colours, from the forest's species: their mean albedo, and the
/// darker species' (`dark`: albedo and share of the crowns).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Canopy {
    /// Mean linear albedo of the crowns, species by their share of the forest.
    pub mean: [f32; 3],
    /// Linear albedo of the darker crowns, and their share (0: one colour).
    pub dark: [f32; 4],
}

impl Canopy {
    /// From each species' mean albedo and share of the forest. Species whose luminance is
    /// below 0.85 of the mean's are the darker crowns; none, or all, gives one colour.
    pub fn of(species: &[([f32; 3], f32)]) -> Canopy {
        let luma = |a: [f32; 3]| 0.2126 * a[0] + 0.7152 * a[1] + 0.0722 * a[2];
        let blend = |pick: &dyn Fn([f32; 3]) -> bool| {
            let (mut sum, mut share) = ([0.0f32; 3], 0.0f32);
            for &(a, s) in species.iter().filter(|(a, s)| *s > 0.0 && pick(*a)) {
                for k in 0..3 {
                    sum[k] += a[k] * s;
                }
                share += s;
            }
            (sum.map(|x| x / share.max(1e-9)), share)
        };
        let (mean, total) = blend(&|_| true);
        let (dark, dark_share) = blend(&|a| luma(a) < 0.85 * luma(mean));
        let share = dark_share / total.max(1e-9);
        if !(share > 0.0 && share < 0.999) {
            return Canopy { mean, dark: [0.0; 4] };
        }
        Canopy { mean, dark: [dark[0], dark[1], dark[2], share] }
    }
}

/// Mean linear albedo of the opaque texels (alpha ≥ ½) of an sRGB RGBA8 image; grey where
/// none is opaque.
pub fn mean_albedo(rgba: &[u8]) -> [f32; 3] {
    let lin = |v: u8| {
        let c = v as f32 / 255.0;
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    };
    let (mut sum, mut n) = ([0.0f64; 3], 0usize);
    for p in rgba.chunks_exact(4).filter(|p| p[3] >= 128) {
        for k in 0..3 {
            sum[k] += lin(p[k]) as f64;
        }
        n += 1;
    }
    if n == 0 {
        return [0.1; 3];
    }
    sum.map(|v| (v / n as f64) as f32)
}

/// Side of the clearings that break the woodland up, m (the scale of its value noise).
pub const CLEARING_SCALE: f32 = 900.0;

impl Woodland {
    /// Share of woodland at ground point (x, y): 0 out to [`Woodland::start`], rising
    /// smoothly to 1 over [`Woodland::ramp`], unbroken for half a [`CLEARING_SCALE`] beyond,
    /// and farther out lowered in clearings (low values of a seeded value noise on a
    /// [`CLEARING_SCALE`] grid; about a fifth of the area is open).
    pub fn share(&self, x: f32, y: f32) -> f32 {
        let r = (x * x + y * y).sqrt();
        let full = self.start + self.ramp.max(1e-3);
        let edge = smoothstep(self.start, full, r);
        let n = value_noise(x / CLEARING_SCALE, y / CLEARING_SCALE);
        let clearings = smoothstep(full, full + 0.5 * CLEARING_SCALE, r);
        edge * (1.0 - clearings * (1.0 - smoothstep(0.15, 0.3, n)))
    }
}

fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Smooth value noise in [0, 1]: a seeded hash of the integer lattice, interpolated with
/// smoothstep weights.
fn value_noise(x: f32, y: f32) -> f32 {
    let hash = |i: f32, j: f32| -> f32 {
        let h = sylva_core::rng::mix64(((i as i64 as u64) << 32) ^ (j as i64 as u32 as u64));
        (h >> 40) as f32 / (1u64 << 24) as f32
    };
    let (i, j) = (x.floor(), y.floor());
    let (u, v) = (smoothstep(0.0, 1.0, x - i), smoothstep(0.0, 1.0, y - j));
    let a = hash(i, j) + (hash(i + 1.0, j) - hash(i, j)) * u;
    let b = hash(i, j + 1.0) + (hash(i + 1.0, j + 1.0) - hash(i, j + 1.0)) * u;
    a + (b - a) * v
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

fn ground_mesh(
    gpu: &Gpu,
    terrain: &Terrain,
    extent: f32,
    crowns: &[[f32; 3]],
    woodland: Option<(&Woodland, Canopy)>,
) -> Mesh {
    let paint = |x: f32, y: f32| woodland.map_or(0.0, |(w, _)| w.share(x, y));
    let crown_spacing = woodland.map_or(1.0, |(w, _)| w.spacing);
    let canopy = woodland.map_or([0.0; 3], |(_, c)| c.mean);
    let canopy_dark = woodland.map_or([0.0; 4], |(_, c)| c.dark);
    let woodland_edge = woodland.map_or([0.0; 2], |(w, _)| [w.start, w.ramp]);
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
                woodland: paint(x, y),
                crown_spacing,
                canopy,
                woodland_edge,
                canopy_dark,
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
        let (x, y) = (p[0] * HORIZON, p[1] * HORIZON);
        verts.push(GroundVertex {
            position: [x, y, p[2]],
            normal: [0.0, 0.0, 1.0],
            open: 1.0,
            woodland: paint(x, y),
            crown_spacing,
            canopy,
            woodland_edge,
            canopy_dark,
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
    fn woodland_starts_past_its_meadow_and_leaves_clearings() {
        let w = Woodland { start: 1000.0, ramp: 70.0, spacing: 7.0, shares: vec![1.0] };
        // None on the meadow, whatever the direction.
        for k in 0..64 {
            let a = k as f32 / 64.0 * std::f32::consts::TAU;
            assert_eq!(w.share(999.0 * a.cos(), 999.0 * a.sin()), 0.0);
        }
        // Beyond the edge: mostly woodland, with some clearings, over a ring 3–9 km out.
        let (mut wood, mut open, mut n) = (0, 0, 0);
        for i in 0..200 {
            for j in 0..200 {
                let (x, y) = (-9000.0 + 90.0 * i as f32, -9000.0 + 90.0 * j as f32);
                let r = (x * x + y * y).sqrt();
                if !(3000.0..9000.0).contains(&r) {
                    continue;
                }
                let s = w.share(x, y);
                assert!((0.0..=1.0).contains(&s));
                n += 1;
                wood += (s > 0.99) as usize;
                open += (s < 0.01) as usize;
            }
        }
        let (wood, open) = (wood as f32 / n as f32, open as f32 / n as f32);
        assert!(wood > 0.5 && open > 0.03 && open < 0.35, "woodland {wood}, clearings {open}");
        // It thickens over the ramp, monotonically along a ray that misses the clearings.
        let ray = (0..64)
            .map(|k| k as f32 / 64.0 * std::f32::consts::TAU)
            .find(|a| w.share(2000.0 * a.cos(), 2000.0 * a.sin()) > 0.99)
            .expect("a direction with woodland at 2 km");
        let along: Vec<f32> = (0..=14)
            .map(|k| 995.0 + 5.0 * k as f32)
            .map(|r| w.share(r * ray.cos(), r * ray.sin()))
            .collect();
        assert!(along.windows(2).all(|p| p[1] >= p[0]), "{along:?}");
    }

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

    /// The woodland shows the forest's darker species as darker crowns in their share,
    /// the rest in the colour that keeps the mean of what the crowns show the species'
    /// share-weighted mean; a forest of one shade has one colour.
    #[test]
    fn the_woodland_shows_the_darker_species_in_their_share_and_keeps_the_mean() {
        // The shader's constant is this one.
        let src = crate::shader_source("ground.wgsl").expect("ground.wgsl");
        assert!(
            src.contains(&format!("const CONE_SHOWN: f32 = {CONE_SHOWN:?};")),
            "ground.wgsl's CONE_SHOWN differs from ground.rs's {CONE_SHOWN}"
        );
        let (fir, aspen, maple) = ([0.02, 0.05, 0.03], [0.10, 0.16, 0.05], [0.09, 0.14, 0.05]);
        let c = Canopy::of(&[(fir, 3.0), (aspen, 3.0), (maple, 2.0), (fir, 0.0)]);
        let mean: Vec<f32> =
            (0..3).map(|k| (3.0 * fir[k] + 3.0 * aspen[k] + 2.0 * maple[k]) / 8.0).collect();
        for k in 0..3 {
            assert!((c.mean[k] - mean[k]).abs() < 1e-6, "{:?} against {mean:?}", c.mean);
            assert!((c.dark[k] - fir[k]).abs() < 1e-6, "the fir alone is dark: {:?}", c.dark);
            // The lighter crowns as the shader takes them (the mean over what the crowns
            // show): darker than aspen and maple's mean, since the darker cones show less
            // of themselves than their share of the crowns.
            let shown = c.dark[3] * CONE_SHOWN;
            let light = (c.mean[k] - shown * c.dark[k]) / (1.0 - shown);
            let broadleaf = (3.0 * aspen[k] + 2.0 * maple[k]) / 5.0;
            assert!(light < broadleaf, "light {light} against the broadleaves' {broadleaf}");
        }
        assert!((c.dark[3] - 3.0 / 8.0).abs() < 1e-6, "share {}", c.dark[3]);
        // One species, or species of one shade: one colour.
        assert_eq!(Canopy::of(&[(fir, 1.0)]).dark, [0.0; 4]);
        assert_eq!(Canopy::of(&[(aspen, 1.0), (maple, 4.0)]).dark, [0.0; 4]);
        assert_eq!(Canopy::of(&[]).dark, [0.0; 4]);
    }
}
