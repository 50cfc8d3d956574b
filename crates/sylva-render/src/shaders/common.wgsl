// Declarations shared by every pipeline: globals, joint palettes, sampler, helpers.
// The renderer prepends this file to each pipeline's shader.

struct Globals {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // xyz: eye position (m).
    eye: vec4<f32>,
    // xyz: camera right and up in world space (billboards).
    cam_right: vec4<f32>,
    cam_up: vec4<f32>,
    // xyz: unit direction towards the sun; w: its intensity.
    sun: vec4<f32>,
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    // rgb: fog colour; a: density per metre.
    fog: vec4<f32>,
    // x: time (s); y: leaf-atlas cells per side.
    misc: vec4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
// Joint palettes: three rows (rotation | translation) per joint, rest -> animated tree space.
// An instance's joint j sits `stride` palettes after its joint 0 (the simulation keeps the
// palettes of up to 16 instances side by side per joint).
@group(0) @binding(1) var<storage, read> palettes: array<vec4<f32>>;
@group(0) @binding(2) var linear_sampler: sampler;

fn palette_apply(j: u32, p: vec3<f32>) -> vec3<f32> {
    let r0 = palettes[3u * j];
    let r1 = palettes[3u * j + 1u];
    let r2 = palettes[3u * j + 2u];
    return vec3<f32>(dot(r0.xyz, p) + r0.w, dot(r1.xyz, p) + r1.w, dot(r2.xyz, p) + r2.w);
}

fn palette_rotate(j: u32, v: vec3<f32>) -> vec3<f32> {
    let r0 = palettes[3u * j];
    let r1 = palettes[3u * j + 1u];
    let r2 = palettes[3u * j + 2u];
    return vec3<f32>(dot(r0.xyz, v), dot(r1.xyz, v), dot(r2.xyz, v));
}

fn rotate_z(v: vec3<f32>, yaw: f32) -> vec3<f32> {
    let s = sin(yaw);
    let c = cos(yaw);
    return vec3<f32>(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
}

// Tree space -> world: scale, turn by yaw, move to the trunk base (base.xyz, base.w = yaw).
fn tree_to_world(p: vec3<f32>, base: vec4<f32>, scale: f32) -> vec3<f32> {
    return base.xyz + rotate_z(p * scale, base.w);
}

fn sky_colour(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.z, -1.0, 1.0);
    let t = pow(clamp(up, 0.0, 1.0), 0.6);
    var c = mix(globals.sky_horizon.rgb, globals.sky_zenith.rgb, t);
    // Below the horizon the haze continues.
    c = select(c, globals.sky_horizon.rgb * 0.9, up < 0.0);
    let sun = max(dot(dir, globals.sun.xyz), 0.0);
    return c + vec3<f32>(1.0, 0.9, 0.7) * (pow(sun, 600.0) * 4.0 + pow(sun, 12.0) * 0.15);
}

fn apply_fog(colour: vec3<f32>, world: vec3<f32>) -> vec3<f32> {
    let d = distance(world, globals.eye.xyz);
    let f = 1.0 - exp(-globals.fog.a * d);
    return mix(colour, globals.fog.rgb, clamp(f, 0.0, 1.0));
}

// Ambient from the sky plus one directional light.
fn lighting(n: vec3<f32>) -> vec3<f32> {
    let sky = mix(vec3<f32>(0.22, 0.2, 0.16), vec3<f32>(0.32, 0.38, 0.48), 0.5 + 0.5 * n.z);
    let sun = max(dot(n, globals.sun.xyz), 0.0) * globals.sun.w;
    return sky + vec3<f32>(1.0, 0.95, 0.85) * sun;
}
