//! The `embed` example's host draws a pillar of its own among the trees: its frame,
//! rendered offscreen with and without the pillar, shows the two hiding each other.

#[allow(dead_code)]
#[path = "../examples/embed.rs"]
mod embed;

use embed::{PILLAR, offscreen};
use sylva_forest::{Camera, Forest, SceneSpec};

/// Corner `i` of the pillar (bit 0: x, bit 1: y, bit 2: z at the high side).
fn corner(i: usize) -> [f32; 3] {
    let (lo, hi) = PILLAR;
    std::array::from_fn(|k| if i >> k & 1 == 0 { lo[k] } else { hi[k] })
}

/// The pillar and the trees hide each other: within the pillar's image some pixels are
/// the pillar's and some are the forest's own (trees and ground in front of it), the
/// same as in the frame drawn without the pillar.
#[test]
fn the_hosts_pillar_and_the_trees_hide_each_other() {
    let (w, h) = (256u32, 192u32);
    let (with, without) = (offscreen((w, h), 3, true), offscreen((w, h), 3, false));
    let scene_camera = Camera {
        eye: [40.0 * (-2.3f32).cos(), 40.0 * (-2.3f32).sin(), 9.0],
        target: [0.0, 0.0, 7.0],
        ..Forest::new(&SceneSpec::builtin("small").expect("scene"))
            .expect("forest")
            .default_camera()
    };
    let vp = scene_camera.view_projection(w as f32 / h as f32);
    let (mut x0, mut x1, mut y0, mut y1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    for p in (0..8).map(corner) {
        let c: Vec<f32> =
            (0..4).map(|r| (0..3).map(|k| vp[k][r] * p[k]).sum::<f32>() + vp[3][r]).collect();
        let (x, y) = ((c[0] / c[3] + 1.0) * 0.5 * w as f32, (1.0 - c[1] / c[3]) * 0.5 * h as f32);
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let (mut pillar, mut forest, mut n) = (0, 0, 0);
    for y in y0.max(0.0) as u32 + 1..(y1 as u32).min(h - 1) {
        for x in x0.max(0.0) as u32 + 1..(x1 as u32).min(w - 1) {
            let i = ((y * w + x) * 4) as usize;
            let (a, b) = (&with[i..i + 3], &without[i..i + 3]);
            n += 1;
            let g = 2 * a[1].max(8) as u32;
            pillar += (a[0] as u32 > g && a[2] as u32 > g) as usize;
            forest += (a == b) as usize;
        }
    }
    assert!(n > 100, "the pillar covers {n} pixels");
    assert!(pillar > n / 10 && forest > n / 20, "pillar {pillar}, forest in front {forest} of {n}");
}
