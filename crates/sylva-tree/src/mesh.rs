//! The renderable parts of the hybrid representation (paper §4.1) and the geometry LOD chain
//! (paper §4.3): branch meshes (generalized cylinders skinned to the skeleton) and leaf
//! clusters (billboards hung on joints), at several levels of detail.
//!
//! **Branch mesh.** Every stem is a chain of rings, one at each joint and one at the stem's
//! tip, joined by quad strips. A ring where two segments of one stem meet is weighted half
//! to each of the two joints, so a bend at the joint bends the surface smoothly; a stem's
//! first ring belongs to its first joint only. Radial resolution falls with the stem level
//! ([`SIDES`]); rings are parallel-transported along the stem so the surface never twists.
//! The trunk's rings carry WP95's lobes: radius × (1 + LobeDepth · sin(Lobes · θ)).
//! Bark UVs: u around the stem (0 … 1, seam duplicated), v the distance along the stem
//! divided by the stem's base circumference, so bark texels stay square.
//!
//! **Leaf clusters.** A leaf cluster is one square card showing a cell of the leaf atlas
//! (see [`crate::texture`]): a twig with its leaves drawn at their true size, so the card's
//! side is the atlas span (3.5 leaf lengths; 15 needles for a spray) and it shows
//! `coverage · span²` of leaf area. Walking the joints in order, each joint's leaf area is
//! owed to cards; a card is hung when at least half its area is owed (so the tree's total
//! leaf area is kept within half a card), spread along the joint's segment on a golden-angle
//! spiral. A tree that would need more than [`MAX_CLUSTERS`] cards gets larger cards
//! (leaves shown larger than true) rather than more. Cards are oriented in 3D: facing out of
//! the crown (the gradient of the crown's ellipsoid, half-blended with the direction out of
//! the branch) and tilted towards the sky by a random amount; the renderer turns them part
//! way towards the viewer so none is seen edge-on. Each card carries its exposure: 1 at the
//! crown's surface, 0 at its centre, which darkens the inner foliage (ambient occlusion).
//!
//! **LOD chain.** Level k's branches aim at about `3^-k` of level 0's branch triangles:
//! coarser cylinders (sides halved per level, but at least [`MIN_SIDES`], so the trunk
//! and the main branches stay round), the thinnest stems dropped first (with everything
//! they carry; the threshold radius is found by bisection so the branch triangles meet
//! their share). Level 1 keeps level 0's leaf cards, card for card and each on its own
//! joint (a card whose twig is dropped still hangs from the twig's joint and moves with
//! it), on a third of its wood. From level 2 on the cards are thinned stochastically
//! (Cook et al. 2007): a level keeps a subset of level 0's cards, in
//! place, and grows them so the crown shows its whole leaf area; it grows them no more
//! than its dropped stems' diameter ([`leaf_growth`]), so the leaves never make a level
//! coarser than its wood. The cards of dropped stems are re-hung on the nearest kept
//! ancestor joint. The wood is most of a tree's triangles (85–96 % at level 0 but for
//! the Douglas fir's 64 %), so level 1 costs 24–58 % of level 0, and its picture of the
//! foliage — which pixels the leaves cover, and how they move — is level 0's. The
//! skeleton is shared: joint indices are valid at every level.

use std::f32::consts::{PI, TAU};

use sylva_core::v3::{V3, add, cross, dot, length, norm, scale, sub};

use crate::generate::Tree;
use crate::skeleton::{NO_PARENT, Skeleton, SkeletonError};
use crate::species::Species;
use crate::texture::{Image, LeafAtlas, bark, leaf_atlas, unit};

/// Ring sides per stem level at LOD 0 (trunk, branches, sub-branches, twigs).
pub const SIDES: [u32; 4] = [14, 8, 5, 4];
/// Most leaf cards one tree gets at LOD 0; beyond it cards grow instead.
pub const MAX_CLUSTERS: usize = 150_000;
/// Triangle ratio between consecutive LOD levels.
pub const LOD_RATIO: f32 = 3.0;
/// Number of levels in the default LOD chain.
pub const LOD_LEVELS: usize = 6;

