//! glTF export: deterministic bytes and a well-formed GLB container whose JSON describes
//! the skin and meshes of the model. (Full conformance is checked in CI by the Khronos
//! validator, `.ci/validate-gltf.mjs`.)

use sylva_tree::Species;
use sylva_tree::gltf::GltfOptions;
use sylva_tree::mesh::LOD_LEVELS;

fn glb(name: &str, seed: u64, opts: &GltfOptions) -> Vec<u8> {
    Species::preset(name).expect("preset").model(seed, LOD_LEVELS).expect("tree").to_glb(opts)
}

fn u32_at(b: &[u8], at: usize) -> usize {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as usize
}

/// The JSON chunk of a `.glb`.
fn json_of(b: &[u8]) -> serde_json::Value {
    serde_json::from_slice(&b[20..20 + u32_at(b, 12)]).expect("glTF JSON")
}

#[test]
fn same_seed_same_bytes_and_another_seed_another_file() {
    let all = GltfOptions { lods: vec![], ..Default::default() };
    let a = glb("quaking_aspen", 4, &all);
    assert_eq!(a, glb("quaking_aspen", 4, &all));
    assert_ne!(a, glb("quaking_aspen", 5, &all));
}

#[test]
fn glb_container_holds_json_and_binary_chunks_describing_the_model() {
    let model = Species::preset("sugar_maple").expect("preset").model(2, LOD_LEVELS).expect("tree");
    let bytes = model.to_glb(&GltfOptions { lods: vec![], ..Default::default() });
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(&bytes, 4), 2, "version");
    assert_eq!(u32_at(&bytes, 8), bytes.len(), "declared length");
    let json_len = u32_at(&bytes, 12);
    assert_eq!(&bytes[16..20], b"JSON");
    assert_eq!(json_len % 4, 0);
    let json = std::str::from_utf8(&bytes[20..20 + json_len]).expect("utf-8 JSON");
    let bin_at = 20 + json_len;
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    assert_eq!(bin_at + 8 + u32_at(&bytes, bin_at), bytes.len());
    // Per LOD: a skin over the joints it uses (every joint at LOD 0, fewer after), a mesh
    // and a scene; alpha-masked leaves; PNG textures.
    let joints = json.matches("\"name\":\"joint").count();
    let n = model.tree.skeleton.len();
    assert!(joints > n && joints < n * model.lods.len(), "{joints} joint nodes");
    assert_eq!(json.matches("\"inverseBindMatrices\"").count(), model.lods.len());
    // The node list itself, and one scene per LOD.
    assert_eq!(json.matches("\"nodes\":[").count(), 1 + model.lods.len());
    assert_eq!(json.matches("\"primitives\"").count(), model.lods.len());
    assert!(json.contains("\"alphaMode\":\"MASK\"") && json.contains("\"image/png\""));
    // Only the requested LOD.
    let one = model.to_glb(&GltfOptions { lods: vec![3], ..Default::default() });
    assert!(one.len() < bytes.len());
}

#[test]
fn joint_budget_folds_light_joints_into_ancestors() {
    let opts = GltfOptions { lods: vec![0], max_joints: 100, name: "fir".into(), animation: None };
    let bytes = glb("douglas_fir", 1, &opts);
    let json_len = u32_at(&bytes, 12);
    let json = std::str::from_utf8(&bytes[20..20 + json_len]).expect("json");
    assert_eq!(json.matches("\"name\":\"joint").count(), 100);
}

#[test]
fn the_willows_default_export_keeps_its_hanging_twigs() {
    // The command line's default budget, 1 024 of the willow's 36 000 joints: the twigs
    // that hang keep joints of their own (with their paths to the limbs), so the exported
    // twig tips (exported joints with no exported child) point down about as often as the
    // tree's own tips do, and its curtains sway instead of riding rigidly on the limbs.
    let m = Species::preset("weeping_willow").expect("preset").model(1, LOD_LEVELS).expect("tree");
    let js = m.tree.skeleton.joints();
    let down = |j: usize| js[j].axis[2] < 0.0;
    let own_tips: Vec<usize> =
        (0..js.len()).filter(|&j| m.tree.skeleton.children(j).is_empty()).collect();
    let own = own_tips.iter().filter(|&&j| down(j)).count() as f32 / own_tips.len() as f32;
    let exported = m.exported_joints(0, 1024);
    assert_eq!(exported.len(), 1024);
    let mut parent_of_exported = vec![false; js.len()];
    for &j in &exported {
        if js[j].parent != sylva_tree::NO_PARENT {
            parent_of_exported[js[j].parent as usize] = true;
        }
    }
    let tips: Vec<usize> = exported.iter().copied().filter(|&j| !parent_of_exported[j]).collect();
    let share = tips.iter().filter(|&&j| down(j)).count() as f32 / tips.len() as f32;
    assert!(
        share >= 0.75,
        "{share:.2} of {} exported twig tips point down (the tree: {own:.2})",
        tips.len()
    );
    // Every exported joint's parent is exported (the skin is one tree).
    let set: std::collections::HashSet<usize> = exported.iter().copied().collect();
    assert!(
        exported
            .iter()
            .all(|&j| js[j].parent == sylva_tree::NO_PARENT
                || set.contains(&(js[j].parent as usize)))
    );
}

