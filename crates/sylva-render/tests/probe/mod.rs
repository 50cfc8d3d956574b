//! Running a piece of the renderer's WGSL on the adapter: a compute entry point `cs_main`
//! (workgroups of 64) appended to a shader file, reading its inputs from group 2, binding
//! 0 and writing f32s to group 2, binding 1; group 0 may bind storage buffers the file's
//! own functions read (the palettes, at binding 1).

use sylva_render::Gpu;
use wgpu::util::DeviceExt;

/// Run `probe` appended to shader file `file` (with common.wgsl) over `count` items:
/// `inputs` at group 2 binding 0, `group0` (binding, bytes) storage buffers at group 0;
/// returns the `outputs` f32s it wrote at group 2 binding 1.
pub fn run(
    file: &str,
    probe: &str,
    group0: &[(u32, &[u8])],
    inputs: &[u8],
    count: usize,
    outputs: usize,
) -> Vec<f32> {
    let gpu = Gpu::headless().unwrap_or_else(|e| panic!("{e}"));
    let dev = &gpu.device;
    let src = format!("{}\n{probe}", sylva_render::shader_source(file).expect("shader file"));
    let module = dev.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("probe"),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    });
    let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("probe"),
        layout: None,
        module: &module,
        entry_point: Some("cs_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let storage = |label: &str, bytes: &[u8]| {
        dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let held: Vec<(u32, wgpu::Buffer)> =
        group0.iter().map(|(binding, bytes)| (*binding, storage("group 0", bytes))).collect();
    let input = storage("inputs", inputs);
    let size = (outputs * 4) as u64;
    let out = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let group = |index: u32, entries: &[wgpu::BindGroupEntry<'_>]| {
        dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(index),
            entries,
        })
    };
    let entries0: Vec<wgpu::BindGroupEntry<'_>> = held
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    let groups = [
        group(0, &entries0),
        group(1, &[]),
        group(
            2,
            &[
                wgpu::BindGroupEntry { binding: 0, resource: input.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: out.as_entire_binding() },
            ],
        ),
    ];
    let mut enc = dev.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        for (index, g) in groups.iter().enumerate() {
            pass.set_bind_group(index as u32, g, &[]);
        }
        pass.dispatch_workgroups(count.div_ceil(64) as u32, 1, 1);
    }
    enc.copy_buffer_to_buffer(&out, 0, &readback, 0, size);
    gpu.queue.submit([enc.finish()]);
    let slice = readback.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    dev.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("poll");
    rx.recv().expect("map").expect("map");
    let data = slice.get_mapped_range().expect("mapped");
    bytemuck::cast_slice::<u8, f32>(&data).to_vec()
}
