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
//! **Leaf clusters.** A joint carrying leaf area A gets `n = max(1, round(A / (8·a_leaf)))`
//! clusters (a_leaf the area of one leaf), spread along its segment on a golden-angle
//! spiral. Each cluster is one square billboard that shows several leaves (a cell of the
//! leaf atlas, see [`crate::texture`]); its side `s` is chosen so that
//! `coverage · s² = A / n`, with `coverage` the opaque fraction of its atlas cell — the
//! billboards show exactly the tree's one-sided leaf area.
//!
//! **LOD chain.** Level k aims at about `3^-k` of level 0's triangles: coarser cylinders
//! (sides halved per level, at least 3), the thinnest stems dropped first (with everything
//! they carry; the threshold radius is found by bisection so the branch triangles meet
//! their share), their clusters re-hung on the nearest kept ancestor joint (they keep their
//! place in the crown, so the crown keeps its volume), and runs of `3^k` neighbouring
//! clusters (in joint order, so neighbours along the branches) merged into one, placed at
//! their area-weighted centre and enlarged so the merged billboard shows their summed area.
//! The skeleton is shared: joint indices are valid at every level.

use std::f32::consts::{PI, TAU};

use crate::generate::Tree;
use crate::skeleton::{NO_PARENT, Skeleton, SkeletonError};
use crate::species::Species;
use crate::texture::{Image, LeafAtlas, bark, leaf_atlas, unit};
use crate::v3::{V3, add, cross, dot, norm, scale, sub};

/// Ring sides per stem level at LOD 0 (trunk, branches, sub-branches, twigs).
pub const SIDES: [u32; 4] = [14, 8, 5, 4];
/// Leaves shown by one leaf-cluster billboard at LOD 0.
pub const LEAVES_PER_CLUSTER: f32 = 8.0;
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

/// One leaf-cluster billboard.
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

