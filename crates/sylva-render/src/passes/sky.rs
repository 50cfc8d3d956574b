//! Sky: one full-screen triangle, a gradient from horizon to zenith with the sun's glow
//! (`sky.wgsl`). Drawn last, at the far plane and without depth writes, so only the pixels
//! no tree or ground covers run its shader.

use crate::shared::{PipelineSpec, pipeline};

/// The sky pass.
#[derive(Debug)]
pub struct SkyPass {
    pipeline: wgpu::RenderPipeline,
}

impl SkyPass {
    /// The pipeline for colour `format` with `samples` MSAA samples; `layout` holds the
    /// globals.
    pub fn new(
        dev: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> SkyPass {
        let spec = PipelineSpec {
            shader: "sky.wgsl",
            fragment: "fs_main",
            layout,
            buffers: &[],
            depth: false,
            cull: None,
            samples,
            targets: &[format],
            shadow: false,
            strip: false,
            coverage: false,
        };
        SkyPass { pipeline: pipeline(dev, &spec) }
    }

    /// Draw (globals bound at group 0).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.draw(0..3, 0..1);
    }
}
