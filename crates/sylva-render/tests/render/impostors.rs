//! Impostors against full detail: no jump between baked views, brightness, outline, lean.

use super::*;

/// One tree, always an impostor (h₀ = 100), in calm air without shadows, seen by each of
/// the cameras of `path` (given the tree's base) in turn: the mean |Δ| between consecutive
/// images.
fn impostor_steps(path: impl Fn([f32; 3]) -> Vec<Camera>) -> Vec<f64> {
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    spec.trees = 1;
    spec.wind = "calm".into();
    spec.lod.fraction = 100.0;
    spec.lighting.shadows = false;
    let mut forest = Forest::new(&spec).expect("forest");
    let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
    let mut frame = FrameData::default();
    forest.step(1.0 / 30.0);
    forest.frame(&forest.default_camera(), W as f32 / H as f32, &mut frame);
    let base = frame.instances[0].position;
    let mut images = Vec::new();
    for camera in path(base) {
        forest.frame(&camera, W as f32 / H as f32, &mut frame);
        assert!(frame.instances.iter().all(|i| i.tag & 15 == 15), "an impostor");
        images.push(gpu.render(&frame, &camera).expect("render"));
    }
    images.windows(2).map(|p| mean_abs_diff(&p[0], &p[1])).collect()
}

/// No step of `steps` more than three times their median (and the median not nothing).
fn assert_no_jump(mut steps: Vec<f64>, what: &str) {
    let max = steps.iter().copied().fold(0.0, f64::max);
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    eprintln!("{what}: median {median:.3}, max {max:.3}");
    assert!(median > 0.0, "{what}: the impostor changes with the camera");
    assert!(
        max < 3.0 * median,
        "{what}: one step changes the image by {max:.3}, the median by {median:.3}"
    );
}

fn looking_at(base: [f32; 3], eye: [f32; 3]) -> Camera {
    Camera {
        eye: [base[0] + eye[0], base[1] + eye[1], base[2] + eye[2]],
        target: [base[0], base[1], base[2] + 8.0],
        fov_deg: 30.0,
        near: 0.5,
        far: 8000.0,
    }
}

#[test]
fn an_impostor_turns_from_one_baked_view_to_the_next_without_a_jump() {
    // The camera circles the tree in steps of 1° through 100°, so it passes at least two
    // half-way directions between baked views (they are 22.5° apart). Without the
    // cross-fade, the step across one swaps the whole crown's picture at once; with it,
    // the swap is spread over the steps of the band.
    let path = |base: [f32; 3]| -> Vec<Camera> {
        (0..=100)
            .map(|deg| {
                let a = (deg as f32).to_radians();
                looking_at(base, [45.0 * a.cos(), 45.0 * a.sin(), 8.0])
            })
            .collect()
    };
    assert_no_jump(impostor_steps(path), "view steps");
}

#[test]
fn an_impostor_rises_from_one_baked_elevation_to_the_next_without_a_jump() {
    // The camera rises over the tree in steps of 0.5° from 10° to 50° above the horizon, so
    // it passes the half-way elevations between the baked ones (0, 30 and 60°), at 15 and
    // 45°.
    let path = |base: [f32; 3]| -> Vec<Camera> {
        (20..=100)
            .map(|half_deg| {
                let (s, c) = (0.5 * half_deg as f32).to_radians().sin_cos();
                looking_at(base, [45.0 * c, 10.0 * c, 8.0 + 46.1 * s])
            })
            .collect()
    };
    assert_no_jump(impostor_steps(path), "elevation steps");
}

/// The small scene's mix as a stand of `trees` at 7 m spacing in `wind`, without shadows:
/// at full detail, and every tree an impostor.
fn stand(trees: usize, wind: &str) -> (SceneSpec, SceneSpec) {
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    spec.trees = trees;
    spec.spacing = 7.0;
    spec.wind = wind.into();
    spec.lighting.shadows = false;
    let mut full = spec.clone();
    full.lod.geometry = false;
    spec.lod.fraction = 100.0;
    (full, spec)
}

