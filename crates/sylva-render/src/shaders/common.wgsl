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
// Joint palettes (rest -> animated tree space, 3x4 row-major), as the simulation lays them
// out: element e of an instance's joint j is at base + (12 j + e) * stride, where base and
// stride come with the instance (up to 16 instances' palettes are interleaved).
@group(0) @binding(1) var<storage, read> palettes: array<f32>;
@group(0) @binding(2) var linear_sampler: sampler;

struct Palette {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
};

fn palette(base: u32, stride: u32, j: u32) -> Palette {
    let at = base + 12u * j * stride;
    var m: Palette;
    m.r0 = vec4<f32>(palettes[at], palettes[at + stride], palettes[at + 2u * stride], palettes[at + 3u * stride]);
    m.r1 = vec4<f32>(palettes[at + 4u * stride], palettes[at + 5u * stride], palettes[at + 6u * stride], palettes[at + 7u * stride]);
    m.r2 = vec4<f32>(palettes[at + 8u * stride], palettes[at + 9u * stride], palettes[at + 10u * stride], palettes[at + 11u * stride]);
    return m;
}

fn palette_apply(m: Palette, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(m.r0.xyz, p) + m.r0.w, dot(m.r1.xyz, p) + m.r1.w, dot(m.r2.xyz, p) + m.r2.w);
}

fn palette_rotate(m: Palette, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(m.r0.xyz, v), dot(m.r1.xyz, v), dot(m.r2.xyz, v));
}

// Per-instance inputs of the tree pipelines (sylva-forest's `Instance`): trunk base and yaw,
// scale, first palette element, leaf flutter (phase, amplitude), palette stride.
struct InstanceIn {
    @location(5) base: vec4<f32>,
    @location(6) scale: f32,
    @location(7) palette: u32,
    @location(8) leaf: vec2<f32>,
    @location(9) stride: u32,
};

// Vertex output of the tree pipelines, and their species textures.
struct TreeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

@group(1) @binding(0) var bark_texture: texture_2d<f32>;
@group(1) @binding(1) var leaf_texture: texture_2d<f32>;

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
