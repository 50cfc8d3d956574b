//! Occlusion culling: trees hidden behind nearer trunks and crowns are not drawn.
//!
//! Each frame, the trees in view that cover enough of the image write what of them stops
//! the eye into a coarse buffer ([`DepthBuffer`], [`DEPTH_COLUMNS`] columns): per species
//! an [`Occluder`], a rectangle inside the bole (opaque) and one inside the crown's dense
//! core, turned to face the camera about the vertical (upright, or flat for views from
//! above). A crown core lets some light through: the rectangles go in from near to far,
//! and each pixel multiplies the light they let through until it falls to
//! [`HIDDEN_TRANSMISSION`]; from that depth on, the pixel is hidden. A tree whose bounding
//! box lies behind that depth at every pixel it may cover is hidden.
//!
//! Conservative in its geometry: a pixel takes a rectangle only where the rectangle covers
//! it whole, at the depth of the far side of the crown it stands in; a tree is hidden only
//! where its nearest corner lies behind every pixel its box's image touches. The light a
//! crown's rectangle lets through is measured once per species against its own leaves
//! ([`Occluder::of`]), the cards' alpha taken as their leaf area over their area, and
//! taken at the ninth decile of its lines of sight; wood inside the crown is not counted,
//! so the cores err transparent.

use rayon::prelude::*;
use sylva_core::v3::{cross, dot, norm, sub};
use sylva_tree::mesh::{LeafCluster, TreeModel};

use crate::camera::{Camera, Mat4};

/// Columns of the occlusion depth buffer (its rows follow the image's aspect).
pub const DEPTH_COLUMNS: u32 = 320;

/// A pixel is hidden from the depth at which the cores and boles in front of it let at
/// most this share of the light behind through: a tree behind would show at most this much.
pub const HIDDEN_TRANSMISSION: f32 = 0.05;

/// A crown core is the largest centred rectangle (in quarters of the crown's extent)
/// whose lines of sight, nine in ten of them, let at most this share of the light through.
pub const CORE_TRANSMISSION: f32 = 0.6;

/// A tree writes its occluder only where its rectangles' smallest side spans at least this
/// many pixels of the depth buffer (smaller ones cover few pixels whole).
const MIN_CORE_PIXELS: f32 = 1.0;

/// What of one species' tree surely stops the eye, unscaled tree space (trunk base at the
/// origin, z up). Rectangles: half extents, m; a zero half extent means none.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Occluder {
    /// The bole: a vertical rectangle on the trunk's axis from the ground to `trunk_top`,
    /// `trunk_half_width` either side, inside the wood wherever the trunk leans or tapers.
    pub trunk_half_width: f32,
    /// Height of the bole's rectangle, m.
    pub trunk_top: f32,
    /// Height of the crown core's centre over the trunk base, m.
    pub core_z: f32,
    /// The core's vertical rectangle, facing the camera: half width and half height.
    pub core_half_width: f32,
    /// See `core_half_width`.
    pub core_half_height: f32,
    /// The core's horizontal square at `core_z`, for views from above: half side.
    pub core_half_side: f32,
    /// Light the upright rectangle lets through, nine lines of sight in ten at most.
    pub upright_transmission: f32,
    /// Light the flat square lets through, nine lines of sight in ten at most.
    pub flat_transmission: f32,
    /// Farthest any leaf card reaches from the core's centre, m: the depth behind a core
    /// rectangle within which the leaves that stop the eye lie.
    pub reach: f32,
    /// The tree's bounds: the farthest anything reaches from the trunk's axis, and its
    /// lowest and highest points, m.
    pub bound_radius: f32,
    /// See `bound_radius`.
    pub bound_bottom: f32,
    /// See `bound_radius`.
    pub bound_top: f32,
}

/// The light a line of sight through `p` along unit `d` keeps after the leaf cards it
/// crosses, each taking its alpha (leaf area over card area). A card is tested only where
/// the line passes within its half diagonal of its centre.
fn card_transmission(clusters: &[Card], p: [f32; 3], d: [f32; 3]) -> f32 {
    let mut t = 1.0f32;
    for c in clusters {
        let off = sub(c.center, p);
        let along = dot(off, d);
        let miss = dot(off, off) - along * along;
        if miss > c.radius2 {
            continue;
        }
        let dn = dot(d, c.normal);
        if dn.abs() < 1e-6 {
            continue;
        }
        let s = dot(off, c.normal) / dn;
        let q: [f32; 3] = std::array::from_fn(|k| p[k] + d[k] * s - c.center[k]);
        if dot(q, c.right).abs() <= c.half && dot(q, c.up).abs() <= c.half {
            t *= 1.0 - c.alpha;
        }
    }
    t
}

