// Declarations shared by every pipeline: globals, joint palettes, sampler, helpers.
// The renderer prepends this file to each pipeline's shader.

struct Globals {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // Eye position (m) and simulation time (s).
    eye: vec3<f32>,
    time: f32,
    // Unit direction towards the sun; fog density per metre.
    sun_dir: vec3<f32>,
    fog_density: f32,
    sun_colour: vec3<f32>,
    sun_intensity: f32,
    ambient_sky: vec3<f32>,
    pad2: f32,
    ambient_ground: vec3<f32>,
    pad3: f32,
    sky_zenith: vec3<f32>,
    pad4: f32,
    // Sky at the horizon.
    sky_horizon: vec3<f32>,
    // Exposure before the filmic tone map.
    exposure: f32,
    // World -> the sun's shadow-map clip space (zero: no shadow map).
    sun_view_proj: mat4x4<f32>,
    // One shadow-map texel in texture coordinates (0: no shadow map).
    shadow_texel: f32,
    // Colour overlay of the trees: 0 off, 1 geometry level, 2 instance group.
    overlay: f32,
    pad6: f32,
    pad7: f32,
    // World -> the far cascade's clip space (zero: none).
    sun_view_proj_far: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
// Joint palettes (rest -> animated tree space, 3x4 row-major), as the simulation lays them
// out: element e of an instance's joint j is at base + (12 j + e) * stride, where base and
// stride come with the instance (up to 16 instances' palettes are interleaved). Where
// vertex shaders cannot read storage buffers (WebGL2), the renderer replaces these two
// declarations with a float texture of the same values (`shared::PALETTE_TEXTURE`).
@group(0) @binding(1) var<storage, read> palettes: array<f32>;
fn palette_value(i: u32) -> f32 { return palettes[i]; }
@group(0) @binding(2) var linear_sampler: sampler;
// The sun's shadow map (passes/shadow.rs: two cascades side by side, near on the left) and
// its comparison sampler.
@group(0) @binding(3) var shadow_map: texture_depth_2d;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;

// True in the shadow pass's pipelines: vertex shaders project with the sun's matrix and
// turn cards towards the sun.
override SHADOW: bool = false;

// True where the pipeline turns the fragment's alpha into MSAA sample coverage (alpha to
// coverage): the leaf cards and impostors of a multisampled frame.
override COVERAGE: bool = false;

// Coverage of an alpha-tested texel whose alpha is `alpha`, changing by `width` (fwidth)
// to the next pixel. With alpha to coverage the edge at alpha 0.5 is spread over one
// pixel, so a leaf's outline stays as sharp as the alpha test's close up while getting
// the coverage steps MSAA gives the card's own edges, instead of all samples or none
// (closer to a 64-sample reference: see render.rs's `leaf_edges_come_closer_…`).
// Without it, the alpha test: 1 from alpha 0.5 up, else 0.
fn coverage(alpha: f32, width: f32) -> f32 {
    if (COVERAGE) {
        return clamp((alpha - 0.5) / max(width, 1e-3) + 0.5, 0.0, 1.0);
    }
    return select(0.0, 1.0, alpha >= 0.5);
}

// Clip position of `world` for the pass being drawn (the camera's, or the sun's).
fn project(world: vec3<f32>) -> vec4<f32> {
    if (SHADOW) {
        return globals.sun_view_proj * vec4<f32>(world, 1.0);
    }
    return globals.view_proj * vec4<f32>(world, 1.0);
}

// Unit direction from `world` towards the viewer of the pass (the eye, or the sun).
fn towards_viewer(world: vec3<f32>) -> vec3<f32> {
    if (SHADOW) {
        return globals.sun_dir;
    }
    return normalize(globals.eye - world);
}

// Percentage-closer filtering in one cascade (`half`: 0 near, 0.5 far) at its clip-space
// point `p`: four bilinear comparisons half a texel apart, a 3 x 3 texel footprint.
fn cascade_visibility(p: vec4<f32>, half: f32) -> f32 {
    let uv = vec2<f32>(0.25 + 0.25 * p.x + half, 0.5 - 0.5 * p.y);
    var lit = 0.0;
    for (var k = 0; k < 4; k = k + 1) {
        let o = (vec2<f32>(f32(k & 1), f32(k >> 1u)) - 0.5) * vec2<f32>(0.5, 1.0) * globals.shadow_texel;
        lit = lit + textureSampleCompareLevel(shadow_map, shadow_sampler, uv + o, p.z);
    }
    return lit / 4.0;
}

// Whether clip-space point `p` lies inside its cascade.
fn in_cascade(p: vec4<f32>) -> bool {
    return max(abs(p.x), abs(p.y)) < 1.0 && p.z > 0.0 && p.z < 1.0;
}

// Share of the sun reaching `world` (1 lit, 0 in shadow) from the shadow map's two
// cascades: the near one where it reaches, blending into the far one over its outer fifth,
// and the far one fading to 1 over its own outer tenth.
fn sun_visibility(world: vec3<f32>, normal: vec3<f32>) -> f32 {
    if (globals.shadow_texel <= 0.0) {
        return 1.0;
    }
    return cascades_visibility(shadow_near(world, normal), shadow_far(world, normal), false);
}

// `world` in the near and far cascades' clip spaces, offset along the normal by about a
// texel against self-shadowing. The sun's projection is orthographic, so these are affine
// in `world`: a vertex shader may compute them and let the rasteriser interpolate.
fn shadow_near(world: vec3<f32>, normal: vec3<f32>) -> vec4<f32> {
    return globals.sun_view_proj * vec4<f32>(world + normal * 0.06, 1.0);
}

fn shadow_far(world: vec3<f32>, normal: vec3<f32>) -> vec4<f32> {
    return globals.sun_view_proj_far * vec4<f32>(world + normal * 0.25, 1.0);
}

// `sun_visibility` from the point's positions in the two cascades; `single` reads one
// bilinear comparison (2 x 2 texels) per cascade instead of four.
fn cascades_visibility(p: vec4<f32>, f: vec4<f32>, single: bool) -> f32 {
    if (globals.shadow_texel <= 0.0) {
        return 1.0;
    }
    var far = 1.0;
    if (in_cascade(f)) {
        far = mix(cascade_lookup(f, 0.5, single), 1.0, smoothstep(0.9, 1.0, max(abs(f.x), abs(f.y))));
    }
    if (!in_cascade(p)) {
        return far;
    }
    return mix(cascade_lookup(p, 0.0, single), far, far_share(p));
}

// The far cascade's share where the near one reaches (position `p` in it): 0 inside,
// rising to 1 over the near one's outer fifth.
fn far_share(p: vec4<f32>) -> f32 {
    return smoothstep(0.8, 1.0, max(abs(p.x), abs(p.y)));
}

// How much of the shadow map's shade reaches the point with cascade positions `p`, `f`
// (as `cascades_visibility` weighs them): 1 inside either cascade, falling to 0 over the
// far one's outer tenth and 0 beyond it, where nothing casts a shadow.
fn cascades_reach(p: vec4<f32>, f: vec4<f32>) -> f32 {
    if (globals.shadow_texel <= 0.0) {
        return 0.0;
    }
    if (in_cascade(p)) {
        return 1.0;
    }
    if (in_cascade(f)) {
        return 1.0 - smoothstep(0.9, 1.0, max(abs(f.x), abs(f.y)));
    }
    return 0.0;
}

fn cascade_lookup(p: vec4<f32>, half: f32, single: bool) -> f32 {
    if (single) {
        let uv = vec2<f32>(0.25 + 0.25 * p.x + half, 0.5 - 0.5 * p.y);
        return textureSampleCompareLevel(shadow_map, shadow_sampler, uv, p.z);
    }
    return cascade_visibility(p, half);
}

// Filmic tone map of linear HDR colour (Narkowicz's fit of the ACES curve, 2015), after
// the exposure; the sRGB target encodes the result.
fn finish(colour: vec3<f32>) -> vec4<f32> {
    let x = max(colour * globals.exposure, vec3<f32>(0.0));
    let mapped = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    return vec4<f32>(clamp(mapped, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0);
}

struct Palette {
    r0: vec4<f32>,
    r1: vec4<f32>,
    r2: vec4<f32>,
};

// Joint j's palette of the instance whose slot is (base, stride): sylva-sway's
// `PaletteSlot`, element e at base + (12 j + e) * stride.
fn palette(slot: vec2<u32>, j: u32) -> Palette {
    let stride = slot.y;
    let at = slot.x + 12u * j * stride;
    var m: Palette;
    m.r0 = vec4<f32>(palette_value(at), palette_value(at + stride), palette_value(at + 2u * stride), palette_value(at + 3u * stride));
    m.r1 = vec4<f32>(palette_value(at + 4u * stride), palette_value(at + 5u * stride), palette_value(at + 6u * stride), palette_value(at + 7u * stride));
    m.r2 = vec4<f32>(palette_value(at + 8u * stride), palette_value(at + 9u * stride), palette_value(at + 10u * stride), palette_value(at + 11u * stride));
    return m;
}

fn palette_apply(m: Palette, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(m.r0.xyz, p) + m.r0.w, dot(m.r1.xyz, p) + m.r1.w, dot(m.r2.xyz, p) + m.r2.w);
}

fn palette_rotate(m: Palette, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(m.r0.xyz, v), dot(m.r1.xyz, v), dot(m.r2.xyz, v));
}

