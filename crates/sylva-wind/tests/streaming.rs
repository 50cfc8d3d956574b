//! A field larger than the memory it may use: streamed to a Zarr store, the synthesis keeps
//! one block of columns in memory whatever the field's size. Heap use is measured with a
//! tracking allocator.

use sylva_wind::io::write_zarr_streaming;
use sylva_wind::synth::streaming_memory_estimate;
use sylva_wind::{Grid, Method, SynthParams, WindParams};

use sylva_testkit::{CountingAllocator, exclusive, peak_during};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn a_field_four_times_the_memory_budget_streams_within_it() {
    let _one = exclusive();
    let budget = 40usize << 20;
    // 512 × 32 points × 3 components × 1024 frames of f32: 201 MB, 4.8× the budget.
    let grid = Grid::regular(512, 32, 4.0, &[20.0], 1024, 0.1);
    let output = grid.points() * 3 * grid.frames * 4;
    assert!(output > 4 * budget);
    assert!(streaming_memory_estimate(&grid) < budget as f64);
    let dir = sylva_testkit::TempDir::new("sylva-stream");
    let store = dir.join("big.zarr");
    let sp = SynthParams { seed: 4, method: Method::Separable };
    let (written, peak) =
        peak_during(|| write_zarr_streaming(&WindParams::default(), &grid, sp, &store, &|_| {}));
    written.expect("stream");
    let written: u64 = walk(&store);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(written >= output as u64, "wrote {written} bytes of {output}");
    assert!(peak < budget, "peak heap {peak} bytes over the {budget}-byte budget");
}

fn walk(p: &std::path::Path) -> u64 {
    std::fs::read_dir(p)
        .expect("list")
        .flatten()
        .map(|e| {
            let q = e.path();
            if q.is_dir() { walk(&q) } else { e.metadata().map(|m| m.len()).unwrap_or(0) }
        })
        .sum()
}
