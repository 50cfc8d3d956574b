//! The far forest as scene E draws it: impostors thinned with distance (Cook et al. 2007's
//! stochastic simplification of whole trees), the ones kept drawn wider. Its brightness is
//! that of every tree drawn, and it moves with the wind.

use super::*;

/// The small scene's mix as a stand of 20 000 trees at 7 m spacing in `wind`, far
/// impostors thinned under `thin_px` pixels (0: every tree drawn).
fn far_stand(wind: &str, thin_px: f32) -> SceneSpec {
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    spec.trees = 20_000;
    spec.spacing = 7.0;
    spec.wind = wind.into();
    spec.lod.thin_px = thin_px;
    spec
}

/// From 300 m up beyond the stand's western edge, looking across it: trees from about
/// 20 pixels tall near the edge to 2 far away.
fn across() -> Camera {
    Camera {
        eye: [-900.0, -100.0, 300.0],
        target: [0.0, 0.0, 0.0],
        fov_deg: 40.0,
        near: 1.0,
        far: 8000.0,
    }
}

/// The stand of `spec` seen `across`, stepped by 1/30 s and framed each step, rendered at
/// each of the times `at` (s, ascending); the images and the last frame's figures.
fn frames(spec: &SceneSpec, at: &[f32]) -> (Vec<Vec<u8>>, sylva_forest::FrameStats) {
    let mut forest = Forest::new(spec).expect("forest");
    let camera = across();
    let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
    let mut frame = FrameData::with_rows(H);
    let (mut images, mut steps) = (Vec::new(), 0);
    for &t in at {
        // A frame each step, as a host draws them.
        while (steps as f32) < t * 30.0 {
            forest.step(1.0 / 30.0);
            forest.frame(&camera, W as f32 / H as f32, &mut frame);
            steps += 1;
        }
        images.push(gpu.render(&frame, &camera).expect("render"));
    }
    (images, frame.stats)
}

/// The bytes of the rows a third to half way down the image: the far trees, 800 m to the
/// stand's far edge 1.6 km away, under the thinning's 8 pixels.
fn far_rows() -> std::ops::Range<usize> {
    (W * H / 3 * 4) as usize..(W * H / 2 * 4) as usize
}

/// Mean Rec. 709 luma of the rows below the horizon's band (the forest and its ground).
fn forest_luma(img: &[u8]) -> f64 {
    let rows = &img[(W * H / 3 * 4) as usize..];
    rows.chunks(4)
        .map(|p| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64)
        .sum::<f64>()
        / (rows.len() / 4) as f64
}

#[test]
fn a_thinned_far_forest_keeps_the_brightness_of_every_tree_drawn() {
    // A third or more of the trees in view are left out; the ones kept, drawn wider, keep
    // the forest's mean brightness within 5 % of what the trees take from the bare
    // ground's (measured: within 0.2 %).
    let (thinned, stats) = frames(&far_stand("0", 8.0), &[1.0]);
    let (whole, all) = frames(&far_stand("0", 0.0), &[1.0]);
    let bare = SceneSpec { trees: 1, ..far_stand("0", 0.0) };
    let (ground, _) = frames(&bare, &[1.0]);
    let (a, b, g) = (forest_luma(&thinned[0]), forest_luma(&whole[0]), forest_luma(&ground[0]));
    eprintln!(
        "{} of {} trees in view thinned out; mean luma {a:.2} against {b:.2} with every tree, \
         {g:.2} without trees",
        stats.thinned, all.drawn
    );
    assert!(stats.thinned * 3 > all.drawn, "a third of the trees thinned: {stats:?}");
    assert!((g - b).abs() > 20.0, "the trees darken the picture: {b:.2} against {g:.2}");
    assert!((a - b).abs() < 0.05 * (g - b).abs(), "{a:.2} against {b:.2} (bare {g:.2})");
}

#[test]
fn a_thinned_far_forest_moves_with_the_wind_and_not_in_still_air() {
    let diff = |wind: &str| {
        // (Past the first seconds, whose joints switched off blend to rest.)
        let (images, _) = frames(&far_stand(wind, 8.0), &[3.0, 4.0]);
        let far = |img: &[u8]| img[far_rows()].to_vec();
        mean_abs_diff(&far(&images[0]), &far(&images[1]))
    };
    let (storm, still) = (diff("storm"), diff("0"));
    eprintln!("a second apart: {storm:.3} in a storm, {still:.3} in still air");
    assert!(storm > 0.05, "the far forest moves in a storm: {storm}");
    assert_eq!(still, 0.0, "nothing moves in still air");
}
