// Declarations shared by every pipeline: globals, joint palettes, sampler, helpers.
// The renderer prepends this file to each pipeline's shader.

struct Globals {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // Eye position (m) and simulation time (s).
    eye: vec3<f32>,
    time: f32,
    // Camera right and up in world space (billboards); fog density per metre.
    cam_right: vec3<f32>,
    fog_density: f32,
    cam_up: vec3<f32>,
    sun_intensity: f32,
    // Unit direction towards the sun.
    sun_dir: vec3<f32>,
    pad0: f32,
    sun_colour: vec3<f32>,
    pad1: f32,
    ambient_sky: vec3<f32>,
    pad2: f32,
    ambient_ground: vec3<f32>,
    pad3: f32,
    sky_zenith: vec3<f32>,
    pad4: f32,
    // Sky at the horizon; also the fog colour.
    sky_horizon: vec3<f32>,
    pad5: f32,
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

// Per-instance inputs of the tree pipelines (sylva-forest's `Instance`, attributes in
// layout.rs): trunk base and yaw, scale, first palette element, leaf flutter (phase,
// amplitude), palette stride, cross-fade range of the dither.
struct InstanceIn {
    @location(5) base: vec4<f32>,
    @location(6) scale: f32,
    @location(7) palette: u32,
    @location(8) leaf: vec2<f32>,
    @location(9) stride: u32,
    @location(10) fade: vec2<f32>,
};

// Vertex output of the tree pipelines, and their species textures.
struct TreeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) @interpolate(flat) fade: vec2<f32>,
    // Leaves: 1 at the crown's surface … 0 at its centre (1 for bark).
    @location(4) exposure: f32,
    // Leaves: this tree's colour variation (1 for bark).
    @location(5) @interpolate(flat) tint: vec3<f32>,
};

// Ambient occlusion inside a crown: foliage at its centre gets 40 % of the light at its
// surface.
fn foliage_occlusion(exposure: f32) -> f32 {
    return mix(0.4, 1.0, clamp(exposure, 0.0, 1.0));
}

// Colour variation between trees, from the trunk position: brightness ± 10 %, a shift
// between yellower and bluer greens.
fn tree_tint(base: vec4<f32>) -> vec3<f32> {
    let h = fract(sin(dot(base.xy, vec2<f32>(12.9898, 78.233))) * 43758.5453);
    let g = fract(h * 7.31);
    let b = 0.9 + 0.2 * h;
    return b * vec3<f32>(1.0 + 0.12 * (g - 0.5), 1.0, 1.0 - 0.2 * (g - 0.5));
}

// Cross-fade between two levels of a tree: a screen-space dither value in [0, 1) per pixel
// (interleaved gradient noise, Jimenez 2014); a draw keeps the pixels whose value lies in
// its instance's fade range, so the two levels of a fading tree cover complementary pixels.
fn dither_keeps(pixel: vec2<f32>, fade: vec2<f32>) -> bool {
    let d = fract(52.9829189 * fract(dot(floor(pixel), vec2<f32>(0.06711056, 0.00583715))));
    return d >= fade.x && d < fade.y;
}

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
    var c = mix(globals.sky_horizon, globals.sky_zenith, t);
    // Below the horizon the haze continues.
    c = select(c, globals.sky_horizon * 0.9, up < 0.0);
    let sun = max(dot(dir, globals.sun_dir), 0.0);
    return c + vec3<f32>(1.0, 0.9, 0.7) * (pow(sun, 600.0) * 4.0 + pow(sun, 12.0) * 0.15);
}

fn apply_fog(colour: vec3<f32>, world: vec3<f32>) -> vec3<f32> {
    let d = distance(world, globals.eye);
    let f = 1.0 - exp(-globals.fog_density * d);
    return mix(colour, globals.sky_horizon, clamp(f, 0.0, 1.0));
}

// Ambient from the sky plus one directional light.
fn lighting(n: vec3<f32>) -> vec3<f32> {
    let sky = mix(globals.ambient_ground, globals.ambient_sky, 0.5 + 0.5 * n.z);
    let sun = max(dot(n, globals.sun_dir), 0.0) * globals.sun_intensity;
    return sky + globals.sun_colour * sun;
}

// Thin leaves pass some light: a little sun shows through from behind.
fn translucency(world: vec3<f32>) -> vec3<f32> {
    let through = 0.25 * max(-dot(normalize(world - globals.eye), -globals.sun_dir), 0.0);
    return vec3<f32>(0.5, 0.6, 0.2) * through;
}

// What the impostor bake writes: albedo (alpha 1 where the tree is) and the tree-space unit
// normal as n * 0.5 + 0.5 (alpha: 1 leaf, 0 bark).
struct BakeOut {
    @location(0) albedo: vec4<f32>,
    @location(1) normal: vec4<f32>,
};