/// Sum of the Rec. 709 luma of an RGBA image's pixels.
fn luma(img: &[u8]) -> f64 {
    img.chunks(4).map(|p| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64).sum()
}

#[test]
fn a_stand_drawn_as_impostors_keeps_the_brightness_of_full_detail() {
    // 200 trees in calm air without shadows, seen from 60 and 120 m (crowns 30–70 pixels
    // tall, sampling the atlas's coarser mips): the mean brightness of the image with every
    // tree an impostor stays within 3 % of full detail's. Lit from renormalised averaged
    // normals, the impostors read about 9 % brighter at 60 m (the mean of a crown's leaves'
    // light is below the light of their mean normal made unit); lit from the mean normals
    // as they are, 3.2 % darker (the mean of their light is above the light of the mean).
    let (full, spec) = stand(200, "calm");
    let cameras: Vec<Camera> = [60.0f32, 120.0]
        .iter()
        .map(|&dist| Camera {
            eye: [-dist, -0.3 * dist, 0.3 * dist + 10.0],
            target: [0.0, 0.0, 5.0],
            fov_deg: 30.0,
            near: 0.5,
            far: 8000.0,
        })
        .collect();
    let ratios = impostor_brightness(&full, &spec, &cameras, 0);
    for (ratio, dist) in ratios.iter().zip([60, 120]) {
        eprintln!("{dist} m: impostors / full detail {ratio:.3}");
        assert!((ratio - 1.0).abs() < 0.03, "{dist} m: impostors / full detail {ratio:.3}");
    }
}

/// The mean brightness (luma) of `impostors` against that of `full` (the same stand at
/// full detail), both rendered from each of `cameras` after one step. At most `stray`
/// trees in view may be drawn at full detail among the impostors (close enough to be).
fn impostor_brightness(
    full: &SceneSpec,
    impostors: &SceneSpec,
    cameras: &[Camera],
    stray: usize,
) -> Vec<f64> {
    let mut sums = Vec::new();
    // One renderer for both: the two scenes differ in their level choice only.
    let mut gpu =
        Headless::new(&Forest::new(full).expect("forest"), W, H).unwrap_or_else(|e| panic!("{e}"));
    for s in [full, impostors] {
        let mut forest = Forest::new(s).expect("forest");
        let mut frame = FrameData::default();
        forest.step(1.0 / 30.0);
        let mut row = Vec::new();
        for camera in cameras {
            forest.frame(camera, W as f32 / H as f32, &mut frame);
            if s.lod.geometry {
                let (shown, drawn) = (frame.stats.impostors, frame.stats.drawn);
                assert!(shown + stray >= drawn, "{shown} of {drawn} trees drawn as impostors");
            }
            row.push(luma(&gpu.render(&frame, camera).expect("render")));
        }
        sums.push(row);
    }
    sums[1].iter().zip(&sums[0]).map(|(i, f)| i / f).collect()
}

