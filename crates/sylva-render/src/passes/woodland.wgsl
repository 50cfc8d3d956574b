// The distant woodland painted on the ground around a forest (`surround = "woodland"`):
// crowns on a jittered grid met along the view ray, lobed spheroids and tiered cones, their
// boughs and leaf clumps. Appended to ground.wgsl (shared.rs), whose fragment shader calls
// `canopy` and whose value noise it uses.

// The painted woodland's crowns, in spacings: a jittered grid of cells one spacing wide,
// each with a crown, a spheroid of radius 0.6–0.75 whose centre stands 1.05 above the
// ground and whose vertical half-axis is 0.85, both scaled by 0.85–1.15 from crown to
// crown (so it reaches from about 0.2 to 2.2 spacings up: 1.4 to 15 m at 7 m spacing).
// A crown stands where a hash of its cell is below the woodland's radial edge at its
// centre, so the woodland thins out crown by crown at its edge.
struct Crown {
    id: vec2<f32>,
    // Its centre: across the ground, and height above it.
    across: vec2<f32>,
    up: f32,
    radius: f32,
    half_height: f32,
    // One of the darker crowns (the forest's darker species): a cone (`enter_cone`),
    // narrower than the others.
    dark: bool,
};

// A crown's mean albedo against its leaves', for the shade among them that the forest's
// own trees show and a smooth spheroid does not. Set by eye in scene D's opening view,
// where it takes the woodland's crowns from 93 to 85 (mean grey level of their band)
// against 75 for the forest's own edge.
const SHADED_CROWN: f32 = 0.75;

// A painted crown's centre height and vertical half-axis, spacings, before its scale of
// 0.85 up to CROWN_SCALE_MAX.
const CROWN_CENTRE: f32 = 1.05;
const CROWN_HALF_HEIGHT: f32 = 0.85;
const CROWN_SCALE_MAX: f32 = 1.15;

// The darker crowns (conifers, in the built-in mixes) are narrower and taller: their
// radius and vertical half-axis against the others'.
const DARK_NARROW: f32 = 0.65;
const DARK_TALL: f32 = 1.15;

// Tallest a painted crown reaches, spacings.
const CROWN_TOP: f32 = (CROWN_CENTRE + CROWN_HALF_HEIGHT * DARK_TALL) * CROWN_SCALE_MAX;

// Where the woodland's crowns stand, spacings: from `start` out from the forest's centre,
// thickening to full over `ramp` (the radial edge of `Woodland::share`; its clearings,
// hundreds of metres across, are not cut crown by crown but faded). `dark`: the share of
// darker crowns.
struct Edge {
    start: f32,
    ramp: f32,
    dark: f32,
};

// The crown of cell `id`, and whether one stands there.
fn crown_of(id: vec2<f32>, edge: Edge) -> Crown {
    var c: Crown;
    c.id = id;
    c.across = id + 0.2 + 0.6 * vec2<f32>(hash2(id), hash2(id + vec2<f32>(17.0, 31.0)));
    let scale = mix(0.85, CROWN_SCALE_MAX, hash2(id + vec2<f32>(13.0, 29.0)));
    c.radius = 0.6 + 0.15 * hash2(id + vec2<f32>(5.0, 3.0));
    c.up = CROWN_CENTRE * scale;
    c.half_height = CROWN_HALF_HEIGHT * scale;
    c.dark = hash2(id + vec2<f32>(37.0, 43.0)) < edge.dark;
    if (c.dark) {
        c.radius *= DARK_NARROW;
        c.half_height *= DARK_TALL;
    }
    // No crown: radius 0, which no ray meets.
    let stands = smoothstep(edge.start, edge.start + edge.ramp, length(c.across));
    if (hash2(id + vec2<f32>(23.0, 41.0)) >= stands) {
        c.radius = 0.0;
    }
    return c;
}