/// A skinned triangle mesh of a tree's branches, structure of arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BranchMesh {
    /// Rest positions, tree space, m.
    pub positions: Vec<[f32; 3]>,
    /// Unit normals, tree space.
    pub normals: Vec<[f32; 3]>,
    /// Bark texture coordinates.
    pub uvs: Vec<[f32; 2]>,
    /// Up to four joint indices per vertex (unused slots repeat the first with weight 0).
    pub joints: Vec<[u32; 4]>,
    /// Joint weights per vertex, summing to 1.
    pub weights: Vec<[f32; 4]>,
    /// Triangles, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

impl BranchMesh {
    /// Number of triangles.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

/// One leaf-cluster card. Laid out as C lays out its fields (the C interface hands cards
/// out in place).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeafCluster {
    /// Joint the cluster hangs from.
    pub joint: u32,
    /// Hanging point on the branch (rest pose, tree space), m: the cluster swings about it.
    pub hang: [f32; 3],
    /// Billboard centre (rest pose, tree space), m.
    pub center: [f32; 3],
    /// Side of the square billboard, m.
    pub size: f32,
    /// Roll of the billboard in its plane, rad.
    pub roll: f32,
    /// Cell of the leaf atlas.
    pub atlas: u32,
    /// Flutter phase offset, rad (so neighbouring clusters do not swing in step).
    pub phase: f32,
    /// One-sided leaf area this billboard shows, m².
    pub leaf_area: f32,
    /// Unit normal of the card, tree space: out of the crown, tilted towards the sky.
    pub normal: [f32; 3],
    /// 1 at the crown's surface … 0 at its centre (ambient occlusion of inner foliage).
    pub exposure: f32,
}

impl LeafCluster {
    /// Unit axes (right, up) of the card in its plane, tree space: up is the direction out
    /// of the branch (the atlas twig grows from the cell's lower edge) projected onto the
    /// card, turned by `roll`.
    pub fn axes(&self) -> (V3, V3) {
        let n = self.normal;
        let off = sub(self.center, self.hang);
        let mut up = sub(off, scale(n, dot(off, n)));
        if dot(up, up) < 1e-12 {
            let z = [0.0, 0.0, 1.0];
            up = sub(z, scale(n, dot(z, n)));
            if dot(up, up) < 1e-12 {
                up = [1.0, 0.0, 0.0];
            }
        }
        let up = norm(up);
        let right = cross(up, n);
        let (s, c) = self.roll.sin_cos();
        (add(scale(right, c), scale(up, s)), add(scale(up, c), scale(right, -s)))
    }
}

/// One level of detail of a tree.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeLod {
    /// Level, 0 = full detail.
    pub level: usize,
    /// Radius below which stems were dropped, m (0 at level 0).
    pub min_radius: f32,
    /// Branch geometry.
    pub branches: BranchMesh,
    /// Leaf billboards.
    pub clusters: Vec<LeafCluster>,
}

impl TreeLod {
    /// Triangles drawn: the branch mesh plus two per leaf billboard.
    pub fn triangles(&self) -> usize {
        self.branches.triangles() + 2 * self.clusters.len()
    }

    /// One-sided leaf area shown by the billboards, m².
    pub fn leaf_area(&self) -> f32 {
        self.clusters.iter().map(|c| c.leaf_area).sum()
    }
}

/// Per-joint facts the mesh builder needs.
struct Topology {
    /// Stem level of each joint (0 trunk).
    level: Vec<u32>,
    /// The next segment of the same stem, or NO_PARENT at a stem's tip.
    next: Vec<u32>,
    /// Whether this joint's base ring is its parent's tip ring (same stem, not a split clone).
    shares_parent_ring: Vec<bool>,
    /// First joint of the stem this joint belongs to (a split clone starts its own).
    stem_start: Vec<u32>,
}

/// Each joint's stem level (0 the trunk, at most 3): its parent's where it continues the
/// parent's stem, one more where it starts a stem of its own.
pub(crate) fn stem_levels(sk: &Skeleton) -> Vec<u32> {
    let js = sk.joints();
    let mut level = vec![0u32; js.len()];
    for (i, j) in js.iter().enumerate() {
        if j.parent != NO_PARENT {
            let p = j.parent as usize;
            level[i] = if j.continues { level[p] } else { (level[p] + 1).min(3) };
        }
    }
    level
}