#[test]
fn impostors_darken_in_a_strong_wind_as_full_detail_does() {
    // A stand of 100 trees (about 80 m across) seen from 60 m off its centre, without
    // shadows, at rest and after 3 s of a steady 12 m/s wind. Full detail darkens
    // (measured 3–4 %): the bent limbs and twigs turn the leaves from the sky, the mean
    // cosine of their tilt falling to 0.88 for the aspen and 0.92 for the fir
    // (`CrownLean::tilt`). The impostors, which bend at the trunk alone, turn their baked
    // leaf normals by that mean and darken too, the light their spread loses going to
    // leaves that face the sun or pass it through (measured here 3.1 % against 4.0 %; 6.1
    // against 6.7 % before leaves passed light through); unturned they came out brighter.
    let (full, spec) = stand(100, "12");
    let camera = Camera {
        eye: [-60.0, -18.0, 28.0],
        target: [0.0, 0.0, 5.0],
        fov_deg: 30.0,
        near: 0.5,
        far: 8000.0,
    };
    let mut darkening = Vec::new();
    // One renderer for both: the two scenes differ in their level choice only.
    let mut gpu =
        Headless::new(&Forest::new(&full).expect("forest"), W, H).unwrap_or_else(|e| panic!("{e}"));
    for s in [&full, &spec] {
        let mut forest = Forest::new(s).expect("forest");
        let mut frame = FrameData::default();
        // Before the first step every tree stands in its rest pose.
        forest.frame(&camera, W as f32 / H as f32, &mut frame);
        let rest = luma(&gpu.render(&frame, &camera).expect("render"));
        for _ in 0..90 {
            forest.step(1.0 / 30.0);
        }
        forest.frame(&camera, W as f32 / H as f32, &mut frame);
        if s.lod.geometry {
            assert!(frame.instances.iter().all(|i| i.tag & 15 == 15), "all impostors");
        }
        let wind = luma(&gpu.render(&frame, &camera).expect("render"));
        darkening.push(1.0 - wind / rest);
    }
    let (full_detail, impostors) = (darkening[0], darkening[1]);
    eprintln!("darkening in 12 m/s: full detail {full_detail:.4}, impostors {impostors:.4}");
    assert!(full_detail > 0.015, "full detail darkens: {full_detail:.4}");
    assert!(
        impostors > 0.3 * full_detail && impostors < 1.2 * full_detail,
        "impostors {impostors:.4} against full detail {full_detail:.4}"
    );
}

#[test]
fn leaf_edges_come_closer_to_a_supersampled_reference() {
    // The small scene close up, rendered at 256×192 with 4× MSAA, against the same frame
    // rendered at 1024×768 and averaged down 4×4 (64 samples a pixel). Leaf outlines are
    // alpha edges inside the cards: MSAA alone leaves them one step (all samples or none),
    // alpha to coverage spreads each over one pixel. Measured: mean |Δ| 4.27 with alpha
    // to coverage, 4.95 alpha-tested (4.29 and 4.99 against an alpha-tested reference).
    // The image stays opaque: the coverage alpha is not written.
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    spec.wind = "calm".into();
    spec.lighting.shadows = false;
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.default_camera();
    let mut frame = FrameData::default();
    forest.step(1.0 / 30.0);
    forest.frame(&camera, W as f32 / H as f32, &mut frame);
    let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
    let img = gpu.render(&frame, &camera).expect("render");
    let mut big = Headless::new(&forest, 4 * W, 4 * H).unwrap_or_else(|e| panic!("{e}"));
    let fine = big.render(&frame, &camera).expect("render");
    assert!(img.chunks(4).all(|p| p[3] == 255), "the image is opaque");
    let (w, h) = (W as usize, H as usize);
    let mut reference = vec![0u8; 4 * w * h];
    for y in 0..h {
        for x in 0..w {
            for c in 0..4 {
                let sum: u32 = (0..16)
                    .map(|k| fine[4 * ((4 * y + k / 4) * 4 * w + 4 * x + k % 4) + c] as u32)
                    .sum();
                reference[4 * (y * w + x) + c] = ((sum + 8) / 16) as u8;
            }
        }
    }
    let d = mean_abs_diff(&img, &reference);
    eprintln!("against the supersampled reference: mean |Δ| {d:.3}");
    assert!(d < 4.6, "mean |Δ| {d:.3} from the supersampled frame");
}

