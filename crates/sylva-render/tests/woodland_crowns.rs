//! The painted woodland's crowns, on the adapter: `enter_crown` in ground.wgsl meets a ray
//! where it first enters the crown's solid — a spheroid for a broadleaf, a cone standing
//! on its base for one of the darker (conifer) crowns — as found on the CPU by walking
//! the ray in small steps and testing each point against the solid; and `past_outline`
//! cuts a near crown's outline, a broadleaf's in lobes and a conifer's in tiers, and
//! leaves a far one's whole.

mod probe;

use sylva_core::SplitMix64;

/// Calls ground.wgsl's `enter_crown` and `past_outline` once per ray: where the ray
/// enters the crown's solid, and 1 where it meets the crown within its outline (0 where
/// not).
const PROBE: &str = r#"
struct RayProbe { o: vec4<f32>, d: vec4<f32>, crown: vec4<f32>, shape: vec4<f32> };
@group(2) @binding(0) var<storage, read> rays: array<RayProbe>;
@group(2) @binding(1) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&rays)) { return; }
    let r = rays[id.x];
    var c: Crown;
    c.id = vec2<f32>(3.0, 5.0);
    c.across = r.crown.xy;
    c.up = r.crown.z;
    c.radius = r.crown.w;
    c.half_height = r.shape.x;
    c.dark = r.shape.y > 0.5;
    let t = enter_crown(r.o.xyz, r.d.xyz, c);
    out[2u * id.x] = t;
    out[2u * id.x + 1u] = select(0.0, 1.0, t >= 0.0 && !past_outline(r.o.xyz, r.d.xyz, c, r.shape.z));
}
"#;

/// A crown: centre across the ground and height, radius, vertical half-axis, conifer.
#[derive(Clone, Copy, Debug)]
struct Crown {
    across: [f32; 2],
    up: f32,
    radius: f32,
    half_height: f32,
    cone: bool,
}

/// A cone's base radius against the crown's radius (ground.wgsl's CONE_BASE, checked by
/// `the_cone_is_the_shaders`).
const CONE_BASE: f32 = 1.5;

#[test]
fn the_cone_is_the_shaders() {
    let src = sylva_render::shader_source("ground.wgsl").expect("ground.wgsl");
    assert!(
        src.contains(&format!("const CONE_BASE: f32 = {CONE_BASE:?};")),
        "ground.wgsl's CONE_BASE differs from this test's {CONE_BASE}"
    );
}

/// One ray of the probes: origin, direction, the crown (centre across, height, radius;
/// half-height, conifer) and the pixel's span there (spacings), as `vec4`s.
fn probe_ray(o: [f32; 3], d: [f32; 3], crown: &Crown, pixel: f32) -> [f32; 16] {
    let cone = if crown.cone { 1.0 } else { 0.0 };
    let [ax, ay] = crown.across;
    let (up, radius, half) = (crown.up, crown.radius, crown.half_height);
    [o[0], o[1], o[2], 0.0, d[0], d[1], d[2], 0.0, ax, ay, up, radius, half, cone, pixel, 0.0]
}

impl Crown {
    /// Whether point `p` lies in the crown's solid.
    fn contains(&self, p: [f32; 3]) -> bool {
        let (x, y) = (p[0] - self.across[0], p[1] - self.across[1]);
        if self.cone {
            // The apex at the top of the span, the base (CONE_BASE · radius) at its
            // bottom.
            let below = self.up + self.half_height - p[2];
            let depth = 2.0 * self.half_height;
            let r = CONE_BASE * self.radius * below / depth;
            (0.0..=depth).contains(&below) && x * x + y * y <= r * r
        } else {
            let z = (p[2] - self.up) / self.half_height;
            (x * x + y * y) / (self.radius * self.radius) + z * z <= 1.0
        }
    }

    /// Where the ray `o + v d` first enters the solid within `reach`, walked in steps of
    /// `step` (v, or none).
    fn walk(&self, o: [f32; 3], d: [f32; 3], reach: f32, step: f32) -> Option<f32> {
        (0..=(reach / step) as usize)
            .map(|i| i as f32 * step)
            .find(|v| self.contains(std::array::from_fn(|k| o[k] + v * d[k])))
    }
}

