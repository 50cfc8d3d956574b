//! The sun's shadow map: the trees' branches and leaf cards drawn from the sun into a depth
//! texture, which every lit pass samples (`sun_visibility` in common.wgsl, four bilinear
//! percentage-closer comparisons). Two cascades lie side by side in it, each
//! [`SHADOW_SIZE`] texels square: the near one an orthographic view of a sphere around the
//! first [`ShadowPass::reach`] metres of the view, the far one of the first
//! [`ShadowPass::far_reach`]; each centre is snapped to whole texels so the shadows do not
//! shimmer as the camera moves. Lit passes read the near cascade where it reaches and blend
//! into the far one over its outer fifth. Trees drawn as impostors cast through
//! `far.wgsl`'s shadow stage: their quad turned to the sun, alpha-tested.
//!
//! The pipelines are the branch and leaf shaders themselves with the `SHADOW` override set:
//! the same skinning and flutter, projected with the sun's matrix, cards turned towards the
//! sun, leaves alpha-tested (`fs_shadow`) so light falls between them.

use sylva_forest::{Camera, ShadowBox};

use crate::layout::{BRANCH_ATTRIBUTES, BranchVertex, LEAF_ATTRIBUTES, LeafVertex};
use crate::layout::{instance_layout, vertex_layout};
use crate::shared::{DEPTH, GlobalsBinding, PipelineSpec, pipeline};

/// Side of each cascade of the shadow map, texels (the forest culls casters for it).
pub const SHADOW_SIZE: u32 = ShadowBox::TEXELS;

/// Cascades of the shadow map, side by side.
pub const CASCADES: u32 = 2;

/// The shadow pass: its two pipelines, the map and a placeholder bound while drawing it.
#[derive(Debug)]
pub struct ShadowPass {
    /// Branches into the map.
    pub branch: wgpu::RenderPipeline,
    /// Leaf cards into the map.
    pub leaf: wgpu::RenderPipeline,
    map: wgpu::TextureView,
    placeholder: wgpu::TextureView,
    /// Comparison sampler of the map.
    sampler: wgpu::Sampler,
}