#[test]
fn an_impostor_keeps_the_outline_of_full_detail_seen_level_and_from_above() {
    // One quaking aspen 120 m off, seen level, from 45° above (half-way between two baked
    // elevations, where both are shown, cross-faded) and from 60° (as a camera over a
    // forest sees the trees below it): the pixels its impostor covers against those full
    // detail covers, each told from the same frame drawn without the tree. Baked at one
    // elevation only, the tree seen from above showed its side, the trunk reaching below
    // the crown: at 60° the outlines overlapped by 0.58 and the impostor covered 10 % more
    // pixels (0.71 and 7 % fewer with the views baked at 0, 30 and 60°). Each pixel showing
    // where its line of sight meets the view's depth map (`surface_uv`), not the view's
    // pixel at the same place on the quad: overlaps 0.844, 0.729 and 0.784 at 0, 45 and 60°
    // with the impostor 0.999 of full detail's pixels level, against 0.843, 0.719 and 0.711
    // and 0.952 without.
    let text = r#"
        name = "aspen"
        seed = 3
        trees = 1
        terrain_amplitude = 0.0
        wind = "calm"
        species = [ { name = "quaking_aspen" } ]
        [lighting]
        shadows = false
    "#;
    let spec = SceneSpec::from_toml("aspen.toml", text).expect("scene");
    let mut full = spec.clone();
    full.lod.geometry = false;
    let mut far = spec.clone();
    far.lod.fraction = 100.0;
    let cameras = [0.0f32, 45.0, 60.0].map(|elevation| {
        let (s, c) = elevation.to_radians().sin_cos();
        Camera {
            eye: [-120.0 * c, 0.0, 6.5 + 120.0 * s],
            target: [0.0, 0.0, 6.5],
            fov_deg: 7.0,
            near: 0.5,
            far: 8000.0,
        }
    });
    // Per build (full detail, impostor), per camera: the pixels the tree changes.
    let masks: Vec<Vec<Vec<bool>>> = [&full, &far]
        .iter()
        .map(|s| {
            let mut forest = Forest::new(s).expect("forest");
            let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
            let mut frame = FrameData::default();
            cameras
                .iter()
                .map(|camera| {
                    forest.frame(camera, W as f32 / H as f32, &mut frame);
                    if s.lod.geometry {
                        assert!(frame.instances.iter().all(|i| i.tag & 15 == 15), "an impostor");
                    }
                    let img = gpu.render(&frame, camera).expect("render");
                    frame.instances.clear();
                    frame.buckets.clear();
                    let empty = gpu.render(&frame, camera).expect("render");
                    img.chunks(4)
                        .zip(empty.chunks(4))
                        .map(|(a, b)| (0..3).map(|k| a[k].abs_diff(b[k]) as u32).sum::<u32>() > 24)
                        .collect()
                })
                .collect()
        })
        .collect();
    for (i, elevation) in [0, 45, 60].into_iter().enumerate() {
        let masks = [masks[0][i].as_slice(), masks[1][i].as_slice()];
        let count = |m: &[bool]| m.iter().filter(|&&m| m).count();
        let both = masks[0].iter().zip(masks[1]).filter(|(a, b)| **a && **b).count();
        let either = masks[0].iter().zip(masks[1]).filter(|(a, b)| **a || **b).count();
        let (nf, ni) = (count(masks[0]), count(masks[1]));
        let overlap = both as f64 / either.max(1) as f64;
        eprintln!("{elevation}°: full detail {nf} px, impostor {ni} px, overlap {overlap:.3}");
        assert!(nf > 3000, "the tree fills too little of the image: {nf} px");
        let size = ni as f64 / nf as f64;
        assert!((size - 1.0).abs() < 0.1, "{elevation}°: impostor / full detail pixels {size:.3}");
        assert!(overlap > 0.72, "{elevation}°: outlines overlap by {overlap:.3}");
    }
}