// Per-instance inputs of the tree pipelines (sylva-forest's `Instance`, attributes in
// layout.rs): trunk base and yaw, scale, palette slot (base, stride), leaf flutter (phase,
// amplitude), cross-fade range of the dither.
struct InstanceIn {
    @location(5) base: vec4<f32>,
    @location(6) scale: f32,
    @location(7) palette: vec2<u32>,
    @location(8) leaf: vec2<f32>,
    @location(10) fade: vec2<f32>,
    // Overlay tag: bits 0-3 level, 4-7 species, 8-31 instance group.
    @location(9) tag: u32,
};

// The colour overlay (the viewer's): a lit colour tinted by the draw's geometry level
// (full detail white, then yellow, orange, red, magenta, blue; impostors, tagged 15, cyan)
// or by its
// instance group (a colour hashed from species and group), keeping the shading.
fn overlay(lit: vec3<f32>, tag: u32) -> vec3<f32> {
    if (globals.overlay < 0.5) {
        return lit;
    }
    var c: vec3<f32>;
    if (globals.overlay < 1.5) {
        // A chain of selects, not an indexed array (which a CPU rasteriser keeps in memory
        // for every pixel).
        let l = tag & 15u;
        c = vec3<f32>(0.6, 0.6, 0.6);
        c = select(c, vec3<f32>(0.25, 0.35, 1.0), l == 5u);
        c = select(c, vec3<f32>(0.85, 0.2, 0.85), l == 4u);
        c = select(c, vec3<f32>(0.95, 0.15, 0.1), l == 3u);
        c = select(c, vec3<f32>(1.0, 0.55, 0.1), l == 2u);
        c = select(c, vec3<f32>(1.0, 0.9, 0.2), l == 1u);
        c = select(c, vec3<f32>(1.0, 1.0, 1.0), l == 0u);
        c = select(c, vec3<f32>(0.1, 0.9, 0.9), l == 15u);
    } else {
        var h = (tag >> 4u) * 2654435761u;
        h = h ^ (h >> 15u);
        c = vec3<f32>(f32(h & 255u), f32((h >> 8u) & 255u), f32((h >> 16u) & 255u)) / 255.0;
        c = 0.25 + 0.75 * c;
    }
    let grey = dot(lit, vec3<f32>(0.3, 0.6, 0.1));
    return c * (0.4 + 2.0 * grey);
}

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
    let d = dither_value(pixel);
    return d >= fade.x && d < fade.y;
}

