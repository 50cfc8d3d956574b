//! The viewer's control panel: egui's triangles drawn over the finished frame (its own
//! pipeline and bind groups come from `egui-wgpu`, whose shader blends in the target's
//! colour space), loading what is already there.

use crate::gpu::Gpu;

/// What one egui frame asks to draw: its tessellated shapes and texture changes.
#[derive(Debug, Default)]
pub struct PanelFrame {
    /// Clipped triangle meshes, in paint order.
    pub primitives: Vec<egui::ClippedPrimitive>,
    /// Font and image textures to create, update or free.
    pub textures: egui::TexturesDelta,
    /// Physical pixels per egui point.
    pub pixels_per_point: f32,
}

/// The panel's pass: egui-wgpu's renderer for one target format.
pub struct PanelPass {
    renderer: egui_wgpu::Renderer,
}

impl std::fmt::Debug for PanelPass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PanelPass").finish_non_exhaustive()
    }
}

impl PanelPass {
    /// A pass drawing into targets of `format` (single-sampled, no depth).
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> PanelPass {
        PanelPass {
            renderer: egui_wgpu::Renderer::new(
                &gpu.device,
                format,
                egui_wgpu::RendererOptions::default(),
            ),
        }
    }

    /// Draw `frame` over `target` (`size` pixels), keeping what the target holds.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        target: &wgpu::TextureView,
        size: [u32; 2],
        frame: &mut PanelFrame,
    ) {
        for (id, deltas) in &frame.textures.set {
            for delta in deltas {
                self.renderer.update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: size,
            pixels_per_point: frame.pixels_per_point.max(0.1),
        };
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("panel") });
        let extra = self.renderer.update_buffers(
            &gpu.device,
            &gpu.queue,
            &mut enc,
            &frame.primitives,
            &screen,
        );
        {
            let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("panel"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            self.renderer.render(&mut pass, &frame.primitives, &screen);
        }
        gpu.queue.submit(extra.into_iter().chain([enc.finish()]));
        for id in &frame.textures.free {
            self.renderer.free_texture(id);
        }
        frame.textures.clear();
    }
}