// Where the ray `o + v d` (v ≥ 0) enters crown `c`: v, or a negative number if it misses.
fn enter_crown(o: vec3<f32>, d: vec3<f32>, c: Crown) -> f32 {
    if (c.radius <= 0.0) {
        return -1.0;
    }
    if (c.dark) {
        return enter_cone(o, d, c);
    }
    // In the crown's frame scaled to a unit sphere.
    let scale = vec3<f32>(c.radius, c.radius, c.half_height);
    let p = (o - vec3<f32>(c.across, c.up)) / scale;
    let e = d / scale;
    let a = dot(e, e);
    let b = dot(p, e);
    let k = dot(p, p) - 1.0;
    let disc = b * b - a * k;
    if (disc < 0.0) {
        return -1.0;
    }
    let v = (-b - sqrt(disc)) / a;
    if (v >= 0.0) {
        return v;
    }
    // Starting inside the crown.
    return select(-1.0, 0.0, k <= 0.0);
}

// A darker crown is a cone: its apex at the top of the crown's span (up + half_height),
// widening to CONE_BASE times its radius at the bottom (up - half_height), as a
// conifer's crown does; a spheroid reads as a broadleaf's. At most 1.5 · 0.65 · 0.75 =
// 0.73 spacings, within the 0.75 the march's cells assume.
const CONE_BASE: f32 = 1.5;
// What a cone shows of itself in a canopy seen at a glancing angle (its upper side)
// against a spheroid of the same radius; ground.rs's CONE_SHOWN, the same value.
const CONE_SHOWN: f32 = 0.6;

// The cone's slope: its radius per unit of depth below the apex.
fn cone_slope(c: Crown) -> f32 {
    return CONE_BASE * c.radius / (2.0 * c.half_height);
}

// Where the ray `o + v d` (v ≥ 0) enters the cone of darker crown `c`: v, or a negative
// number if it misses. The base, facing down, is never met by the descending rays the
// canopy traces, so only the mantle is.
fn enter_cone(o: vec3<f32>, d: vec3<f32>, c: Crown) -> f32 {
    let q = o - vec3<f32>(c.across, c.up + c.half_height);
    let k2 = cone_slope(c) * cone_slope(c);
    let depth = 2.0 * c.half_height;
    // On the mantle: q.x² + q.y² = k² q.z², with -depth ≤ q.z ≤ 0.
    let a = d.x * d.x + d.y * d.y - k2 * d.z * d.z;
    let b = q.x * d.x + q.y * d.y - k2 * q.z * d.z;
    let f = q.x * q.x + q.y * q.y - k2 * q.z * q.z;
    if (f <= 0.0 && q.z <= 0.0 && q.z >= -depth) {
        // Starting inside the crown.
        return 0.0;
    }
    let disc = b * b - a * f;
    if (disc < 0.0 || abs(a) < 1e-9) {
        return -1.0;
    }
    let root = sqrt(disc);
    let v0 = (-b - root) / a;
    let v1 = (-b + root) / a;
    var v = 1e9;
    for (var i = 0; i < 2; i++) {
        let t = select(v1, v0, i == 0);
        let z = q.z + t * d.z;
        if (t >= 0.0 && z <= 0.0 && z >= -depth) {
            v = min(v, t);
        }
    }
    return select(-1.0, v, v < 1e9);
}

// A broadleaf's crown is not a ball: boughs stand out past the hollows between them, so
// its outline is lobed. In the crown's frame scaled to a unit sphere, a ray that passes
// the centre closer than 1 - LOBE_DEPTH meets the crown; one that passes nearer the rim
// meets it only where the lobe there reaches out that far. The lobes are value noise over
// the direction from the centre (LOBE_FREQ cells per unit of its projection: some ten
// lobes around the rim), cutting the rim in by up to LOBE_DEPTH. A ray that passes a lobe
// goes on to whatever lies behind. They fade out, the outline round again, where a pixel
// spans LOBE_FADE spacings: a crown there is about ten to five pixels across, a lobe two
// or three.
const LOBE_DEPTH: f32 = 0.3;
const LOBE_FREQ: f32 = 2.0;
const LOBE_FADE: vec2<f32> = vec2<f32>(0.15, 0.3);
// How much a bough's slope bends a crown's normal, and how much darker its hollows are
// (and lighter its tops).
const BOUGH_BEND: f32 = 0.1;
const BOUGH_SHADE: f32 = 0.2;