impl ShadowPass {
    /// Pipelines (with the trees' `layout`) and the map.
    pub fn new(dev: &wgpu::Device, layout: &wgpu::PipelineLayout) -> ShadowPass {
        let spec = |shader, fragment, buffers| PipelineSpec {
            shader,
            fragment,
            layout,
            buffers,
            depth: true,
            cull: None,
            samples: 1,
            targets: &[],
            shadow: true,
            strip: false,
            coverage: false,
        };
        let branch_buffers =
            [Some(vertex_layout::<BranchVertex>(&BRANCH_ATTRIBUTES)), Some(instance_layout())];
        let leaf_buffers =
            [Some(vertex_layout::<LeafVertex>(&LEAF_ATTRIBUTES)), Some(instance_layout())];
        let depth = |size, cascades, label| {
            dev.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: size * cascades,
                    height: size,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: DEPTH,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&wgpu::TextureViewDescriptor::default())
        };
        ShadowPass {
            branch: pipeline(dev, &spec("branch.wgsl", "fs_shadow", &branch_buffers)),
            leaf: pipeline(dev, &spec("leaf.wgsl", "fs_shadow", &leaf_buffers)),
            map: depth(SHADOW_SIZE, CASCADES, "shadow map"),
            placeholder: depth(1, 1, "no shadow map"),
            sampler: dev.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
        }
    }

    /// Group 0's resources with `globals` and `sampler`: (lit) the map to sample, for the
    /// frame's passes; (unlit) a 1 × 1 placeholder in its place, for passes that draw into
    /// the map or must not be shadowed (the impostor bake).
    pub fn bindings<'a>(
        &'a self,
        globals: &'a wgpu::Buffer,
        sampler: &'a wgpu::Sampler,
    ) -> (GlobalsBinding<'a>, GlobalsBinding<'a>) {
        let lit =
            GlobalsBinding { globals, sampler, shadow: &self.map, shadow_sampler: &self.sampler };
        (lit, GlobalsBinding { shadow: &self.placeholder, ..lit })
    }

    /// Open the pass drawing into the map (both cascades cleared), writing `timestamps`
    /// at its start and end when given.
    pub fn begin<'e>(
        &self,
        enc: &'e mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.map,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// Restrict drawing to cascade `k` (0 near, 1 far) of the map.
    pub fn viewport(pass: &mut wgpu::RenderPass<'_>, k: u32) {
        let s = SHADOW_SIZE as f32;
        pass.set_viewport(k as f32 * s, 0.0, s, s, 0.0, 1.0);
    }

    /// How far along the view the far cascade reaches for `camera`, m: four times the near
    /// one, within 160 … 1200 m ([`Camera::shadow_reach`], which the forest culls shadow
    /// casters by).
    pub fn far_reach(camera: &Camera) -> f32 {
        camera.shadow_reach().1
    }

    /// How far along the view the near cascade reaches for `camera`, m: 1.2 × the distance
    /// to the point looked at, within 40 … 250 m.
    pub fn reach(camera: &Camera) -> f32 {
        camera.shadow_reach().0
    }

    /// World → the near cascade's clip space for `camera` (image `aspect`) and the unit
    /// direction towards the sun: an orthographic view along the sun's rays of the sphere
    /// around the first [`ShadowPass::reach`] metres of the view, depth reaching 150 m
    /// beyond it so tall trees outside still cast into it.
    pub fn sun_matrix(camera: &Camera, aspect: f32, sun: [f32; 3]) -> [[f32; 4]; 4] {
        ShadowPass::sun_matrix_reaching(camera, aspect, sun, ShadowPass::reach(camera))
    }

    /// The same for the sphere around the first `reach` metres of the view (the far
    /// cascade: [`ShadowPass::far_reach`]).
    pub fn sun_matrix_reaching(
        camera: &Camera,
        aspect: f32,
        sun: [f32; 3],
        reach: f32,
    ) -> [[f32; 4]; 4] {
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        // Sphere around the view's first `reach` metres (half-depth, corner spread), seen
        // along the sun's rays: the box the forest culls casters by.
        let b = ShadowBox::new(camera, aspect, reach, sun);
        let (centre, radius, r, u, f) = (b.centre, b.radius, b.right, b.up, b.along);
        // Snap the centre to whole texels across the sun's view.
        let texel = 2.0 * radius / SHADOW_SIZE as f32;
        let cr = (dot(centre, r) / texel).round() * texel;
        let cu = (dot(centre, u) / texel).round() * texel;
        let cf = dot(centre, f);
        let depth = radius + ShadowBox::BEYOND;
        let zs = 1.0 / (2.0 * depth);
        // Column-major: m[column][row].
        [
            [r[0] / radius, u[0] / radius, f[0] * zs, 0.0],
            [r[1] / radius, u[1] / radius, f[1] * zs, 0.0],
            [r[2] / radius, u[2] / radius, f[2] * zs, 0.0],
            [-cr / radius, -cu / radius, (depth - cf) * zs, 1.0],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_matrix_maps_the_near_view_inside_the_map_and_depth_along_the_rays() {
        let camera = Camera {
            eye: [-30.0, -20.0, 8.0],
            target: [0.0, 0.0, 5.0],
            fov_deg: 50.0,
            near: 0.5,
            far: 2000.0,
        };
        let sun = [-0.35f32, -0.55, 0.75];
        let n = (sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]).sqrt();
        let sun = [sun[0] / n, sun[1] / n, sun[2] / n];
        let m = ShadowPass::sun_matrix(&camera, 1.5, sun);
        let apply = |p: [f32; 3]| {
            let mut o = [0.0f32; 4];
            for (row, v) in o.iter_mut().enumerate() {
                *v = m[0][row] * p[0] + m[1][row] * p[1] + m[2][row] * p[2] + m[3][row];
            }
            o
        };
        // The point looked at and a tree top beside it lie inside the map.
        for p in [camera.target, [5.0, 3.0, 25.0], camera.eye] {
            let c = apply(p);
            assert!(c[0].abs() < 1.0 && c[1].abs() < 1.0, "{p:?} at {c:?}");
            assert!((0.0..1.0).contains(&c[2]), "{p:?} depth {}", c[2]);
            assert!((c[3] - 1.0).abs() < 1e-6, "orthographic");
        }
        // Moving towards the sun brings a point nearer (smaller depth), across it not.
        let a = apply(camera.target);
        let b = apply([
            camera.target[0] + 3.0 * sun[0],
            camera.target[1] + 3.0 * sun[1],
            camera.target[2] + 3.0 * sun[2],
        ]);
        assert!(b[2] < a[2], "towards the sun is nearer: {} vs {}", b[2], a[2]);
        assert!((b[0] - a[0]).abs() < 1e-4 && (b[1] - a[1]).abs() < 1e-4, "along a ray");
        // The far cascade holds what the near one does and reaches four times as far.
        let far_reach = ShadowPass::far_reach(&camera);
        assert_eq!(far_reach, 4.0 * ShadowPass::reach(&camera));
        let f = ShadowPass::sun_matrix_reaching(&camera, 1.5, sun, far_reach);
        let fwd = [30.0f32, 20.0, -3.0];
        let n = (fwd[0] * fwd[0] + fwd[1] * fwd[1] + fwd[2] * fwd[2]).sqrt();
        let far_point: [f32; 3] =
            std::array::from_fn(|i| camera.eye[i] + fwd[i] / n * 0.9 * far_reach);
        for p in [camera.target, camera.eye, far_point] {
            let c: Vec<f32> = (0..4)
                .map(|row| f[0][row] * p[0] + f[1][row] * p[1] + f[2][row] * p[2] + f[3][row])
                .collect();
            assert!(c[0].abs() < 1.0 && c[1].abs() < 1.0 && (0.0..1.0).contains(&c[2]));
        }
        let near_far = apply(far_point);
        assert!(near_far[0].abs() > 1.0 || near_far[1].abs() > 1.0, "beyond the near cascade");
    }
}
