//! A tree's sway exported as a glTF animation: played back, the joint nodes are where the
//! simulation's palettes put them; keyframe reduction keeps its error bound; a looping clip
//! closes on itself.

use serde_json::Value;
use sylva_forest::WindSource;
use sylva_forest::clip::{ClipSettings, PointWind, SwayClip, record};
use sylva_sway::{SwayParams, transform};
use sylva_tree::gltf::{GltfOptions, JointAnimation};
use sylva_tree::{Species, TreeModel};

/// The glTF JSON and binary chunk of a `.glb`.
fn chunks(glb: &[u8]) -> (Value, Vec<u8>) {
    let word =
        |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().expect("4 bytes")) as usize;
    let json_len = word(12);
    let json: Value = serde_json::from_slice(&glb[20..20 + json_len]).expect("json");
    let bin_at = 20 + json_len;
    (json, glb[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec())
}

/// The names of the nodes, in order.
fn node_names(json: &Value) -> Vec<String> {
    let nodes = json["nodes"].as_array().expect("nodes");
    nodes.iter().map(|n| n["name"].as_str().unwrap_or("").to_string()).collect()
}

/// The floats of accessor `a`.
fn floats(json: &Value, bin: &[u8], a: usize) -> Vec<f32> {
    let acc = &json["accessors"][a];
    let view = &json["bufferViews"][acc["bufferView"].as_u64().expect("view") as usize];
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let len = view["byteLength"].as_u64().expect("length") as usize;
    bin[at..at + len].chunks(4).map(|c| f32::from_le_bytes(c.try_into().expect("4"))).collect()
}

fn mul_q(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let p = mul_q(mul_q(q, [v[0], v[1], v[2], 0.0]), [-q[0], -q[1], -q[2], q[3]]);
    [p[0], p[1], p[2]]
}

/// World positions of the joint nodes at time `t`, channels interpolated as glTF does.
fn world_positions(json: &Value, bin: &[u8], t: f32) -> Vec<Option<[f64; 3]>> {
    let nodes = json["nodes"].as_array().expect("nodes");
    let mut rot: Vec<Option<[f64; 4]>> = nodes
        .iter()
        .map(|n| {
            n["rotation"].as_array().map(|r| std::array::from_fn(|i| r[i].as_f64().expect("f")))
        })
        .collect();
    let anim = &json["animations"][0];
    let channels = anim["channels"].as_array().expect("channels");
    for c in channels.iter().filter(|c| c["target"]["path"] == "rotation") {
        let s = &anim["samplers"][c["sampler"].as_u64().expect("sampler") as usize];
        let q = floats(json, bin, s["output"].as_u64().expect("output") as usize);
        let times = floats(json, bin, s["input"].as_u64().expect("input") as usize);
        let node = c["target"]["node"].as_u64().expect("node") as usize;
        let key = |i: usize| -> [f64; 4] { std::array::from_fn(|c| q[4 * i + c] as f64) };
        let b = times.iter().position(|&x| x >= t).unwrap_or(times.len() - 1);
        rot[node] = Some(if times[b] <= t || b == 0 {
            key(b)
        } else {
            let u = ((t - times[b - 1]) / (times[b] - times[b - 1])) as f64;
            slerp(key(b - 1), key(b), u)
        });
    }
    let mut parent = vec![usize::MAX; nodes.len()];
    for (i, n) in nodes.iter().enumerate() {
        for c in n["children"].as_array().into_iter().flatten() {
            parent[c.as_u64().expect("child") as usize] = i;
        }
    }
    // World (rotation, translation, uniform scale) of every node, parents first by
    // recursion.
    fn world(
        i: usize,
        nodes: &[Value],
        rot: &[Option<[f64; 4]>],
        parent: &[usize],
    ) -> ([f64; 4], [f64; 3], f64) {
        let r = rot[i].unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let t: [f64; 3] = nodes[i]["translation"]
            .as_array()
            .map(|v| std::array::from_fn(|c| v[c].as_f64().expect("f")))
            .unwrap_or([0.0; 3]);
        let s = nodes[i]["scale"].as_array().map_or(1.0, |v| v[0].as_f64().expect("f"));
        if parent[i] == usize::MAX {
            return (r, t, s);
        }
        let (pr, pt, ps) = world(parent[i], nodes, rot, parent);
        let o = rotate(pr, t);
        (mul_q(pr, r), [pt[0] + ps * o[0], pt[1] + ps * o[1], pt[2] + ps * o[2]], ps * s)
    }
    (0..nodes.len())
        .map(|i| {
            nodes[i]["name"]
                .as_str()
                .is_some_and(|n| n.contains("joint"))
                .then(|| world(i, nodes, &rot, &parent).1)
        })
        .collect()
}