fn topology(sk: &Skeleton) -> Topology {
    let js = sk.joints();
    let n = js.len();
    let level = stem_levels(sk);
    let mut next = vec![NO_PARENT; n];
    let mut stem_start = vec![0u32; n];
    for (i, j) in js.iter().enumerate() {
        // The last continuing child is the stem itself; earlier ones are split clones.
        if j.parent != NO_PARENT && j.continues {
            next[j.parent as usize] = i as u32;
        }
    }
    let mut shares = vec![false; n];
    for (i, j) in js.iter().enumerate() {
        shares[i] = j.parent != NO_PARENT && next[j.parent as usize] == i as u32;
        stem_start[i] = if shares[i] { stem_start[j.parent as usize] } else { i as u32 };
    }
    Topology { level, next, shares_parent_ring: shares, stem_start }
}

/// `r` made perpendicular to the unit `axis`; `fallback` when `r` is (nearly) parallel.
fn perpendicular(r: V3, axis: V3, fallback: V3) -> V3 {
    let p = sub(r, scale(axis, dot(r, axis)));
    if dot(p, p) > 1e-8 { norm(p) } else { fallback }
}

/// Fewest ring sides per stem level at any LOD: the trunk and the main branches, the
/// widest stems, keep their roundness, for their ring error (the radius times
/// `1 − cos(π / sides)`) is most of a coarse level's geometric error otherwise (at 3
/// sides, half the radius: 15 cm on a 60 cm trunk) and costs few triangles.
pub const MIN_SIDES: [u32; 4] = [8, 5, 3, 3];

/// Ring sides of a stem of `level` at LOD `lod`: [`SIDES`] halved per level, at least
/// [`MIN_SIDES`].
pub fn sides(level: u32, lod: usize) -> u32 {
    let level = level.min(3) as usize;
    (SIDES[level] >> lod).max(MIN_SIDES[level])
}

struct MeshBuilder<'a> {
    sk: &'a Skeleton,
    topo: &'a Topology,
    lod: usize,
    kept: &'a [bool],
    mesh: BranchMesh,
    /// Per joint: first vertex of its tip ring and the ring's reference direction.
    tip_ring: Vec<u32>,
    ring_ref: Vec<V3>,
    /// Per joint: v coordinate at its base.
    v_base: Vec<f32>,
    /// WP95 Lobes and LobeDepth of the trunk's cross-section.
    lobes: (u32, f32),
    /// Lobes of the ring being built (the trunk's, or none).
    ring_lobes: (u32, f32),
    /// WP95 Flare of the trunk base.
    flare: f32,
}

/// WP95's trunk flare: the radius factor at relative height z ∈ [0, 1] of the trunk,
/// `1 + Flare · (100^y − 1) / 100` with `y = max(0, 1 − 8 z)`.
pub fn flare_factor(flare: f32, z: f32) -> f32 {
    let y = (1.0 - 8.0 * z).max(0.0);
    1.0 + flare * (100f32.powf(y) - 1.0) / 100.0
}

/// Heights of the extra rings at the trunk's base, as fractions of the trunk's length: the
/// flare widens over the first eighth, most of it in the first 2 %.
const FLARE_RINGS: [f32; 4] = [0.0, 0.012, 0.03, 0.065];