#[test]
fn an_impostor_leans_downwind_by_its_crowns_lean() {
    // A weeping willow seen across a steady 8 m/s wind once its sway has died down, drawn
    // as an impostor: its hanging twigs stream out about a metre (leaf-weighted mean) while
    // its thick trunk's top moves 2 cm, so swayed by the trunk top alone its picture stood
    // all but still. The same frame drawn with the crown's lean (`Instance::lean`) and with
    // it taken off: the picture's foot stays where it stands, its upper half moves
    // downwind, by about the crown's mean displacement (`CrownLean`) at that distance.
    let text = r#"
        name = "willow"
        seed = 3
        trees = 1
        terrain_amplitude = 0.0
        wind = "8"
        wind_direction_deg = 90.0
        species = [ { name = "weeping_willow" } ]
        [lod]
        fraction = 100.0
        [lighting]
        shadows = false
    "#;
    let spec = SceneSpec::from_toml("willow.toml", text).expect("scene");
    let mut forest = Forest::new(&spec).expect("forest");
    let (base, height) = (
        forest.placement(0).expect("a tree").position,
        forest.tree_info(0).expect("a tree").height,
    );
    // Seen level, the tree 60 % of the image tall.
    let fov_deg = 10.0f32;
    let view = 2.0 * (0.5 * fov_deg).to_radians().tan();
    let distance = height / (0.6 * view);
    let mid = base[2] + 0.5 * height;
    let camera = Camera {
        eye: [base[0] - distance, base[1], mid],
        target: [base[0], base[1], mid],
        fov_deg,
        near: 0.5,
        far: 8000.0,
    };
    let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
    let mut frame = FrameData::default();
    forest.frame(&camera, W as f32 / H as f32, &mut frame);
    // 40 s (the step is exact for any dt): the trunk, the slowest joint, has settled.
    for _ in 0..400 {
        forest.step(0.1);
    }
    forest.frame(&camera, W as f32 / H as f32, &mut frame);
    assert!(frame.instances.len() == 1 && frame.instances[0].tag & 15 == 15, "one impostor");
    let yaw = frame.instances[0].yaw;
    let leaning = gpu.render(&frame, &camera).expect("render");
    frame.instances[0].lean = [0; 2];
    let upright = gpu.render(&frame, &camera).expect("render");
    // The crown's mean displacement: tree space, turned into the world by the tree's yaw;
    // across the image (the camera looks along +x, its right is −y) in pixels.
    let w = forest.wind_sample([base[0] as f64, base[1] as f64, mid as f64]);
    let (sn, cs) = yaw.sin_cos();
    let tree_wind = [cs * w[0] + sn * w[1], -sn * w[0] + cs * w[1], w[2]];
    let m = forest.species[0].lean().mean(tree_wind);
    let world_y = sn * m[0] + cs * m[1];
    let expected = -world_y * H as f32 / (distance * view);
    // The best horizontal shift of the upright picture onto the leaning one over rows
    // `rows` (least mean |Δ luma|, to a tenth of a pixel by a parabola through the best
    // three).
    let luma = |img: &[u8], x: u32, y: u32| px(img, x, y).iter().sum::<i32>() as f64;
    let shift = |rows: std::ops::Range<u32>| {
        let cost = |dx: i32| {
            rows.clone()
                .flat_map(|y| (20..W - 20).map(move |x| (x, y)))
                .map(|(x, y)| {
                    (luma(&leaning, x, y) - luma(&upright, (x as i32 - dx) as u32, y)).abs()
                })
                .sum::<f64>()
        };
        let costs: Vec<f64> = (-15..=15).map(cost).collect();
        let best =
            (1..costs.len() - 1).min_by(|&a, &b| costs[a].total_cmp(&costs[b])).expect("a shift");
        let (l, c, r) = (costs[best - 1], costs[best], costs[best + 1]);
        let sub = if l + r - 2.0 * c > 0.0 { 0.5 * (l - r) / (l + r - 2.0 * c) } else { 0.0 };
        (best as f64 - 15.0 + sub) as f32
    };
    let foot = pixel_of(&camera, base).expect("the foot in view").1;
    let top = pixel_of(&camera, [base[0], base[1], base[2] + height]).expect("the top in view").1;
    let (at_foot, upper) = (shift(foot - 6..foot), shift(top..(top + foot) / 2));
    eprintln!(
        "mean displacement {m:.2?} m (tree space), {expected:.2} px across the image; \
         the picture moves {at_foot:.2} px at its foot, {upper:.2} px over its upper half"
    );
    assert!(expected.abs() > 3.0, "the crown leans {expected} px");
    assert!(at_foot.abs() < 0.5, "the foot moves {at_foot} px");
    // The shear grows with height: the upper half moves more than the crown's mean.
    let ratio = upper / expected;
    assert!((1.0..2.0).contains(&ratio), "the upper half moves {upper} px, the crown {expected}");
}