/// Quaternion (x, y, z, w) applied to v.
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
    let t = [2.0 * (y * v[2] - z * v[1]), 2.0 * (z * v[0] - x * v[2]), 2.0 * (x * v[1] - y * v[0])];
    [
        v[0] + w * t[0] + (y * t[2] - z * t[1]),
        v[1] + w * t[1] + (z * t[0] - x * t[2]),
        v[2] + w * t[2] + (x * t[1] - y * t[0]),
    ]
}

/// glTF is +Y up: walking scene 0's node tree as a client does (translation, then rotation,
/// parent by parent), the joints span the tree's height along +Y, from the ground upward,
/// and much less across.
#[test]
fn the_exported_tree_stands_along_plus_y() {
    let model = Species::preset("douglas_fir").expect("preset").model(1, LOD_LEVELS).expect("tree");
    let bytes = model.to_glb(&GltfOptions::default());
    let json_len = u32_at(&bytes, 12);
    let gltf: serde_json::Value =
        serde_json::from_slice(&bytes[20..20 + json_len]).expect("JSON chunk");
    let nodes = gltf["nodes"].as_array().expect("nodes");
    let f = |v: &serde_json::Value, n: usize| -> Vec<f64> {
        (0..n).map(|k| v.get(k).and_then(|x| x.as_f64()).unwrap_or(0.0)).collect()
    };
    // World position and rotation of every node reachable from scene 0.
    let mut joints = Vec::new();
    let mut stack: Vec<(usize, [f64; 3], [f64; 4])> = gltf["scenes"][0]["nodes"]
        .as_array()
        .expect("scene nodes")
        .iter()
        .map(|n| (n.as_u64().expect("index") as usize, [0.0; 3], [0.0, 0.0, 0.0, 1.0]))
        .collect();
    while let Some((i, pos, rot)) = stack.pop() {
        let node = &nodes[i];
        let t = node.get("translation").map(|t| f(t, 3)).unwrap_or(vec![0.0; 3]);
        let r = node.get("rotation").map(|r| f(r, 4)).unwrap_or(vec![0.0, 0.0, 0.0, 1.0]);
        let moved = rotate(rot, [t[0], t[1], t[2]]);
        let world = [pos[0] + moved[0], pos[1] + moved[1], pos[2] + moved[2]];
        // rot · r (Hamilton product)
        let (a, b) = (rot, [r[0], r[1], r[2], r[3]]);
        let q = [
            a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
            a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
            a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
            a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
        ];
        if node["name"].as_str().is_some_and(|n| n.starts_with("joint")) {
            joints.push(world);
        }
        for c in node.get("children").and_then(|c| c.as_array()).into_iter().flatten() {
            stack.push((c.as_u64().expect("child") as usize, world, q));
        }
    }
    assert!(joints.len() > 100, "{} joints reached from scene 0", joints.len());
    let span = |k: usize| {
        let lo = joints.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = joints.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    };
    let (y0, y1) = span(1);
    let height = model.tree.stats.height as f64;
    assert!(y0.abs() < 0.05 * height && y1 > 0.8 * height, "y from {y0} to {y1}, tree {height} m");
    for k in [0, 2] {
        let (lo, hi) = span(k);
        assert!(hi - lo < 0.7 * (y1 - y0), "axis {k} spans {lo} … {hi}");
    }
}

/// Rotate `v` about the unit axis `k` by `a` (Rodrigues), as the renderer's leaf shader does.
fn rotate_about(v: [f32; 3], k: [f32; 3], a: f32) -> [f32; 3] {
    let (s, c) = a.sin_cos();
    let kxv = [k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]];
    let kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    std::array::from_fn(|i| v[i] * c + kxv[i] * s + k[i] * kv * (1.0 - c))
}

