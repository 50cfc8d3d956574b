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
//! exported: beyond `max_joints`, the lightest joints (least carried mass) are folded into
//! their nearest exported ancestor. Leaf cards, which the renderer turns part way towards
//! the viewer, are exported as their fixed oriented quads (facing out of the crown).

use serde::Serialize;
use serde_json::json;
use sylva_core::v3::{V3, cross, dot, norm, scale, sub};

use crate::mesh::{LeafCluster, TreeModel};
use crate::skeleton::{NO_PARENT, Skeleton};
use crate::texture::Image;

// OpenGL enumerants that glTF 2.0 uses by number (glTF 2.0 specification, §5).
const ARRAY_BUFFER: u32 = 34_962;
const ELEMENT_ARRAY_BUFFER: u32 = 34_963;
const UNSIGNED_SHORT: u32 = 5_123;
const UNSIGNED_INT: u32 = 5_125;
const FLOAT: u32 = 5_126;
const LINEAR: u32 = 9_729;
const LINEAR_MIPMAP_LINEAR: u32 = 9_987;
const REPEAT: u32 = 10_497;
const CLAMP_TO_EDGE: u32 = 33_071;

/// Rotation (x, y, z, w) of −90° about x: Sylva's +Z up becomes glTF's +Y up (and Sylva's +Y,
/// north, becomes glTF's −Z).
const Z_UP_TO_Y_UP: [f32; 4] =
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
fn to_local(f: &[V3; 3], v: V3) -> V3 {
    [dot(f[0], v), dot(f[1], v), dot(f[2], v)]
}

/// Unit quaternion (x, y, z, w) of the rotation matrix with columns c.
fn quaternion(c: &[V3; 3]) -> [f32; 4] {
    sylva_core::quat::from_matrix(|r, k| c[k][r] as f64).map(|v| v as f32)
}

/// An orthonormal rest frame per joint (columns x, y, z; z along the segment), made
/// exactly orthonormal in f64 so the quaternions are unit.
fn frame(sk: &Skeleton, j: usize) -> [V3; 3] {
    let f = sk.joints()[j].frame();
    let z = norm(f[2]);
    let x = norm(sub(f[0], scale(z, dot(f[0], z))));
    let y = cross(z, x);
    [x, y, z]
}

/// A `bufferViews` entry.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct BufferView {
    buffer: usize,
    byte_offset: usize,
    byte_length: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    target: Option<u32>,
}

/// An `accessors` entry.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Accessor {
    /// None: every element zero (glTF §3.6.2.3), as the bark's flutter targets are.
    #[serde(skip_serializing_if = "Option::is_none")]
    buffer_view: Option<usize>,
    component_type: u32,
    count: usize,
    #[serde(rename = "type")]
    ty: &'static str,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    min: Vec<f32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    max: Vec<f32>,
}

/// A `nodes` entry: a joint (translation, rotation, children) or a mesh with its skin.
#[derive(Serialize)]
struct Node {
    name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    translation: Option<V3>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rotation: Option<[f32; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    scale: Option<V3>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    children: Vec<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mesh: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    skin: Option<usize>,
}

/// A `skins` entry.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Skin {
    inverse_bind_matrices: usize,
    skeleton: usize,
    joints: Vec<usize>,
}

/// The attributes of a skinned, textured primitive.
#[derive(Serialize)]
struct Attributes {
    #[serde(rename = "POSITION")]
    position: usize,
    #[serde(rename = "NORMAL")]
    normal: usize,
    #[serde(rename = "TEXCOORD_0")]
    texcoord: usize,
    #[serde(rename = "JOINTS_0")]
    joints: usize,
    #[serde(rename = "WEIGHTS_0")]
    weights: usize,
}

/// A morph target: position displacements.
#[derive(Serialize)]
struct Target {
    #[serde(rename = "POSITION")]
    position: usize,
}

/// A mesh primitive (triangles).
#[derive(Serialize)]
struct Primitive {
    attributes: Attributes,
    indices: usize,
    material: usize,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    targets: Vec<Target>,
}