#[test]
fn a_ray_enters_a_painted_crown_where_it_first_meets_its_spheroid_or_cone() {
    // Crowns in spacings, as the shader has them: radius 0.6–0.75 (a conifer's 0.65 of
    // it), centre about 1 up, half-height about 0.85 (a conifer's 1.15 of it).
    let crowns = [
        Crown { across: [0.4, 0.5], up: 1.05, radius: 0.7, half_height: 0.85, cone: false },
        Crown { across: [0.6, 0.3], up: 1.1, radius: 0.45, half_height: 1.0, cone: true },
    ];
    let mut rng = SplitMix64::new(0x5eed_c0de);
    let mut rays = Vec::new();
    let mut cases = Vec::new();
    for crown in crowns {
        for _ in 0..400 {
            // Descending rays from points around and above the crown, aimed at points
            // about it (as the canopy's march traces them, from above the crowns' tops
            // down to the ground), some starting inside.
            let o = [
                crown.across[0] + 4.0 * (rng.unit() - 0.5),
                crown.across[1] + 4.0 * (rng.unit() - 0.5),
                0.3 + 2.5 * rng.unit(),
            ];
            let aim = [
                crown.across[0] + 1.6 * (rng.unit() - 0.5),
                crown.across[1] + 1.6 * (rng.unit() - 0.5),
                crown.up + 2.0 * (rng.unit() - 0.5) - 0.6,
            ];
            let mut d: [f32; 3] = std::array::from_fn(|k| aim[k] - o[k]);
            if d[2] >= -0.05 {
                d[2] = -0.05 - 0.5 * rng.unit();
            }
            let len = d.iter().map(|x| x * x).sum::<f32>().sqrt();
            let d = d.map(|x| x / len);
            rays.push(probe_ray(o, d, &crown, 0.0));
            cases.push((crown, o, d));
        }
    }
    let gpu = probe_crowns(&rays).0;
    let step = 1e-3;
    let (mut met, mut missed) = ([0; 2], [0; 2]);
    for ((crown, o, d), v) in cases.iter().zip(&gpu) {
        let walked = crown.walk(*o, *d, 8.0, step);
        let kind = crown.cone as usize;
        match walked {
            Some(w) => {
                met[kind] += 1;
                // Within three steps of the walk (the walk lands up to a step past the
                // surface; a grazing ray's entry moves more with rounding).
                assert!(
                    (v - w).abs() < 3.0 * step,
                    "{crown:?}: ray from {o:?} along {d:?} enters at {v}, the walk at {w}"
                );
            }
            None => {
                missed[kind] += 1;
                assert!(
                    *v < 0.0,
                    "{crown:?}: ray from {o:?} along {d:?} enters at {v}, the walk never"
                );
            }
        }
    }
    // Both kinds of crown met and missed, so the comparison covers both answers.
    for kind in 0..2 {
        assert!(met[kind] > 50 && missed[kind] > 50, "kind {kind}: met {met:?}, missed {missed:?}");
    }
}

#[test]
fn a_painted_conifer_narrows_to_its_apex_where_a_broadleaf_stays_round() {
    // Level rays across the crown at heights through its span, offset sideways by
    // `x`: the widest offset met at each height is the crown's half-width there. A cone
    // of base CONE_BASE · radius narrows linearly to nothing at its top; the spheroid is
    // widest at its middle, round above and below.
    let (up, half) = (1.0f32, 1.0f32);
    let width_at = |cone: bool, z: f32| {
        let xs: Vec<f32> = (0..400).map(|i| i as f32 * 0.002).collect();
        let rays: Vec<[f32; 16]> = xs
            .iter()
            .map(|&x| {
                let flag = if cone { 1.0 } else { 0.0 };
                [x, -3.0, z, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, up, 0.5, half, flag, 0.0, 0.0]
            })
            .collect();
        let v = probe_crowns(&rays).0;
        xs.iter().zip(&v).filter(|(_, v)| **v >= 0.0).map(|(x, _)| *x).fold(0.0f32, f32::max)
    };
    for frac in [0.1f32, 0.5, 0.9, 1.5] {
        // Height below the apex, as a share of the span (2 · half).
        let z = up + half - frac * 2.0 * half;
        let cone = width_at(true, z);
        let want = if frac <= 1.0 { CONE_BASE * 0.5 * frac } else { 0.0 };
        assert!((cone - want).abs() < 0.005, "{frac} of the way down: cone {cone}, want {want}");
        let round = width_at(false, z);
        let t = (z - up) / half;
        let want = if t.abs() <= 1.0 { 0.5 * (1.0 - t * t).sqrt() } else { 0.0 };
        assert!(
            (round - want).abs() < 0.005,
            "{frac} of the way down: spheroid {round}, want {want}"
        );
    }
}

