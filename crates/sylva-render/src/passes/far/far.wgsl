// Impostors: a far tree as one quad (two triangles) facing the camera, showing the view of
// the tree nearest the direction it is seen from; the quad is a trapezoid around what the
// views show (`outline` in far.rs), as a software rasteriser's cost follows the pixels
// covered, shaded or not. The views are rendered once at start-up
// (far.rs) from `views` directions around the tree at each of `rows` elevations (0, 30°,
// 60°): a tree below a camera looking down shows its crown from above, as full detail
// does, not its side. The quad is centred on the tree's middle and perpendicular to the
// line of sight, as each view's orthographic image plane was. Between two baked directions
// or two elevations, over the middle half of the step between them (VIEW_BAND), the two
// are cross-faded per pixel by a screen-space dither, so a tree seen from a turning
// direction never jumps from one view to the next. Each pixel shows what its line of sight
// meets in the view's depth map (`surface_uv`), not the view's pixel at the same place on
// the quad, so a view baked from a few degrees aside still shows each clump of leaves
// where the tree has it. Lit per pixel from the baked tree-space
// normals like the near trees, swayed by its trunk-top joint: the quad shears with the
// trunk top's displacement, in proportion to height, and with the crown's lean beyond it
// (the static bend of the limbs and twigs in the instance's wind, which the trunk-top
// joint does not carry: `Instance::lean`). Into the sun's shadow map (SHADOW) the
// quad stands upright and faces the sun's azimuth, casting the shadow of the horizontal
// view nearest it. A crown shades its own leaves as an ellipsoid of leaves would
// (`crown_light`).

// One species' impostor: where its views lie in the atlas and how to place the quad.
struct FarSpecies {
    // Trunk-top point (rest pose, tree space), m.
    tip: vec3<f32>,
    // Side of the square each view covers, m.
    extent: f32,
    // Height of the point each view is centred on (tree space), m.
    center: f32,
    // Views around the tree (atlas cells in one row).
    views: u32,
    // The trunk-top joint, whose palette sways the quad.
    joint: u32,
    // Elevations baked (rows of cells), row_step apart from the horizontal up.
    rows: u32,
    // The tree's bounds (tree space, m): radius about the trunk axis and height, which
    // size the quad to what a view at a given elevation covers of its cell.
    radius: f32,
    height: f32,
    // Step between the baked elevations, rad.
    row_step: f32,
    // Half the span of the depth maps about the plane through the views' centre, m.
    depth_range: f32,
    // The crown as an ellipsoid about the trunk axis (tree space): centre height,
    // horizontal and vertical radii, m; and the light's extinction in it, 1/m.
    crown: vec4<f32>,
    // The trapezoid the quad is drawn as, per elevation row (far.rs, `outline`; in a
    // cell's units, x across, y down): its sides x = a + s y as (a left, s left, a right,
    // s right), then its top and bottom.
    outline: array<vec4<f32>, OUTLINE_LEN>,
};

// Vectors of the outline for all rows (far.rs OUTLINE_LEN).
const OUTLINE_LEN: u32 = 6u;

@group(1) @binding(0) var far_albedo: texture_2d<f32>;
@group(1) @binding(1) var far_normal: texture_2d<f32>;
@group(1) @binding(2) var<uniform> far: FarSpecies;
// Each view's depth: 0 … 1 across ±depth_range along the view about its centre plane.
@group(1) @binding(3) var far_depth: texture_2d<f32>;

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
    // The instance's fade (`dither_keeps`' range), then the share of the second baked view
    // and of the second elevation in their cross-fades.
    @location(3) @interpolate(flat) fades: vec4<f32>,
    @location(4) @interpolate(flat) tint: vec3<f32>,
    @location(5) @interpolate(flat) tag: u32,
    @location(7) shadow_near: vec4<f32>,
    @location(8) shadow_far: vec4<f32>,
    // The two baked views nearest the direction seen along, and the two elevations.
    @location(9) @interpolate(flat) views: vec2<u32>,
    @location(11) @interpolate(flat) rows: vec2<u32>,
    // The eye in tree space (tree metres): each pixel's line of sight runs from it through
    // the pixel's point on the quad.
    @location(10) @interpolate(flat) eye_tree: vec3<f32>,
    // The leaves' mean turn (`turn_leaves`): the shear's direction (tree space) and the
    // tilt.
    @location(13) @interpolate(flat) tilt: vec4<f32>,
    // The quad's point in tree space (on the plane through the views' centre), and the
    // line of sight to the tree's middle, which the quad faces.
    @location(14) crown_at: vec3<f32>,
    @location(15) @interpolate(flat) crown_look: vec3<f32>,
};