impl MeshBuilder<'_> {
    /// Append a ring and return its first vertex.
    fn ring(
        &mut self,
        center: V3,
        axis: V3,
        refv: V3,
        radius: f32,
        v: f32,
        jw: [(u32, f32); 2],
        n: u32,
    ) -> u32 {
        let first = self.mesh.positions.len() as u32;
        let any = if axis[2].abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
        let refv = perpendicular(refv, axis, norm(cross(axis, any)));
        let side = cross(axis, refv);
        let (j0, w0) = jw[0];
        let (j1, w1) = jw[1];
        for k in 0..=n {
            let a = TAU * k as f32 / n as f32;
            let (s, c) = a.sin_cos();
            let dir = add(scale(refv, c), scale(side, s));
            let (lobes, depth) = self.ring_lobes;
            let r = radius * (1.0 + depth * (lobes as f32 * a).sin());
            self.mesh.positions.push(add(center, scale(dir, r)));
            self.mesh.normals.push(dir);
            self.mesh.uvs.push([k as f32 / n as f32, v]);
            self.mesh.joints.push([j0, j1, j0, j0]);
            self.mesh.weights.push([w0, w1, 0.0, 0.0]);
        }
        first
    }

    /// The trunk's first segment from the ground up to its last flare ring (WP95's Flare,
    /// which the one radius per joint cannot show): rings at [`FLARE_RINGS`] of the trunk's
    /// length, skinned to joint `i`. Returns the last ring, which the segment's strip to its
    /// tip starts from.
    fn flared_base(&mut self, i: usize, refv: V3, n: u32) -> u32 {
        let js = self.sk.joints();
        let j = &js[i];
        // The trunk's length: its chain of level-0 segments.
        let (mut length, mut k) = (0.0, i as u32);
        while k != NO_PARENT && self.topo.level[k as usize] == 0 {
            length += js[k as usize].length;
            k = self.topo.next[k as usize];
        }
        let length = length.max(1e-6);
        // The joint's radius is the stem's at the segment's middle, flare included there.
        let core = j.radius / flare_factor(self.flare, 0.5 * j.length / length);
        let circumference = TAU * j.radius.max(1e-4);
        let mut last = u32::MAX;
        for &z in FLARE_RINGS.iter().filter(|&&z| z * length < 0.8 * j.length) {
            let h = z * length;
            let ring = self.ring(
                add(j.origin, scale(j.axis, h)),
                j.axis,
                refv,
                core * flare_factor(self.flare, z),
                h / circumference,
                [(i as u32, 1.0), (i as u32, 0.0)],
                n,
            );
            if last != u32::MAX {
                self.strip(last, ring, n);
            }
            last = ring;
        }
        last
    }

    fn strip(&mut self, a: u32, b: u32, n: u32) {
        for k in 0..n {
            let (a0, a1, b0, b1) = (a + k, a + k + 1, b + k, b + k + 1);
            self.mesh.indices.extend_from_slice(&[a0, a1, b1, a0, b1, b0]);
        }
    }

    fn build(mut self) -> BranchMesh {
        let js = self.sk.joints();
        for (i, j) in js.iter().enumerate() {
            if !self.kept[i] {
                continue;
            }
            let level = self.topo.level[i];
            let n = sides(level, self.lod);
            self.ring_lobes = if level == 0 { self.lobes } else { (0, 0.0) };
            let start = self.topo.stem_start[i] as usize;
            let circumference = TAU * js[start].radius.max(1e-4);
            let shared = self.topo.shares_parent_ring[i]
                && sides(self.topo.level[j.parent as usize], self.lod) == n;
            let (base, refv) = if shared {
                let p = j.parent as usize;
                self.v_base[i] = self.v_base[p] + js[p].length / circumference;
                (self.tip_ring[p], self.ring_ref[p])
            } else {
                let fallback = j.frame()[0];
                let refv = if j.parent == NO_PARENT {
                    fallback
                } else {
                    perpendicular(self.ring_ref[j.parent as usize], j.axis, fallback)
                };
                let weights = if j.continues && j.parent != NO_PARENT {
                    [(i as u32, 0.5), (j.parent, 0.5)]
                } else {
                    [(i as u32, 1.0), (i as u32, 0.0)]
                };
                self.v_base[i] = 0.0;
                if j.parent == NO_PARENT && level == 0 && self.flare > 0.0 {
                    (self.flared_base(i, refv, n), refv)
                } else {
                    (self.ring(j.origin, j.axis, refv, j.radius, 0.0, weights, n), refv)
                }
            };
            // Tip ring: shared with the next segment of the stem when it is kept.
            let next = self.topo.next[i];
            let v_tip = self.v_base[i] + j.length / circumference;
            let tip = if next != NO_PARENT && self.kept[next as usize] {
                let nj = &js[next as usize];
                let axis = norm(add(j.axis, nj.axis));
                let refv_tip = perpendicular(refv, axis, j.frame()[0]);
                self.ring_ref[i] = refv_tip;
                let r = 0.5 * (j.radius + nj.radius);
                self.ring(j.tip(), axis, refv_tip, r, v_tip, [(i as u32, 0.5), (next, 0.5)], n)
            } else {
                self.ring_ref[i] = refv;
                // A stem's last ring narrows to a quarter: WP95's taper ends near a point.
                self.ring(
                    j.tip(),
                    j.axis,
                    refv,
                    0.25 * j.radius,
                    v_tip,
                    [(i as u32, 1.0), (i as u32, 0.0)],
                    n,
                )
            };
            self.tip_ring[i] = tip;
            self.strip(base, tip, n);
        }
        self.mesh
    }
}