fn aspen() -> TreeModel {
    Species::preset("quaking_aspen").expect("preset").model(1, 4).expect("model")
}

fn clip(model: &TreeModel, joints: &[usize], settings: &ClipSettings) -> SwayClip {
    let crown = [0.0, 0.0, 0.7 * model.tree.stats.height as f64];
    let wind = PointWind::new(
        &WindSource::parse("strong").expect("preset"),
        crown,
        4.0,
        7,
        settings.looped,
    )
    .expect("wind");
    record(&model.tree.skeleton, SwayParams::default(), &wind, joints, settings).expect("clip")
}

fn export_m(model: &TreeModel, clip: &SwayClip, max_error: f32, max_joints: usize) -> Vec<u8> {
    let animation = JointAnimation {
        name: "sway".into(),
        times: clip.times.clone(),
        joints: clip.joints.clone(),
        rotations: clip.rotations(),
        max_error,
        flutter: clip.flutter_track(),
    };
    model.to_glb(&GltfOptions {
        lods: vec![0],
        max_joints,
        name: "aspen".into(),
        animation: Some(animation),
    })
}

#[test]
fn played_back_joints_sit_where_the_palettes_put_them() {
    let model = aspen();
    let joints = model.exported_joints(0, 300);
    assert_eq!(joints.len(), 300);
    let settings =
        ClipSettings { seconds: 2.0, fps: 15.0, warmup: 2.0, looped: false, ..Default::default() };
    let c = clip(&model, &joints, &settings);
    assert_eq!(c.times.len(), 31);
    let glb = export_m(&model, &c, 0.0, 300);
    let (json, bin) = chunks(&glb);
    let names = node_names(&json);
    let sk = &model.tree.skeleton;
    let mut moved = 0.0f64;
    for k in [0, 17, 30] {
        let world = world_positions(&json, &bin, c.times[k]);
        for (slot, &j) in joints.iter().enumerate() {
            let node = names.iter().position(|n| *n == format!("joint{j}")).expect("joint node");
            let got = world[node].expect("joint");
            let o = sk.joints()[j].origin;
            let p = transform(&c.palettes[k][slot], o);
            // Sylva's +Z up is glTF's +Y up: (x, y, z) → (x, z, −y).
            let want = [p[0] as f64, p[2] as f64, -p[1] as f64];
            let err = (0..3).map(|i| (got[i] - want[i]).abs()).fold(0.0, f64::max);
            assert!(err < 1e-4, "joint {j} at key {k}: {got:?} vs {want:?}");
            let rest = [o[0] as f64, o[2] as f64, -o[1] as f64];
            moved = moved.max((0..3).map(|i| (want[i] - rest[i]).abs()).fold(0.0, f64::max));
        }
    }
    // The comparison is not of a tree at rest: strong wind moves the heaviest joints by
    // several centimetres within these two seconds (about 0.1 m).
    assert!(moved > 0.05, "largest displacement {moved} m");
}

#[test]
fn reduction_drops_most_keys_and_keeps_the_clip_span() {
    let model = aspen();
    let joints = model.exported_joints(0, 200);
    let settings =
        ClipSettings { seconds: 3.0, fps: 30.0, warmup: 2.0, looped: false, ..Default::default() };
    let c = clip(&model, &joints, &settings);
    let full = export_m(&model, &c, 0.0, 200);
    let reduced = export_m(&model, &c, 0.01, 200);
    let keys = |glb: &[u8]| -> Vec<Vec<f32>> {
        let (json, bin) = chunks(glb);
        let a = &json["animations"][0];
        // The joints' rotation channels (the flutter's weights channel keeps every sample).
        a["channels"]
            .as_array()
            .expect("channels")
            .iter()
            .filter(|c| c["target"]["path"] == "rotation")
            .map(|c| &a["samplers"][c["sampler"].as_u64().expect("sampler") as usize])
            .map(|s| floats(&json, &bin, s["input"].as_u64().expect("in") as usize))
            .collect()
    };
    let (f, r) = (keys(&full), keys(&reduced));
    assert_eq!(f.len(), joints.len(), "a channel per animated joint");
    assert_eq!(f.len(), r.len());
    let (mut nf, mut nr) = (0, 0);
    for (ft, rt) in f.iter().zip(&r) {
        assert_eq!(ft.len(), c.times.len(), "without reduction every sample is a key");
        assert_eq!((ft[0], ft.last()), (rt[0], rt.last()), "the clip keeps its span");
        nf += ft.len();
        nr += rt.len();
    }
    // Sway is smooth at 30 samples a second: 1 cm lets most keys go.
    assert!(nr * 2 < nf, "{nr} keys after reduction of {nf}");
    assert!(reduced.len() < full.len());
}