const TAU: f32 = 6.28318530718;
// Share of the angle between two baked views over which they are cross-faded (centred on
// the half-way direction); outside it one view is shown alone.
const VIEW_BAND: f32 = 0.5;

// Atlas coordinates of place `uv` on the quad in view `k` of row `r`.
fn view_uv(uv: vec2<f32>, k: u32, r: u32) -> vec2<f32> {
    return vec2<f32>((f32(k) + uv.x) / f32(far.views), (f32(r) + uv.y) / f32(far.rows));
}

// Height of the tree's bounds seen in the views of row `r`, m.
fn row_span(r: u32) -> f32 {
    let e = f32(r) * far.row_step;
    return far.height * cos(e) + 2.0 * far.radius * sin(e);
}

// Baked view `k` of row `r` as tree-space axes: its image's right and up, and the
// direction it looks along (as the bake in far.rs places them).
fn view_axes(k: u32, r: u32) -> mat3x3<f32> {
    let a = TAU * f32(k) / f32(far.views);
    let e = f32(r) * far.row_step;
    let ca = cos(a);
    let sa = sin(a);
    let ce = cos(e);
    let se = sin(e);
    return mat3x3<f32>(
        vec3<f32>(sa, -ca, 0.0),
        vec3<f32>(ca * se, sa * se, ce),
        vec3<f32>(ca * ce, sa * ce, -se),
    );
}

// Steps following a line of sight into a view's depth map. Texels over nothing hold the
// depth of what is beside them (far/atlas.rs, `depth_mips`), so a second step finds the
// surface a first one only nears; more steps change nothing measurable
// (docs/decisions/0005-impostors.md).
const SURFACE_STEPS: i32 = 2;

// Place in the cell of the view with `axes` (0 … 1) of point `p` (tree space, from the
// views' centre).
fn cell_uv(p: vec3<f32>, axes: mat3x3<f32>) -> vec2<f32> {
    let uv = vec2<f32>(0.5 + dot(p, axes[0]) / far.extent, 0.5 - dot(p, axes[1]) / far.extent);
    return clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0));
}

// Where view (k, r) shows what the line of sight through the quad's point `at` (tree
// space) meets, `look` its direction: the place in the view's cell, and how far along
// `look` from `at` that is (m, tree space). The point is projected into the view (at `at`
// itself the place is that of the same point seen along the view, which differs from
// `at`'s place on the quad as soon as the view and the line of sight do), the depth the
// view holds there is read, and the point moved along the line of sight to that depth
// (SURFACE_STEPS times). A view baked up to 11.25° round or 15° above the
// line of sight then shows each clump of leaves where the tree has it, not shifted by its
// depth in the crown times the angle between them (about a metre at the edge of a crown of
// 4 m radius).
fn surface_uv(at: vec3<f32>, look: vec3<f32>, k: u32, r: u32, gx: vec2<f32>, gy: vec2<f32>) -> vec3<f32> {
    let axes = view_axes(k, r);
    let p0 = at - vec3<f32>(0.0, 0.0, far.center);
    // The line of sight's advance along the view's axis per metre (the two are within
    // about 20° of each other).
    let along = max(dot(look, axes[2]), 0.5);
    var t = 0.0;
    for (var i = 0; i < SURFACE_STEPS; i++) {
        let p = p0 + look * t;
        let z = textureSampleGrad(far_depth, linear_sampler, view_uv(cell_uv(p, axes), k, r), gx, gy).r;
        let surface = (2.0 * z - 1.0) * far.depth_range;
        t += (surface - dot(p, axes[2])) / along;
    }
    return vec3<f32>(cell_uv(p0 + look * t, axes), t);
}

// The next baked view's share of the cross-fade at `s` (in steps between baked views,
// from the view below): 0 or 1 outside the middle VIEW_BAND of the step.
fn band(s: f32) -> f32 {
    return clamp((fract(s) - 0.5) / VIEW_BAND + 0.5, 0.0, 1.0);
}