/// A `meshes` entry.
#[derive(Serialize)]
struct Mesh {
    name: String,
    primitives: Vec<Primitive>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    weights: Vec<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    extras: Option<serde_json::Value>,
}

impl Mesh {
    fn new(name: String, primitives: Vec<Primitive>) -> Mesh {
        let morphs = primitives.first().map_or(0, |p| p.targets.len());
        Mesh {
            name,
            primitives,
            weights: vec![0.0; morphs],
            extras: (morphs > 0).then(|| json!({ "targetNames": FLUTTER_TARGETS })),
        }
    }
}

/// A `scenes` entry.
#[derive(Serialize)]
struct Scene {
    name: String,
    nodes: Vec<usize>,
}

/// The glTF JSON chunk. Typed where the values are computed (f32 fields keep their
/// shortest decimal form), literal JSON for the fixed materials, samplers and textures.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
struct Gltf {
    asset: serde_json::Value,
    scene: usize,
    scenes: Vec<Scene>,
    nodes: Vec<Node>,
    meshes: Vec<Mesh>,
    skins: Vec<Skin>,
    materials: serde_json::Value,
    samplers: serde_json::Value,
    images: serde_json::Value,
    textures: serde_json::Value,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    animations: Vec<serde_json::Value>,
    accessors: Vec<Accessor>,
    buffer_views: Vec<BufferView>,
    buffers: serde_json::Value,
}

/// One channel of the animation: the node it drives, what of it (`rotation` of a joint,
/// `weights` of a mesh node's flutter targets), its time and value accessors.
#[derive(Debug, Clone, Copy)]
struct Channel {
    node: usize,
    path: &'static str,
    input: usize,
    output: usize,
}

fn norm_of(v: V3) -> f64 {
    v.iter().map(|&x| x as f64 * x as f64).sum::<f64>().sqrt()
}

/// Angle between two rotations given as quaternions, rad: 2·atan2(|a − b|, |a + b|) after
/// normalising and taking b in a's hemisphere (accurate at small angles, where the acos of
/// a dot product loses everything below about 1e-3 rad to rounding).
fn rotation_angle(a: [f64; 4], b: [f64; 4]) -> f64 {
    let unit = |q: [f64; 4]| {
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        q.map(|v| v / n)
    };
    let (a, mut b) = (unit(a), unit(b));
    if (0..4).map(|i| a[i] * b[i]).sum::<f64>() < 0.0 {
        b = b.map(|v| -v);
    }
    let diff = (0..4).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    let sum = (0..4).map(|i| (a[i] + b[i]).powi(2)).sum::<f64>().sqrt();
    2.0 * diff.atan2(sum)
}

/// Samples to keep as keys so that slerp between kept neighbours stays within `eps` rad of
/// every dropped sample (greedy, from the first sample; the last is always kept). `eps` ≤ 0
/// keeps all.
fn reduce_keys(times: &[f32], q: &[[f64; 4]], eps: f64) -> Vec<usize> {
    let n = q.len();
    if eps <= 0.0 || n <= 2 {
        return (0..n).collect();
    }
    let fits = |a: usize, b: usize| {
        let span = (times[b] - times[a]) as f64;
        (a + 1..b).all(|k| {
            let u = (times[k] - times[a]) as f64 / span;
            rotation_angle(sylva_core::quat::slerp(q[a], q[b], u), q[k]) <= eps
        })
    };
    let mut keep = vec![0];
    let mut a = 0;
    while a + 1 < n {
        let mut b = a + 1;
        while b + 1 < n && fits(a, b + 1) {
            b += 1;
        }
        keep.push(b);
        a = b;
    }
    keep
}