/// Build the branch mesh of `sk` at LOD `lod`, with the joints marked in `kept`.
fn branch_mesh(
    sk: &Skeleton,
    topo: &Topology,
    lod: usize,
    kept: &[bool],
    lobes: (u32, f32),
    flare: f32,
) -> BranchMesh {
    let n = sk.len();
    MeshBuilder {
        sk,
        topo,
        lod,
        kept,
        mesh: BranchMesh::default(),
        tip_ring: vec![0; n],
        ring_ref: vec![[1.0, 0.0, 0.0]; n],
        v_base: vec![0.0; n],
        lobes,
        ring_lobes: (0, 0.0),
        flare,
    }
    .build()
}

/// Triangles of the branch mesh at `lod` keeping the stems whose first radius is at least
/// `r_min` (and their ancestors' stems).
fn kept_joints(sk: &Skeleton, topo: &Topology, r_min: f32, kept: &mut [bool]) {
    let js = sk.joints();
    for (i, j) in js.iter().enumerate() {
        let start = topo.stem_start[i] as usize;
        let own = start == 0 || js[start].radius >= r_min;
        kept[i] = own && (j.parent == NO_PARENT || kept[j.parent as usize]);
    }
}

fn branch_triangles(topo: &Topology, lod: usize, kept: &[bool]) -> usize {
    kept.iter()
        .zip(&topo.level)
        .filter(|(k, _)| **k)
        .map(|(_, &l)| 2 * sides(l, lod) as usize)
        .sum()
}

/// The crown as an ellipsoid: area-weighted centre of the leaf-bearing segments and
/// horizontal and vertical radii (those of a uniformly filled ellipsoid with the same
/// second moments).
struct Crown {
    centre: V3,
    radius_h: f32,
    radius_v: f32,
}

impl Crown {
    fn of(sk: &Skeleton) -> Crown {
        let leafy = || sk.joints().iter().filter(|j| j.leaf_area > 0.0);
        let total: f32 = leafy().map(|j| j.leaf_area).sum::<f32>().max(1e-12);
        let mid = |j: &crate::skeleton::Joint| add(j.origin, scale(j.axis, 0.5 * j.length));
        let centre = leafy().fold([0.0; 3], |acc, j| add(acc, scale(mid(j), j.leaf_area / total)));
        let (mut h2, mut v2) = (0.0f32, 0.0f32);
        for j in leafy() {
            let d = sub(mid(j), centre);
            h2 += j.leaf_area / total * (d[0] * d[0] + d[1] * d[1]);
            v2 += j.leaf_area / total * d[2] * d[2];
        }
        Crown {
            centre,
            radius_h: (2.5 * h2).sqrt().max(0.05),
            radius_v: (5.0 * v2).sqrt().max(0.05),
        }
    }

    /// Ellipsoidal radius of `p`: 0 at the centre, 1 on the surface.
    fn rho(&self, p: V3) -> f32 {
        let d = sub(p, self.centre);
        ((d[0] * d[0] + d[1] * d[1]) / (self.radius_h * self.radius_h)
            + d[2] * d[2] / (self.radius_v * self.radius_v))
            .sqrt()
    }

    /// Outward normal of the ellipsoid through `p`.
    fn outward(&self, p: V3) -> V3 {
        let d = sub(p, self.centre);
        let g = [
            d[0] / (self.radius_h * self.radius_h),
            d[1] / (self.radius_h * self.radius_h),
            d[2] / (self.radius_v * self.radius_v),
        ];
        if dot(g, g) < 1e-12 { [0.0, 0.0, 1.0] } else { norm(g) }
    }
}