// The crown's lean: the shear at the trunk top's height beyond the trunk's own sway (tree
// space, m); and how the same bend turns the leaves: where it takes the vertical on
// average, as its horizontal part along the shear and one minus its vertical part.
struct LeanIn {
    @location(11) shear: vec2<f32>,
    @location(12) tilt: vec2<f32>,
    // How much wider than its tree the impostor is drawn, across the line of sight (1; more
    // for the far trees the forest's thinning keeps).
    @location(13) spread: f32,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: InstanceIn, lean: LeanIn) -> FarOut {
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
    // Elevation of the line of sight to the tree's middle (0 into the shadow map).
    let mid = base + vec3<f32>(0.0, 0.0, far.center * inst.scale);
    var elevation = 0.0;
    if (!SHADOW) {
        let to = globals.eye - mid;
        elevation = atan2(max(to.z, 0.0), max(length(to.xy), 1e-3));
    }
    let e = min(elevation / far.row_step, f32(far.rows - 1u));
    let r0 = min(u32(floor(e)), far.rows - 1u);
    let r1 = min(r0 + 1u, far.rows - 1u);
    // The quad's up edge: perpendicular to the line of sight and to `right`.
    let up = vec3<f32>(d * sin(elevation), cos(elevation));
    // The quad covers of the views' cells (far.extent a side, centred on the tree's
    // middle) what the tree's bounds cover in the two elevations shown: its radius across,
    // and height · cos e + 2 · radius · sin e up (4 % margin), so the empty parts of the
    // cells cost no fragments.
    let span = max(row_span(r0), row_span(r1));
    let half = 0.52 * min(vec2<f32>(2.0 * far.radius, span), vec2<f32>(far.extent));
    // Within that square, the trapezoid around what the two rows' views cover (far.rs,
    // `outline`): on lavapipe an impostor's pixels cost about the same whether shaded or
    // discarded, so the pixels the trapezoid leaves out are what it saves
    // (docs/decisions/0005-impostors.md). It is not widened: the image error is the same
    // without a margin.
    let sides = far.outline[r0 * 2u];
    let ends = far.outline[r0 * 2u + 1u];
    let y = select(ends.x, ends.y, corner.y > 0.5);
    let x = vec2<f32>(sides.x + sides.y * y, sides.z + sides.w * y);
    let across = select(x, vec2<f32>(0.5 * (x.x + x.y)), x.x > x.y);
    let square = half / far.extent;
    let cell_at = clamp(vec2<f32>(select(across.x, across.y, corner.x > 0.5), y), 0.5 - square, 0.5 + square);
    let q = vec2<f32>(cell_at.x - 0.5, 0.5 - cell_at.y) * far.extent;
    // A far tree kept by the thinning is drawn `spread` times its area: wider across the
    // line of sight, and, as the view steepens, taller too (√spread each seen from straight
    // above), so the canopy's gaps close in depth as well; at a grazing view its top stays
    // where it is.
    let taller = pow(max(lean.spread, 1.0), 0.5 * sin(elevation));
    let offset = (right * (q.x * lean.spread / taller) + up * (q.y * taller)) * inst.scale;
    // Sway: the trunk top's displacement and the crown's lean, sheared in with height above
    // the ground: in proportion to it, the trunk top's height moving by the shift (at most
    // 1.5 times it at the quad's top, for a tree whose trunk ends low in its crown). The
    // factor is linear in height through the ground (the quad's bottom corners, below it,
    // move a little the other way), so the foot stays where it stands.
    let z = far.center + offset.z / inst.scale;
    let z_top = far.center + half.y * up.z;
    let per_m = min(1.0 / max(far.tip.z, 0.1), 1.5 / max(z_top, 0.1));
    let m = palette(inst.palette, far.joint);
    let top = palette_apply(m, far.tip) - far.tip + vec3<f32>(lean.shear, 0.0);
    let shift = rotate_z(top, yaw) * inst.scale;
    let p = mid - base + offset + shift * (z * per_m);
    let world = base + p;
    var out: FarOut;
    out.clip = project(world);
    if (!SHADOW) {
        out.fog = fog_at(world);
        // The shadow coordinates are interpolated on the upright plane through the trunk
        // facing the camera, the point moved back to it horizontally (the quad leans back
        // as the camera rises); the fragment moves them to the leaf it shows. The plane
        // sways as the quad does (moved back by the quad's own offset, not to the resting
        // trunk). Offset towards the sun against self-shadowing (the baked normals vary
        // per pixel).
        let across = vec3<f32>(d, 0.0);
        let upright = world - across * dot(offset, across);
        out.shadow_near = shadow_near(upright, globals.sun_dir);
        out.shadow_far = shadow_far(upright, globals.sun_dir);
    }
    out.crown_at = vec3<f32>(0.0, 0.0, far.center) + rotate_z(right * q.x + up * q.y, -yaw);
    // Its length carries the instance's scale (all sixteen locations are taken).
    out.crown_look = rotate_z(vec3<f32>(d * cos(elevation), -sin(elevation)), -yaw) * inst.scale;
    out.uv = vec2<f32>(0.5 + q.x / far.extent, 0.5 - q.y / far.extent);
    out.views = vec2<u32>(k0, (k0 + 1u) % far.views);
    out.rows = vec2<u32>(r0, r1);
    out.yaw = yaw;
    out.fades = vec4<f32>(inst.fade, band(s), band(e));
    out.eye_tree = rotate_z(globals.eye - base, -yaw) / inst.scale;
    out.tint = tree_tint(inst.base);
    out.tag = inst.tag;
    let lean_len = length(lean.shear);
    var w = vec2<f32>(1.0, 0.0);
    if (lean_len > 1e-6) {
        w = lean.shear / lean_len;
    }
    out.tilt = vec4<f32>(w, lean.tilt);
    return out;
}

