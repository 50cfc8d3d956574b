// Ground: the terrain mesh, grass and soil mixed by value noise, lit (trees' shadows from
// the shadow map, the sky it sees past the crowns above) and fogged into the sky at the
// horizon.

struct GroundIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) open: f32,
};

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) open: f32,
};

@vertex
fn vs_main(v: GroundIn) -> GroundOut {
    var out: GroundOut;
    out.clip = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.open = v.open;
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

@fragment
fn fs_main(in: GroundOut) -> @location(0) vec4<f32> {
    let p = in.world.xy;
    let n = 0.55 * noise2(p * 0.08) + 0.3 * noise2(p * 0.5) + 0.15 * noise2(p * 3.0);
    let grass = vec3<f32>(0.07, 0.15, 0.035);
    let dry = vec3<f32>(0.17, 0.16, 0.07);
    let albedo = mix(grass, dry, smoothstep(0.35, 0.75, n));
    let normal = normalize(in.normal);
    // Under the crowns the floor sees less sky: darker than the clearing, and, past the
    // shadow map's reach, shaded by the canopy it lies under.
    let lit = albedo * lighting(normal, sun_visibility(in.world, normal)) * in.open;
    return finish(apply_fog(lit, in.world));
}