/// Leaf clusters of the full-detail tree.
fn leaf_clusters(sk: &Skeleton, coverage: &[f32], span: f32, seed: u64) -> Vec<LeafCluster> {
    let golden = PI * (3.0 - 5f32.sqrt());
    let crown = Crown::of(sk);
    let mean_cov = coverage.iter().sum::<f32>() / coverage.len() as f32;
    let total: f32 = sk.joints().iter().map(|j| j.leaf_area).sum();
    // Cards larger than true when the tree would need too many.
    let span = span.max((total / (MAX_CLUSTERS as f32 * mean_cov)).sqrt());
    let cell_of =
        |h: u64| (unit(seed, 4 * h) * coverage.len() as f32) as u32 % coverage.len() as u32;
    let mut out: Vec<LeafCluster> = Vec::new();
    let mut turn = 0.0f32;
    let mut owed = 0.0f32;
    for (i, j) in sk.joints().iter().enumerate() {
        if j.leaf_area <= 0.0 {
            continue;
        }
        owed += j.leaf_area;
        let first = out.len();
        loop {
            let atlas = cell_of(out.len() as u64);
            let area = coverage[atlas as usize] * span * span;
            if owed < 0.5 * area {
                break;
            }
            owed -= area;
            out.push(LeafCluster {
                joint: i as u32,
                hang: [0.0; 3],
                center: [0.0; 3],
                size: span,
                roll: 0.0,
                atlas,
                phase: 0.0,
                leaf_area: area,
                normal: [0.0, 0.0, 1.0],
                exposure: 1.0,
            });
        }
        let n = out.len() - first;
        let [fx, fy, _] = j.frame();
        for (k, c) in out[first..].iter_mut().enumerate() {
            let h = (first + k) as u64;
            turn += golden;
            let t = (k as f32 + 0.5) / n as f32;
            let hang = add(j.origin, scale(j.axis, t * j.length));
            // Outward from the branch, drooping a little under the leaves' weight.
            let out_dir = add(scale(fx, turn.cos()), scale(fy, turn.sin()));
            let out_dir = norm(add(out_dir, [0.0, 0.0, -0.3]));
            let center = add(hang, scale(out_dir, j.radius + 0.45 * c.size));
            // Facing out of the crown and out of the branch, tilted up by a random amount.
            let face = norm(add(crown.outward(center), out_dir));
            let tilt = 0.2 + 0.9 * unit(seed, 4 * h + 3);
            let normal = norm(add(face, [0.0, 0.0, tilt]));
            *c = LeafCluster {
                hang,
                center,
                roll: 0.8 * (unit(seed, 4 * h + 1) - 0.5),
                phase: TAU * unit(seed, 4 * h + 2),
                normal,
                exposure: (crown.rho(center)).clamp(0.0, 1.0),
                ..*c
            };
        }
    }
    out
}

/// How far a grown leaf card's corners move out per metre of growth in side: half its
/// diagonal, and its centre pushed out from the branch by 0.45 of the growth.
pub const CARD_GROWTH_REACH: f32 = std::f32::consts::FRAC_1_SQRT_2 + 0.45;

/// The most a mesh level may grow its leaf cards (each `side` across), as a factor on
/// their side, when its wood lies up to `wood_error` from full detail (its dropped stems'
/// diameter, `2 · min_radius`): the kept cards' corners then move out by at most that
/// error ([`CARD_GROWTH_REACH`], the growth of `thin_clusters`), so the leaves never
/// make a level coarser than its wood. The level keeps about `1 / growth²` of the cards.
pub fn leaf_growth(wood_error: f32, side: f32) -> f32 {
    let allowed = wood_error / (CARD_GROWTH_REACH * side);
    if allowed.is_nan() || allowed <= 0.0 {
        return 1.0;
    }
    (1.0 + allowed).min(1e3)
}