/// Angle between two palettes' rotations, rad.
fn angle(a: &[f32; 12], b: &[f32; 12]) -> f64 {
    let tr: f64 = (0..3)
        .flat_map(|r| (0..3).map(move |c| 4 * r + c))
        .map(|e| a[e] as f64 * b[e] as f64)
        .sum();
    ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
}

fn slerp(a: [f64; 4], b: [f64; 4], u: f64) -> [f64; 4] {
    let d: f64 = (0..4).map(|i| a[i] * b[i]).sum();
    let b = if d < 0.0 { b.map(|v| -v) } else { b };
    let d = d.abs().min(1.0);
    let th = d.acos();
    let (wa, wb) = if th < 1e-9 {
        (1.0 - u, u)
    } else {
        (((1.0 - u) * th).sin() / th.sin(), (u * th).sin() / th.sin())
    };
    let q: [f64; 4] = std::array::from_fn(|i| wa * a[i] + wb * b[i]);
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    q.map(|v| v / n)
}

#[test]
fn a_looping_clip_is_one_period_of_its_wind_and_closes_on_itself() {
    let model = aspen();
    let joints = model.exported_joints(0, 1000);
    let settings =
        ClipSettings { seconds: 4.0, fps: 20.0, warmup: 0.0, looped: true, ..Default::default() };
    let c = clip(&model, &joints, &settings);
    // The synthesised wind loops every 4 s; the clip is that period.
    assert_eq!(c.times.len(), 81);
    assert!((c.times[80] - 4.0).abs() < 1e-5);
    assert_eq!(c.palettes[0], c.palettes[80]);
    // After three periods of warm-up the damped sway repeats with its wind: the simulation
    // alone comes back to within a degree of where the period began. And no jump anywhere
    // in the loop, the seam included (the last sample is the first): no joint turns further
    // between samples in the blend than the clip's ordinary largest step before it.
    let step = |a: &[[f32; 12]], b: &[[f32; 12]]| {
        a.iter().zip(b).map(|(p, q)| angle(p, q)).fold(0.0f64, f64::max)
    };
    let ordinary = (1..50).map(|k| step(&c.palettes[k - 1], &c.palettes[k])).fold(0.0, f64::max);
    let blend = (56..=80).map(|k| step(&c.palettes[k - 1], &c.palettes[k])).fold(0.0, f64::max);
    eprintln!(
        "seam the simulation left {:.1}°; largest step {:.2}° before the blend, {:.2}° in it",
        c.seam_deg,
        ordinary.to_degrees(),
        blend.to_degrees()
    );
    assert!(c.seam_deg < 1.0, "the seam the simulation left: {}°", c.seam_deg);
    assert!(blend <= 1.5 * ordinary, "steps in the blend {blend} vs before {ordinary}");
}

#[test]
fn reduced_playback_stays_within_max_error_of_the_simulation() {
    let model = aspen();
    let joints = model.exported_joints(0, 300);
    let settings =
        ClipSettings { seconds: 3.0, fps: 30.0, warmup: 2.0, looped: false, ..Default::default() };
    let c = clip(&model, &joints, &settings);
    let tol = 0.002;
    let glb = export_m(&model, &c, tol, 300);
    let (json, bin) = chunks(&glb);
    let names = node_names(&json);
    let sk = &model.tree.skeleton;
    let mut worst = (0.0f64, 0usize, 0usize);
    for (k, &t) in c.times.iter().enumerate() {
        let world = world_positions(&json, &bin, t);
        for (slot, &j) in joints.iter().enumerate() {
            let node = names.iter().position(|n| *n == format!("joint{j}")).expect("joint node");
            let got = world[node].expect("joint");
            let p = transform(&c.palettes[k][slot], sk.joints()[j].origin);
            let want = [p[0] as f64, p[2] as f64, -p[1] as f64];
            let err = (0..3).map(|i| (got[i] - want[i]).abs()).fold(0.0, f64::max);
            if err > worst.0 {
                worst = (err, j, k);
            }
        }
    }
    assert!(worst.0 <= tol as f64 + 1e-4, "{worst:?}");
}

