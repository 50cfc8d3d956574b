//! glTF 2.0 binary export (`.glb`): the branch mesh skinned to the skeleton, the leaf
//! clusters as an alpha-masked primitive, both textures embedded as PNG.
//!
//! Layout of the file:
//! - one node per exported joint, parents first, each with its rest frame (translation and
//!   rotation relative to its parent; the frame's z runs along the segment) — the joint
//!   hierarchy an animator poses — under a root node that turns Sylva's +Z up into glTF's
//!   +Y up (a rotation of −90° about x), so the tree stands upright in every client;
//! - one skin over those nodes, with inverse bind matrices (the inverse of each joint's
//!   rest world transform);
//! - per exported LOD, one mesh of two primitives (bark: `TEXCOORD_0`, `NORMAL`, `JOINTS_0`,
//!   `WEIGHTS_0`; leaves: one double-sided quad per cluster, `alphaMode: MASK`, weighted to
//!   its hanging joint) on a root node with the skin; each LOD is its own scene (scene 0 is
//!   the first exported level) with its own joints.
//!
//! glTF stores joint indices as unsigned 16-bit numbers, so at most 65 535 joints are
//! exported: beyond `max_joints`, joints are folded into their nearest exported ancestor;
//! half the budget goes to the heaviest (carried mass), then to the twigs that hang, with
//! their paths, so a weeping willow's curtains keep joints to sway on (84 % of the exported
//! twig tips of its default 1 024-joint export point down, as 77 % of all its tips do). Leaf cards, which the renderer turns part way towards
//! the viewer, are exported as their fixed oriented quads (facing out of the crown).

mod animation;
mod buffer;
mod forest;
mod schema;
mod skin;

use sylva_core::v3::{V3, cross, dot, norm, scale, sub};

use crate::mesh::{LeafCluster, TreeModel};
use crate::skeleton::{NO_PARENT, Skeleton};

pub use animation::flutter_displacements;
use animation::*;
pub use buffer::leaf_quad;
use buffer::*;
pub use forest::{ForestTree, forest_to_glb};
use schema::*;

// OpenGL enumerants that glTF 2.0 uses by number (glTF 2.0 specification, §5).
pub(super) const ARRAY_BUFFER: u32 = 34_962;
pub(super) const ELEMENT_ARRAY_BUFFER: u32 = 34_963;
pub(super) const UNSIGNED_SHORT: u32 = 5_123;
pub(super) const UNSIGNED_INT: u32 = 5_125;
pub(super) const FLOAT: u32 = 5_126;
pub(super) const LINEAR: u32 = 9_729;
pub(super) const LINEAR_MIPMAP_LINEAR: u32 = 9_987;
pub(super) const REPEAT: u32 = 10_497;
pub(super) const CLAMP_TO_EDGE: u32 = 33_071;

/// Rotation (x, y, z, w) of −90° about x: Sylva's +Z up becomes glTF's +Y up (and Sylva's +Y,
/// north, becomes glTF's −Z).
pub(super) const Z_UP_TO_Y_UP: [f32; 4] =
    [-std::f32::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f32::consts::FRAC_1_SQRT_2];

/// Most joints glTF's 16-bit `JOINTS_0` can index.
pub const MAX_GLTF_JOINTS: usize = 65_535;

/// Export options.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfOptions {
    /// LOD levels to export (each its own scene), in order. Empty: all.
    pub lods: Vec<usize>,
    /// Most joints to export (1 … 65 535).
    pub max_joints: usize,
    /// Name of the tree (the root node's name).
    pub name: String,
    /// A sway clip to export as a glTF animation of the joint nodes (every exported LOD's).
    pub animation: Option<JointAnimation>,
}

impl Default for GltfOptions {
    fn default() -> Self {
        GltfOptions {
            lods: vec![0],
            max_joints: MAX_GLTF_JOINTS,
            name: "tree".into(),
            animation: None,
        }
    }
}

/// A recorded motion of the skeleton, exported as one glTF animation: a rotation channel per
/// exported joint, linearly interpolated (glTF's slerp).
///
/// Each sample gives, for the joints in `joints`, the rotation part of the joint's palette
/// (rest → animated, tree space, row-major 3×3) — what the sway simulation computes. A joint
/// turns about its own origin, which its parent carries, so rotations alone reproduce the
/// palettes: the node's animated local rotation is `F_pᵀ · R_pᵀ · R_j · F_j` (F: rest frames,
/// R: palette rotations, p: the parent), its translation stays the rest one.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointAnimation {
    /// Name of the animation.
    pub name: String,
    /// Sample times, s, increasing.
    pub times: Vec<f32>,
    /// Skeleton joints the samples cover; exported joints not listed do not move.
    pub joints: Vec<usize>,
    /// Per sample, per listed joint: its palette's rotation, row-major 3×3.
    pub rotations: Vec<Vec<[f32; 9]>>,
    /// Keyframe reduction, m: no point of the tree, played back, is farther than this from
    /// where the simulation put it at any sample time. A joint's key is dropped where
    /// interpolating its neighbours reproduces its local rotation within
    /// `max_error / (reach · chain)` rad at every dropped sample — `reach` the farthest its
    /// branches extend from it, `chain` the most animated joints on one path from the root —
    /// since a point's error is at most the sum, over the animated joints above it, of angle
    /// error × reach. 0 keeps every sample.
    pub max_error: f32,
    /// Leaf flutter per sample: the tree's (amplitude A, rad; phase θ, rad) of sylva-sway's
    /// `LeafSway`, or empty for none. Exported as two morph targets of the leaf cards,
    /// weighted `A·sin θ` and `A·cos θ`: a card c swings about its hanging point by
    /// `A·sin(θ + φ_c)`, the renderer's flutter, to first order in the angle (see
    /// [`FLUTTER_TARGETS`]).
    pub flutter: Vec<[f32; 2]>,
}