/// The stratified key of level 0's card `i` (in joint order): the fractional part of
/// `i / φ`. A level keeps the cards of the smallest keys, so a coarser level's cards are a
/// subset of a finer one's, and neighbours along the branches are thinned evenly (by the
/// three-distance theorem the gaps between kept cards take at most three lengths).
pub fn thinning_key(i: usize) -> f32 {
    const INV_PHI: f64 = 0.618_033_988_749_894_8;
    ((i as f64 * INV_PHI).fract()) as f32
}

/// Stochastic simplification of the leaves (Cook, Halstead, Planck & Ryu 2007,
/// "Stochastic simplification of aggregate detail"): of `clusters` (level 0's, in joint
/// order) keep the fewest, in the order of their [`thinning_key`], that show at least
/// `1 / max_growth²` of the leaf area `A`, and grow each in side by the one factor
/// `s = √(A / A_kept) ≤ max_growth` so the level shows the whole leaf area again; each
/// card's centre moves out from its hanging point with its larger half so it still hangs
/// from its branch. Every kept card stays where it was: the crown's outline and the
/// cards' texture and motion are level 0's, only sparser. A larger `max_growth` keeps a
/// subset of a smaller one's cards.
fn thin_clusters(clusters: &[LeafCluster], max_growth: f32) -> Vec<LeafCluster> {
    let total: f32 = clusters.iter().map(|c| c.leaf_area).sum();
    let mut order: Vec<usize> = (0..clusters.len()).collect();
    order.sort_by(|&a, &b| thinning_key(a).total_cmp(&thinning_key(b)));
    let need = total / (max_growth * max_growth).max(1.0);
    let mut shown = 0.0f32;
    let mut count = 0;
    for &i in &order {
        if shown >= need && count > 0 {
            break;
        }
        shown += clusters[i].leaf_area;
        count += 1;
    }
    let mut chosen = order[..count].to_vec();
    chosen.sort_unstable();
    let mut kept: Vec<LeafCluster> = chosen.iter().map(|&i| clusters[i]).collect();
    if shown <= 0.0 {
        return kept;
    }
    let s = (total / shown).sqrt();
    for c in &mut kept {
        let off = sub(c.center, c.hang);
        let reach = length(off);
        let grown = c.size * s;
        if reach > 0.0 {
            c.center = add(c.hang, scale(off, (reach + 0.45 * (grown - c.size)) / reach));
        }
        c.size = grown;
        c.leaf_area *= s * s;
    }
    kept
}

/// The chain of `levels` LODs of `tree`, its leaf cards showing cells of `atlas` (their
/// coverage and span); `seed` drives cluster placement.
pub fn lod_chain(
    tree: &Tree,
    species: &Species,
    atlas: &LeafAtlas,
    seed: u64,
    levels: usize,
) -> Vec<TreeLod> {
    let all: Vec<usize> = (0..levels.max(1)).collect();
    lod_levels(tree, species, atlas, seed, &all)
}

