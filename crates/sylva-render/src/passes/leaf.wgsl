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

// Rotate v about the unit axis k by the angle whose cosine is c and sine s (Rodrigues).
fn rotate_axis(v: vec3<f32>, k: vec3<f32>, c: f32, s: f32) -> vec3<f32> {
    return v * c + cross(k, v) * s + k * dot(k, v) * (1.0 - c);
}

// What a card's fragments need, with the light that is the same across the card (its
// normal, depth in the crown and tint are) computed once per vertex instead of once per
// fragment of a dense, overdrawn crown.
struct LeafOut {
    @builtin(position) clip: vec4<f32>,
    // The card's own normal (out of the crown).
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) fade: vec2<f32>,
    @location(4) @interpolate(flat) exposure: f32,
    @location(6) @interpolate(flat) tag: u32,
    // Sky light (times tint and crown occlusion), and the sun's share when fully lit
    // (on the leaf and through it), so a fragment's light is ambient + sun * visibility.
    @location(7) @interpolate(flat) ambient: vec3<f32>,
    @location(8) @interpolate(flat) sun: vec3<f32>,
    // Aerial perspective at the card (fog_at).
    @location(9) @interpolate(flat) fog: vec4<f32>,
    // The point in the shadow cascades (shadow_near, shadow_far).
    @location(10) shadow_near: vec4<f32>,
    @location(11) shadow_far: vec4<f32>,
    // What reaches the leaf through the leaves that shade it (`through_leaves`), less
    // deep inside the crown, so a fragment adds shade * (1 - visibility).
    @location(12) @interpolate(flat) shade: vec3<f32>,
};

@vertex
fn vs_main(v: LeafIn, inst: InstanceIn) -> LeafOut {
    let swing = inst.leaf.y * sin(inst.leaf.x + v.phase);
    let offset = v.center - v.hang;
    var axis = cross(offset, vec3<f32>(0.0, 0.0, 1.0));
    if (dot(axis, axis) < 1e-10) {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    }
    let k = normalize(axis);
    let cs = cos(swing);
    let sn = sin(swing);
    let swung = v.hang + rotate_axis(offset, k, cs, sn);
    let m = palette(inst.palette, v.joint);
    let c = tree_to_world(palette_apply(m, swung), inst.base, inst.scale);
    var r = rotate_z(palette_rotate(m, rotate_axis(v.right, k, cs, sn)), inst.base.w) * inst.scale;
    var u = rotate_z(palette_rotate(m, rotate_axis(v.up, k, cs, sn)), inst.base.w) * inst.scale;
    // Turn the card towards the viewer about the axis between its normal and the new one.
    let n = normalize(cross(r, u));
    let view = towards_viewer(c);
    let ns = select(-n, n, dot(n, view) >= 0.0);
    let nt = normalize(ns + TURN * view);
    let turn_axis = cross(ns, nt);
    let s = length(turn_axis);
    if (s > 1e-5) {
        // Both unit vectors: the turn's sine is |ns x nt|, its cosine ns . nt.
        let c = dot(ns, nt);
        r = rotate_axis(r, turn_axis / s, c, s);
        u = rotate_axis(u, turn_axis / s, c, s);
    }
    let world = c + r * v.corner.x + u * v.corner.y;
    var out: LeafOut;
    out.clip = project(world);
    // Shade by the card's own normal (out of the crown), whichever side is seen.
    out.normal = unit_or_up(n);
    out.uv = v.uv_origin + vec2<f32>(v.corner.x + 0.5, 0.5 - v.corner.y) * v.uv_size;
    out.fade = inst.fade;
    out.exposure = v.exposure;
    out.tag = inst.tag;
    if (!SHADOW) {
        let tint = tree_tint(inst.base);
        let shaded = tint * foliage_occlusion(v.exposure);
        let sky = lighting(out.normal, 0.0);
        out.ambient = shaded * sky;
        out.sun = shaded * (lighting(out.normal, 1.0) - sky + transmitted(out.normal));
        out.shade = shaded * clamp(v.exposure, 0.0, 1.0) * through_leaves();
        out.fog = fog_at(world);
        // Offset towards the sun, not along the normal: a card lit from behind would
        // otherwise look up its shadow behind itself and shade its own glow.
        out.shadow_near = shadow_near(world, globals.sun_dir);
        out.shadow_far = shadow_far(world, globals.sun_dir);
    }
    return out;
}

fn unit_or_up(n: vec3<f32>) -> vec3<f32> {
    if (dot(n, n) < 1e-12) {
        return vec3<f32>(0.0, 0.0, 1.0);
    }
    return normalize(n);
}

@fragment
fn fs_main(in: LeafOut) -> @location(0) vec4<f32> {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    let a = coverage(t.a, fwidth(t.a));
    if (a <= 0.0 || !dither_keeps(in.clip.xy, in.fade)) {
        discard;
    }
    // One bilinear comparison per cascade: a leaf is small and the crown busy enough that
    // the wider filter of bark and ground shows no difference, at a quarter of the reads.
    let sun = cascades_visibility(in.shadow_near, in.shadow_far, true);
    let lit = t.rgb * (in.ambient + sun * in.sun + (1.0 - sun) * in.shade);
    return vec4<f32>(finish(mix_fog(overlay(lit, in.tag), in.fog)).rgb, a);
}

// The shadow pass: only the alpha test, so light passes between the leaves.
@fragment
fn fs_shadow(in: LeafOut) {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    // The cross-fade's share of the texels, as in branch.wgsl's `fs_shadow`.
    if (t.a < 0.5 || !dither_keeps(in.clip.xy, in.fade)) {
        discard;
    }
}

@fragment
fn fs_bake(in: LeafOut) -> BakeOut {
    let t = textureSample(leaf_texture, linear_sampler, in.uv);
    if (t.a < 0.5) {
        discard;
    }
    var out: BakeOut;
    // The crown's inner darkening goes into the albedo the impostor shows.
    out.albedo = vec4<f32>(t.rgb * foliage_occlusion(in.exposure), 1.0);
    // Alpha 1: leaves (thin: some sun shows through).
    out.normal = vec4<f32>(in.normal * 0.5 + 0.5, 1.0);
    return out;
}