/// A leaf card as the transmission test takes it.
struct Card {
    center: [f32; 3],
    normal: [f32; 3],
    right: [f32; 3],
    up: [f32; 3],
    half: f32,
    radius2: f32,
    alpha: f32,
}

impl Card {
    fn new(c: &LeafCluster) -> Card {
        let (right, up) = c.axes();
        let half = 0.5 * c.size;
        let alpha =
            if c.size > 0.0 { (c.leaf_area / (c.size * c.size)).clamp(0.0, 1.0) } else { 0.0 };
        Card {
            center: c.center,
            normal: c.normal,
            right,
            up,
            half,
            radius2: 2.0 * half * half,
            alpha,
        }
    }
}

/// Samples across a core rectangle, per side (odd: the centre is one).
const SAMPLES: usize = 9;
/// Azimuths the lines of sight come from.
const AZIMUTHS: usize = 8;

/// The largest centred rectangle, as a share `k` of the crown's extent (in steps of
/// 1 / (`SAMPLES` / 2)), whose lines of sight from `dirs` let at most
/// [`CORE_TRANSMISSION`] through, nine in ten of them; and the light they let through (that
/// ninth decile). `point(u, v, d)` gives the line's point for the rectangle's unit
/// coordinates and direction `d`. (0, 1): none.
fn largest_core(
    cards: &[Card],
    dirs: &[[f32; 3]],
    point: impl Fn(f32, f32, [f32; 3]) -> [f32; 3] + Sync,
) -> (f32, f32) {
    let half = (SAMPLES / 2) as i32;
    // Transmission on the grid, for every direction.
    let samples: Vec<(i32, i32, [f32; 3])> = (-half..=half)
        .flat_map(|i| (-half..=half).flat_map(move |j| dirs.iter().map(move |&d| (i, j, d))))
        .collect();
    let trans: Vec<(i32, f32)> = samples
        .par_iter()
        .map(|&(i, j, d)| {
            let (u, v) = (i as f32 / half as f32, j as f32 / half as f32);
            (i.abs().max(j.abs()), card_transmission(cards, point(u, v, d), d))
        })
        .collect();
    let mut best = (0.0, 1.0);
    for ring in 1..=half {
        let mut inside: Vec<f32> =
            trans.iter().filter(|(r, _)| *r <= ring).map(|(_, t)| *t).collect();
        inside.sort_by(f32::total_cmp);
        let p90 = inside[inside.len() * 9 / 10];
        if p90 > CORE_TRANSMISSION {
            break;
        }
        best = (ring as f32 / half as f32, p90);
    }
    best
}