/// Add the rotation channels of `anim` for the joints exported in `keep` (joint nodes from
/// `base`, skeleton joint → exported index in `index`) to `bin` and `channels`.
#[allow(clippy::too_many_arguments)]
fn animate(
    anim: &JointAnimation,
    sk: &Skeleton,
    frames: &[[V3; 3]],
    keep: &[bool],
    base: usize,
    index: &[u16],
    bin: &mut Bin,
    channels: &mut Vec<Channel>,
) {
    let js = sk.joints();
    let samples = anim.times.len().min(anim.rotations.len());
    if samples == 0 {
        return;
    }
    let mut slot = vec![usize::MAX; js.len()];
    for (k, &j) in anim.joints.iter().enumerate() {
        if j < slot.len() {
            slot[j] = k;
        }
    }
    const IDENTITY: [f32; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let rot = |s: usize, j: usize| -> [f32; 9] {
        anim.rotations[s].get(slot[j]).copied().unwrap_or(IDENTITY)
    };
    let apply = |r: &[f32; 9], v: V3| -> V3 {
        [
            r[0] * v[0] + r[1] * v[1] + r[2] * v[2],
            r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
            r[6] * v[0] + r[7] * v[1] + r[8] * v[2],
        ]
    };
    let apply_t = |r: &[f32; 9], v: V3| -> V3 {
        [
            r[0] * v[0] + r[3] * v[1] + r[6] * v[2],
            r[1] * v[0] + r[4] * v[1] + r[7] * v[2],
            r[2] * v[0] + r[5] * v[1] + r[8] * v[2],
        ]
    };
    let times = &anim.times[..samples];
    let tol = anim.max_error.max(0.0) as f64;
    // Reach of each joint: an upper bound on the distance from its origin to any point it
    // carries (children before parents: joints come parents first).
    let mut reach = vec![0.0f64; js.len()];
    for j in (0..js.len()).rev() {
        let own = norm_of(sub(js[j].tip(), js[j].origin));
        reach[j] = reach[j].max(own);
        let p = js[j].parent;
        if p != NO_PARENT {
            let p = p as usize;
            let arm = norm_of(sub(js[j].origin, js[p].origin));
            reach[p] = reach[p].max(arm + reach[j]);
        }
    }
    let mut all_times: Option<usize> = None;
    let (t0, t1) = (times[0], times[samples - 1]);
    // Animated joints on the longest chain from the root: a point's error is at most the
    // sum over the animated joints above it of (angle error × reach), so an angle bound of
    // tol / (reach × chain) per joint bounds every point's error by tol.
    let mut depth = vec![0usize; js.len()];
    let mut chain = 1;
    for j in 0..js.len() {
        let p = js[j].parent;
        let above = if p == NO_PARENT { 0 } else { depth[p as usize] };
        depth[j] = above + (keep[j] && slot[j] != usize::MAX) as usize;
        chain = chain.max(depth[j]);
    }
    for j in (0..js.len()).filter(|&j| keep[j] && slot[j] != usize::MAX) {
        let f = &frames[j];
        let p = js[j].parent;
        let mut q: Vec<[f64; 4]> = Vec::with_capacity(samples);
        for s in 0..samples {
            let rj = rot(s, j);
            let cols: [V3; 3] = std::array::from_fn(|c| {
                let a = apply(&rj, f[c]);
                if p == NO_PARENT {
                    a
                } else {
                    let pf = &frames[p as usize];
                    to_local(pf, apply_t(&rot(s, p as usize), a))
                }
            });
            let mut k = quaternion(&cols).map(f64::from);
            // Neighbouring keys in one hemisphere, so interpolation takes the short way.
            if let Some(prev) = q.last()
                && (0..4).map(|i| prev[i] * k[i]).sum::<f64>() < 0.0
            {
                k = k.map(|v| -v);
            }
            q.push(k);
        }
        let kept = reduce_keys(times, &q, tol / (reach[j].max(1e-3) * chain as f64));
        let input = if kept.len() == samples {
            *all_times.get_or_insert_with(|| {
                let bytes: Vec<u8> = times.iter().flat_map(|v| v.to_le_bytes()).collect();
                bin.accessor(&bytes, None, FLOAT, samples, "SCALAR", Some((&[t0], &[t1])))
            })
        } else {
            let bytes: Vec<u8> = kept.iter().flat_map(|&k| times[k].to_le_bytes()).collect();
            bin.accessor(&bytes, None, FLOAT, kept.len(), "SCALAR", Some((&[t0], &[t1])))
        };
        let values: Vec<[f32; 4]> = kept.iter().map(|&k| q[k].map(|v| v as f32)).collect();
        let output = bin.accessor(&f32_bytes(&values), None, FLOAT, values.len(), "VEC4", None);
        channels.push(Channel { node: base + index[j] as usize, path: "rotation", input, output });
    }
}

/// Whether `anim` carries leaf flutter for every sample.
fn has_flutter(anim: &JointAnimation) -> bool {
    let samples = anim.times.len().min(anim.rotations.len());
    samples > 0 && anim.flutter.len() >= samples
}

/// The `weights` channel of mesh node `node`: per sample the flutter targets' weights
/// (A·sin θ, A·cos θ), every sample kept (two floats each).
fn flutter_channel(anim: &JointAnimation, node: usize, bin: &mut Bin, channels: &mut Vec<Channel>) {
    if !has_flutter(anim) {
        return;
    }
    let samples = anim.times.len().min(anim.rotations.len());
    let times = &anim.times[..samples];
    let bytes: Vec<u8> = times.iter().flat_map(|v| v.to_le_bytes()).collect();
    let range = (&[times[0]][..], &[times[samples - 1]][..]);
    let input = bin.accessor(&bytes, None, FLOAT, samples, "SCALAR", Some(range));
    let weights: Vec<[f32; 2]> = anim.flutter[..samples]
        .iter()
        .map(|&[a, theta]| {
            let (sn, cs) = theta.sin_cos();
            [a * sn, a * cs]
        })
        .collect();
    let output = bin.accessor(&f32_bytes(&weights), None, FLOAT, 2 * samples, "SCALAR", None);
    channels.push(Channel { node, path: "weights", input, output });
}

/// The two flutter targets of a leaf card's four corners (see [`FLUTTER_TARGETS`]), for
/// the corners of [`leaf_quad`].
pub fn flutter_displacements(c: &LeafCluster, corners: &[V3; 4]) -> [[V3; 4]; 2] {
    let o = sub(c.center, c.hang);
    let axis = cross(o, [0.0, 0.0, 1.0]);
    let k = if dot(axis, axis) < 1e-10 { [1.0, 0.0, 0.0] } else { norm(axis) };
    let (sn, cs) = c.phase.sin_cos();
    let swing = corners.map(|p| cross(k, sub(p, c.hang)));
    [swing.map(|d| scale(d, cs)), swing.map(|d| scale(d, sn))]
}

/// Binary buffer under construction, with one view per accessor.
struct Bin {
    data: Vec<u8>,
    views: Vec<BufferView>,
    accessors: Vec<Accessor>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let byte_offset = self.data.len();
        self.data.extend_from_slice(bytes);
        self.views.push(BufferView { buffer: 0, byte_offset, byte_length: bytes.len(), target });
        self.views.len() - 1
    }

    /// Accessor over `bytes`: component type, count, type name, optional min/max.
    fn accessor(
        &mut self,
        bytes: &[u8],
        target: Option<u32>,
        component_type: u32,
        count: usize,
        ty: &'static str,
        bounds: Option<(&[f32], &[f32])>,
    ) -> usize {
        let buffer_view = self.view(bytes, target);
        self.accessors.push(Accessor {
            buffer_view: Some(buffer_view),
            component_type,
            count,
            ty,
            min: bounds.map_or_else(Vec::new, |b| b.0.to_vec()),
            max: bounds.map_or_else(Vec::new, |b| b.1.to_vec()),
        });
        self.accessors.len() - 1
    }

    /// A skinned, textured primitive from vertex data: positions (with bounds), normals,
    /// texture coordinates, joint indices (four u16 per vertex, as bytes), weights, indices.
    #[allow(clippy::too_many_arguments)]
    fn primitive(
        &mut self,
        positions: &[V3],
        normals: &[V3],
        uvs: &[[f32; 2]],
        joints: &[u8],
        weights: &[[f32; 4]],
        indices: &[u32],
        material: usize,
    ) -> Primitive {
        let v = Some(ARRAY_BUFFER);
        let (lo, hi) = bounds(positions);
        let attributes = Attributes {
            position: self.accessor(
                &f32_bytes(positions),
                v,
                FLOAT,
                positions.len(),
                "VEC3",
                Some((&lo, &hi)),
            ),
            normal: self.accessor(&f32_bytes(normals), v, FLOAT, normals.len(), "VEC3", None),
            texcoord: self.accessor(&f32_bytes(uvs), v, FLOAT, uvs.len(), "VEC2", None),
            joints: self.accessor(joints, v, UNSIGNED_SHORT, joints.len() / 8, "VEC4", None),
            weights: self.accessor(&f32_bytes(weights), v, FLOAT, weights.len(), "VEC4", None),
        };
        let ib: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = self.accessor(
            &ib,
            Some(ELEMENT_ARRAY_BUFFER),
            UNSIGNED_INT,
            indices.len(),
            "SCALAR",
            None,
        );
        Primitive { attributes, indices, material, targets: Vec::new() }
    }

    /// A morph target of `count` zero displacements: an accessor with no buffer view.
    fn zero_target(&mut self, count: usize) -> Target {
        self.accessors.push(Accessor {
            buffer_view: None,
            component_type: FLOAT,
            count,
            ty: "VEC3",
            min: vec![0.0; 3],
            max: vec![0.0; 3],
        });
        Target { position: self.accessors.len() - 1 }
    }

    /// A morph target of position displacements.
    fn target(&mut self, d: &[V3]) -> Target {
        let (lo, hi) = bounds(d);
        Target {
            position: self.accessor(
                &f32_bytes(d),
                Some(ARRAY_BUFFER),
                FLOAT,
                d.len(),
                "VEC3",
                Some((&lo, &hi)),
            ),
        }
    }
}