/// The given LOD `levels` of `tree` only. Each is built from the skeleton directly, so
/// level k is the same whether or not the others are built.
pub fn lod_levels(
    tree: &Tree,
    species: &Species,
    atlas: &LeafAtlas,
    seed: u64,
    levels: &[usize],
) -> Vec<TreeLod> {
    let coverage = &atlas.coverage;
    let span = atlas.span.max(1e-4);
    let sk = &tree.skeleton;
    let topo = topology(sk);
    let n = sk.len();
    let coverage: Vec<f32> = if coverage.is_empty() {
        vec![1.0]
    } else {
        coverage.iter().map(|c| c.clamp(0.05, 1.0)).collect()
    };
    // In joint order, as levels 0 and 1 show them.
    let mut base_clusters = leaf_clusters(sk, &coverage, span, seed);
    base_clusters.sort_by_key(|c| c.joint);
    lift_above_ground(&mut base_clusters);
    // Level 0's cards all have one side (the atlas span, or larger for a tree of very
    // many leaves).
    let span_used = base_clusters.first().map_or(span, |c| c.size);
    let all = vec![true; n];
    let base_branch_tris = branch_triangles(&topo, 0, &all);
    // Stem start radii, sorted, for the bisection on the drop threshold.
    let mut radii: Vec<f32> = (1..n)
        .filter(|&i| topo.stem_start[i] as usize == i)
        .map(|i| sk.joints()[i].radius)
        .collect();
    radii.sort_by(f32::total_cmp);
    radii.dedup();
    let mut out = Vec::with_capacity(levels.len());
    let mut kept = vec![true; n];
    for &lod in levels {
        let target = base_branch_tris as f32 / LOD_RATIO.powi(lod as i32);
        let mut r_min = 0.0;
        kept_joints(sk, &topo, 0.0, &mut kept);
        if lod > 0 && (branch_triangles(&topo, lod, &kept) as f32) > target {
            // Smallest threshold index whose kept triangles meet the target.
            let (mut lo, mut hi) = (0usize, radii.len());
            while lo < hi {
                let mid = (lo + hi) / 2;
                kept_joints(sk, &topo, radii[mid], &mut kept);
                if branch_triangles(&topo, lod, &kept) as f32 <= target {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            // Past the thickest branch: the trunk alone (which every level keeps).
            r_min = radii.get(lo).copied().unwrap_or_else(|| {
                radii.last().map_or(f32::INFINITY, |r| r * (1.0 + f32::EPSILON).max(1.0 + 1e-6))
            });
            kept_joints(sk, &topo, r_min, &mut kept);
        }
        let branches =
            branch_mesh(sk, &topo, lod, &kept, (species.lobes, species.lobe_depth), species.flare);
        let clusters = if lod <= 1 {
            // Levels 0 and 1 show every card on its own joint (see the module
            // documentation): a card of a twig level 1 does not draw still moves with it.
            base_clusters.clone()
        } else {
            // Thin the cards (in level 0's joint order), then re-hang those of dropped
            // joints on the nearest kept ancestor: they keep their place in the crown.
            let growth = leaf_growth(2.0 * r_min, span_used);
            let mut thinned = thin_clusters(&base_clusters, growth);
            for c in &mut thinned {
                let mut j = c.joint;
                while !kept[j as usize] {
                    j = sk.joints()[j as usize].parent;
                }
                c.joint = j;
            }
            thinned.sort_by_key(|c| c.joint);
            lift_above_ground(&mut thinned);
            thinned
        };
        out.push(TreeLod { level: lod, min_radius: r_min, branches, clusters });
    }
    out
}

/// Height a leaf card keeps above the ground at its lowest, m.
pub const CARD_CLEARANCE: f32 = 0.02;

/// Raise every card whose square could reach below the ground, however it is turned (the
/// renderer turns cards part way towards the viewer): its centre at least half its
/// diagonal plus [`CARD_CLEARANCE`] up. The willow's and the oak's lowest cards reached
/// 0.16 m into the ground.
fn lift_above_ground(clusters: &mut [LeafCluster]) {
    for c in clusters {
        let lowest = c.center[2] - std::f32::consts::FRAC_1_SQRT_2 * c.size;
        if lowest < CARD_CLEARANCE {
            c.center[2] += CARD_CLEARANCE - lowest;
        }
    }
}

/// Everything the renderer and the exporter need of one tree: skeleton, LOD chain and
/// textures.
#[derive(Debug, Clone)]
pub struct TreeModel {
    /// Skeleton and figures.
    pub tree: Tree,
    /// Level-of-detail chain, level 0 first.
    pub lods: Vec<TreeLod>,
    /// Bark texture.
    pub bark: Image,
    /// Leaf-cluster atlas.
    pub leaves: LeafAtlas,
}

/// Bark texture side, texels.
pub const BARK_SIZE: u32 = 256;
/// Leaf atlas side, texels.
pub const ATLAS_SIZE: u32 = 512;

impl Species {
    /// Generate the tree for `seed` with its `levels`-level LOD chain and its textures.
    pub fn model(&self, seed: u64, levels: usize) -> Result<TreeModel, SkeletonError> {
        let tree = self.generate(seed)?;
        let leaves = leaf_atlas(self, seed, ATLAS_SIZE);
        let lods = lod_chain(&tree, self, &leaves, seed, levels);
        Ok(TreeModel { tree, lods, bark: bark(self, seed, BARK_SIZE), leaves })
    }
}
