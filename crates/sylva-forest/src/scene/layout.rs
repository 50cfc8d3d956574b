//! Where the trees stand: the terrain's seeded hills, and trees placed on it by Poisson-disk
//! sampling with a random yaw and scale each.

use super::*;

/// Gentle terrain: a sum of three seeded sinusoidal hill fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terrain {
    /// Height amplitude, m.
    pub amplitude: f32,
    /// Wavelength, m.
    pub wavelength: f32,
    phases: [[f32; 3]; 3],
}

impl Terrain {
    /// The terrain of `spec`.
    pub fn new(spec: &SceneSpec) -> Terrain {
        let mut rng = Rng::new(spec.seed ^ 0x7e44_a1b0);
        let mut phases = [[0.0; 3]; 3];
        for p in &mut phases {
            *p = [rng.unit() * TAU, rng.unit() * TAU, rng.unit() * PI];
        }
        Terrain { amplitude: spec.terrain_amplitude, wavelength: spec.terrain_wavelength, phases }
    }

    /// Ground height at (x, y), m.
    pub fn height(&self, x: f32, y: f32) -> f32 {
        let k = std::f32::consts::TAU / self.wavelength;
        let mut h = 0.0;
        for (i, p) in self.phases.iter().enumerate() {
            let f = k * (1.0 + 0.7 * i as f32);
            let (s, c) = p[2].sin_cos();
            let u = f * (x * c + y * s);
            let v = f * (-x * s + y * c);
            h += (u + p[0]).sin() * (v + p[1]).cos() / (1.0 + i as f32);
        }
        self.amplitude * h / 1.83
    }

    /// Unit normal at (x, y) (central differences).
    pub fn normal(&self, x: f32, y: f32) -> [f32; 3] {
        let e = 0.5;
        let dx = (self.height(x + e, y) - self.height(x - e, y)) / (2.0 * e);
        let dy = (self.height(x, y + e) - self.height(x, y - e)) / (2.0 * e);
        let n = (1.0 + dx * dx + dy * dy).sqrt();
        [-dx / n, -dy / n, 1.0 / n]
    }
}

/// One tree of the layout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Trunk base, world m (on the terrain).
    pub position: [f32; 3],
    /// Rotation about z, rad.
    pub yaw: f32,
    /// Uniform scale.
    pub scale: f32,
    /// Index into the scene's species list.
    pub species: u32,
}

/// Bridson's Poisson-disk sampling in the square [−side/2, side/2]², minimum distance `r`.
///
/// The background grid's cells are r/√2 wide, so each holds at most one point (the last one
/// placed in it, should rounding ever put two there), and it holds that point's coordinates
/// (NaN where empty): a candidate's test reads the 5 × 5 cells around it in place, its own
/// cell first (the likeliest to reject it).
fn poisson_disk(rng: &mut Rng, side: f32, r: f32) -> Vec<[f32; 2]> {
    let cell = r / std::f32::consts::SQRT_2;
    let n = (side / cell).ceil() as usize;
    let mut grid = vec![[f32::NAN; 2]; n * n];
    let idx = |p: [f32; 2]| {
        let gx = (((p[0] + side / 2.0) / cell) as usize).min(n - 1);
        let gy = (((p[1] + side / 2.0) / cell) as usize).min(n - 1);
        (gx, gy)
    };
    // Whether `o` (a cell's content) is a point nearer `p` than r (false where empty: NaN
    // compares false).
    let near = |o: [f32; 2], p: [f32; 2]| (o[0] - p[0]).powi(2) + (o[1] - p[1]).powi(2) < r * r;
    let mut pts: Vec<[f32; 2]> = vec![[0.0, 0.0]];
    let (gx, gy) = idx(pts[0]);
    grid[gy * n + gx] = pts[0];
    let mut active = vec![0usize];
    while !active.is_empty() {
        let k = (rng.unit() * active.len() as f32) as usize % active.len();
        let base = pts[active[k]];
        let mut found = false;
        for _ in 0..30 {
            let a = rng.unit() * std::f32::consts::TAU;
            let d = r * (1.0 + rng.unit());
            let p = [base[0] + d * a.cos(), base[1] + d * a.sin()];
            if p[0].abs() >= side / 2.0 || p[1].abs() >= side / 2.0 {
                continue;
            }
            let (gx, gy) = idx(p);
            if near(grid[gy * n + gx], p) {
                continue;
            }
            let (x0, x1) = (gx.saturating_sub(2), (gx + 3).min(n));
            let clear = (gy.saturating_sub(2)..(gy + 3).min(n))
                .all(|y| grid[y * n + x0..y * n + x1].iter().all(|&o| !near(o, p)));
            if clear {
                grid[gy * n + gx] = p;
                active.push(pts.len());
                pts.push(p);
                found = true;
                break;
            }
        }
        if !found {
            active.swap_remove(k);
        }
    }
    pts
}

/// The layout of `spec`: `trees` placements, the ones nearest the centre of a Poisson-disk
/// sample, each with a species drawn by weight, a yaw and a scale.
pub fn layout(spec: &SceneSpec, terrain: &Terrain) -> Vec<Placement> {
    let mut rng = Rng::new(spec.seed ^ 0x0001_a700_u64);
    let mut side = spec.side();
    let mut pts = poisson_disk(&mut rng, side, spec.spacing);
    while pts.len() < spec.trees {
        side *= 1.3;
        pts = poisson_disk(&mut rng, side, spec.spacing);
    }
    pts.sort_by(|a, b| (a[0] * a[0] + a[1] * a[1]).total_cmp(&(b[0] * b[0] + b[1] * b[1])));
    pts.truncate(spec.trees);
    let total: f32 = spec.species.iter().map(|s| s.weight).sum();
    pts.iter()
        .map(|&[x, y]| {
            let mut pick = rng.unit() * total;
            let mut species = spec.species.len() - 1;
            for (i, s) in spec.species.iter().enumerate() {
                if pick < s.weight {
                    species = i;
                    break;
                }
                pick -= s.weight;
            }
            Placement {
                position: [x, y, terrain.height(x, y)],
                yaw: rng.unit() * std::f32::consts::TAU,
                scale: 1.0 + spec.scale_variation * (2.0 * rng.unit() - 1.0),
                species: species as u32,
            }
        })
        .collect()
}