// The dither value of a pixel (interleaved gradient noise). Another cross-fade in the same
// draw reads it at transposed, shifted coordinates, which decorrelates the two.
fn dither_value(pixel: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(floor(pixel), vec2<f32>(0.06711056, 0.00583715))));
}

// The tree pipelines' species textures.
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

// The sky's colour looking along `dir`, without the sun's disc: horizon to zenith, the same
// colour below the horizon as at it (no seam), brighter towards the sun.
fn sky_dome(dir: vec3<f32>) -> vec3<f32> {
    let t = pow(clamp(dir.z, 0.0, 1.0), 0.45);
    let c = mix(globals.sky_horizon, globals.sky_zenith, t);
    let sun = max(dot(dir, globals.sun_dir), 0.0);
    return c + vec3<f32>(1.0, 0.9, 0.7) * (pow(sun, 12.0) * 0.25);
}

fn sky_colour(dir: vec3<f32>) -> vec3<f32> {
    let sun = max(dot(dir, globals.sun_dir), 0.0);
    return sky_dome(dir) + vec3<f32>(1.0, 0.9, 0.7) * (pow(sun, 600.0) * 6.0);
}

// Aerial perspective: with distance the colour goes over to the sky's colour in that
// direction (exponential in distance), so the far ground meets the sky without a line.
fn apply_fog(colour: vec3<f32>, world: vec3<f32>) -> vec3<f32> {
    return mix_fog(colour, fog_at(world));
}