impl Occluder {
    /// The occluder of a tree model: its bole from the skeleton, its crown core measured
    /// against the leaf cards of its full detail ([`CORE_TRANSMISSION`]; lines of sight from
    /// eight azimuths, 30° up, level and 30° down for the upright rectangle, straight down
    /// and 50° down for the flat one).
    pub fn of(model: &TreeModel) -> Occluder {
        let mut o = Occluder::default();
        let joints = model.tree.skeleton.joints();
        // The bole: follow the trunk from the root while its segments continue it.
        let mut best_area = 0.0;
        let mut width = f32::INFINITY;
        let mut j = 0usize;
        while let Some(joint) = joints.get(j) {
            let tip = joint.tip();
            let next = (j + 1..joints.len())
                .find(|&k| joints[k].parent == j as u32 && joints[k].continues);
            let r_end = next.map(|k| joints[k].radius).unwrap_or(0.0).min(joint.radius);
            let lateral = |p: [f32; 3]| (p[0] * p[0] + p[1] * p[1]).sqrt();
            width = width.min(joint.radius - lateral(joint.origin)).min(r_end - lateral(tip));
            if width <= 0.0 {
                break;
            }
            // The rectangle reaches no higher than the lowest leafy branch.
            let top = tip[2].min(model.tree.stats.crown_base.max(0.0));
            if 0.9 * width * top > best_area {
                best_area = 0.9 * width * top;
                (o.trunk_half_width, o.trunk_top) = (0.9 * width, top);
            }
            match next {
                Some(k) if tip[2] < model.tree.stats.crown_base => j = k,
                _ => break,
            }
        }
        // Bounds from the wood and the leaf cards.
        let clusters = model.lods.first().map(|l| &l.clusters[..]).unwrap_or(&[]);
        let (mut radius, mut bottom, mut top) = (0.0f32, 0.0f32, 0.0f32);
        for jt in joints {
            for p in [jt.origin, jt.tip()] {
                radius = radius.max((p[0] * p[0] + p[1] * p[1]).sqrt() + jt.radius);
                (bottom, top) = (bottom.min(p[2] - jt.radius), top.max(p[2] + jt.radius));
            }
        }
        for c in clusters {
            let h = 0.7072 * c.size;
            radius = radius.max((c.center[0] * c.center[0] + c.center[1] * c.center[1]).sqrt() + h);
            (bottom, top) = (bottom.min(c.center[2] - h), top.max(c.center[2] + h));
        }
        (o.bound_radius, o.bound_bottom, o.bound_top) = (radius, bottom, top);
        let total: f32 = clusters.iter().map(|c| c.leaf_area).sum();
        if clusters.is_empty() || total <= 0.0 {
            return o;
        }
        // The crown's extent: leaf-area-weighted centre height, the radius within which
        // 90 % of the cards hang, half the height span of the middle 80 % of them.
        o.core_z = clusters.iter().map(|c| c.center[2] * c.leaf_area).sum::<f32>() / total;
        let mut d: Vec<f32> = clusters
            .iter()
            .map(|c| (c.center[0] * c.center[0] + c.center[1] * c.center[1]).sqrt())
            .collect();
        d.sort_by(f32::total_cmp);
        let a = d[d.len() * 9 / 10];
        let mut z: Vec<f32> = clusters.iter().map(|c| c.center[2]).collect();
        z.sort_by(f32::total_cmp);
        let b = 0.5 * (z[z.len() * 9 / 10] - z[z.len() / 10]);
        let centre = [0.0, 0.0, o.core_z];
        o.reach = clusters
            .iter()
            .map(|c| {
                let e = sub(c.center, centre);
                dot(e, e).sqrt() + 0.7072 * c.size
            })
            .fold(0.0, f32::max);
        let cards: Vec<Card> = clusters.iter().map(Card::new).collect();
        let azimuth = |k: usize, down: f32| {
            let phi = k as f32 * std::f32::consts::TAU / AZIMUTHS as f32;
            let (s, c) = phi.sin_cos();
            let (sd, cd) = down.to_radians().sin_cos();
            [c * cd, s * cd, -sd]
        };
        // Upright: the rectangle faces each line of sight's horizontal direction.
        let upright: Vec<[f32; 3]> = (0..AZIMUTHS)
            .flat_map(|k| [azimuth(k, -30.0), azimuth(k, 0.0), azimuth(k, 30.0)])
            .collect();
        let (k_up, t_up) = largest_core(&cards, &upright, |u, v, d| {
            let side = norm([-d[1], d[0], 0.0]);
            [side[0] * u * a, side[1] * u * a, o.core_z + v * b]
        });
        let flat: Vec<[f32; 3]> = std::iter::once([0.0, 0.0, -1.0])
            .chain((0..AZIMUTHS).map(|k| azimuth(k, 50.0)))
            .collect();
        let (k_flat, t_flat) = largest_core(&cards, &flat, |u, v, _| [u * a, v * a, o.core_z]);
        (o.core_half_width, o.core_half_height) = (k_up * a, k_up * b);
        (o.core_half_side, o.upright_transmission, o.flat_transmission) =
            (k_flat * a, t_up, t_flat);
        o
    }

    /// The smallest side of its rectangles, m (0: none): a tree writes its occluder where
    /// this spans a pixel of the depth buffer, so only near trees write, whose bole spans a
    /// pixel too. Writing every tree whose largest rectangle spans one hides 129 trees
    /// instead of 126 on scene D's walk, for twice the frame-building time.
    pub fn smallest_side(&self) -> f32 {
        let mut side = f32::INFINITY;
        for (w, h) in [
            (self.trunk_half_width, 0.5 * self.trunk_top),
            (self.core_half_width, self.core_half_height),
            (self.core_half_side, self.core_half_side),
        ] {
            if w > 0.0 && h > 0.0 {
                side = side.min(2.0 * w.min(h));
            }
        }
        if side.is_finite() { side } else { 0.0 }
    }
}