// A baked leaf normal `n` (tree space) turned as the crown's bend turns its leaves on
// average: the mean of the leaves' rotations, which takes the vertical to s w + c z (w
// the horizontal unit vector along the lean, `tilt` = (s, 1 - c)), taken as a turn in the
// vertical plane through w that also shrinks it (c = the mean cosine) and leaves the
// horizontal across it alone. The light is linear in the normal (as for the coarse mips'
// mean normals), so this lights a texel with the mean of its bent leaves' light: a crown
// in a strong wind darkens as full detail does, its leaves turned from the sky.
fn turn_leaves(n: vec3<f32>, tilt: vec4<f32>) -> vec3<f32> {
    let w = vec3<f32>(tilt.xy, 0.0);
    let a = vec3<f32>(-tilt.y, tilt.x, 0.0);
    let s = tilt.z;
    let c = 1.0 - tilt.w;
    let nw = dot(n, w);
    return a * dot(n, a) + c * (w * nw + vec3<f32>(0.0, 0.0, n.z)) + s * (w * n.z - vec3<f32>(0.0, 0.0, nw));
}

// Where the line `p + t d` (tree space) is inside the crown's ellipsoid: (t in, t out),
// in > out if it misses.
fn crown_chord(p: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let scale = vec3<f32>(far.crown.y, far.crown.y, far.crown.z);
    let q = (p - vec3<f32>(0.0, 0.0, far.crown.x)) / scale;
    let e = d / scale;
    let a = dot(e, e);
    let b = dot(q, e);
    let disc = b * b - a * (dot(q, q) - 1.0);
    if (disc <= 0.0) {
        return vec2<f32>(1.0, 0.0);
    }
    let r = sqrt(disc);
    return vec2<f32>(-b - r, -b + r) / a;
}

// The crown's shade on its own leaves, which the shadow map does not give (the views are
// baked unshadowed, and a leaf behind the tree's own caster is moved up to it): the mean
// sunlight on the leaves a texel may show. Along the line of sight `look` the first leaf
// met lies at an exponentially distributed depth (mean one free path, 1 / extinction) from
// where the line enters the crown's ellipsoid, cut off where it leaves it; the sunlight
// reaching a leaf (towards `sun`, tree space) is dimmed by the leaves between it and the
// ellipsoid's surface (Beer-Lambert), but for the first `lit` of that path, which full
// detail's shadow map leaves lit (`SHADOW_BIAS_TEXELS`, here in tree units). The mean is
// taken at the depths of the distribution's first and third quartiles. 1 where the line of
// sight misses the ellipsoid, and without shadows (full detail then has none either).
// Taken at one depth only, crowns read darker than full detail's
// (docs/decisions/0005-impostors.md).
fn crown_light(at: vec3<f32>, look: vec3<f32>, sun: vec3<f32>, lit: f32) -> f32 {
    let extinction = far.crown.w;
    if (extinction <= 0.0 || globals.shadow_texel <= 0.0) {
        return 1.0;
    }
    let seen = crown_chord(at, look);
    if (seen.x >= seen.y) {
        return 1.0;
    }
    // The share of lines of sight a leaf inside the crown stops.
    let met = 1.0 - exp(-extinction * (seen.y - seen.x));
    var sum = 0.0;
    for (var i = 0u; i < 2u; i++) {
        let depth = -log(1.0 - (0.25 + 0.5 * f32(i)) * met) / extinction;
        let leaf = at + look * (seen.x + depth);
        let to_sun = max(crown_chord(leaf, sun).y - lit, 0.0);
        sum += exp(-extinction * to_sun);
    }
    return 0.5 * sum;
}

