//! Thinning of far impostors (`LodSettings::thin_px`): fewer far trees, each wider, the
//! canopy's cover kept; the near trees and the frame without it unchanged.

use sylva_forest::{Camera, Forest, FrameData, LodSettings, SceneSpec};

fn stand() -> SceneSpec {
    SceneSpec::from_toml(
        "thin.toml",
        "name = \"thin\"\nseed = 3\ntrees = 6000\nspacing = 7.0\nwind = \"breeze\"\n\
         species = [{ name = \"quaking_aspen\" }, { name = \"douglas_fir\" }]\n",
    )
    .expect("scene")
}

/// Each draw's cover as the picture takes it: its share of the dither range (a range
/// reaching 1 is written open to 2) times how much wider it is drawn.
fn cover(frame: &FrameData, far: bool) -> f64 {
    frame
        .instances
        .iter()
        .filter(|i| (i.tag & 15 == 15) == far)
        .map(|i| ((i.fade[1].min(1.0) - i.fade[0]) * i.spread) as f64)
        .sum()
}

/// High over one edge of `forest`, looking across it: near trees large, far ones a few
/// pixels.
fn across(forest: &Forest) -> Camera {
    Camera {
        eye: [-forest.radius - 20.0, 0.0, 60.0],
        target: [0.0, 0.0, 0.0],
        fov_deg: 60.0,
        near: 0.5,
        far: 20_000.0,
    }
}

#[test]
fn thinning_draws_fewer_far_trees_wider_and_keeps_their_cover() {
    let spec = stand();
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = across(&forest);
    let frame_with = |forest: &mut Forest, px: f32| {
        forest.set_lod(LodSettings { thin_px: px, ..forest.lod() });
        let mut f = FrameData::with_rows(768);
        // Two frames, so the LOD state has settled from the first.
        forest.frame(&camera, 4.0 / 3.0, &mut f);
        forest.frame(&camera, 4.0 / 3.0, &mut f);
        f
    };
    let whole = frame_with(&mut forest, 0.0);
    assert!(whole.instances.iter().all(|i| i.spread == 1.0), "without thinning, spread 1");
    assert_eq!(whole.stats.thinned, 0);
    let thin = frame_with(&mut forest, 64.0);
    let (far_whole, far_thin) = (cover(&whole, true), cover(&thin, true));
    assert!(thin.stats.thinned > whole.stats.impostors / 4, "thinned {}", thin.stats.thinned);
    assert!(
        thin.stats.impostors + thin.stats.thinned == whole.stats.impostors,
        "every far tree is drawn or thinned: {} + {} against {}",
        thin.stats.impostors,
        thin.stats.thinned,
        whole.stats.impostors
    );
    assert!(
        (far_thin / far_whole - 1.0).abs() < 0.05,
        "far cover {far_thin} against {far_whole} without thinning"
    );
    // The meshes are the same draws.
    let meshes = |f: &FrameData| -> Vec<[f32; 3]> {
        f.instances.iter().filter(|i| i.tag & 15 != 15).map(|i| i.position).collect()
    };
    assert_eq!(meshes(&thin), meshes(&whole));
    assert!(thin.instances.iter().any(|i| i.spread > 2.0), "the far trees kept are wider");
    // Off again: the frame without thinning, bit for bit.
    let again = frame_with(&mut forest, 0.0);
    assert_eq!(again.instances, whole.instances);
}

#[test]
fn far_trees_fading_out_keep_their_shares_at_different_places_in_the_dither_range() {
    // The dither is the screen's: far trees fading out at the same place in the picture,
    // all keeping the range's start, would all drop the same pixels, and the ground would
    // show through the far canopy in the dither's pattern. Each keeps its share at its
    // own place instead: the starts, as fractions of the room a share leaves, are spread
    // evenly over [0, 1).
    let spec = stand();
    let mut forest = Forest::new(&spec).expect("forest");
    forest.set_lod(LodSettings { thin_px: 64.0, ..forest.lod() });
    let camera = across(&forest);
    let mut frame = FrameData::with_rows(768);
    forest.frame(&camera, 4.0 / 3.0, &mut frame);
    forest.frame(&camera, 4.0 / 3.0, &mut frame);
    let places: Vec<f32> = frame
        .instances
        .iter()
        .filter(|i| i.tag & 15 == 15 && i.fade[1] < 1.0)
        .map(|i| i.fade[0] / (1.0 - (i.fade[1] - i.fade[0])))
        .collect();
    assert!(places.len() > 100, "{} trees fading", places.len());
    assert!(places.iter().all(|p| (0.0..1.0).contains(p)), "places in [0, 1)");
    // Evenly spread: each quarter of [0, 1) holds about a quarter of them.
    for q in 0..4 {
        let share = places.iter().filter(|&&p| (p * 4.0) as usize == q).count() as f32
            / places.len() as f32;
        assert!((share - 0.25).abs() < 0.06, "quarter {q} holds {share} of the places");
    }
}