fn f32_bytes<const N: usize>(v: &[[f32; N]]) -> Vec<u8> {
    v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
}

fn bounds(p: &[V3]) -> (V3, V3) {
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for v in p {
        for c in 0..3 {
            lo[c] = lo[c].min(v[c]);
            hi[c] = hi[c].max(v[c]);
        }
    }
    (lo, hi)
}

fn png(img: &Image) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut e = png::Encoder::new(&mut out, img.width, img.height);
        e.set_color(png::ColorType::Rgba);
        e.set_depth(png::BitDepth::Eight);
        // Writing into a Vec cannot fail for a well-formed image.
        if let Ok(mut w) = e.write_header() {
            let _ = w.write_image_data(&img.rgba);
        }
    }
    out
}

/// The leaf quad of a cluster as exported: four corners (rest pose, tree space) and its
/// normal (out of the crown).
pub fn leaf_quad(c: &LeafCluster) -> ([V3; 4], V3) {
    let (u, v) = c.axes();
    let h = 0.5 * c.size;
    let corner = |a: f32, b: f32| {
        [
            c.center[0] + h * (a * u[0] + b * v[0]),
            c.center[1] + h * (a * u[1] + b * v[1]),
            c.center[2] + h * (a * u[2] + b * v[2]),
        ]
    };
    ([corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)], c.normal)
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

    /// Joints exported for level `lod` with at most `max_joints` of them (as
    /// [`to_glb`](Self::to_glb) picks them): those its vertices and clusters use, with
    /// their ancestors, heaviest first (carried mass). Parents come before children; every
    /// exported joint's parent is exported. A sway clip for `tree animate` records these.
    pub fn exported_joints(&self, lod: usize, max_joints: usize) -> Vec<usize> {
        let order = self.joint_priority();
        let keep = self.exported_mask(lod, max_joints.clamp(1, MAX_GLTF_JOINTS), &order);
        (0..keep.len()).filter(|&j| keep[j]).collect()
    }

    /// Joints by priority: carried mass, heaviest first (a parent carries at least what its
    /// child does; ties go to the lower index, which is the parent).
    fn joint_priority(&self) -> Vec<usize> {
        let sk = &self.tree.skeleton;
        let mut order: Vec<usize> = (0..sk.len()).collect();
        order.sort_by(|&a, &b| sk.carried_mass(b).total_cmp(&sk.carried_mass(a)).then(a.cmp(&b)));
        order
    }

    /// Per joint: exported at level `l` (see [`exported_joints`](Self::exported_joints)).
    fn exported_mask(&self, l: usize, limit: usize, order: &[usize]) -> Vec<bool> {
        let js = self.tree.skeleton.joints();
        let n = js.len();
        let Some(lod) = self.lods.get(l) else { return vec![false; n] };
        let b = &lod.branches;
        let mut used = vec![false; n];
        for (j, w) in b.joints.iter().zip(&b.weights) {
            for s in 0..4 {
                if w[s] > 0.0 {
                    used[j[s] as usize] = true;
                }
            }
        }
        for c in &lod.clusters {
            used[c.joint as usize] = true;
        }
        used[0] = true;
        for j in (1..n).rev() {
            if used[j] && js[j].parent != NO_PARENT {
                used[js[j].parent as usize] = true;
            }
        }
        let mut keep = vec![false; n];
        for &j in order.iter().filter(|&&j| used[j]).take(limit) {
            keep[j] = true;
        }
        for j in 0..n {
            let p = js[j].parent;
            if keep[j] && p != NO_PARENT && !keep[p as usize] {
                keep[j] = false;
            }
        }
        keep
    }

    /// Append the joint nodes of the joints marked in `keep` (parents first) to `nodes`,
    /// their inverse bind matrices and a skin over them. Returns, per skeleton joint, its
    /// exported index (or its nearest exported ancestor's).
    fn joint_nodes(
        &self,
        keep: &[bool],
        frames: &[[V3; 3]],
        nodes: &mut Vec<Node>,
        bin: &mut Bin,
        skins: &mut Vec<Skin>,
    ) -> Vec<u16> {
        let base = nodes.len();
        let js = self.tree.skeleton.joints();
        let n = js.len();
        let mut index = vec![0u16; n];
        let mut exported = Vec::new();
        for j in 0..n {
            if keep[j] {
                index[j] = exported.len() as u16;
                exported.push(j);
            } else if js[j].parent != NO_PARENT {
                index[j] = index[js[j].parent as usize];
            }
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); exported.len()];
        for (i, &j) in exported.iter().enumerate().skip(1) {
            children[index[js[j].parent as usize] as usize].push(i);
        }
        let mut ibm = Vec::with_capacity(exported.len());
        for (i, &j) in exported.iter().enumerate() {
            let f = &frames[j];
            let (t, r) = if js[j].parent == NO_PARENT {
                (js[j].origin, quaternion(f))
            } else {
                let p = js[j].parent as usize;
                let pf = &frames[p];
                let local = [to_local(pf, f[0]), to_local(pf, f[1]), to_local(pf, f[2])];
                (to_local(pf, sub(js[j].origin, js[p].origin)), quaternion(&local))
            };
            nodes.push(Node {
                name: format!("joint{j}"),
                translation: Some(t),
                rotation: Some(r),
                scale: None,
                children: children[i].iter().map(|c| base + c).collect(),
                mesh: None,
                skin: None,
            });
            // Inverse bind: [Rᵀ | −Rᵀ o], column-major.
            let o = js[j].origin;
            ibm.push([
                f[0][0],
                f[1][0],
                f[2][0],
                0.0,
                f[0][1],
                f[1][1],
                f[2][1],
                0.0,
                f[0][2],
                f[1][2],
                f[2][2],
                0.0,
                -dot(f[0], o),
                -dot(f[1], o),
                -dot(f[2], o),
                1.0,
            ]);
        }
        let inverse_bind_matrices =
            bin.accessor(&f32_bytes(&ibm), None, FLOAT, ibm.len(), "MAT4", None);
        skins.push(Skin {
            inverse_bind_matrices,
            skeleton: base,
            joints: (base..base + exported.len()).collect(),
        });
        index
    }
}

