// Ground: the terrain mesh, grass and soil mixed by value noise, lit (trees' shadows from
// the shadow map, the sky it sees past the crowns above) and fogged into the sky at the
// horizon. Around a forest with a woodland surround, distant woodland is painted on it
// (woodland.wgsl, appended to this file: crowns met along the view ray, so that they stand
// up from the ground and hide one another).

struct GroundIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) open: f32,
    @location(3) woodland: f32,
    @location(4) crown_spacing: f32,
    @location(5) canopy: vec3<f32>,
    @location(6) woodland_edge: vec2<f32>,
    @location(7) canopy_dark: vec4<f32>,
};

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) open: f32,
    @location(3) woodland: f32,
    @location(4) @interpolate(flat) crown_spacing: f32,
    @location(5) @interpolate(flat) canopy: vec3<f32>,
    @location(6) @interpolate(flat) woodland_edge: vec2<f32>,
    @location(7) @interpolate(flat) canopy_dark: vec4<f32>,
};

@vertex
fn vs_main(v: GroundIn) -> GroundOut {
    var out: GroundOut;
    out.clip = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.open = v.open;
    out.woodland = v.woodland;
    out.crown_spacing = v.crown_spacing;
    out.canopy = v.canopy;
    out.woodland_edge = v.woodland_edge;
    out.canopy_dark = v.canopy_dark;
    return out;
}

fn hash2(p: vec2<f32>) -> f32 {
    let q = fract(p * vec2<f32>(0.1031, 0.1030));
    let r = q + dot(q, q.yx + 33.33);
    return fract((r.x + r.y) * r.x);
}

fn noise2(p: vec2<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let a = mix(hash2(i), hash2(i + vec2<f32>(1.0, 0.0)), u.x);
    let b = mix(hash2(i + vec2<f32>(0.0, 1.0)), hash2(i + vec2<f32>(1.0, 1.0)), u.x);
    return mix(a, b, u.y);
}

// The same value noise with its gradient: (value, ∂/∂x, ∂/∂y), from the four hashes one
// value takes.
fn noise2_grad(p: vec2<f32>) -> vec3<f32> {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let du = 6.0 * f * (1.0 - f);
    let a = hash2(i);
    let b = hash2(i + vec2<f32>(1.0, 0.0));
    let c = hash2(i + vec2<f32>(0.0, 1.0));
    let k = a - b - c + hash2(i + vec2<f32>(1.0, 1.0));
    let v = a + (b - a) * u.x + (c - a) * u.y + k * u.x * u.y;
    return vec3<f32>(v, du.x * (b - a + k * u.y), du.y * (c - a + k * u.x));
}

@fragment
fn fs_main(in: GroundOut) -> @location(0) vec4<f32> {
    let p = in.world.xy;
    // Metres a pixel spans here (in uniform control flow, before any branch).
    let footprint = length(fwidth(p));
    let pixel_angle = length(fwidth(normalize(in.world - globals.eye)));
    let n = 0.55 * noise2(p * 0.08) + 0.3 * noise2(p * 0.5) + 0.15 * noise2(p * 3.0);
    let grass = vec3<f32>(0.07, 0.15, 0.035);
    let dry = vec3<f32>(0.17, 0.16, 0.07);
    let albedo = mix(grass, dry, smoothstep(0.35, 0.75, n));
    let normal = normalize(in.normal);
    // Under the crowns the floor sees less sky: darker than the clearing, and, past the
    // shadow map's reach, shaded by the canopy it lies under.
    var lit = albedo * lighting(normal, sun_visibility(in.world, normal)) * in.open;
    // Painted woodland where the ground is woodland, and on the meadow where the view ray
    // passes over woodland crowns before it (the ray's farthest point from the forest's
    // centre below the crowns' tops is one of its ends).
    let s = in.crown_spacing;
    let over = in.world + (globals.eye - in.world) * min(CROWN_TOP * s / max(globals.eye.z - in.world.z, 1e-3), 1.0);
    if (in.woodland > 0.0 || (in.woodland_edge.x > 0.0 && length(over.xy) > in.woodland_edge.x - s)) {
        let c = canopy(in.world, s, in.canopy, in.woodland, in.woodland_edge, in.canopy_dark, lit, footprint, pixel_angle);
        // Fogged where the ray meets the crown.
        return finish(apply_fog(c.rgb, mix(globals.eye, in.world, c.a)));
    }
    return finish(apply_fog(lit, in.world));
}
