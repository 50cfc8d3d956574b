//! Each preset's foliage in the sun: the median brightness of its crown in a one-tree scene
//! against the aspen's, so no preset renders as a dark silhouette of its species.

use super::*;

/// The crown pixels of a one-tree scene of `species` in calm air (sun behind the camera's
/// left shoulder, the scene's default), seen from 1.7 tree heights at mid-crown height:
/// the pixels where the tree changes the image (the same frame with the tree drawn into
/// the shadow map only, so its shadow is in both), above the crown's base (where a tenth
/// of its leaf cards hang lower). Returns their
/// brightnesses (mean of R, G, B, 0 … 255).
fn crown_pixels(species: &str) -> Vec<f64> {
    let text = format!(
        r#"
        name = "one"
        seed = 1
        trees = 1
        terrain_amplitude = 0.0
        wind = "calm"
        species = [ {{ name = "{species}", seed = 1 }} ]
        "#
    );
    let spec = SceneSpec::from_toml("one.toml", &text).expect("scene");
    let mut forest = Forest::new(&spec).expect("forest");
    let foot = forest.placement(0).expect("tree").position;
    let tall = forest.tree_info(0).expect("tree").height;
    // The crown's base: the height below which a tenth of the leaf cards hang.
    let model = &forest.species[0].model;
    let mut card_z: Vec<f32> = model.lods[0].clusters.iter().map(|c| c.center[2]).collect();
    card_z.sort_by(f32::total_cmp);
    let crown_base = card_z[card_z.len() / 10];
    let scale = tall / model.tree.stats.height;
    let mid = [foot[0], foot[1], foot[2] + 0.55 * tall];
    let sun = spec.lighting.sun_direction;
    // From the sun's side (the camera's back to it, a little aside), level with mid-crown.
    let (sx, sy) = (sun[0], sun[1]);
    let norm = (sx * sx + sy * sy).sqrt().max(1e-6);
    let (dx, dy) = (sx / norm, sy / norm);
    let (ax, ay) = (dx * 0.94 - dy * 0.34, dy * 0.94 + dx * 0.34);
    let d = 1.7 * tall;
    let camera = Camera {
        eye: [mid[0] + ax * d, mid[1] + ay * d, mid[2]],
        target: mid,
        fov_deg: 45.0,
        near: 0.3,
        far: 2000.0,
    };
    let mut gpu = Headless::new(&forest, W, H).unwrap_or_else(|e| panic!("{e}"));
    let mut frame = FrameData::default();
    forest.step(1.0 / 30.0);
    forest.frame(&camera, W as f32 / H as f32, &mut frame);
    let with = gpu.render(&frame, &camera).expect("render");
    for b in &mut frame.buckets {
        b.shadow_only = true;
    }
    let without = gpu.render(&frame, &camera).expect("render");
    let base_row =
        pixel_of(&camera, [foot[0], foot[1], foot[2] + crown_base * scale]).map_or(H, |(_, y)| y);
    let mut out = Vec::new();
    for y in 0..base_row.min(H) {
        for x in 0..W {
            let (a, b) = (px(&with, x, y), px(&without, x, y));
            if (0..3).map(|k| (a[k] - b[k]).abs()).sum::<i32>() > 12 {
                out.push((a[0] + a[1] + a[2]) as f64 / 3.0);
            }
        }
    }
    out
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn every_presets_crown_in_sun_is_within_a_factor_of_the_aspens_brightness() {
    // The aspen's light yellow-green leaves are the reference. A darker species (the
    // fir's blue-green needles, the oak's dense crown) may be darker, but not a silhouette:
    // every preset's median crown brightness lies within 0.6–1.6 of the aspen's.
    let aspen = crown_pixels("quaking_aspen");
    assert!(aspen.len() > 500, "the aspen covers {} pixels", aspen.len());
    let reference = median(aspen);
    let mut off = Vec::new();
    for (name, _) in sylva_tree::PRESETS {
        let pixels = crown_pixels(name);
        let n = pixels.len();
        let m = median(pixels);
        println!(
            "{name}: median {m:.1} over {n} pixels (aspen {reference:.1}): ×{:.2}",
            m / reference
        );
        assert!(n > 500, "{name}: {n} crown pixels");
        if !(0.6..=1.6).contains(&(m / reference)) {
            off.push(format!("{name} ×{:.2}", m / reference));
        }
    }
    assert!(off.is_empty(), "crowns out of 0.6–1.6 × the aspen's median brightness: {off:?}");
}