#[test]
fn a_forest_export_places_each_tree_and_plays_its_own_simulation() {
    use sylva_forest::{Forest, SceneSpec};
    use sylva_tree::gltf::{ForestTree, forest_to_glb};
    let mut spec = SceneSpec::builtin("small").expect("small");
    spec.lod.animation = false;
    let mut forest = Forest::new(&spec).expect("forest");
    for _ in 0..30 {
        forest.step(1.0 / 30.0);
    }
    let joints: Vec<Vec<usize>> =
        forest.species.iter().map(|s| s.model.exported_joints(0, 60)).collect();
    let times = vec![0.0, 0.1];
    let mut poses = Vec::new();
    let mut trees = Vec::new();
    for t in 0..forest.trees() {
        let p = forest.placement(t).expect("tree");
        let js = &joints[p.species as usize];
        let a = forest.tree_palettes(t, js);
        poses.push(a.clone());
        let rot = |ps: &[[f32; 12]]| -> Vec<[f32; 9]> {
            ps.iter().map(sylva_sway::rotation_of).collect()
        };
        trees.push(ForestTree {
            species: p.species as usize,
            position: p.position,
            yaw: p.yaw,
            scale: p.scale,
            animation: Some(JointAnimation {
                name: "sway".into(),
                times: times.clone(),
                joints: js.clone(),
                rotations: vec![rot(&a), rot(&a)],
                max_error: 0.0,
                flutter: Vec::new(),
            }),
        });
    }
    let models: Vec<&TreeModel> = forest.species.iter().map(|s| &s.model).collect();
    let glb = forest_to_glb(&models, &trees, 60, "small");
    let (json, bin) = chunks(&glb);
    assert_eq!(json["skins"].as_array().expect("skins").len(), forest.trees(), "a skin per tree");
    let names = node_names(&json);
    let world = world_positions(&json, &bin, 0.0);
    let mut spread = 0.0f64;
    for (t, tree) in trees.iter().enumerate() {
        let sk = &models[tree.species].tree.skeleton;
        let (s, c) = tree.yaw.sin_cos();
        for (k, &j) in joints[tree.species].iter().enumerate() {
            let node = names.iter().position(|n| *n == format!("tree{t} joint{j}")).expect("node");
            let got = world[node].expect("joint");
            // Sylva world: position + yaw · (scale · palette · origin), then +Z up → +Y up.
            let p = transform(&poses[t][k], sk.joints()[j].origin);
            let q = [
                tree.scale * (c * p[0] - s * p[1]),
                tree.scale * (s * p[0] + c * p[1]),
                tree.scale * p[2],
            ];
            let w = [tree.position[0] + q[0], tree.position[1] + q[1], tree.position[2] + q[2]];
            let want = [w[0] as f64, w[2] as f64, -w[1] as f64];
            let err = (0..3).map(|i| (got[i] - want[i]).abs()).fold(0.0, f64::max);
            assert!(err < 1e-3, "tree {t} joint {j}: {got:?} vs {want:?}");
            spread = spread.max(
                (got[0]
                    - world[names.iter().position(|n| n == "tree0 joint0").expect("root")]
                        .expect("j")[0])
                    .abs(),
            );
        }
    }
    // The trees stand apart (the scene spaces them 9 m).
    assert!(spread > 5.0, "spread {spread} m");
}

#[test]
fn flutter_follows_the_wind_at_the_crown_and_a_looping_clip_closes_it() {
    let model = aspen();
    let joints = model.exported_joints(0, 100);
    let leaves = sylva_sway::LeafParams::default();
    // In a steady wind the flutter's amplitude is the model's at that speed and its phase
    // turns at the model's frequency: 8 m/s → 3 Hz, so 0.1 s between samples is 0.3 cycle.
    let skeleton = &model.tree.skeleton;
    let steady = PointWind::Steady([8.0, 0.0, 0.0]);
    let settings = ClipSettings { seconds: 1.0, fps: 10.0, warmup: 1.0, looped: false, leaves };
    let c = record(skeleton, SwayParams::default(), &steady, &joints, &settings).expect("clip");
    assert_eq!(c.flutter.len(), c.times.len());
    let tau = std::f32::consts::TAU;
    for pair in c.flutter.windows(2) {
        assert!((pair[1].amplitude - leaves.amplitude(8.0)).abs() < 1e-6);
        let turned = (pair[1].phase - pair[0].phase).rem_euclid(tau);
        assert!((turned - 0.3 * tau).abs() < 1e-3, "phase turned {turned} rad in 0.1 s");
    }
    // A looping clip: the last sample's flutter is the first's, and no step between samples
    // turns the phase much further than the wind's own rate allows (f ≤ f0 + f1·|u|).
    let settings =
        ClipSettings { seconds: 4.0, fps: 20.0, warmup: 0.0, looped: true, ..Default::default() };
    let c = clip(&model, &joints, &settings);
    let (first, last) = (c.flutter[0], c.flutter[c.flutter.len() - 1]);
    assert_eq!(first.amplitude, last.amplitude);
    assert!((first.phase - last.phase).abs() < 1e-4, "{first:?} vs {last:?}");
    let fastest = leaves.frequency(40.0) * tau * 0.05;
    for pair in c.flutter.windows(2) {
        let turned = (pair[1].phase - pair[0].phase).rem_euclid(tau);
        assert!(turned > 0.0 && turned < fastest, "phase turned {turned} rad in 0.05 s");
    }
    assert!(c.flutter.iter().any(|l| l.amplitude > 0.05), "strong wind sets the leaves fluttering");
}