// The aerial perspective at `world`: the sky's colour in that direction (rgb) and how much
// of it covers the surface (a). Smooth over a triangle, so vertex shaders compute it once
// per vertex and fragments only mix (`mix_fog`).
fn fog_at(world: vec3<f32>) -> vec4<f32> {
    let d = distance(world, globals.eye);
    let f = 1.0 - exp(-globals.fog_density * d);
    let dir = (world - globals.eye) / max(d, 1e-3);
    return vec4<f32>(sky_dome(dir), clamp(f, 0.0, 1.0));
}

fn mix_fog(colour: vec3<f32>, fog: vec4<f32>) -> vec3<f32> {
    return mix(colour, fog.rgb, fog.a);
}

// Ambient from the sky plus one directional light, `sun` the share of it reaching here.
fn lighting(n: vec3<f32>, sun: f32) -> vec3<f32> {
    let sky = mix(globals.ambient_ground, globals.ambient_sky, 0.5 + 0.5 * n.z);
    let direct = max(dot(n, globals.sun_dir), 0.0) * globals.sun_intensity * sun;
    return sky + globals.sun_colour * direct;
}

// Leaves are thin: the sun that falls on a leaf's inner face comes out of its outer face,
// diffusely and yellower (chlorophyll passes green and absorbs red and blue). `n` is the
// leaf's normal out of the crown, so a leaf on the crown's side away from the sun shows the
// light that came through it: the glow of a crown seen against the sun, at the edges the
// shadow map lets the sun reach. Green leaves transmit about as much as they reflect
// (PROSPECT leaf spectra, Jacquemoud & Baret 1990: both near 0.1 at 550 nm, transmission
// less in red and blue); this is the sun's share, before visibility, times the albedo.
const LEAF_TRANSMIT: vec3<f32> = vec3<f32>(0.75, 0.9, 0.3);
fn transmitted(n: vec3<f32>) -> vec3<f32> {
    let back = max(-dot(n, globals.sun_dir), 0.0);
    return LEAF_TRANSMIT * globals.sun_colour * (globals.sun_intensity * back);
}

// A leaf in the shade of other leaves still gets the sun they let through, green and
// diffuse: a leaf layer passes about a tenth of it (as above) and scatters as much again,
// so the inside of a crown is darker than its sunlit face but not black. The sun's share
// before (1 - visibility), times the albedo.
const LEAF_SHADE_THROUGH: f32 = 0.15;
fn through_leaves() -> vec3<f32> {
    return LEAF_TRANSMIT * globals.sun_colour * (globals.sun_intensity * LEAF_SHADE_THROUGH);
}

// What the impostor bake writes: albedo (alpha 1 where the tree is) and the tree-space unit
// normal as n * 0.5 + 0.5 (alpha: 1 leaf, 0 bark).
struct BakeOut {
    @location(0) albedo: vec4<f32>,
    @location(1) normal: vec4<f32>,
};