// A conifer's outline steps in tiers, as its whorls of branches droop: over its span
// TIERS tiers (their phase per crown), each widest at its foot and TIER_DEPTH of the
// cone's radius narrower at its top, half to one and a half times that about the axis
// (value noise over the direction from it). A ray is tested where it passes the axis
// closest across the ground, against the tier's radius at that height. They fade out
// with the lobes.
const TIERS: f32 = 6.0;
const TIER_DEPTH: f32 = 0.3;

// Whether the ray `o + v d`, which enters crown `c`'s spheroid or cone, passes outside
// its outline, lobed or in tiers (a pixel spanning `pixel` spacings there).
fn past_outline(o: vec3<f32>, d: vec3<f32>, c: Crown, pixel: f32) -> bool {
    let fade = 1.0 - smoothstep(LOBE_FADE.x, LOBE_FADE.y, pixel);
    if (fade <= 0.0) {
        return false;
    }
    if (c.dark) {
        return past_tiers(o, d, c, fade);
    }
    let scale = vec3<f32>(c.radius, c.radius, c.half_height);
    let p = (o - vec3<f32>(c.across, c.up)) / scale;
    let e = d / scale;
    // The ray's point nearest the centre, and how near.
    let closest = p - e * (dot(p, e) / max(dot(e, e), 1e-12));
    let m = length(closest);
    let inner = 1.0 - LOBE_DEPTH * fade;
    if (m <= inner) {
        return false;
    }
    let lobe = bough_height(bough_coords(closest / max(m, 1e-6), c.id)).x;
    return m > mix(inner, 1.0, lobe);
}

// Whether the ray `o + v d` passes conifer `c` outside its tiers, cut in by `fade` of
// TIER_DEPTH.
fn past_tiers(o: vec3<f32>, d: vec3<f32>, c: Crown, fade: f32) -> bool {
    // From the apex: where the ray's track passes the axis closest.
    let q = o - vec3<f32>(c.across, c.up + c.half_height);
    let a = q + d * (-dot(q.xy, d.xy) / max(dot(d.xy, d.xy), 1e-12));
    let below = -a.z;
    let span = 2.0 * c.half_height;
    if (below <= 0.0 || below >= span) {
        return false;
    }
    let h = length(a.xy);
    // Within the tier, 0 at its top to 1 at its foot.
    let s = fract(TIERS * below / span + hash2(c.id + vec2<f32>(29.0, 3.0)));
    let around = 0.5 + noise2(3.0 * a.xy / max(h, 1e-6) + 5.3 * c.id);
    return h > cone_slope(c) * below * (1.0 - TIER_DEPTH * fade * around * (1.0 - s));
}

// Where direction `u` from a crown's centre (unit, crown space) falls on the boughs'
// noise: projected along a slanted axis, so the lobes vary with height as well as around.
fn bough_coords(u: vec3<f32>, id: vec2<f32>) -> vec2<f32> {
    return LOBE_FREQ * vec2<f32>(u.x + 0.6 * u.z, u.y - 0.6 * u.z) + 5.3 * id;
}

// How far the bough at `q` stands out, 0 (a hollow) to 1, and its gradient: two octaves
// of value noise, its contrast raised so that boughs and hollows are distinct.
fn bough_height(q: vec2<f32>) -> vec3<f32> {
    let x = 0.7 * noise2_grad(q) + 0.3 * noise2_grad(2.7 * q + vec2<f32>(3.0, 11.0)) * vec3<f32>(1.0, 2.7, 2.7);
    let t = clamp((x.x - 0.2) / 0.6, 0.0, 1.0);
    return vec3<f32>(t * t * (3.0 - 2.0 * t), x.yz * (6.0 * t * (1.0 - t) / 0.6));
}

// Farthest the march walks across the ground, spacings; past it, the canopy's mean.
const MARCH_REACH: f32 = 32.0;
// Most cell boundaries the march's track crosses within MARCH_REACH: 32 √2 ≈ 45.3 at
// worst (a diagonal track), rounded up.
const MARCH_CELLS: i32 = 48;

