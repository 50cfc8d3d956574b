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
    let opts = GltfOptions { lods: vec![0], max_joints: 100, name: "fir".into() };
    let bytes = glb("douglas_fir", 1, &opts);
    let json_len = u32_at(&bytes, 12);
    let json = std::str::from_utf8(&bytes[20..20 + json_len]).expect("json");
    assert_eq!(json.matches("\"name\":\"joint").count(), 100);
}
