// Leaf clusters: camera-facing billboards hung on a joint. Each swings about its hanging
// point by amplitude * sin(tree phase + cluster phase) (the flutter model of sylva-sway),
// then follows its joint's palette. Alpha-tested against the leaf atlas. `fs_bake` writes
// albedo and tree-space normal instead, for the impostor atlas (far.rs).

struct LeafIn {
    @location(0) center: vec3<f32>,
    @location(1) hang: vec3<f32>,
    @location(2) corner: vec2<f32>,
    @location(3) size: f32,
    @location(4) roll: f32,
    @location(11) phase: f32,
    @location(12) joint: u32,
    // Top-left of the atlas cell and its side, in texture coordinates.
    @location(13) uv_origin: vec2<f32>,
    @location(14) uv_size: f32,
};

// Rotate v about the unit axis k by angle a (Rodrigues).
fn rotate_axis(v: vec3<f32>, k: vec3<f32>, a: f32) -> vec3<f32> {
    let c = cos(a);
    let s = sin(a);
    return v * c + cross(k, v) * s + k * dot(k, v) * (1.0 - c);
}

@vertex
fn vs_main(v: LeafIn, inst: InstanceIn) -> TreeOut {
    let swing = inst.leaf.y * sin(inst.leaf.x + v.phase);
    let offset = v.center - v.hang;
    var axis = cross(offset, vec3<f32>(0.0, 0.0, 1.0));
    if (dot(axis, axis) < 1e-10) {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    }
    let swung = v.hang + rotate_axis(offset, normalize(axis), swing);
    let m = palette(inst.palette, inst.stride, v.joint);
    let c = tree_to_world(palette_apply(m, swung), inst.base, inst.scale);
    let s = sin(v.roll);
    let co = cos(v.roll);
    let r = vec2<f32>(co * v.corner.x - s * v.corner.y, s * v.corner.x + co * v.corner.y);
    let size = v.size * inst.scale;
    let world = c + (globals.cam_right * r.x + globals.cam_up * r.y) * size;
    var out: TreeOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    // Shade as a piece of a rounded crown: outward from the branch, tilted up.
    out.normal = rotate_z(palette_rotate(m, offset), inst.base.w) + vec3<f32>(0.0, 0.0, 0.6 * length(offset));
    out.uv = v.uv_origin + vec2<f32>(v.corner.x + 0.5, 0.5 - v.corner.y) * v.uv_size;
    out.fade = inst.fade;
    return out;
}

fn leaf_normal(in: TreeOut) -> vec3<f32> {
    var n = in.normal;
    if (dot(n, n) < 1e-12) {
        n = vec3<f32>(0.0, 0.0, 1.0);
    }
    return normalize(n);
}

@fragment
fn fs_main(in: TreeOut) -> @location(0) vec4<f32> {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    if (t.a < 0.5 || !dither_keeps(in.clip.xy, in.fade)) {
        discard;
    }
    let light = lighting(leaf_normal(in));
    let lit = t.rgb * (light + translucency(in.world));
    return vec4<f32>(apply_fog(lit, in.world), 1.0);
}

@fragment
fn fs_bake(in: TreeOut) -> BakeOut {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    if (t.a < 0.5) {
        discard;
    }
    var out: BakeOut;
    out.albedo = vec4<f32>(t.rgb, 1.0);
    // Alpha 1: leaves (thin: some sun shows through).
    out.normal = vec4<f32>(leaf_normal(in) * 0.5 + 0.5, 1.0);
    return out;
}
