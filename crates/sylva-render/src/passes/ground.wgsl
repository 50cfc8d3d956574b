// Ground: the terrain mesh, grass and soil mixed by value noise, lit (trees' shadows from
// the shadow map, the sky it sees past the crowns above) and fogged into the sky at the
// horizon. Around a forest with a woodland surround, distant woodland is painted on it:
// crowns on a jittered grid at the given spacing, each a dome lit by the sun, with shaded
// gaps between them.

struct GroundIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) open: f32,
    @location(3) woodland: f32,
    @location(4) crown_spacing: f32,
    @location(5) canopy: vec3<f32>,
};

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) open: f32,
    @location(3) woodland: f32,
    @location(4) @interpolate(flat) crown_spacing: f32,
    @location(5) @interpolate(flat) canopy: vec3<f32>,
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

// Canopy of the painted woodland at `p`: crowns `s` m apart of mean albedo `albedo` (the
// forest's own impostors'), resolved to `detail` (1: each crown drawn, 0: their mean, for
// crowns a few pixels across or less). Returns the lit colour.
fn canopy(p: vec2<f32>, s: f32, albedo: vec3<f32>, detail: f32) -> vec3<f32> {
    // Gaps between crowns: the shaded floor under the canopy, a third of the crowns' albedo.
    let gap = albedo * 0.35 * lighting(vec3<f32>(0.0, 0.0, 1.0), 0.0);
    // The mean, for crowns too small to draw: far woodland is seen at a glancing angle,
    // where crowns hide the gaps between them and show their sunlit upper sides.
    let mean = 0.85 * albedo * lighting(normalize(vec3<f32>(0.0, 0.0, 1.0) + 0.4 * globals.sun_dir), 1.0);
    if (detail <= 0.0) {
        return mean;
    }
    // Nearest crown centre on a jittered grid of cells `s` wide.
    let q = p / s;
    let cell = floor(q);
    var best = 1e9;
    var offset = vec2<f32>(0.0);
    var id = vec2<f32>(0.0);
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let c = cell + vec2<f32>(f32(i), f32(j));
            let centre = c + 0.2 + 0.6 * vec2<f32>(hash2(c), hash2(c + vec2<f32>(17.0, 31.0)));
            let d = q - centre;
            let dd = dot(d, d);
            if (dd < best) {
                best = dd;
                offset = d;
                id = c;
            }
        }
    }
    // A crown of radius 0.6–0.75 spacings, a dome: its normal tilts out towards the rim,
    // and its rim sees less sky. Brightness and hue vary from crown to crown.
    let radius = 0.6 + 0.15 * hash2(id + vec2<f32>(5.0, 3.0));
    let t = sqrt(best) / radius;
    var lit = gap;
    if (t < 1.0) {
        let up = sqrt(1.0 - t * t);
        let n = normalize(vec3<f32>(offset / radius, up));
        let h = hash2(id + vec2<f32>(11.0, 7.0));
        let tint = vec3<f32>(0.8 + 0.4 * h, 0.85 + 0.3 * hash2(id + vec2<f32>(2.0, 9.0)), 0.9 + 0.2 * h);
        lit = albedo * tint * lighting(n, 1.0) * (0.55 + 0.45 * up);
    }
    return mix(mean, lit, detail);
}

@fragment
fn fs_main(in: GroundOut) -> @location(0) vec4<f32> {
    let p = in.world.xy;
    // Metres a pixel spans here (in uniform control flow, before any branch).
    let footprint = length(fwidth(p));
    let n = 0.55 * noise2(p * 0.08) + 0.3 * noise2(p * 0.5) + 0.15 * noise2(p * 3.0);
    let grass = vec3<f32>(0.07, 0.15, 0.035);
    let dry = vec3<f32>(0.17, 0.16, 0.07);
    let albedo = mix(grass, dry, smoothstep(0.35, 0.75, n));
    let normal = normalize(in.normal);
    // Under the crowns the floor sees less sky: darker than the clearing, and, past the
    // shadow map's reach, shaded by the canopy it lies under.
    var lit = albedo * lighting(normal, sun_visibility(in.world, normal)) * in.open;
    if (in.woodland > 0.0) {
        let s = in.crown_spacing;
        let detail = 1.0 - smoothstep(0.12 * s, 0.4 * s, footprint);
        lit = mix(lit, canopy(p, s, in.canopy, detail), in.woodland);
    }
    return finish(apply_fog(lit, in.world));
}