/// The `.glb` bytes: the JSON chunk from these parts and the binary chunk `bin`. Per species
/// `k` of `images` (its bark and leaf images' buffer views), materials `2k` (bark) and
/// `2k + 1` (leaves) and textures of the same numbers.
#[allow(clippy::too_many_arguments)]
fn assemble(
    scenes: Vec<Scene>,
    nodes: Vec<Node>,
    meshes: Vec<Mesh>,
    skins: Vec<Skin>,
    images: &[(usize, usize)],
    animation: Option<&str>,
    channels: &[Channel],
    bin: Bin,
) -> Vec<u8> {
    let len = bin.data.len().next_multiple_of(4);
    let mut materials = Vec::new();
    let mut image_list = Vec::new();
    let mut textures = Vec::new();
    for (k, &(bark, leaf)) in images.iter().enumerate() {
        materials.push(json!({
            "name": "bark",
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": 2 * k },
                "metallicFactor": 0,
                "roughnessFactor": 0.9
            }
        }));
        materials.push(json!({
            "name": "leaves",
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": 2 * k + 1 },
                "metallicFactor": 0,
                "roughnessFactor": 0.7
            },
            "alphaMode": "MASK",
            "alphaCutoff": 0.5,
            "doubleSided": true
        }));
        image_list.push(json!({ "bufferView": bark, "mimeType": "image/png" }));
        image_list.push(json!({ "bufferView": leaf, "mimeType": "image/png" }));
        textures.push(json!({ "sampler": 0, "source": 2 * k }));
        textures.push(json!({ "sampler": 1, "source": 2 * k + 1 }));
    }
    let gltf = Gltf {
        asset: json!({ "version": "2.0", "generator": "sylva" }),
        scene: 0,
        scenes,
        nodes,
        meshes,
        skins,
        materials: serde_json::Value::Array(materials),
        samplers: json!([
            {
                "magFilter": LINEAR,
                "minFilter": LINEAR_MIPMAP_LINEAR,
                "wrapS": REPEAT,
                "wrapT": REPEAT
            },
            {
                "magFilter": LINEAR,
                "minFilter": LINEAR_MIPMAP_LINEAR,
                "wrapS": CLAMP_TO_EDGE,
                "wrapT": CLAMP_TO_EDGE
            }
        ]),
        images: serde_json::Value::Array(image_list),
        textures: serde_json::Value::Array(textures),
        animations: match animation {
            Some(name) if !channels.is_empty() => vec![json!({
                "name": name,
                "channels": channels.iter().enumerate().map(|(i, c)| json!({
                    "sampler": i,
                    "target": { "node": c.node, "path": c.path }
                })).collect::<Vec<_>>(),
                "samplers": channels.iter().map(|c| json!({
                    "input": c.input,
                    "output": c.output,
                    "interpolation": "LINEAR"
                })).collect::<Vec<_>>(),
            })],
            _ => Vec::new(),
        },
        accessors: bin.accessors,
        buffer_views: bin.views,
        buffers: json!([{ "byteLength": len }]),
    };
    // Serialising plain structs and numbers cannot fail.
    let mut json = serde_json::to_vec(&gltf).unwrap_or_default();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut data = bin.data;
    while !data.len().is_multiple_of(4) {
        data.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + data.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&data);
    out
}

