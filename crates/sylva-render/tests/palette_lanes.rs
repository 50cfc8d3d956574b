//! The palette lane layout, GPU side: `palette()` in common.wgsl, given an instance's
//! `PaletteSlot`, reads on the adapter exactly the palette `PaletteSlot::read` reads on the
//! CPU, for every joint of every drawn tree of a frame (lane groups of several widths).
//! The simulation side is checked in sylva-sway's `tests/lanes.rs`.

mod probe;

use sylva_forest::{Forest, FrameData, PaletteSlot, SceneSpec};

/// The shader under test: common.wgsl's reader, called once per (slot, joint) probe.
const PROBE: &str = r#"
struct Probe { slot: vec2<u32>, joint: u32, pad: u32 };
@group(2) @binding(0) var<storage, read> probes: array<Probe>;
@group(2) @binding(1) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&probes)) { return; }
    let p = probes[id.x];
    let m = palette(p.slot, p.joint);
    let rows = array<vec4<f32>, 3>(m.r0, m.r1, m.r2);
    for (var r = 0u; r < 3u; r++) {
        for (var c = 0u; c < 4u; c++) {
            out[id.x * 12u + r * 4u + c] = rows[r][c];
        }
    }
}
"#;

/// Palettes read on the adapter for each `(slot, joint)`.
fn read_on_gpu(palettes: &[f32], probes: &[(PaletteSlot, u32)]) -> Vec<[f32; 12]> {
    let packed: Vec<[u32; 4]> = probes.iter().map(|(s, j)| [s.base, s.stride, *j, 0]).collect();
    let out = probe::run(
        "common.wgsl",
        PROBE,
        &[(1, bytemuck::cast_slice(palettes))],
        bytemuck::cast_slice(&packed),
        probes.len(),
        probes.len() * 12,
    );
    out.chunks(12).map(|c| std::array::from_fn(|e| c[e])).collect()
}

#[test]
fn the_wgsl_reader_reads_the_palettes_the_slot_addresses() {
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    spec.wind = "storm".into();
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.default_camera();
    let mut frame = FrameData::default();
    for _ in 0..10 {
        forest.step(1.0 / 30.0);
    }
    forest.frame(&camera, 4.0 / 3.0, &mut frame);
    let mut probes = Vec::new();
    for b in &frame.buckets {
        let joints = forest.species[b.species as usize].joints_drawn(b.lod);
        for inst in &frame.instances[b.first as usize..(b.first + b.count) as usize] {
            probes.extend((0..joints as u32).map(|j| (inst.palette, j)));
        }
    }
    let strides: std::collections::BTreeSet<u32> =
        frame.instances.iter().map(|i| i.palette.stride).collect();
    assert!(probes.len() > 100, "{} probes", probes.len());
    let gpu = read_on_gpu(&frame.palettes, &probes);
    let mut moved = 0;
    for (k, (slot, j)) in probes.iter().enumerate() {
        let cpu = slot.read(&frame.palettes, *j as usize).expect("slot inside the frame");
        assert_eq!(gpu[k], cpu, "slot {slot:?}, joint {j}");
        moved += (cpu[3].abs() + cpu[7].abs() > 1e-4) as usize;
    }
    // Palettes in a storm are not the identity, so equal reads compare real numbers.
    assert!(moved > 0, "no palette moved: strides {strides:?}");
}
