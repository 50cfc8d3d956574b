// Leaf clusters: camera-facing billboards hung on a joint. Each swings about its hanging
// point by amplitude * sin(tree phase + cluster phase) (the flutter model of sylva-sway),
// then follows its joint's palette. Alpha-tested against the leaf atlas.

struct LeafIn {
    @location(0) center: vec3<f32>,
    @location(1) hang: vec3<f32>,
    @location(2) corner: vec2<f32>,
    // size (m), roll (rad), phase (rad), atlas cell
    @location(3) params: vec4<f32>,
    @location(4) joint: u32,
};

// Rotate v about the unit axis k by angle a (Rodrigues).
fn rotate_axis(v: vec3<f32>, k: vec3<f32>, a: f32) -> vec3<f32> {
    let c = cos(a);
    let s = sin(a);
    return v * c + cross(k, v) * s + k * dot(k, v) * (1.0 - c);
}

@vertex
fn vs_main(v: LeafIn, inst: InstanceIn) -> TreeOut {
    let swing = inst.leaf.y * sin(inst.leaf.x + v.params.z);
    let offset = v.center - v.hang;
    var axis = cross(offset, vec3<f32>(0.0, 0.0, 1.0));
    if (dot(axis, axis) < 1e-10) {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    }
    let swung = v.hang + rotate_axis(offset, normalize(axis), swing);
    let m = palette(inst.palette, inst.stride, v.joint);
    let c = tree_to_world(palette_apply(m, swung), inst.base, inst.scale);
    let s = sin(v.params.y);
    let co = cos(v.params.y);
    let r = vec2<f32>(co * v.corner.x - s * v.corner.y, s * v.corner.x + co * v.corner.y);
    let size = v.params.x * inst.scale;
    let world = c + (globals.cam_right.xyz * r.x + globals.cam_up.xyz * r.y) * size;
    let cells = globals.misc.y;
    let cell = u32(v.params.w + 0.5);
    let n_cells = u32(cells);
    let origin = vec2<f32>(f32(cell % n_cells), f32(cell / n_cells));
    var out: TreeOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    // Shade as a piece of a rounded crown: outward from the branch, tilted up.
    out.normal = rotate_z(palette_rotate(m, offset), inst.base.w) + vec3<f32>(0.0, 0.0, 0.6 * length(offset));
    out.uv = (origin + vec2<f32>(v.corner.x + 0.5, 0.5 - v.corner.y)) / cells;
    return out;
}

@fragment
fn fs_main(in: TreeOut) -> @location(0) vec4<f32> {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    if (t.a < 0.5) {
        discard;
    }
    var n = in.normal;
    if (dot(n, n) < 1e-12) {
        n = vec3<f32>(0.0, 0.0, 1.0);
    }
    let light = lighting(normalize(n));
    // Thin leaves pass some light: a little sun shows through from behind.
    let through = 0.25 * max(-dot(normalize(in.world - globals.eye.xyz), -globals.sun.xyz), 0.0);
    let lit = t.rgb * (light + vec3<f32>(0.5, 0.6, 0.2) * through);
    return vec4<f32>(apply_fog(lit, in.world), 1.0);
}