/// Names of the two morph targets that carry leaf flutter (`extras.targetNames` of each
/// mesh, glTF's convention). A leaf card c hangs at h_c with phase offset φ_c and turns about
/// k_c = unit(o × z), o = its centre − h_c (the renderer's axis). For a corner p, r = p − h_c,
/// the targets hold `cos φ_c · (k_c × r)` and `sin φ_c · (k_c × r)`. With weights `A·sin θ`
/// and `A·cos θ` the corner moves by `A·sin(θ + φ_c) · (k_c × r)`: the rotation by the
/// renderer's angle a = A·sin(θ + φ_c) to first order. The rest, r·(1 − cos a) towards the
/// axis and r·(a − sin a) along the swing, is at most `a²/2 · |r|` — 6 % of a corner's
/// distance from its hanging point at the largest default swing (0.35 rad). Weights are
/// interpolated linearly between samples. The bark primitive carries the same two targets,
/// all zero (accessors without a buffer view), as glTF asks every primitive of a mesh to.
pub const FLUTTER_TARGETS: [&str; 2] = ["flutter_sin", "flutter_cos"];

/// Rᵀ·v for the frame R with columns f[0], f[1], f[2].
pub(super) fn to_local(f: &[V3; 3], v: V3) -> V3 {
    [dot(f[0], v), dot(f[1], v), dot(f[2], v)]
}

/// Unit quaternion (x, y, z, w) of the rotation matrix with columns c.
pub(super) fn quaternion(c: &[V3; 3]) -> [f32; 4] {
    sylva_core::quat::from_matrix(|r, k| c[k][r] as f64).map(|v| v as f32)
}

/// An orthonormal rest frame per joint (columns x, y, z; z along the segment), made
/// exactly orthonormal in f64 so the quaternions are unit.
pub(super) fn frame(sk: &Skeleton, j: usize) -> [V3; 3] {
    let f = sk.joints()[j].frame();
    let z = norm(f[2]);
    let x = norm(sub(f[0], scale(z, dot(f[0], z))));
    let y = cross(z, x);
    [x, y, z]
}

impl TreeModel {
    /// The model as a `.glb` file. Same model and options, same bytes.
    pub fn to_glb(&self, opts: &GltfOptions) -> Vec<u8> {
        let sk = &self.tree.skeleton;
        let js = sk.joints();
        let n = js.len();
        let frames: Vec<[V3; 3]> = (0..n).map(|j| frame(sk, j)).collect();
        let order = self.joint_priority();
        let mut channels: Vec<Channel> = Vec::new();
        let limit = opts.max_joints.clamp(1, MAX_GLTF_JOINTS);
        let mut bin = Bin { data: Vec::new(), views: Vec::new(), accessors: Vec::new() };
        let mut nodes: Vec<Node> = Vec::new();
        let mut skins: Vec<Skin> = Vec::new();
        // Textures: image 0 bark, image 1 leaves.
        let bark_view = bin.view(&png(&self.bark), None);
        let leaf_view = bin.view(&png(&self.leaves.image), None);
        let lods: Vec<usize> = if opts.lods.is_empty() {
            (0..self.lods.len()).collect()
        } else {
            opts.lods.iter().copied().filter(|&l| l < self.lods.len()).collect()
        };
        let mut meshes: Vec<Mesh> = Vec::new();
        let mut scenes: Vec<Scene> = Vec::new();
        for (k, &l) in lods.iter().enumerate() {
            let keep = self.exported_mask(l, limit, &order);
            let base = nodes.len();
            let index = self.joint_nodes(&keep, &frames, &mut nodes, &mut bin, &mut skins);
            if let Some(anim) = &opts.animation {
                animate(anim, sk, &frames, &keep, base, &index, &mut bin, &mut channels);
            }
            let flutter = opts.animation.as_ref().is_some_and(has_flutter);
            let prims = self.lod_primitives(l, &index, &mut bin, [0, 1], flutter);
            meshes.push(Mesh::new(format!("lod{l}"), prims));
            // glTF is +Y up, Sylva +Z up: the joints hang under a node turning Z up into Y up.
            // The skinned mesh node stays a root with no transform (glTF ignores it), so its
            // vertices follow the joints, turned with them.
            nodes.push(Node {
                name: format!("{} lod{l} Y-up", opts.name),
                translation: None,
                rotation: Some(Z_UP_TO_Y_UP),
                scale: None,
                children: vec![base],
                mesh: None,
                skin: None,
            });
            let up = nodes.len() - 1;
            nodes.push(Node {
                name: format!("{} lod{l}", opts.name),
                translation: None,
                rotation: None,
                scale: None,
                children: Vec::new(),
                mesh: Some(k),
                skin: Some(k),
            });
            if let Some(anim) = &opts.animation {
                flutter_channel(anim, nodes.len() - 1, &mut bin, &mut channels);
            }
            scenes.push(Scene { name: format!("lod{l}"), nodes: vec![up, nodes.len() - 1] });
        }
        let animation = opts.animation.as_ref().map(|a| a.name.as_str());
        assemble(scenes, nodes, meshes, skins, &[(bark_view, leaf_view)], animation, &channels, bin)
    }

