// Leaf clusters: cards oriented in 3D (out of the crown, tilted to the sky; sylva-tree's
// mesh.rs) and turned part way towards the viewer, so none is seen edge-on, keeping the
// twig's direction. Each swings about its hanging point by amplitude * sin(tree phase +
// cluster phase) (the flutter model of sylva-sway), then follows its joint's palette.
// Alpha-tested against the leaf atlas; darker deeper in the crown (exposure), shadowed by
// the sun's shadow map. In the shadow pass the cards turn towards the sun instead. `fs_bake`
// writes albedo and tree-space normal instead, for the impostor atlas (far.rs).

struct LeafIn {
    @location(0) center: vec3<f32>,
    @location(1) hang: vec3<f32>,
    @location(2) corner: vec2<f32>,
    // The card's right and up edges, each times its side (tree space).
    @location(3) right: vec3<f32>,
    @location(4) up: vec3<f32>,
    @location(15) exposure: f32,
    @location(11) phase: f32,
    @location(12) joint: u32,
    // Top-left of the atlas cell and its side, in texture coordinates.
    @location(13) uv_origin: vec2<f32>,
    @location(14) uv_size: f32,
};

// How far a card turns towards the viewer: its normal moves to normalize(n + TURN * view).
const TURN: f32 = 0.8;

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
    let k = normalize(axis);
    let swung = v.hang + rotate_axis(offset, k, swing);
    let m = palette(inst.palette, v.joint);
    let c = tree_to_world(palette_apply(m, swung), inst.base, inst.scale);
    var r = rotate_z(palette_rotate(m, rotate_axis(v.right, k, swing)), inst.base.w) * inst.scale;
    var u = rotate_z(palette_rotate(m, rotate_axis(v.up, k, swing)), inst.base.w) * inst.scale;
    // Turn the card towards the viewer about the axis between its normal and the new one.
    let n = normalize(cross(r, u));
    let view = towards_viewer(c);
    let ns = select(-n, n, dot(n, view) >= 0.0);
    let nt = normalize(ns + TURN * view);
    let turn_axis = cross(ns, nt);
    let s = length(turn_axis);
    if (s > 1e-5) {
        let a = atan2(s, dot(ns, nt));
        r = rotate_axis(r, turn_axis / s, a);
        u = rotate_axis(u, turn_axis / s, a);
    }
    let world = c + r * v.corner.x + u * v.corner.y;
    var out: TreeOut;
    out.clip = project(world);
    out.world = world;
    // Shade by the card's own normal (out of the crown), whichever side is seen.
    out.normal = n;
    out.uv = v.uv_origin + vec2<f32>(v.corner.x + 0.5, 0.5 - v.corner.y) * v.uv_size;
    out.fade = inst.fade;
    out.exposure = v.exposure;
    out.tint = tree_tint(inst.base);
    out.tag = inst.tag;
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
    let n = leaf_normal(in);
    let sun = sun_visibility(in.world, n);
    let light = lighting(n, sun) * foliage_occlusion(in.exposure);
    let lit = t.rgb * in.tint * (light + sun * translucency(in.world));
    return finish(apply_fog(overlay(lit, in.tag), in.world));
}

// The shadow pass: only the alpha test, so light passes between the leaves.
@fragment
fn fs_shadow(in: TreeOut) {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    if (t.a < 0.5) {
        discard;
    }
}

@fragment
fn fs_bake(in: TreeOut) -> BakeOut {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    if (t.a < 0.5) {
        discard;
    }
    var out: BakeOut;
    // The crown's inner darkening goes into the albedo the impostor shows.
    out.albedo = vec4<f32>(t.rgb * foliage_occlusion(in.exposure), 1.0);
    // Alpha 1: leaves (thin: some sun shows through).
    out.normal = vec4<f32>(leaf_normal(in) * 0.5 + 0.5, 1.0);
    return out;
}