fn topology(sk: &Skeleton) -> Topology {
    let js = sk.joints();
    let n = js.len();
    let mut level = vec![0u32; n];
    let mut next = vec![NO_PARENT; n];
    let mut stem_start = vec![0u32; n];
    for (i, j) in js.iter().enumerate() {
        if j.parent != NO_PARENT {
            let p = j.parent as usize;
            level[i] = if j.continues { level[p] } else { (level[p] + 1).min(3) };
            if j.continues {
                // The last continuing child is the stem itself; earlier ones are split clones.
                next[p] = i as u32;
            }
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

/// Ring sides of a stem of `level` at LOD `lod`.
pub fn sides(level: u32, lod: usize) -> u32 {
    (SIDES[level.min(3) as usize] >> lod).max(3)
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
}

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
                (self.ring(j.origin, j.axis, refv, j.radius, 0.0, weights, n), refv)
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
    }
    .build()
}

/// Triangles of the branch mesh at `lod` keeping the stems whose first radius is at least
/// `r_min` (and their ancestors' stems).
fn kept_joints(sk: &Skeleton, topo: &Topology, r_min: f32, kept: &mut [bool]) {
    let js = sk.joints();
    for (i, j) in js.iter().enumerate() {
        let start = topo.stem_start[i] as usize;
        let own = i == 0 || js[start].radius >= r_min;
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

/// Leaf clusters of the full-detail tree.
fn leaf_clusters(
    sk: &Skeleton,
    species: &Species,
    coverage: &[f32],
    seed: u64,
) -> Vec<LeafCluster> {
    let leaf_size = species.leaf_scale / species.leaf_quality.max(1e-3).sqrt();
    let one_leaf = (leaf_size * leaf_size * species.leaf_scale_x * PI / 4.0).max(1e-8);
    let golden = PI * (3.0 - 5f32.sqrt());
    let mut out = Vec::new();
    let mut turn = 0.0f32;
    for (i, j) in sk.joints().iter().enumerate() {
        if j.leaf_area <= 0.0 {
            continue;
        }
        let n = ((j.leaf_area / (LEAVES_PER_CLUSTER * one_leaf)).round() as usize).max(1);
        let area = j.leaf_area / n as f32;
        let [fx, fy, _] = j.frame();
        for k in 0..n {
            let h = out.len() as u64;
            let atlas = (unit(seed, 4 * h) * coverage.len() as f32) as u32 % coverage.len() as u32;
            let size = (area / coverage[atlas as usize]).sqrt();
            turn += golden;
            let t = (k as f32 + 0.5) / n as f32;
            let hang = add(j.origin, scale(j.axis, t * j.length));
            // Outward from the branch, drooping a little under the leaves' weight.
            let out_dir = add(scale(fx, turn.cos()), scale(fy, turn.sin()));
            let out_dir = norm(add(out_dir, [0.0, 0.0, -0.3]));
            let center = add(hang, scale(out_dir, j.radius + 0.5 * size));
            out.push(LeafCluster {
                joint: i as u32,
                hang,
                center,
                size,
                roll: TAU * unit(seed, 4 * h + 1),
                atlas,
                phase: TAU * unit(seed, 4 * h + 2),
                leaf_area: area,
            });
        }
    }
    out
}

/// Merge runs of `m` consecutive clusters (already re-hung and in joint order).
fn merge_clusters(clusters: &[LeafCluster], m: usize, coverage: &[f32]) -> Vec<LeafCluster> {
    clusters
        .chunks(m.max(1))
        .map(|run| {
            let area: f32 = run.iter().map(|c| c.leaf_area).sum();
            let w = |f: &dyn Fn(&LeafCluster) -> V3| {
                run.iter()
                    .fold([0.0; 3], |acc, c| add(acc, scale(f(c), c.leaf_area / area.max(1e-20))))
            };
            let center = w(&|c| c.center);
            // Hang on the joint of the member nearest the merged centre.
            let lead = run
                .iter()
                .min_by(|a, b| {
                    let da = sub(a.center, center);
                    let db = sub(b.center, center);
                    dot(da, da).total_cmp(&dot(db, db))
                })
                .unwrap_or(&run[0]);
            // Keep the lead's offset from its branch: it points out of the crown, and the
            // renderer shades and swings the cluster by it. (Averaged offsets of clusters
            // around a branch cancel: merged cards would face random ways and render dark.)
            let hang = sub(center, sub(lead.center, lead.hang));
            LeafCluster {
                hang,
                center,
                size: (area / coverage[lead.atlas as usize]).sqrt(),
                leaf_area: area,
                ..*lead
            }
        })
        .collect()
}

/// The chain of `levels` LODs of `tree`. `coverage[k]` is the opaque fraction of leaf-atlas
/// cell k ([`crate::texture::LeafAtlas::coverage`]); `seed` drives cluster placement.
pub fn lod_chain(
    tree: &Tree,
    species: &Species,
    coverage: &[f32],
    seed: u64,
    levels: usize,
) -> Vec<TreeLod> {
    let all: Vec<usize> = (0..levels.max(1)).collect();
    lod_levels(tree, species, coverage, seed, &all)
}

/// The given LOD `levels` of `tree` only. Each is built from the skeleton directly, so
/// level k is the same whether or not the others are built.
pub fn lod_levels(
    tree: &Tree,
    species: &Species,
    coverage: &[f32],
    seed: u64,
    levels: &[usize],
) -> Vec<TreeLod> {
    let sk = &tree.skeleton;
    let topo = topology(sk);
    let n = sk.len();
    let coverage: Vec<f32> = if coverage.is_empty() {
        vec![1.0]
    } else {
        coverage.iter().map(|c| c.clamp(0.05, 1.0)).collect()
    };
    let base_clusters = leaf_clusters(sk, species, &coverage, seed);
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
            r_min = radii.get(lo).copied().unwrap_or(f32::INFINITY);
            kept_joints(sk, &topo, r_min, &mut kept);
        }
        let branches = branch_mesh(sk, &topo, lod, &kept, (species.lobes, species.lobe_depth));
        // Re-hang clusters of dropped joints on the nearest kept ancestor, then merge.
        let mut rehung: Vec<LeafCluster> = base_clusters
            .iter()
            .map(|c| {
                let mut j = c.joint;
                while !kept[j as usize] {
                    j = sk.joints()[j as usize].parent;
                }
                LeafCluster { joint: j, ..*c }
            })
            .collect();
        rehung.sort_by_key(|c| c.joint);
        let m = LOD_RATIO.powi(lod as i32).round() as usize;
        let clusters = if lod == 0 { rehung } else { merge_clusters(&rehung, m, &coverage) };
        out.push(TreeLod { level: lod, min_radius: r_min, branches, clusters });
    }
    out
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
        let lods = lod_chain(&tree, self, &leaves.coverage, seed, levels);
        Ok(TreeModel { tree, lods, bark: bark(seed, BARK_SIZE), leaves })
    }
}
