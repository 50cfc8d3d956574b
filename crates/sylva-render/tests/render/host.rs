//! A host application's own drawing and the forest in one frame: the renderer records over
//! the host's colour and depth, so each hides the other by depth.

use sylva_forest::{Forest, FrameData, SceneSpec};
use sylva_render::{DEPTH, Gpu, Headless, wgpu};

use super::{H, W, px};

/// The host's "box": a flat quad over the columns `x0..x1` of the image at NDC depth
/// `depth` (0 near, 1 far), magenta, drawn with a pipeline of the host's own.
fn draw_box(
    gpu: &Gpu,
    enc: &mut wgpu::CommandEncoder,
    (color, depth_view): (&wgpu::TextureView, &wgpu::TextureView),
    (format, samples): (wgpu::TextureFormat, u32),
    (x0, x1, depth): (u32, u32, f32),
) {
    let src = format!(
        "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {{
            let p = array(vec2(-1.0, -1.0), vec2(3.0, -1.0), vec2(-1.0, 3.0));
            return vec4(p[i], {depth:.6}, 1.0);
        }}
        @fragment fn fs() -> @location(0) vec4<f32> {{ return vec4(1.0, 0.0, 1.0, 1.0); }}"
    );
    let dev = &gpu.device;
    let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host box"),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    });
    let pipeline = dev.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("host box"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
        multiview_mask: None,
        cache: None,
    });
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("host"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(&pipeline);
    pass.set_scissor_rect(x0, 0, x1 - x0, H);
    pass.draw(0..3, 0..1);
}

fn magenta(p: [i32; 3]) -> bool {
    p[0] > 200 && p[1] < 40 && p[2] > 200
}

#[test]
fn a_hosts_box_and_the_trees_hide_each_other_by_depth() {
    let spec = SceneSpec::builtin("small").expect("small scene");
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.default_camera();
    let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
    let mut frame = FrameData::with_rows(H);
    forest.step(1.0 / 30.0);
    forest.frame(&camera, W as f32 / H as f32, &mut frame);
    let plain = gpu.render(&frame, &camera).expect("render");
    let target = (gpu.renderer().format(), gpu.renderer().samples());
    // A box right in front of the camera over the left half: the left half is the box's,
    // trees and sky alike; the right half is the forest's own image.
    let near = gpu
        .render_over(&frame, &camera, |g, enc, c, d| {
            draw_box(g, enc, (c, d), target, (0, W / 2, 1e-4))
        })
        .expect("render over");
    for y in (0..H).step_by(7) {
        for x in (0..W / 2 - 1).step_by(5) {
            assert!(
                magenta(px(&near, x, y)),
                "({x}, {y}) behind the box shows {:?}",
                px(&near, x, y)
            );
        }
        for x in (W / 2 + 1..W).step_by(5) {
            assert_eq!(px(&near, x, y), px(&plain, x, y), "({x}, {y}) beside the box");
        }
    }
    // A wall across the whole image far back: the trees in front of it hide it, it hides
    // the sky (and the far ground) behind it.
    let wall = gpu
        .render_over(&frame, &camera, |g, enc, c, d| {
            draw_box(g, enc, (c, d), target, (0, W, 0.9995))
        })
        .expect("render over");
    let (mut trees, mut walled) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let (w, p) = (px(&wall, x, y), px(&plain, x, y));
            if magenta(w) {
                walled += 1;
            } else if w == p {
                trees += 1;
            }
        }
    }
    let n = (W * H) as usize;
    assert!(
        trees > n / 20 && walled > n / 20,
        "in front of the wall {trees}, wall {walled} of {n}"
    );
    // The sky is behind the wall: its top row is the wall's.
    assert!(magenta(px(&wall, W / 2, 0)), "sky over the wall: {:?}", px(&wall, W / 2, 0));
}
