//! The per-frame step allocates nothing once running (DESIGN: "the per-frame step does not
//! allocate in steady state"). A counting global allocator watches a single-threaded step:
//! the allocations made on the one thread of its pool, where the step and all its parallel
//! work run (the harness's other threads may allocate meanwhile).

use sylva_sway::{SwayBatch, SwayParams, SwaySpecies};
use sylva_tree::{Joint, NO_PARENT, Skeleton};

use sylva_testkit::{CountingAllocator, exclusive, thread_allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn steady_state_steps_do_not_allocate() {
    let _one = exclusive();
    let joints: Vec<Joint> = (0..20)
        .map(|i| Joint {
            parent: if i == 0 { NO_PARENT } else { (i - 1) as u32 },
            origin: [0.0, 0.0, i as f32],
            axis: [0.0, 0.0, 1.0],
            length: 1.0,
            radius: 0.1,
            own_mass: 20.0,
            leaf_area: 1.0,
            leaf_mass: 0.3,
            continues: i > 0,
        })
        .collect();
    let sp = SwaySpecies::new(&Skeleton::new(joints).expect("valid"), SwayParams::default())
        .expect("params");
    let mut b = SwayBatch::new(sp, 16);
    let wind = vec![[6.0f32, 1.0, 0.0]; 16];
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("pool");
    pool.install(|| {
        b.step(1.0 / 60.0, &wind); // first step at this dt builds the transition table
        let before = thread_allocations();
        for _ in 0..100 {
            b.step(1.0 / 60.0, &wind);
        }
        let after = thread_allocations();
        assert_eq!(after - before, 0, "{} allocations in 100 steps", after - before);
    });
}
