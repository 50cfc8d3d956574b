//! DESIGN: "the per-frame step cannot fail and does not allocate in steady state". A
//! counting global allocator watches `Forest::step` and `Forest::frame` once warmed up.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use sylva_forest::{Forest, FrameData, SceneSpec};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn steady_state_frames_do_not_allocate() {
    let spec = SceneSpec::builtin("small").expect("small scene");
    let mut forest = Forest::new(&spec).expect("forest");
    let camera = forest.default_camera();
    let mut frame = FrameData::default();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    pool.install(|| {
        for _ in 0..3 {
            forest.step(1.0 / 30.0);
            forest.frame(&camera, 1.5, &mut frame);
        }
        let before = ALLOCS.load(Ordering::Relaxed);
        for _ in 0..10 {
            forest.step(1.0 / 30.0);
            forest.frame(&camera, 1.5, &mut frame);
        }
        let n = ALLOCS.load(Ordering::Relaxed) - before;
        assert_eq!(n, 0, "{n} allocations in 10 steady-state frames");
    });
    assert!(frame.stats.drawn > 0);
}