/// How far in a broadleaf's lobes cut its rim, as a share of the radius (ground.wgsl's
/// LOBE_DEPTH), and the pixel size (spacings) from which its outline is round (the end of
/// LOBE_FADE).
const LOBE_DEPTH: f32 = 0.3;
const LOBE_ROUND: f32 = 0.3;

#[test]
fn the_lobes_are_the_shaders() {
    let src = sylva_render::shader_source("ground.wgsl").expect("ground.wgsl");
    assert!(src.contains(&format!("const LOBE_DEPTH: f32 = {LOBE_DEPTH:?};")), "LOBE_DEPTH");
    assert!(
        src.contains(&format!("const LOBE_FADE: vec2<f32> = vec2<f32>(0.15, {LOBE_ROUND:?});")),
        "LOBE_FADE"
    );
}

/// A ray passing `crown`'s centre at `m` (in the crown's frame scaled to a unit sphere)
/// in direction `u` (unit), running along `e` (unit, perpendicular to `u`): origin and
/// direction in spacings, as the probe takes them.
fn passing(crown: &Crown, m: f32, u: [f32; 3], e: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let scale = [crown.radius, crown.radius, crown.half_height];
    let centre = [crown.across[0], crown.across[1], crown.up];
    let o = std::array::from_fn(|k| centre[k] + scale[k] * (m * u[k] - 3.0 * e[k]));
    let d: [f32; 3] = std::array::from_fn(|k| scale[k] * e[k]);
    let len = d.iter().map(|x| x * x).sum::<f32>().sqrt();
    (o, d.map(|x| x / len))
}

fn unit_vector(rng: &mut SplitMix64) -> [f32; 3] {
    loop {
        let v = [rng.sym(), rng.sym(), rng.sym()];
        let len = v.iter().map(|x| x * x).sum::<f32>().sqrt();
        if (0.1..=1.0).contains(&len) {
            return v.map(|x| x / len);
        }
    }
}