// The crown of cell `id`, if the ray `o + v d` enters it before `nearest` (kept as `hit`,
// the one before becoming `hit2`) or before `second` (kept as `hit2`).
fn meet(id: vec2<f32>, o: vec3<f32>, d: vec3<f32>, edge: Edge, nearest: ptr<function, f32>, second: ptr<function, f32>, hit: ptr<function, Crown>, hit2: ptr<function, Crown>) {
    let c = crown_of(id, edge);
    let t = enter_crown(o, d, c);
    if (t >= 0.0 && t < *second) {
        if (t < *nearest) {
            *second = *nearest;
            *hit2 = *hit;
            *nearest = t;
            *hit = c;
        } else {
            *second = t;
            *hit2 = c;
        }
    }
}

// Canopy of the painted woodland seen along the ray from the eye to ground point `world`:
// crowns `s` m apart (see `Crown`) whose leaves have the mean albedo `leaves` (the forest's
// own impostors'),
// standing past `edge` (m) and faded in clearings to the share `share`, over `ground` (the
// lit ground where no crown stands). The view ray is met with the crowns it passes,
// so seen at a glancing angle they stand up and hide the gaps between them, as a canopy
// does. Crowns and floor a few pixels across or less are drawn as their mean: `footprint`
// is the metres a pixel spans on the ground point, `pixel_angle` the angle it spans
// (radians), which sizes the crowns.
// Returns the lit colour, and where along the ray from the eye to the ground point it lies
// (0 to 1).
fn canopy(
    world: vec3<f32>,
    s: f32,
    leaves: vec3<f32>,
    share: f32,
    edge_m: vec2<f32>,
    dark: vec4<f32>,
    ground: vec3<f32>,
    footprint: f32,
    pixel_angle: f32,
) -> vec4<f32> {
    // A crown is its leaves and the shade within it: SHADED_CROWN of their albedo.
    let albedo = SHADED_CROWN * leaves;
    // The floor under the canopy: shaded, a third of the crowns' albedo.
    let gap = mix(ground, albedo * 0.35 * lighting(vec3<f32>(0.0, 0.0, 1.0), 0.0), share);
    // The mean, for crowns too small to draw: far woodland is seen at a glancing angle,
    // where crowns hide the gaps between them and show their sunlit upper sides.
    let mean = mix(ground, 0.85 * albedo * lighting(normalize(vec3<f32>(0.0, 0.0, 1.0) + 0.4 * globals.sun_dir), 1.0), share);
    // In spacings, heights above the ground point: the ray from where it comes down
    // through the crowns' tops (or from the eye, if that is lower) to the ground point.
    let to_eye = (globals.eye - world) / s;
    let length_to_eye = max(length(to_eye), 1e-6);
    let back = to_eye / length_to_eye;
    // How fully a crown `r` spacings from the eye is resolved (1: each crown drawn, 0:
    // the mean).
    let per_spacing = pixel_angle;
    let floor_detail = 1.0 - smoothstep(0.12 * s, 0.4 * s, footprint);
    let start = min(CROWN_TOP / max(back.z, 1e-6), 0.999 * length_to_eye);
    let start_detail = 1.0 - smoothstep(0.12, 0.4, per_spacing * (length_to_eye - start));
    // Nor where the aerial perspective leaves less than a twentieth of the nearest crown
    // the ray can meet (the far woodland under the haze near the horizon).
    let haze = 1.0 - exp(-globals.fog_density * (length_to_eye - start) * s);
    if (back.z <= 1e-4 || start_detail <= 0.0 || haze > 0.95) {
        return vec4<f32>(mix(mean, gap, floor_detail), 1.0);
    }
    let q0 = world.xy / s;
    let edge = Edge(edge_m.x / s, max(edge_m.y / s, 1e-3), dark.w);
    // What clearings leave of the woodland here (1 but in clearings): the share over its
    // radial edge, taken smoothly from the middle of the edge on (nearer the start both
    // are small, and their ratio is the mesh's interpolation more than the clearings).
    let radial = smoothstep(edge.start, edge.start + edge.ramp, length(q0));
    let ratio = clamp(share / max(radial, 1e-3), 0.0, 1.0);
    let past_middle = smoothstep(edge.start + 0.5 * edge.ramp, edge.start + edge.ramp, length(q0));
    let clearing = mix(1.0, ratio, past_middle);
    let o = vec3<f32>(q0, 0.0) + back * start;
    let d = -back;
    // Every crown the ray can meet has its centre in a cell next to the cell where the
    // ray's track on the ground enters it (a centre lies 0.2–0.8 into its cell, a crown
    // reaches at most 0.75 from it). Walk the cells the track crosses, one boundary at a
    // time, with the nine cells about the first and the three new ones each step brings
    // (the far row or column), until the track enters a cell past the nearest crown met,
    // the ground point, or MARCH_REACH spacings. Each step meets three crowns in every
    // pixel alike, so neighbouring pixels run it together.
    let across = max(length(d.xy), 1e-6);
    let reach = min(start, MARCH_REACH / across);
    let toward = select(vec2<f32>(-1.0), vec2<f32>(1.0), d.xy >= vec2<f32>(0.0));
    // Ray parameter per cell crossed, and to the track's next boundary on each axis.
    let moving = abs(d.xy) > vec2<f32>(1e-9);
    let per_cell = select(vec2<f32>(1e9), 1.0 / abs(d.xy), moving);
    let boundary = floor(o.xy) + max(toward, vec2<f32>(0.0));
    // The march keeps the two nearest crowns the ray enters. A crown it passes by its lobes
    // (`past_outline`) is not a hit: the march then walks on until the second is sure to be
    // the nearest after it, and that one is kept (whatever its lobes). The lobes are
    // tested once per pixel, not in `meet`, which keeps the march's loop small.
    var nearest = 1e9;
    var second = 1e9;
    var hit: Crown;
    var hit2: Crown;
    var cell = floor(o.xy);
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            meet(cell + vec2<f32>(f32(i), f32(j)), o, d, edge, &nearest, &second, &hit, &hit2);
        }
    }
    var next = select(vec2<f32>(1e9), (boundary - o.xy) / d.xy, moving);
    var passed = false;
    var walked = 0;
    loop {
        let entered = min(next.x, next.y);
        if (walked >= MARCH_CELLS || entered > reach || entered > select(nearest, second, passed)) {
            let pixel = per_spacing * (length_to_eye - start + nearest);
            if (!passed && nearest <= start && past_outline(o, d, hit, pixel)) {
                passed = true;
                continue;
            }
            break;
        }
        walked++;
        let by_x = next.x < next.y;
        let step = select(vec2<f32>(0.0, toward.y), vec2<f32>(toward.x, 0.0), by_x);
        cell += step;
        next += select(vec2<f32>(0.0, per_cell.y), vec2<f32>(per_cell.x, 0.0), by_x);
        let ahead = cell + step;
        let side = abs(step.yx);
        meet(ahead - side, o, d, edge, &nearest, &second, &hit, &hit2);
        meet(ahead, o, d, edge, &nearest, &second, &hit, &hit2);
        meet(ahead + side, o, d, edge, &nearest, &second, &hit, &hit2);
    }
    if (passed) {
        nearest = second;
        hit = hit2;
    }
    if (nearest > start) {
        // No crown met; past the points visited, the mean.
        let covered = start * across <= MARCH_REACH;
        return vec4<f32>(mix(mean, gap, select(0.0, floor_detail, covered)), 1.0);
    }
    // Lit by the spheroid's normal there; w from -1 (its base) to 1 (its top): the
    // lower side and the rim see less sky than the top.
    let p = o + d * nearest - vec3<f32>(hit.across, hit.up);
    let w = clamp(p.z / hit.half_height, -1.0, 1.0);
    let axes = vec3<f32>(hit.radius, hit.radius, hit.half_height);
    var n: vec3<f32>;
    if (hit.dark) {
        // The cone's mantle: the gradient of x² + y² - k² z² about its apex (up at the
        // apex itself, where the gradient vanishes).
        let k = cone_slope(hit);
        n = normalize(vec3<f32>(p.xy, k * k * (hit.half_height - p.z) + 1e-6));
    } else {
        n = normalize(p / (axes * axes));
    }
    let h = hash2(hit.id + vec2<f32>(11.0, 7.0));
    let tint = vec3<f32>(0.8 + 0.4 * h, 0.85 + 0.3 * hash2(hit.id + vec2<f32>(2.0, 9.0)), 0.9 + 0.2 * h);
    let open = select(0.55 + 0.3 * w, 0.55 + 0.45 * w, w >= 0.0);
    let r = length_to_eye - start + nearest;
    let clumps = leaf_clumps(p / axes, n, hit.id, hit.dark, per_spacing * r);
    // The darker crowns take their own albedo; the others the one that keeps the mean
    // over what the crowns show of themselves (a cone's upper side, all a canopy seen
    // at a glancing angle shows, is about CONE_SHOWN of a spheroid's).
    let shown = dark.w * CONE_SHOWN;
    let light = (leaves - shown * dark.rgb) / max(1.0 - shown, 1e-3);
    let own = SHADED_CROWN * select(light, dark.rgb, hit.dark);
    let lit = mix(gap, own * tint * lighting(clumps.xyz, 1.0) * open * clumps.w, clearing);
    let detail = 1.0 - smoothstep(0.12, 0.4, per_spacing * r);
    return vec4<f32>(mix(mean, lit, detail), r / length_to_eye);
}