    /// Level `l`'s two primitives (bark; leaf quads) with joint indices mapped through
    /// `index` (skeleton joint → exported joint) and the given (bark, leaf) materials; with
    /// `flutter`, the two morph targets of [`FLUTTER_TARGETS`] on each.
    fn lod_primitives(
        &self,
        l: usize,
        index: &[u16],
        bin: &mut Bin,
        materials: [usize; 2],
        flutter: bool,
    ) -> Vec<Primitive> {
        let lod = &self.lods[l];
        let b = &lod.branches;
        let cells = self.leaves.cells.max(1);
        let mut prims = Vec::new();
        if !b.indices.is_empty() {
            // Joints folded into the same exported joint add their weights; unused
            // slots are joint 0 with weight 0, as the specification asks.
            let mut jb = Vec::with_capacity(8 * b.joints.len());
            let mut wv = Vec::with_capacity(b.weights.len());
            for (j, w) in b.joints.iter().zip(&b.weights) {
                let mut js4 = [0u16; 4];
                let mut ws4 = [0f32; 4];
                let mut used = 0;
                for s in 0..4 {
                    if w[s] <= 0.0 {
                        continue;
                    }
                    let e = index[j[s] as usize];
                    match js4[..used].iter().position(|&x| x == e) {
                        Some(k) => ws4[k] += w[s],
                        None => {
                            js4[used] = e;
                            ws4[used] = w[s];
                            used += 1;
                        }
                    }
                }
                for v in js4 {
                    jb.extend_from_slice(&v.to_le_bytes());
                }
                wv.push(ws4);
            }
            let mut bark =
                bin.primitive(&b.positions, &b.normals, &b.uvs, &jb, &wv, &b.indices, materials[0]);
            if flutter {
                bark.targets = (0..2).map(|_| bin.zero_target(b.positions.len())).collect();
            }
            prims.push(bark);
        }
        if !lod.clusters.is_empty() {
            let mut p = Vec::with_capacity(4 * lod.clusters.len());
            let mut nrm = Vec::with_capacity(4 * lod.clusters.len());
            let mut uv = Vec::with_capacity(4 * lod.clusters.len());
            let mut jb = Vec::with_capacity(32 * lod.clusters.len());
            let mut w = Vec::with_capacity(4 * lod.clusters.len());
            let mut ids: Vec<u32> = Vec::with_capacity(6 * lod.clusters.len());
            let mut swing: [Vec<V3>; 2] = Default::default();
            for c in &lod.clusters {
                let (corners, normal) = leaf_quad(c);
                if flutter {
                    let d = flutter_displacements(c, &corners);
                    for (t, dt) in swing.iter_mut().zip(d) {
                        t.extend_from_slice(&dt);
                    }
                }
                let first = p.len() as u32;
                let cell = [(c.atlas % cells) as f32, (c.atlas / cells) as f32];
                for (q, corner) in corners.iter().enumerate() {
                    p.push(*corner);
                    nrm.push(normal);
                    let (a, bb) = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)][q];
                    uv.push([(cell[0] + a) / cells as f32, (cell[1] + bb) / cells as f32]);
                    for v in [index[c.joint as usize], 0, 0, 0] {
                        jb.extend_from_slice(&v.to_le_bytes());
                    }
                    w.push([1.0f32, 0.0, 0.0, 0.0]);
                }
                ids.extend_from_slice(&[first, first + 1, first + 2, first, first + 2, first + 3]);
            }
            let mut leaves = bin.primitive(&p, &nrm, &uv, &jb, &w, &ids, materials[1]);
            if flutter {
                leaves.targets = swing.iter().map(|d| bin.target(d)).collect();
            }
            prims.push(leaves);
        }
        prims
    }
}