/// A unit vector perpendicular to the unit `u`, turned by `angle` about it.
fn across(u: [f32; 3], angle: f32) -> [f32; 3] {
    let a = if u[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let dot = a[0] * u[0] + a[1] * u[1] + a[2] * u[2];
    let p: [f32; 3] = std::array::from_fn(|k| a[k] - dot * u[k]);
    let len = p.iter().map(|x| x * x).sum::<f32>().sqrt();
    let p = p.map(|x| x / len);
    let q = [u[1] * p[2] - u[2] * p[1], u[2] * p[0] - u[0] * p[2], u[0] * p[1] - u[1] * p[0]];
    std::array::from_fn(|k| angle.cos() * p[k] + angle.sin() * q[k])
}

#[test]
fn a_near_broadleaf_has_a_lobed_outline_and_a_far_one_a_round_one() {
    let broadleaf =
        Crown { across: [0.3, 0.4], up: 1.0, radius: 0.7, half_height: 0.85, cone: false };
    let mut rng = SplitMix64::new(0x10be_5eed);
    // Rays passing the centre at every distance up to the rim, in every direction, each
    // once along two different lines through the same nearest point.
    let mut cases = Vec::new();
    for _ in 0..600 {
        let m = rng.unit();
        let u = unit_vector(&mut rng);
        let turn = std::f32::consts::TAU * rng.unit();
        cases.push((m, u, turn, turn + 1.0 + 2.0 * rng.unit()));
    }
    let run = |crown: &Crown, pixel: f32, second_line: bool| -> Vec<f32> {
        let rays: Vec<[f32; 16]> = cases
            .iter()
            .map(|&(m, u, a, b)| {
                let (o, d) = passing(crown, m, u, across(u, if second_line { b } else { a }));
                probe_ray(o, d, crown, pixel)
            })
            .collect();
        // Every one of these rays enters the crown's solid (it passes the centre nearer
        // than the surface): where it does not meet the crown, it passes by the outline.
        let met = probe_crowns(&rays).1;
        met.iter().map(|m| 1.0 - m).collect::<Vec<f32>>()
    };
    let near = run(&broadleaf, 0.01, false);
    let mut rim = (0, 0);
    for ((m, ..), past) in cases.iter().zip(&near) {
        if *m <= 1.0 - LOBE_DEPTH {
            assert_eq!(*past, 0.0, "a ray {m} from the centre passes by the lobes");
        } else {
            rim.0 += (*past > 0.5) as usize;
            rim.1 += 1;
        }
    }
    // In the rim's band the lobes reach out in some directions and not in others.
    let share = rim.0 as f32 / rim.1 as f32;
    assert!(
        (0.2..=0.8).contains(&share),
        "{} of {} rays in the rim's band pass: {share}",
        rim.0,
        rim.1
    );
    // The outline is the crown's: another line through the same nearest point agrees.
    assert_eq!(near, run(&broadleaf, 0.01, true), "the outline depends on the ray's direction");
    // Far off, the outline is round again (what a pixel spans could not show the lobes).
    assert!(run(&broadleaf, LOBE_ROUND, false).iter().all(|p| *p == 0.0), "far crown lobed");
}

/// Runs `PROBE` over `rays` (see [`probe_ray`]): where each enters its crown's solid (or a
/// negative number), and 1 where it meets the crown within its outline.
fn probe_crowns(rays: &[[f32; 16]]) -> (Vec<f32>, Vec<f32>) {
    let out = probe::run(
        "ground.wgsl",
        PROBE,
        &[],
        bytemuck::cast_slice(rays),
        rays.len(),
        2 * rays.len(),
    );
    (out.iter().step_by(2).copied().collect(), out.iter().skip(1).step_by(2).copied().collect())
}

/// How far in a conifer's tiers cut its cone at their tops, at most, as a share of its
/// radius (ground.wgsl's TIER_DEPTH times the 1.5 its variation about the axis reaches).
const TIER_CUT: f32 = 0.3 * 1.5;

#[test]
fn a_near_conifer_steps_in_tiers_and_a_far_one_is_a_cone() {
    let src = sylva_render::shader_source("ground.wgsl").expect("ground.wgsl");
    assert!(src.contains("const TIER_DEPTH: f32 = 0.3;"), "TIER_DEPTH");
    // Level rays across the conifer at heights through its span, offset sideways by `x`:
    // the widest offset met at each height is its half-width there.
    let (up, half, radius) = (1.0f32, 1.0f32, 0.45f32);
    let widths = |pixel: f32, z: f32| {
        let xs: Vec<f32> = (0..400).map(|i| i as f32 * 0.002).collect();
        let rays: Vec<[f32; 16]> = xs
            .iter()
            .map(|&x| {
                [x, -3.0, z, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, up, radius, half, 1.0, pixel, 0.0]
            })
            .collect();
        let met = probe_crowns(&rays).1;
        xs.iter().zip(&met).filter(|(_, m)| **m > 0.5).map(|(x, _)| *x).fold(0.0f32, f32::max)
    };
    let mut shares = Vec::new();
    for i in 1..60 {
        // Down from the apex, a share of the span.
        let frac = i as f32 / 60.0;
        let z = up + half - frac * 2.0 * half;
        let cone = CONE_BASE * radius * frac;
        let near = widths(0.01, z);
        // Never wider than the cone, never cut in by more than a tier can.
        assert!(near <= cone + 0.005, "{frac} down: {near} wider than the cone's {cone}");
        assert!(near >= cone * (1.0 - TIER_CUT) - 0.005, "{frac} down: {near} of {cone}");
        shares.push(near / cone);
        let far = widths(LOBE_ROUND, z);
        assert!((far - cone).abs() < 0.005, "{frac} down, far off: {far}, the cone {cone}");
    }
    // Near, the outline steps: full at the tiers' feet, cut in at their tops.
    let (low, high) = shares.iter().fold((f32::MAX, 0.0f32), |(l, h), s| (l.min(*s), h.max(*s)));
    assert!(high > 0.95 && low < 0.85, "tiers: half-width {low} to {high} of the cone's");
}
