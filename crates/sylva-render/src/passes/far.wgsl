// Impostors: a far tree as one quad (two triangles) turned about the vertical to face the
// camera, showing the view of the tree (rendered once at start-up from `views` directions
// around it, far.rs) nearest the direction it is seen from. Between two baked views, over
// the middle half of the angle between them (VIEW_BAND), the two are cross-faded per pixel
// by a screen-space dither, so a tree seen from a turning direction never jumps from one
// view to the next. Lit per pixel from the baked tree-space normals like the near trees,
// swayed by its trunk-top joint: the quad shears with the trunk top's displacement, in
// proportion to height. Into the sun's shadow map
// (SHADOW) the quad is turned to face the sun instead, so the tree casts the shadow of the
// view nearest the sun's azimuth.

// One species' impostor: where its views lie in the atlas and how to place the quad.
struct FarSpecies {
    // Trunk-top point (rest pose, tree space), m.
    tip: vec3<f32>,
    // Side of the square each view covers, m.
    extent: f32,
    // Height of the views' bottom edge (tree space), m.
    bottom: f32,
    // Views around the tree (atlas cells in one row).
    views: u32,
    // The trunk-top joint, whose palette sways the quad.
    joint: u32,
    pad0: u32,
};

@group(1) @binding(0) var far_albedo: texture_2d<f32>;
@group(1) @binding(1) var far_normal: texture_2d<f32>;
@group(1) @binding(2) var<uniform> far: FarSpecies;

// What varies smoothly over the quad is computed per vertex and interpolated, as for the
// leaf cards: the aerial perspective (fog_at), the light shining through the leaves, and
// the point's place in the two shadow cascades (affine in the world position). Only the
// baked normal's lighting and the shadow lookups are per pixel.
struct FarOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) fog: vec4<f32>,
    // Place on the quad: x across (0 … 1), y down (0 at the top).
    @location(1) uv: vec2<f32>,
    @location(2) @interpolate(flat) yaw: f32,
    @location(3) @interpolate(flat) fade: vec2<f32>,
    @location(4) @interpolate(flat) tint: vec3<f32>,
    @location(5) @interpolate(flat) tag: u32,
    @location(6) glow: vec3<f32>,
    @location(7) shadow_near: vec4<f32>,
    @location(8) shadow_far: vec4<f32>,
    // The two baked views nearest the direction seen along, and the second's share.
    @location(9) @interpolate(flat) views: vec2<u32>,
    @location(10) @interpolate(flat) blend: f32,
};

const TAU: f32 = 6.28318530718;
// Share of the angle between two baked views over which they are cross-faded (centred on
// the half-way direction); outside it one view is shown alone.
const VIEW_BAND: f32 = 0.5;

// Atlas coordinates of place `uv` on the quad in view `k`.
fn view_uv(uv: vec2<f32>, k: u32) -> vec2<f32> {
    return vec2<f32>((f32(k) + uv.x) / f32(far.views), uv.y);
}

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: InstanceIn) -> FarOut {
    // A quad as one triangle strip per instance: corners (0,0) (1,0) (0,1) (1,1).
    let corner = vec2<f32>(f32(vi & 1u), f32(vi >> 1u));
    let base = inst.base.xyz;
    let yaw = inst.base.w;
    // Direction seen along (eye -> tree, or along the sun's rays), horizontal.
    var d = base.xy - globals.eye.xy;
    if (SHADOW) {
        d = -globals.sun_dir.xy;
    }
    if (dot(d, d) < 1e-8) {
        d = vec2<f32>(1.0, 0.0);
    }
    d = normalize(d);
    let right = vec3<f32>(d.y, -d.x, 0.0);
    // Baked view k looked along azimuth k * TAU / views in tree space: the two either side
    // of this direction, and how far it lies from the first towards the second.
    let n = f32(far.views);
    let azimuth = atan2(d.y, d.x) - yaw;
    let s = ((azimuth / TAU * n) % n + n) % n;
    let k0 = u32(floor(s)) % far.views;
    let blend = clamp((fract(s) - 0.5) / VIEW_BAND + 0.5, 0.0, 1.0);
    let z = far.bottom + corner.y * far.extent;
    var p = right * ((corner.x - 0.5) * far.extent * inst.scale) + vec3<f32>(0.0, 0.0, z * inst.scale);
    // Sway: the trunk top's displacement, sheared in with height.
    let m = palette(inst.palette, far.joint);
    let shift = rotate_z(palette_apply(m, far.tip) - far.tip, yaw) * inst.scale;
    p = p + shift * clamp(z / max(far.tip.z, 0.1), 0.0, 1.5);
    let world = base + p;
    var out: FarOut;
    out.clip = project(world);
    if (!SHADOW) {
        out.fog = fog_at(world);
        out.glow = translucency(world);
        // Offset towards the sun against self-shadowing (the baked normals vary per pixel).
        out.shadow_near = shadow_near(world, globals.sun_dir);
        out.shadow_far = shadow_far(world, globals.sun_dir);
    }
    out.uv = vec2<f32>(corner.x, 1.0 - corner.y);
    out.views = vec2<u32>(k0, (k0 + 1u) % far.views);
    out.blend = blend;
    out.yaw = yaw;
    out.fade = inst.fade;
    out.tint = tree_tint(inst.base);
    out.tag = inst.tag;
    return out;
}

// Into the shadow map: where the view nearest the sun's azimuth shows the tree.
@fragment
fn fs_shadow(in: FarOut) {
    let k = select(in.views.x, in.views.y, in.blend >= 0.5);
    if (textureSample(far_albedo, linear_sampler, view_uv(in.uv, k)).a < 0.5) {
        discard;
    }
}

@fragment
fn fs_main(in: FarOut) -> @location(0) vec4<f32> {
    // The view is chosen per pixel, so the atlas is sampled with the place's own gradients
    // (a view's cell is 1 / views of the atlas wide): neighbouring pixels showing different
    // views must not read as a jump across the atlas.
    let scale = vec2<f32>(1.0 / f32(far.views), 1.0);
    let gx = dpdx(in.uv) * scale;
    let gy = dpdy(in.uv) * scale;
    let k = select(in.views.x, in.views.y, dither_value(in.clip.yx + vec2<f32>(7.0, 3.0)) < in.blend);
    let uv = view_uv(in.uv, k);
    let albedo = textureSampleGrad(far_albedo, linear_sampler, uv, gx, gy);
    let a = coverage(albedo.a, fwidth(albedo.a));
    if (a <= 0.0 || !dither_keeps(in.clip.xy, in.fade)) {
        discard;
    }
    let baked = textureSampleGrad(far_normal, linear_sampler, uv, gx, gy);
    // The mean of the normals under this texel, not made unit again: the sky's share of
    // the light is linear in the normal and the sun's nearly so, so this lights a coarse
    // texel with the mean of its leaves' light, as full detail's pixels average it (made
    // unit, a distant crown of leaves facing every way came out 5-9 % too bright).
    let n = rotate_z(baked.xyz * 2.0 - 1.0, in.yaw);
    // Leaf pixels (normal alpha 1) take the tree's colour variation, as near trees do.
    let tint = mix(vec3<f32>(1.0), in.tint, baked.a);
    let sun = cascades_visibility(in.shadow_near, in.shadow_far, true);
    let lit = albedo.rgb * tint * (lighting(n, sun) + sun * baked.a * in.glow);
    return vec4<f32>(finish(mix_fog(overlay(lit, in.tag), in.fog)).rgb, a);
}
