// Branches: generalized cylinders skinned to the joint palette of their instance
// (up to four joints per vertex), bark-textured, lit (with the sun's shadow) and fogged;
// the shadow pass draws them into the sun's depth map with the same vertex shader (`fs_shadow`:
// the cross-fade's share only). `fs_bake` writes albedo and
// tree-space normal instead, for the impostor atlas (far.rs).

struct BranchIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) joints: vec4<u32>,
    @location(4) weights: vec4<f32>,
};

struct BranchOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) fade: vec2<f32>,
    // The instance's overlay tag.
    @location(6) @interpolate(flat) tag: u32,
    // Aerial perspective at the vertex (`fog_at`; not in the shadow pass).
    @location(7) fog: vec4<f32>,
};

@vertex
fn vs_main(v: BranchIn, inst: InstanceIn) -> BranchOut {
    var p = vec3<f32>(0.0);
    var n = vec3<f32>(0.0);
    for (var k = 0u; k < 4u; k = k + 1u) {
        let w = v.weights[k];
        if (w > 0.0) {
            let m = palette(inst.palette, v.joints[k]);
            p = p + w * palette_apply(m, v.position);
            n = n + w * palette_rotate(m, v.normal);
        }
    }
    let world = tree_to_world(p, inst.base, inst.scale);
    var out: BranchOut;
    out.clip = project(world);
    out.world = world;
    out.normal = rotate_z(n, inst.base.w);
    out.uv = v.uv;
    out.fade = inst.fade;
    out.tag = inst.tag;
    if (!SHADOW) {
        out.fog = fog_at(world);
    }
    return out;
}

@fragment
fn fs_main(in: BranchOut) -> @location(0) vec4<f32> {
    if (!dither_keeps(in.clip.xy, in.fade)) {
        discard;
    }
    let albedo = textureSample(bark_texture, linear_sampler, in.uv).rgb;
    let n = normalize(in.normal);
    let lit = albedo * lighting(n, sun_visibility(in.world, n));
    return finish(mix_fog(overlay(lit, in.tag), in.fog));
}

// Into the sun's shadow map: a tree cross-fading between two levels (or two instance
// groups) casts from each draw the texels of its share of the fade, as it is seen, so its
// shadow fades with it rather than doubling while it fades and jumping when it ends.
@fragment
fn fs_shadow(in: BranchOut) {
    if (!dither_keeps(in.clip.xy, in.fade)) {
        discard;
    }
}

@fragment
fn fs_bake(in: BranchOut) -> BakeOut {
    var out: BakeOut;
    out.albedo = vec4<f32>(textureSample(bark_texture, linear_sampler, in.uv).rgb, 1.0);
    // Alpha 0: bark (no light shows through).
    out.normal = vec4<f32>(normalize(in.normal) * 0.5 + 0.5, 0.0);
    return out;
}
