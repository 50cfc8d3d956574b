//! One species on the GPU: its textures, its meshes at every level and its impostor, as the
//! renderer builds them once per scene.

use sylva_tree::mesh::TreeModel;

use crate::gpu::{Gpu, RenderError};
use crate::passes::far::{BakeContext, FarPass, FarSpeciesGpu, bake_level};
use crate::passes::{branch, leaf};
use crate::shared::{Mesh, box_mips, upload_mips};

/// One species on the GPU: its LOD meshes (branches, leaves), textures and impostor.
#[derive(Debug)]
pub(crate) struct SpeciesGpu {
    pub(crate) lods: Vec<(Option<Mesh>, Option<Mesh>)>,
    /// Per level (the impostor last): joints its draw reads palettes of (highest + 1).
    pub(crate) joints_read: Vec<usize>,
    pub(crate) textures: wgpu::BindGroup,
    pub(crate) far: FarSpeciesGpu,
}

impl SpeciesGpu {
    pub(crate) fn reads(&self, lod: u32) -> usize {
        self.joints_read.get(lod as usize).or(self.joints_read.last()).copied().unwrap_or(1)
    }
}

/// One species on the GPU: its bark and leaf textures (the leaf atlas with opacity-weighted,
/// coverage-preserving mips), its meshes at every level, and its impostor baked.
pub(crate) async fn upload_species(
    gpu: &Gpu,
    m: &TreeModel,
    species_layout: &wgpu::BindGroupLayout,
    far: &FarPass,
    bake: &BakeContext<'_>,
) -> Result<SpeciesGpu, RenderError> {
    let dev = &gpu.device;
    let texture = |img: &sylva_tree::texture::Image, label| {
        let mips = box_mips(&img.rgba, img.width, img.height);
        let format = wgpu::TextureFormat::Rgba8UnormSrgb;
        upload_mips(gpu, &mips, img.width, img.height, format, label)
    };
    let bark = texture(&m.bark, "bark");
    // Leaves: opacity-weighted colour and coverage-preserving alpha in the mips, so
    // far crowns keep their leaves instead of fading out under the alpha test.
    let img = &m.leaves.image;
    let cells = (m.leaves.cells, m.leaves.cells);
    let (mips, _) =
        crate::passes::far::impostor_mips(&img.rgba, &img.rgba, img.width, img.height, cells);
    let srgb = wgpu::TextureFormat::Rgba8UnormSrgb;
    // Mips stop at cells of 4 × 4 texels: a cell of one texel cannot show a card's
    // partial coverage (it would be all leaf or, as rounded, nothing), so cards
    // seen smaller than that take the sparse 4 × 4 pattern and overlap into crowns.
    let cell0 = (img.width / m.leaves.cells.max(1)).max(1);
    let keep = (cell0.max(4).ilog2() - 1) as usize;
    let mips = &mips[..mips.len().min(keep)];
    let leaves = upload_mips(gpu, mips, img.width, img.height, srgb, "leaf atlas");
    let textures = dev.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("species textures"),
        layout: species_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&bark),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(&leaves),
            },
        ],
    });
    let lods: Vec<(Option<Mesh>, Option<Mesh>)> =
        m.lods.iter().map(|l| (branch::mesh(gpu, l), leaf::mesh(gpu, l, m.leaves.cells))).collect();
    let baked = lods.get(bake_level(m));
    let meshes = baked.map(|(b, l)| (b.as_ref(), l.as_ref())).unwrap_or((None, None));
    let far = far.bake(gpu, bake, m, &textures, meshes).await?;
    let mut joints_read: Vec<usize> = m
        .lods
        .iter()
        .map(|l| {
            let b = l.branches.joints.iter().flatten().copied().max().unwrap_or(0);
            let c = l.clusters.iter().map(|c| c.joint).max().unwrap_or(0);
            b.max(c) as usize + 1
        })
        .collect();
    joints_read.push(far.params.joint as usize + 1);
    Ok(SpeciesGpu { lods, joints_read, textures, far })
}
