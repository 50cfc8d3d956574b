//! The glTF 2.0 JSON schema's parts that Sylva writes (glTF 2.0 specification, §5).

use serde::Serialize;
use serde_json::json;
use sylva_core::v3::V3;

use super::FLUTTER_TARGETS;

/// A `bufferViews` entry.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct BufferView {
    pub(super) buffer: usize,
    pub(super) byte_offset: usize,
    pub(super) byte_length: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) target: Option<u32>,
}

/// An `accessors` entry.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Accessor {
    /// None: every element zero (glTF §3.6.2.3), as the bark's flutter targets are.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) buffer_view: Option<usize>,
    pub(super) component_type: u32,
    pub(super) count: usize,
    #[serde(rename = "type")]
    pub(super) ty: &'static str,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) min: Vec<f32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) max: Vec<f32>,
}

/// A `nodes` entry: a joint (translation, rotation, children) or a mesh with its skin.
#[derive(Serialize)]
pub(super) struct Node {
    pub(super) name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) translation: Option<V3>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) rotation: Option<[f32; 4]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) scale: Option<V3>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) children: Vec<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) mesh: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) skin: Option<usize>,
}

/// A `skins` entry.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Skin {
    pub(super) inverse_bind_matrices: usize,
    pub(super) skeleton: usize,
    pub(super) joints: Vec<usize>,
}

/// The attributes of a skinned, textured primitive.
#[derive(Serialize)]
pub(super) struct Attributes {
    #[serde(rename = "POSITION")]
    pub(super) position: usize,
    #[serde(rename = "NORMAL")]
    pub(super) normal: usize,
    #[serde(rename = "TEXCOORD_0")]
    pub(super) texcoord: usize,
    #[serde(rename = "JOINTS_0")]
    pub(super) joints: usize,
    #[serde(rename = "WEIGHTS_0")]
    pub(super) weights: usize,
}

/// A morph target: position displacements.
#[derive(Serialize)]
pub(super) struct Target {
    #[serde(rename = "POSITION")]
    pub(super) position: usize,
}

/// A mesh primitive (triangles).
#[derive(Serialize)]
pub(super) struct Primitive {
    pub(super) attributes: Attributes,
    pub(super) indices: usize,
    pub(super) material: usize,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) targets: Vec<Target>,
}

/// A `meshes` entry.
#[derive(Serialize)]
pub(super) struct Mesh {
    pub(super) name: String,
    pub(super) primitives: Vec<Primitive>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) weights: Vec<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) extras: Option<serde_json::Value>,
}

impl Mesh {
    pub(super) fn new(name: String, primitives: Vec<Primitive>) -> Mesh {
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
pub(super) struct Scene {
    pub(super) name: String,
    pub(super) nodes: Vec<usize>,
}

/// The glTF JSON chunk. Typed where the values are computed (f32 fields keep their
/// shortest decimal form), literal JSON for the fixed materials, samplers and textures.
#[derive(Serialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct Gltf {
    pub(super) asset: serde_json::Value,
    pub(super) scene: usize,
    pub(super) scenes: Vec<Scene>,
    pub(super) nodes: Vec<Node>,
    pub(super) meshes: Vec<Mesh>,
    pub(super) skins: Vec<Skin>,
    pub(super) materials: serde_json::Value,
    pub(super) samplers: serde_json::Value,
    pub(super) images: serde_json::Value,
    pub(super) textures: serde_json::Value,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) animations: Vec<serde_json::Value>,
    pub(super) accessors: Vec<Accessor>,
    pub(super) buffer_views: Vec<BufferView>,
    pub(super) buffers: serde_json::Value,
}

/// One channel of the animation: the node it drives, what of it (`rotation` of a joint,
/// `weights` of a mesh node's flutter targets), its time and value accessors.
#[derive(Debug, Clone, Copy)]
pub(super) struct Channel {
    pub(super) node: usize,
    pub(super) path: &'static str,
    pub(super) input: usize,
    pub(super) output: usize,
}