/// One tree of a forest export: its species (index into the models), placement in Sylva's
/// world (+Z up: trunk base, turn about z, uniform scale) and its motion.
#[derive(Debug, Clone, PartialEq)]
pub struct ForestTree {
    /// Index into the species models.
    pub species: usize,
    /// Trunk base, world m.
    pub position: V3,
    /// Turn about the vertical, rad.
    pub yaw: f32,
    /// Uniform scale.
    pub scale: f32,
    /// Its sway (joints of the species' exported set; see [`TreeModel::exported_joints`]).
    pub animation: Option<JointAnimation>,
}

/// A forest as one `.glb`: per species one mesh (full detail, at most `max_joints` joints
/// exported) and its textures; per tree its own joint hierarchy and skin — trees sway
/// apart — under a node placing it (translation, turn about the vertical, scale), all under
/// one root turning Sylva's +Z up into glTF's +Y up; the skinned mesh nodes stay roots.
/// One animation holds every tree's rotation channels.
pub fn forest_to_glb(
    models: &[&TreeModel],
    trees: &[ForestTree],
    max_joints: usize,
    name: &str,
) -> Vec<u8> {
    let limit = max_joints.clamp(1, MAX_GLTF_JOINTS);
    let mut bin = Bin { data: Vec::new(), views: Vec::new(), accessors: Vec::new() };
    let (mut nodes, mut skins, mut meshes) = (Vec::new(), Vec::new(), Vec::new());
    let mut channels = Vec::new();
    // Textures and materials of the species some tree uses, in order: slot k holds
    // materials 2k and 2k + 1.
    let mut slot_of = vec![None; models.len()];
    let mut images = Vec::new();
    for t in trees {
        if let Some(m) = models.get(t.species)
            && slot_of[t.species].is_none()
        {
            slot_of[t.species] = Some(images.len());
            images.push((bin.view(&png(&m.bark), None), bin.view(&png(&m.leaves.image), None)));
        }
    }
    // Per species: exported joints, rest frames, and its mesh once built.
    let prepared: Vec<(Vec<bool>, Vec<[V3; 3]>)> = models
        .iter()
        .map(|m| {
            let sk = &m.tree.skeleton;
            let keep = m.exported_mask(0, limit, &m.joint_priority());
            (keep, (0..sk.len()).map(|j| frame(sk, j)).collect())
        })
        .collect();
    let mut mesh_of: Vec<Option<usize>> = vec![None; models.len()];
    // Species meshes carry the flutter targets when some tree's clip has flutter.
    let flutter = trees.iter().any(|t| t.animation.as_ref().is_some_and(has_flutter));
    let mut places = Vec::new();
    let mut roots = Vec::new();
    let mut name_of = None;
    for (i, tree) in trees.iter().enumerate() {
        let Some(model) = models.get(tree.species) else { continue };
        let (keep, frames) = &prepared[tree.species];
        let base = nodes.len();
        let index = model.joint_nodes(keep, frames, &mut nodes, &mut bin, &mut skins);
        for n in &mut nodes[base..] {
            n.name = format!("tree{i} {}", n.name);
        }
        if let Some(anim) = &tree.animation {
            let sk = &model.tree.skeleton;
            animate(anim, sk, frames, keep, base, &index, &mut bin, &mut channels);
            name_of.get_or_insert(anim.name.clone());
        }
        let mesh = *mesh_of[tree.species].get_or_insert_with(|| {
            let s = tree.species;
            let k = slot_of[s].unwrap_or(0);
            let primitives = model.lod_primitives(0, &index, &mut bin, [2 * k, 2 * k + 1], flutter);
            meshes.push(Mesh::new(format!("species{s}"), primitives));
            meshes.len() - 1
        });
        let (sn, cs) = (0.5 * tree.yaw).sin_cos();
        nodes.push(Node {
            name: format!("tree{i}"),
            translation: Some(tree.position),
            rotation: Some([0.0, 0.0, sn, cs]),
            scale: Some([tree.scale; 3]),
            children: vec![base],
            mesh: None,
            skin: None,
        });
        places.push(nodes.len() - 1);
        nodes.push(Node {
            name: format!("tree{i} mesh"),
            translation: None,
            rotation: None,
            scale: None,
            children: Vec::new(),
            mesh: Some(mesh),
            skin: Some(skins.len() - 1),
        });
        roots.push(nodes.len() - 1);
        if let Some(anim) = &tree.animation {
            flutter_channel(anim, nodes.len() - 1, &mut bin, &mut channels);
        }
    }
    nodes.push(Node {
        name: format!("{name} Y-up"),
        translation: None,
        rotation: Some(Z_UP_TO_Y_UP),
        scale: None,
        children: places,
        mesh: None,
        skin: None,
    });
    let mut scene_nodes = vec![nodes.len() - 1];
    scene_nodes.extend(roots);
    let scenes = vec![Scene { name: name.to_string(), nodes: scene_nodes }];
    assemble(scenes, nodes, meshes, skins, &images, name_of.as_deref(), &channels, bin)
}
