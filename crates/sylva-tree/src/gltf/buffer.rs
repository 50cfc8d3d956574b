//! The binary chunk (buffer views, accessors, primitives, morph targets, embedded PNGs)
//! and the `.glb` container around it.

use serde_json::json;
use sylva_core::v3::V3;

use super::*;
use crate::mesh::LeafCluster;
use crate::texture::Image;

/// Binary buffer under construction, with one view per accessor.
pub(super) struct Bin {
    pub(super) data: Vec<u8>,
    pub(super) views: Vec<BufferView>,
    pub(super) accessors: Vec<Accessor>,
}

impl Bin {
    pub(super) fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let byte_offset = self.data.len();
        self.data.extend_from_slice(bytes);
        self.views.push(BufferView { buffer: 0, byte_offset, byte_length: bytes.len(), target });
        self.views.len() - 1
    }

    /// Accessor over `bytes`: component type, count, type name, optional min/max.
    pub(super) fn accessor(
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
    pub(super) fn primitive(
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
    pub(super) fn zero_target(&mut self, count: usize) -> Target {
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
    pub(super) fn target(&mut self, d: &[V3]) -> Target {
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

pub(super) fn f32_bytes<const N: usize>(v: &[[f32; N]]) -> Vec<u8> {
    v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
}

pub(super) fn bounds(p: &[V3]) -> (V3, V3) {
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

pub(super) fn png(img: &Image) -> Vec<u8> {
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

/// The `.glb` bytes: the JSON chunk from these parts and the binary chunk `bin`. Per species
/// `k` of `images` (its bark and leaf images' buffer views), materials `2k` (bark) and
/// `2k + 1` (leaves) and textures of the same numbers.
#[allow(clippy::too_many_arguments)]
pub(super) fn assemble(
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