// How deep into a full-detail crown, in texels of the shadow map along the sun's rays,
// sunlight reaches before the crown's own leaves shade it: the shadow pass's depth bias
// (slope-scaled, `DepthBiasState` in shared.rs) and the comparison's filter both grow
// with the texel, so a close view's near cascade (texels of 0.1 m) shades a crown almost
// to its surface and a far view's (0.49 m in scenes B to D's last frames) leaves its outer
// layer lit. The crown's shade on an impostor's leaves follows the shadow map's resolution
// with it (`crown_light`). Matched against full detail at rest and in motion: 2 texels
// made the canopy's brightness at rest exact (within 0.2 %) but raised C's error in wind
// (FLIP 0.0800 to 0.0834), as full detail's leaves darken in wind more than an impostor's.
const SHADOW_BIAS_TEXELS: f32 = 1.0;

// The side of a texel of the shadow map's cascade with clip-space matrix `m`, m: the
// cascade spans 2 in clip space across its 1 / shadow_texel texels, and the matrix's first
// row scales world metres into it.
fn cascade_texel(m: mat4x4<f32>) -> f32 {
    let row = vec3<f32>(m[0].x, m[1].x, m[2].x);
    return 2.0 * globals.shadow_texel / max(length(row), 1e-9);
}

// Into the shadow map: where the view nearest the sun's azimuth shows the tree.
@fragment
fn fs_shadow(in: FarOut) {
    let k = select(in.views.x, in.views.y, in.fades.z >= 0.5);
    let a = textureSample(far_albedo, linear_sampler, view_uv(in.uv, k, 0u)).a;
    // The cross-fade's share of the texels, as in branch.wgsl's `fs_shadow`.
    if (a < 0.5 || !dither_keeps(in.clip.xy, in.fades.xy)) {
        discard;
    }
}