/// A coarse depth buffer of occluders for one camera: per pixel the nearest distance
/// (along the view direction) behind which everything is hidden.
#[derive(Debug, Clone, Default)]
pub struct DepthBuffer {
    columns: u32,
    rows: u32,
    world_to_clip: Mat4,
    near: f32,
    /// Per pixel, row-major from the top: clip w (view depth, m) from which the pixel is
    /// hidden; infinite where it is not.
    depth: Vec<f32>,
    /// Per pixel: the light the rectangles written so far let through.
    light: Vec<f32>,
    /// Eye position, for turning rectangles to face it.
    eye: [f32; 3],
}

impl DepthBuffer {
    /// Clear for `camera` and an image of `aspect` = width / height, [`DEPTH_COLUMNS`]
    /// wide.
    pub fn reset(&mut self, camera: &Camera, aspect: f32) {
        self.columns = DEPTH_COLUMNS;
        self.rows = ((DEPTH_COLUMNS as f32 / aspect.max(1e-3)).round() as u32).clamp(1, 4096);
        self.world_to_clip = camera.view_projection(aspect);
        self.near = camera.near;
        self.eye = camera.eye;
        self.depth.clear();
        self.depth.resize((self.columns * self.rows) as usize, f32::INFINITY);
        self.light.clear();
        self.light.resize((self.columns * self.rows) as usize, 1.0);
    }

    /// Pixel position (x right, y down) and clip w of world point `p`.
    fn project(&self, p: [f32; 3]) -> [f32; 3] {
        let m = &self.world_to_clip;
        let c = |r: usize| m[0][r] * p[0] + m[1][r] * p[1] + m[2][r] * p[2] + m[3][r];
        let w = c(3);
        let (x, y) = (c(0) / w, c(1) / w);
        [(0.5 + 0.5 * x) * self.columns as f32, (0.5 - 0.5 * y) * self.rows as f32, w]
    }

    /// Write the convex quad `corners` (world, in order round it), which lets `light` of
    /// the light behind it through, at `depth` (clip w) into every pixel it covers whole. Quads
    /// go in from near to far (by `depth`): a pixel is hidden from the depth of the quad
    /// that brings its light to [`HIDDEN_TRANSMISSION`]. A quad reaching behind the near
    /// plane writes nothing.
    pub fn add_quad(&mut self, corners: [[f32; 3]; 4], light: f32, depth: f32) {
        let q = corners.map(|c| self.project(c));
        // NaN depths fail the comparison too.
        let in_front = |c: &[f32; 3]| c[2] > self.near && c[0].is_finite() && c[1].is_finite();
        if !q.iter().all(in_front) {
            return;
        }
        // Edges as a x + b y + c ≥ 0 inside, whichever way round the corners go.
        let area: f32 =
            (0..4).map(|i| q[i][0] * q[(i + 1) % 4][1] - q[(i + 1) % 4][0] * q[i][1]).sum();
        let s = if area >= 0.0 { 1.0 } else { -1.0 };
        let edges: [[f32; 3]; 4] = std::array::from_fn(|i| {
            let (p, n) = (q[i], q[(i + 1) % 4]);
            let (a, b) = (s * (p[1] - n[1]), s * (n[0] - p[0]));
            // Inside by half a pixel's extent along the edge's normal: the whole pixel.
            [a, b, -(a * p[0] + b * p[1]) - 0.5 * (a.abs() + b.abs())]
        });
        let lo = |k: usize, n: u32| {
            q.iter().map(|c| c[k]).fold(f32::INFINITY, f32::min).max(0.0).min(n as f32) as u32
        };
        let hi = |k: usize, n: u32| {
            q.iter().map(|c| c[k]).fold(f32::NEG_INFINITY, f32::max).ceil().max(0.0).min(n as f32)
                as u32
        };
        let (x0, x1, y0, y1) =
            (lo(0, self.columns), hi(0, self.columns), lo(1, self.rows), hi(1, self.rows));
        for y in y0..y1 {
            let py = y as f32 + 0.5;
            let row = (y * self.columns) as usize;
            for x in x0..x1 {
                let px = x as f32 + 0.5;
                let i = row + x as usize;
                if self.depth[i].is_infinite()
                    && edges.iter().all(|e| e[0] * px + e[1] * py + e[2] >= 0.0)
                {
                    self.light[i] *= light;
                    if self.light[i] <= HIDDEN_TRANSMISSION {
                        self.depth[i] = depth;
                    }
                }
            }
        }
    }

