//! The cells: a frame visits the cells in view and the trees in them, not the forest.

use super::*;

/// A flat stand of aspens 7 m apart, `trees` of them, in a steady wind (no field to make).
fn stand(trees: usize) -> SceneSpec {
    SceneSpec::from_toml(
        "stand.toml",
        &format!(
            "name = \"stand\"\nseed = 3\ntrees = {trees}\nspacing = 7.0\n\
             terrain_amplitude = 0.0\nwind = \"5\"\nspecies = [{{ name = \"quaking_aspen\" }}]\n"
        ),
    )
    .expect("scene")
}

#[test]
fn a_frames_work_grows_with_the_view_not_with_the_forest() {
    // A walker at the centre of a stand of 20 000 trees and of one of 320 000, looking
    // along the ground to 300 m: the same view over the same density of trees. The frame
    // visits the cells the view reaches, so the cells and trees it visits are about equal
    // (the two layouts differ, and so do the cells cut by the view's edge), far fewer than
    // the larger forest's; trees out of the cells visited are never looked at.
    let mut visited = Vec::new();
    for trees in [20_000, 320_000] {
        let mut forest = Forest::new(&stand(trees)).expect("forest");
        let foot = forest.placement(0).expect("a tree").position;
        let camera = Camera {
            eye: [foot[0] + 3.0, foot[1], foot[2] + 1.7],
            target: [foot[0] + 100.0, foot[1] + 30.0, foot[2] + 1.7],
            fov_deg: 60.0,
            near: 0.3,
            far: 300.0,
        };
        let mut frame = FrameData::with_rows(768);
        forest.step(0.1);
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
        let s = frame.stats;
        eprintln!(
            "{trees} trees: {} cells and {} trees visited, {} drawn",
            s.cells_visited, s.trees_visited, s.drawn
        );
        assert!(s.drawn > 100 && s.trees_visited >= s.drawn, "{s:?}");
        visited.push(s);
    }
    let (small, large) = (visited[0], visited[1]);
    let near = |a: usize, b: usize, by: f64| (a as f64 / b as f64 - 1.0).abs() <= by;
    assert!(near(large.trees_visited, small.trees_visited, 0.35), "{small:?}\n{large:?}");
    assert!(large.cells_visited <= small.cells_visited + 30, "{small:?}\n{large:?}");
    assert!(near(large.drawn, small.drawn, 0.1), "the same view: {small:?}\n{large:?}");
    assert!(large.trees_visited * 20 < large.trees, "{large:?}");
}