@fragment
fn fs_main(in: FarOut) -> @location(0) vec4<f32> {
    // The view is chosen per pixel, so the atlas is sampled with the place's own gradients
    // (a view's cell is 1 / views of the atlas wide): neighbouring pixels showing different
    // views must not read as a jump across the atlas.
    let scale = vec2<f32>(1.0 / f32(far.views), 1.0 / f32(far.rows));
    let gx = dpdx(in.uv) * scale;
    let gy = dpdy(in.uv) * scale;
    // One dither value picks the row (below the row blend: the upper one), then, rescaled
    // to the part it fell in, the view: both cross-fades from one uniform value.
    let u = dither_value(in.clip.yx + vec2<f32>(7.0, 3.0));
    let row_blend = in.fades.w;
    let upper = u < row_blend;
    let v = select((u - row_blend) / max(1.0 - row_blend, 1e-6), u / max(row_blend, 1e-6), upper);
    let r = select(in.rows.x, in.rows.y, upper);
    let k = select(in.views.x, in.views.y, v < in.fades.z);
    // Each pixel follows its own line of sight, from the eye through its point on the quad:
    // across a crown 200 pixels tall seen 110 m off, the lines to its top and to its
    // middle part by about 5°, which moves a leaf 4 m before or behind the quad by 3 to 4
    // pixels. A stand seen from 40° above (`impostor_stand`, 70 / 110 / 170 m):
    // FLIP against full detail 0.242 / 0.189 / 0.077 with the line to the middle for
    // every pixel, 0.231 / 0.183 / 0.075 with each pixel's own.
    let look = normalize(in.crown_at - in.eye_tree);
    let hit = surface_uv(in.crown_at, look, k, r, gx, gy);
    let uv = view_uv(hit.xy, k, r);
    let albedo = textureSampleGrad(far_albedo, linear_sampler, uv, gx, gy);
    let a = coverage(albedo.a, fwidth(albedo.a));
    if (a <= 0.0 || !dither_keeps(in.clip.xy, in.fades.xy)) {
        discard;
    }
    let baked = textureSampleGrad(far_normal, linear_sampler, uv, gx, gy);
    // The mean of the normals under this texel, made longer by the square root of its
    // shortening, half way (in logarithm) to unit length. The sky's share of the light is
    // linear in the normal, but the sun's is not: leaves turned from the sun take none, so
    // the mean of the leaves' light is above the light of their mean normal. Made unit, a
    // distant crown of leaves facing every way came out 5-9 % too bright; left as the mean,
    // a stand without shadows 60 m off read 3.2 % too dark (render tests) once the depth
    // map's empty texels held the depth beside them; so lengthened, 0.9 % too bright.
    let n_mean = baked.xyz * 2.0 - 1.0;
    let n_tree = n_mean / sqrt(max(length(n_mean), 1e-3));
    let turned = turn_leaves(n_tree, in.tilt);
    let n = rotate_z(mix(n_tree, turned, baked.a), in.yaw);
    // What the turn shrinks off the mean normal are leaves turned every which way: their
    // mean light is the sun's over a sphere of normals, a quarter of it on each face, the
    // lit face reflecting and the other passing light through (`transmitted`).
    let scattered = max(length(n_tree) - length(turned), 0.0) * 0.25;
    // Leaf pixels (normal alpha 1) take the tree's colour variation, as near trees do.
    let tint = mix(vec3<f32>(1.0), in.tint, baked.a);
    // The shadow is looked up where the leaf the pixel shows is (the shadow coordinates are
    // affine in the world position): `rel` is that leaf in tree space from the views'
    // centre, `to_leaf` its offset in world metres from the point on the upright plane
    // through the trunk the coordinates were interpolated at.
    let size = length(in.crown_look);
    let q = in.crown_at - vec3<f32>(0.0, 0.0, far.center);
    let rel = q + look * hit.z;
    // Back to the upright plane across the line of sight to the middle, as the vertex
    // stage took the shadow coordinates there.
    let middle = normalize(in.crown_look);
    let across = normalize(vec3<f32>(middle.xy, 0.0));
    var to_leaf = rotate_z(across * dot(q, across) + look * hit.z, in.yaw) * size;
    // The tree casts its shadow from an upright quad through its trunk facing the sun's
    // azimuth. A leaf behind that quad would lie in the shadow of the whole crown's side
    // view, cut off along the trunk (seen from above, each crown showed a dark half with a
    // vertical edge): it is moved along the sun's rays up to the quad (their horizontal
    // part taken as at least a tenth, so the move is bounded), and the crown's shade on
    // its own leaves is `crown_light`'s alone.
    let sun_h = globals.sun_dir.xy;
    if (dot(sun_h, sun_h) > 1e-8) {
        let behind = -dot(rotate_z(vec3<f32>(rel.xy, 0.0), in.yaw) * size, vec3<f32>(normalize(sun_h), 0.0));
        to_leaf += globals.sun_dir * (max(behind, 0.0) / max(length(sun_h), 0.1));
    }
    let near = in.shadow_near + globals.sun_view_proj * vec4<f32>(to_leaf, 0.0);
    let far_c = in.shadow_far + globals.sun_view_proj_far * vec4<f32>(to_leaf, 0.0);
    // The crown's shade on its own leaves stands for what full detail's shadow map gives
    // it, so it follows the map: light reaches as deep as the bias of the cascade the point
    // reads (the two blended as `cascades_visibility` blends them), none of it beyond.
    var near_w = 0.0;
    if (in_cascade(near)) {
        near_w = 1.0 - far_share(near);
    }
    let texel = mix(cascade_texel(globals.sun_view_proj_far), cascade_texel(globals.sun_view_proj), near_w);
    let lit_depth = SHADOW_BIAS_TEXELS * texel / size;
    let own = mix(1.0, crown_light(in.crown_at, look, rotate_z(globals.sun_dir, -in.yaw), lit_depth), cascades_reach(near, far_c));
    let sun = cascades_visibility(near, far_c, true) * own;
    let spread = scattered * globals.sun_intensity * globals.sun_colour * (1.0 + LEAF_TRANSMIT);
    let leaf = sun * (transmitted(n) + spread) + (1.0 - sun) * through_leaves();
    let lit = albedo.rgb * tint * (lighting(n, sun) + baked.a * leaf);
    return vec4<f32>(finish(mix_fog(overlay(lit, in.tag), in.fog)).rgb, a);
}
