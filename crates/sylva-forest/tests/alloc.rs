//! DESIGN: "the per-frame step cannot fail and does not allocate in steady state". A
//! counting global allocator watches `Forest::step` and `Forest::frame` once warmed up.

use sylva_forest::{Forest, FrameData, SceneSpec};

use sylva_testkit::{CountingAllocator, allocations, exclusive};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn steady_state_frames_do_not_allocate() {
    let _one = exclusive();
    let mut spec = SceneSpec::builtin("small").expect("small scene");
    // With occlusion culling on: its depth buffer and lists are kept between frames too.
    spec.lod.occlusion = true;
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.default_camera();
    let mut frame = FrameData::default();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    pool.install(|| {
        for _ in 0..3 {
            forest.step(1.0 / 30.0);
            forest.frame(&camera, 1.5, &mut frame);
        }
        let before = allocations();
        for _ in 0..10 {
            forest.step(1.0 / 30.0);
            forest.frame(&camera, 1.5, &mut frame);
        }
        let n = allocations() - before;
        assert_eq!(n, 0, "{n} allocations in 10 steady-state frames");
    });
    assert!(frame.stats.drawn > 0);
}