#[test]
fn a_stand_drawn_as_impostors_keeps_the_brightness_of_full_detail_under_shadows() {
    // The stand of 200 trees in calm air with the sun's shadows, seen from three sides at
    // 60, 120 and 240 m and from a fourth at 60 m (lit from the front, the side and
    // partly against the light: the sun stands at azimuth -122°, 49° up). Full detail's
    // crowns shade their own leaves in the shadow map; an impostor's leaf is not shadowed
    // by its own caster and darkens as an ellipsoid of leaves would (`crown_light`).
    // Measured (impostors / full detail, 256×192), without that shade 1.050 1.025 1.008 |
    // 1.126 1.045 1.002 | 1.094 1.080 1.002 | 1.012 (off by 12.6 % at worst, 4.4 % on
    // average, when half of each crown also lay in its own caster's shadow), with it
    // (its mean over the leaves' depths, the outer texel of the shadow map left lit)
    // 1.016 0.987 0.993 | 0.995 0.987 0.987 | 0.999 0.983 0.982 | 0.978 (2.2 %, 1.25 %;
    // at one depth, half a free path, nothing left lit: 3.3 %, 1.24 %).
    // With the fir's and the oak's lighter foliage and the maple's denser crown (the
    // crowns a larger share of the image) and the extinction at 1.1 instead of 1.5:
    // 1.004 0.978 0.994 | 0.977 0.991 0.990 | 0.972 0.995 0.988 | 0.962 (3.8 %, 1.6 %).
    let (mut full, mut spec) = stand(200, "calm");
    full.lighting.shadows = true;
    spec.lighting.shadows = true;
    // (Direction of the eye from the stand's centre, horizontal; distance.)
    let views: [([f32; 2], f32); 10] = [
        ([-1.0, -0.3], 60.0),
        ([-1.0, -0.3], 120.0),
        ([-1.0, -0.3], 240.0),
        ([-1.0, 0.3], 60.0),
        ([-1.0, 0.3], 120.0),
        ([-1.0, 0.3], 240.0),
        ([1.0, -0.3], 60.0),
        ([1.0, -0.3], 120.0),
        ([1.0, -0.3], 240.0),
        ([0.3, -1.0], 60.0),
    ];
    let cameras: Vec<Camera> = views
        .iter()
        .map(|&(dir, dist)| Camera {
            eye: [dir[0] * dist, dir[1] * dist, 0.3 * dist + 10.0],
            target: [0.0, 0.0, 5.0],
            fov_deg: 30.0 * 60.0 / dist.min(120.0),
            near: 0.5,
            far: 8000.0,
        })
        .collect();
    // (One tree in one view stands close enough to be drawn at full detail in both.)
    let ratios = impostor_brightness(&full, &spec, &cameras, 1);
    eprintln!("impostors / full detail under shadows: {ratios:.3?}");
    let worst = ratios.iter().map(|r| (r - 1.0).abs()).fold(0.0, f64::max);
    let mean = ratios.iter().map(|r| (r - 1.0).abs()).sum::<f64>() / ratios.len() as f64;
    assert!(worst < 0.045 && mean < 0.02, "off by {worst:.3} at worst, {mean:.3} on average");
}