    /// The far side of the occluder `o` of a tree standing at `base`, scaled by `scale`:
    /// the depth (clip w) its rectangles are written at, for ordering them near to far.
    pub fn tree_depth(&self, o: &Occluder, base: [f32; 3], scale: f32) -> f32 {
        self.project([base[0], base[1], base[2] + o.core_z * scale])[2] + o.reach * scale
    }

    /// Write the occluder `o` of a tree standing at `base`, scaled by `scale`, at `depth`,
    /// its [`tree_depth`](Self::tree_depth) (after those of nearer trees). The crown writes
    /// its upright rectangle, or its flat square where the eye looks down on it from over
    /// 40°.
    pub fn add_tree(&mut self, o: &Occluder, base: [f32; 3], scale: f32, depth: f32) {
        let at = |dz: f32| [base[0], base[1], base[2] + dz * scale];
        let to_eye = sub(self.eye, base);
        let side = norm(cross([0.0, 0.0, 1.0], to_eye));
        if !side.iter().all(|v| v.is_finite()) || dot(side, side) < 0.5 {
            return;
        }
        let upright = |c: [f32; 3], hw: f32, z0: f32, z1: f32| {
            let (dx, dy) = (side[0] * hw, side[1] * hw);
            [
                [c[0] - dx, c[1] - dy, z0],
                [c[0] + dx, c[1] + dy, z0],
                [c[0] + dx, c[1] + dy, z1],
                [c[0] - dx, c[1] - dy, z1],
            ]
        };
        // Trunk and crown at the crown's far side: one depth keeps the tree's rectangles
        // in the order the trees go in.
        if o.trunk_half_width > 0.0 && o.trunk_top > 0.0 {
            let c = at(0.5 * o.trunk_top);
            let quad = upright(c, o.trunk_half_width * scale, base[2], at(o.trunk_top)[2]);
            self.add_quad(quad, 0.0, depth);
        }
        let c = at(o.core_z);
        let e = sub(self.eye, c);
        let looks_down = e[2] > 0.0 && e[2] * e[2] > 0.7041 * (e[0] * e[0] + e[1] * e[1]);
        if looks_down && o.core_half_side > 0.0 {
            let h = o.core_half_side * scale;
            let quad = [
                [c[0] - h, c[1] - h, c[2]],
                [c[0] + h, c[1] - h, c[2]],
                [c[0] + h, c[1] + h, c[2]],
                [c[0] - h, c[1] + h, c[2]],
            ];
            self.add_quad(quad, o.flat_transmission, depth);
        } else if !looks_down && o.core_half_width > 0.0 && o.core_half_height > 0.0 {
            let hh = o.core_half_height * scale;
            let quad = upright(c, o.core_half_width * scale, c[2] - hh, c[2] + hh);
            self.add_quad(quad, o.upright_transmission, depth);
        }
    }

    /// Whether a rectangle whose smallest side is `side` m, at view distance `w` m, spans
    /// enough of the buffer to be worth writing. `cot` is 1 / tan(fov / 2).
    pub fn worth_writing(&self, side: f32, w: f32, cot: f32) -> bool {
        w > self.near && side * cot * 0.5 * self.rows as f32 >= MIN_CORE_PIXELS * w
    }