// A crown's leaves are not a smooth surface: they hang in clumps that stand out from the
// crown, each lit on its sunward side, with shaded hollows between them. The clumps are a
// height field over the crown's unit sphere (`u`, projected along a slanted axis so its
// sides vary with height too), about an eighth of the crown across; it bends the normal
// `n0` (crown space, unit) and darkens the hollows. Under them, a broadleaf's (not a
// `dark` conifer's) boughs do the same at the scale of its lobes. Returns the bent normal
// and the hollows' shade (about 1 on average); both fade to the smooth crown where a pixel
// spans more than a sixth of a spacing (`pixel`, spacings), the boughs where it spans
// LOBE_FADE.
fn leaf_clumps(u: vec3<f32>, n0: vec3<f32>, id: vec2<f32>, dark: bool, pixel: f32) -> vec4<f32> {
    var n = n0;
    var shade = 1.0;
    // A broadleaf's boughs, the lobes of its outline (`past_outline`), each lit on its
    // sunward side with a shaded hollow between: they still show where the clumps are
    // too small to.
    let boughs = select(1.0 - smoothstep(LOBE_FADE.x, LOBE_FADE.y, pixel), 0.0, dark);
    if (boughs > 0.0) {
        let hb = bough_height(bough_coords(normalize(u), id));
        // The height's gradient on the sphere (through the coordinates' dependence on u).
        let grad = LOBE_FREQ * vec3<f32>(hb.y, hb.z, 0.6 * (hb.y - hb.z));
        n = normalize(n - BOUGH_BEND * boughs * (grad - dot(grad, n) * n));
        shade = 1.0 + boughs * BOUGH_SHADE * (2.0 * hb.x - 1.0);
    }
    let fade = 1.0 - smoothstep(0.08, 0.17, pixel);
    if (fade <= 0.0) {
        return vec4<f32>(n, shade);
    }
    let k = 4.0;
    let q = k * vec2<f32>(u.x + 0.6 * u.z, u.y - 0.6 * u.z) + 7.3 * id;
    let hg = clump_height(q);
    let h = hg.x;
    let g = hg.yz;
    // The height's gradient on the sphere (through q's dependence on u), in the tangent plane.
    let grad = k * vec3<f32>(g.x, g.y, 0.6 * (g.x - g.y));
    let tangent = grad - dot(grad, n) * n;
    let bent = normalize(n - 0.12 * fade * tangent);
    return vec4<f32>(bent, shade * (1.0 + fade * 0.25 * (2.0 * smoothstep(0.25, 0.75, h) - 1.0)));
}

// The clumps' height, 0 to 1, and its gradient: two octaves of value noise.
fn clump_height(q: vec2<f32>) -> vec3<f32> {
    return 0.65 * noise2_grad(q) + 0.35 * noise2_grad(2.3 * q + vec2<f32>(19.0, 7.0)) * vec3<f32>(1.0, 2.3, 2.3);
}