#[test]
fn flutter_targets_are_the_renderers_leaf_swing_to_first_order() {
    use sylva_tree::gltf::{flutter_displacements, leaf_quad};
    let model = Species::preset("quaking_aspen").expect("preset").model(3, 2).expect("model");
    let clusters = &model.lods[0].clusters;
    assert!(clusters.len() > 100);
    // Weights A·sin θ and A·cos θ move a corner by A·sin(θ + φ)·(k × r): the renderer's
    // rotation by a = A·sin(θ + φ) about the card's hanging point, up to a²/2·|r|.
    for (amplitude, theta) in [(0.01f32, 0.3f32), (0.1, 2.0), (0.35, 4.5)] {
        let (w0, w1) = (amplitude * theta.sin(), amplitude * theta.cos());
        let mut worst_ratio = 0.0f32;
        for c in clusters.iter().step_by(37) {
            let (corners, _) = leaf_quad(c);
            let d = flutter_displacements(c, &corners);
            let o = [c.center[0] - c.hang[0], c.center[1] - c.hang[1], c.center[2] - c.hang[2]];
            let axis = [o[1], -o[0], 0.0f32];
            let len = (axis[0] * axis[0] + axis[1] * axis[1]).sqrt();
            let k = if len < 1e-5 { [1.0, 0.0, 0.0] } else { [axis[0] / len, axis[1] / len, 0.0] };
            let a = amplitude * (theta + c.phase).sin();
            for q in 0..4 {
                let r: [f32; 3] = std::array::from_fn(|i| corners[q][i] - c.hang[i]);
                let exact = rotate_about(r, k, a);
                let morphed: [f32; 3] =
                    std::array::from_fn(|i| r[i] + w0 * d[0][q][i] + w1 * d[1][q][i]);
                let err = (0..3).map(|i| (exact[i] - morphed[i]).powi(2)).sum::<f32>().sqrt();
                let rlen = r.iter().map(|v| v * v).sum::<f32>().sqrt();
                let bound = 0.5 * a * a * rlen + 1e-6;
                assert!(err <= bound * 1.01, "corner off by {err} m, bound {bound} (a = {a})");
                if a.abs() > 0.05 && rlen > 1e-2 {
                    worst_ratio = worst_ratio.max(err / (a * a * rlen));
                }
            }
        }
        // The error is second order: it shrinks with the square of the swing.
        assert!(worst_ratio <= 0.51, "error / (a²|r|) up to {worst_ratio}");
    }
}

#[test]
fn a_clip_with_flutter_carries_two_targets_on_every_primitive_and_a_weights_channel() {
    use sylva_tree::gltf::{FLUTTER_TARGETS, GltfOptions, JointAnimation};
    let model = Species::preset("quaking_aspen").expect("preset").model(3, 2).expect("model");
    let joints = model.exported_joints(0, 64);
    let identity = [1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let animation = JointAnimation {
        name: "flutter".into(),
        times: vec![0.0, 0.5, 1.0],
        joints: joints.clone(),
        rotations: vec![vec![identity; joints.len()]; 3],
        max_error: 0.0,
        flutter: vec![[0.2, 0.0], [0.2, 1.0], [0.1, 2.0]],
    };
    let glb = model.to_glb(&GltfOptions {
        max_joints: 64,
        animation: Some(animation),
        ..GltfOptions::default()
    });
    let json = json_of(&glb);
    let mesh = &json["meshes"][0];
    assert_eq!(mesh["weights"].as_array().map(Vec::len), Some(2));
    assert_eq!(mesh["extras"]["targetNames"], serde_json::json!(FLUTTER_TARGETS));
    for p in mesh["primitives"].as_array().expect("primitives") {
        assert_eq!(p["targets"].as_array().map(Vec::len), Some(2), "{p}");
    }
    let channels = json["animations"][0]["channels"].as_array().expect("channels");
    let weights: Vec<_> = channels.iter().filter(|c| c["target"]["path"] == "weights").collect();
    assert_eq!(weights.len(), 1);
    let sampler = &json["animations"][0]["samplers"]
        [weights[0]["sampler"].as_u64().expect("sampler") as usize];
    // Two weights per sample.
    assert_eq!(json["accessors"][sampler["output"].as_u64().expect("output") as usize]["count"], 6);
    // Without flutter, no targets.
    let still = model.to_glb(&GltfOptions { max_joints: 64, ..GltfOptions::default() });
    assert!(json_of(&still)["meshes"][0].get("weights").is_none());
}
