//! Occlusion culling: trees hidden behind nearer trunks and crowns are not drawn.

use sylva_forest::{Camera, Forest, FrameData, LodSettings, SceneSpec};

/// A stand of `trees` sugar maples `spacing` m apart on flat ground, occlusion culling on.
fn stand(trees: usize, spacing: f32) -> Forest {
    let text = format!(
        "name = \"stand\"\nseed = 3\ntrees = {trees}\nspacing = {spacing}\nterrain_amplitude = 0.0\n\
         wind = \"strong\"\nspecies = [{{ name = \"sugar_maple\" }}]\nlod = {{ occlusion = true }}\n"
    );
    Forest::new(&SceneSpec::from_toml("stand.toml", &text).expect("scene")).expect("forest")
}

/// Whether the tree standing at `at` is drawn in view (not only into the shadow map).
fn drawn(f: &FrameData, at: [f32; 3]) -> bool {
    f.buckets.iter().filter(|b| !b.shadow_only).any(|b| {
        f.instances[b.first as usize..(b.first + b.count) as usize].iter().any(|i| i.position == at)
    })
}

/// Trunk bases of the trees drawn in view.
fn drawn_bases(f: &FrameData) -> Vec<[f32; 3]> {
    let mut out: Vec<[f32; 3]> = f
        .buckets
        .iter()
        .filter(|b| !b.shadow_only)
        .flat_map(|b| f.instances[b.first as usize..(b.first + b.count) as usize].iter())
        .map(|i| i.position)
        .collect();
    out.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    out.dedup();
    out
}

/// A camera `offset` from `at`, looking at the point 8 m above `at`.
fn camera_from(at: [f32; 3], offset: [f32; 3]) -> Camera {
    let eye = [at[0] + offset[0], at[1] + offset[1], at[2] + offset[2]];
    Camera { eye, target: [at[0], at[1], at[2] + 8.0], fov_deg: 50.0, near: 0.3, far: 3000.0 }
}

#[test]
fn a_tree_behind_a_stand_is_not_drawn_and_alone_or_with_culling_off_it_is() {
    // 3 000 maples 6 m apart (a stand 470 m across); the camera 250 m west of its centre
    // (16 m out from its edge), 20 m up (level with the crowns' tops), looks across it.
    let mut forest = stand(3000, 6.0);
    let centre = forest.placement(0).expect("a tree").position;
    let offset = [-250.0, 0.0, 20.0];
    let camera = camera_from(centre, offset);
    let mut f = FrameData::with_rows(768);
    forest.step(1.0 / 30.0);
    forest.frame(&camera, 4.0 / 3.0, &mut f);
    let on = drawn_bases(&f);
    let occluded = f.stats.occluded;
    assert!(occluded > 100, "crowns in front hide trees behind them: {occluded} hidden");
    assert_eq!(on.len(), f.stats.drawn);
    forest.set_lod(LodSettings { occlusion: false, ..forest.lod() });
    forest.frame(&camera, 4.0 / 3.0, &mut f);
    let off = drawn_bases(&f);
    assert_eq!(f.stats.occluded, 0, "culling off hides nothing");
    // Every tree in the view cone is drawn or hidden, and culling only takes trees away.
    assert_eq!(off.len(), on.len() + occluded);
    assert!(on.iter().all(|p| off.binary_search_by(|q| q.partial_cmp(p).expect("finite")).is_ok()));
    // The hidden trees stand behind the drawn ones: none is nearer than the nearest
    // drawn tree in front of the camera.
    let hidden: Vec<[f32; 3]> = off
        .iter()
        .filter(|p| on.binary_search_by(|q| q.partial_cmp(p).expect("finite")).is_err())
        .copied()
        .collect();
    let distance =
        |p: &[f32; 3]| ((p[0] - camera.eye[0]).powi(2) + (p[1] - camera.eye[1]).powi(2)).sqrt();
    let nearest_hidden = hidden.iter().map(distance).fold(f32::INFINITY, f32::min);
    let nearest_drawn = on.iter().map(distance).fold(f32::INFINITY, f32::min);
    assert!(
        nearest_hidden > nearest_drawn + 20.0,
        "hidden from {nearest_hidden} m, drawn from {nearest_drawn} m"
    );
    // One of the hidden trees, with the stand in front of it gone: a lone tree seen from
    // where the camera saw it is drawn.
    let h = hidden[hidden.len() / 2];
    let mut lone = stand(1, 6.0);
    let at = lone.placement(0).expect("a tree").position;
    let seen_from = [camera.eye[0] - h[0], camera.eye[1] - h[1], camera.eye[2] - h[2]];
    let lone_camera = Camera {
        eye: [at[0] + seen_from[0], at[1] + seen_from[1], at[2] + seen_from[2]],
        target: [
            camera.target[0] - h[0] + at[0],
            camera.target[1] - h[1] + at[1],
            camera.target[2] - h[2] + at[2],
        ],
        ..camera
    };
    lone.step(1.0 / 30.0);
    lone.frame(&lone_camera, 4.0 / 3.0, &mut f);
    assert!(drawn(&f, at) && f.stats.occluded == 0, "alone, the hidden tree is drawn");
}