    /// Whether the axis-aligned box `lo`…`hi` (world) is hidden at every pixel its image may
    /// touch. A box reaching behind the near plane, or out of the image, is not hidden
    /// there.
    pub fn hides_box(&self, lo: [f32; 3], hi: [f32; 3]) -> bool {
        let (mut x0, mut x1, mut y0, mut y1) =
            (f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY);
        let mut nearest = f32::INFINITY;
        for k in 0..8 {
            let p = [
                if k & 1 == 0 { lo[0] } else { hi[0] },
                if k & 2 == 0 { lo[1] } else { hi[1] },
                if k & 4 == 0 { lo[2] } else { hi[2] },
            ];
            let q = self.project(p);
            if q[2].is_nan() || q[2] <= self.near {
                return false;
            }
            (x0, x1, y0, y1) = (x0.min(q[0]), x1.max(q[0]), y0.min(q[1]), y1.max(q[1]));
            nearest = nearest.min(q[2]);
        }
        if !(x0.is_finite() && x1.is_finite() && y0.is_finite() && y1.is_finite()) {
            return false;
        }
        // Pixels the box's image touches, clamped to the buffer: out of the image nothing
        // is drawn, so only the part in it must be hidden.
        let clamp = |v: f32, n: u32| v.max(0.0).min(n as f32);
        let (x0, x1) =
            (clamp(x0.floor(), self.columns) as u32, clamp(x1.ceil(), self.columns) as u32);
        let (y0, y1) = (clamp(y0.floor(), self.rows) as u32, clamp(y1.ceil(), self.rows) as u32);
        if x0 >= x1 || y0 >= y1 {
            return false;
        }
        for y in y0..y1 {
            let row = &self.depth[(y * self.columns) as usize..][x0 as usize..x1 as usize];
            if row.iter().any(|&d| d >= nearest) {
                return false;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: [0.0, 0.0, 2.0],
            target: [100.0, 0.0, 2.0],
            fov_deg: 60.0,
            near: 0.5,
            far: 2000.0,
        }
    }

    fn wall(buffer: &mut DepthBuffer, x: f32) {
        // A wall of rectangles 2 m wide, from y = −20 … 20 and 0 … 10 m up.
        for k in 0..20 {
            let y = -20.0 + 2.0 * k as f32;
            buffer.add_quad(
                [[x, y, 0.0], [x, y + 2.0, 0.0], [x, y + 2.0, 10.0], [x, y, 10.0]],
                0.0,
                x + 1.0,
            );
        }
    }

    fn tree_box(x: f32) -> ([f32; 3], [f32; 3]) {
        ([x - 2.0, -2.0, 0.0], [x + 2.0, 2.0, 12.0])
    }

    #[test]
    fn a_box_behind_a_wall_is_hidden_and_one_in_front_of_it_or_without_it_is_not() {
        let mut b = DepthBuffer::default();
        b.reset(&camera(), 4.0 / 3.0);
        let (lo, hi) = tree_box(60.0);
        assert!(!b.hides_box(lo, hi), "nothing written hides nothing");
        wall(&mut b, 30.0);
        assert!(b.hides_box(lo, hi), "a box behind a wall covering its image is hidden");
        let (lo, hi) = tree_box(20.0);
        assert!(!b.hides_box(lo, hi), "a box in front of the wall is not");
        let (lo, hi) = tree_box(30.5);
        assert!(!b.hides_box(lo, hi), "a box reaching in front of the wall's far side is not");
        // A box wider than the wall: its side shows past the wall's end.
        assert!(!b.hides_box([58.0, -40.0, 0.0], [62.0, -10.0, 12.0]));
        // Taller than the wall (10 m high, 30 m away, eye at 2 m): its top shows above.
        assert!(!b.hides_box([58.0, -2.0, 0.0], [62.0, 2.0, 40.0]));
    }

    #[test]
    fn a_pixel_takes_an_occluder_only_where_covered_whole() {
        let mut b = DepthBuffer::default();
        b.reset(&camera(), 4.0 / 3.0);
        // A post 0.05 m wide 30 m away spans a fraction of a pixel: nothing written, so a
        // box behind it shows.
        b.add_quad(
            [[30.0, -0.025, 0.0], [30.0, 0.025, 0.0], [30.0, 0.025, 20.0], [30.0, -0.025, 20.0]],
            0.0,
            31.0,
        );
        assert!(b.depth.iter().all(|d| d.is_infinite()));
        let (lo, hi) = ([60.0, -0.01, 0.0], [60.02, 0.01, 12.0]);
        assert!(!b.hides_box(lo, hi));
    }

    #[test]
    fn a_quad_behind_the_eye_writes_nothing_and_a_box_around_the_eye_is_never_hidden() {
        let mut b = DepthBuffer::default();
        b.reset(&camera(), 4.0 / 3.0);
        b.add_quad(
            [[-5.0, -5.0, 0.0], [-5.0, 5.0, 0.0], [-5.0, 5.0, 9.0], [-5.0, -5.0, 9.0]],
            0.0,
            1.0,
        );
        assert!(b.depth.iter().all(|d| d.is_infinite()));
        wall(&mut b, 30.0);
        assert!(!b.hides_box([-1.0, -1.0, 0.0], [1.0, 1.0, 3.0]));
    }
}
