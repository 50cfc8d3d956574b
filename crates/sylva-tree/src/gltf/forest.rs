//! A forest's trees as one animated `.glb`: per species one mesh, per tree its own skeleton
//! under a node placing it, with its rotation channels and flutter weights.

use super::*;

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
