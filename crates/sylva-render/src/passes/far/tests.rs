//! The bake's CPU parts: outlines, crown ellipsoid, depth and alpha mips.

use super::*;

/// Whether texel (x, y) of a `cell`-texel cell lies within row `r`'s trapezoid of
/// `outline` (its four corners inside, to rounding).
fn inside(outline: &[[f32; 4]], r: usize, x: u32, y: u32, cell: u32) -> bool {
    let ([al, sl, ar, sr], [top, bottom, _, _]) = (outline[2 * r], outline[2 * r + 1]);
    let c = cell as f32;
    let eps = 1e-4;
    [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].iter().all(|&(px, py)| {
        let (px, py) = (px as f32 / c, py as f32 / c);
        py >= top - eps
            && py <= bottom + eps
            && px >= al + sl * py - eps
            && px <= ar + sr * py + eps
    })
}

#[test]
fn an_impostor_outline_holds_every_covered_texel_of_its_rows_and_hugs_a_cone() {
    // Two views a row, three rows of 64-texel cells. Row 0 shows a cone (a conifer
    // from the side: apex at the top, 40 texels wide at its foot) on a two-texel trunk;
    // row 1 the same cone shifted 6 texels right in its second view (a view baked from
    // a turned direction); row 2 a disc (the crown from above). Each row's trapezoid
    // must hold every texel its own row and the next cover, and the side view's must be
    // about the cone's area, not the square's.
    let (views, rows, cell) = (2u32, 3u32, 64u32);
    let (w, h) = (views * cell, rows * cell);
    let mut albedo = vec![0u8; (w * h * 4) as usize];
    let mut cover = |k: u32, r: u32, x: u32, y: u32| {
        let i = (((r * cell + y) * w + k * cell + x) * 4 + 3) as usize;
        albedo[i] = 200;
    };
    let cone = |x: i32, y: i32, shift: i32| {
        // Apex at (32, 8), foot at y = 48, half-width 20 there; trunk below to 60.
        let x = x - shift;
        (8..48).contains(&y) && (x - 32).abs() * 40 <= 20 * (y - 8)
            || (48..60).contains(&y) && (31..33).contains(&x)
    };
    for y in 0..cell {
        for x in 0..cell {
            let (xi, yi) = (x as i32, y as i32);
            for k in 0..views {
                if cone(xi, yi, 0) {
                    cover(k, 0, x, y);
                }
                if cone(xi, yi, if k == 1 { 6 } else { 0 }) {
                    cover(k, 1, x, y);
                }
                if (xi - 32).pow(2) + (yi - 30).pow(2) <= 18 * 18 {
                    cover(k, 2, x, y);
                }
            }
        }
    }
    let o = outline(&albedo, w, h, views, rows, cell);
    assert_eq!(o.len(), rows as usize * OUTLINE_PER_ROW);
    for r in 0..rows {
        for shown in [r, (r + 1).min(rows - 1)] {
            for k in 0..views {
                for y in 0..cell {
                    for x in 0..cell {
                        let i = (((shown * cell + y) * w + k * cell + x) * 4 + 3) as usize;
                        if albedo[i] > 0 {
                            assert!(
                                inside(&o, r as usize, x, y, cell),
                                "row {r}'s outline misses texel ({x}, {y}) of row {shown}"
                            );
                        }
                    }
                }
            }
        }
    }
    let area = |o: &[[f32; 4]], r: usize| {
        let ([al, sl, ar, sr], [top, bottom, _, _]) = (o[2 * r], o[2 * r + 1]);
        let mid = 0.5 * (top + bottom);
        (bottom - top) * (ar + sr * mid - (al + sl * mid))
    };
    let texel = 1.0 / cell as f32;
    // Row 2 alone (the disc, 37 texels across): its bounding box, no more.
    let disc_box = (37.0 * texel) * (37.0 * texel);
    assert!((area(&o, 2) / disc_box - 1.0).abs() < 0.05, "disc {} box {disc_box}", area(&o, 2));
    // Rows 0 and 1: the two cones on their trunk. The trapezoid through the apexes and
    // the feet's corners, extended down to the trunk's end (6 … 64 at y = 60, 6 texels
    // wide at the top: 0.41 of the cell), not the box around them (46 × 52: 0.58).
    assert!(area(&o, 0) < 0.43, "the cones' outline: {}", area(&o, 0));
    // A cone alone, apex up: half its box, which the square of the cells draws whole.
    let mut albedo = vec![0u8; (w * h * 4) as usize];
    for r in 0..rows {
        for y in 0..cell {
            for x in 0..cell {
                if (8..48).contains(&(y as i32)) && cone(x as i32, y as i32, 0) {
                    let i = (((r * cell + y) * w + x) * 4 + 3) as usize;
                    albedo[i] = 255;
                }
            }
        }
    }
    let o = outline(&albedo, w, h, views, rows, cell);
    let cone_box = 41.0 * 40.0 * texel * texel;
    for r in 0..rows as usize {
        assert!(area(&o, r) < 0.56 * cone_box, "row {r}: {} for a box {cone_box}", area(&o, r));
    }
}

#[test]
fn an_impostor_with_nothing_baked_is_drawn_over_its_whole_cell() {
    let (w, h) = (2 * 8, 3 * 8);
    let o = outline(&vec![0u8; (w * h * 4) as usize], w, h, 2, 3, 8);
    for r in 0..3 {
        assert!(inside(&o, r, 0, 0, 8) && inside(&o, r, 7, 7, 8), "row {r}: {o:?}");
    }
}

#[test]
fn impostors_are_baked_from_level_one_with_every_leaf_card_of_full_detail() {
    // Every preset's impostor is rendered from level 1 (each preset's level 1 is within
    // BAKE_TRIANGLES), which has full detail's leaf cards on less wood: only the wood is
    // thinned, not the foliage the impostor mostly shows. Full detail itself is within
    // the cap for most presets, so it is BAKE_FINEST, not the cap, that picks level 1.
    let mut full_within_cap = 0;
    for (name, _) in sylva_tree::species::PRESETS {
        let species = sylva_tree::species::Species::preset(name).expect("preset");
        let model = species.model(1, sylva_tree::mesh::LOD_LEVELS).expect("model");
        let (full, baked) = (&model.lods[0], &model.lods[bake_level(&model)]);
        assert_eq!(bake_level(&model), 1, "{name}");
        assert!(baked.triangles() <= BAKE_TRIANGLES, "{name}: {}", baked.triangles());
        assert_eq!(baked.clusters.len(), full.clusters.len(), "{name}: leaf cards");
        assert!(baked.triangles() < full.triangles(), "{name}: less wood");
        full_within_cap += usize::from(full.triangles() <= BAKE_TRIANGLES);
    }
    assert!(full_within_cap > 0);
}

#[test]
fn the_crown_ellipsoid_of_clusters_filling_one_gives_back_its_radii_and_leaf_density() {
    // Clusters of 0.05 m² each on a 0.25 m lattice filling an ellipsoid of radii 3 m
    // across and 4 m up about (0, 0, 8): leaf area density 0.05 / 0.25³
    // = 3.2 m²/m³. The moments of a uniformly filled ellipsoid give its radii back (to
    // the lattice's step), and the extinction is CROWN_EXTINCTION times the density.
    let (a, b, z0, step, area) = (3.0f32, 4.0f32, 8.0f32, 0.25f32, 0.05f32);
    let mut clusters = Vec::new();
    let n = (b / step) as i32 + 1;
    for i in -n..=n {
        for j in -n..=n {
            for k in -n..=n {
                let p = [i as f32 * step, j as f32 * step, k as f32 * step];
                if (p[0] * p[0] + p[1] * p[1]) / (a * a) + p[2] * p[2] / (b * b) <= 1.0 {
                    clusters.push(sylva_tree::mesh::LeafCluster {
                        joint: 0,
                        hang: [0.0; 3],
                        center: [p[0], p[1], p[2] + z0],
                        size: 0.3,
                        roll: 0.0,
                        atlas: 0,
                        phase: 0.0,
                        leaf_area: area,
                        normal: [0.0, 0.0, 1.0],
                        exposure: 1.0,
                    });
                }
            }
        }
    }
    let [z, ra, rb, extinction] = crown_ellipsoid(&clusters);
    assert!((z - z0).abs() < 1e-3, "centre {z}");
    assert!((ra - a).abs() < 0.1 && (rb - b).abs() < 0.1, "radii {ra}, {rb}");
    let density = area / (step * step * step);
    assert!(
        (extinction / (CROWN_EXTINCTION * density) - 1.0).abs() < 0.05,
        "extinction {extinction} for density {density}"
    );
    assert_eq!(crown_ellipsoid(&[]), [0.0; 4], "no leaves, no shade");
}

#[test]
fn a_coarse_depth_texel_holds_the_depth_of_the_leaves_under_it_not_of_the_background() {
    // An 8 × 8 view: a leaf at depth 60 covering one texel of each 2 × 2 block in the
    // left half, one at depth 200 in the top right quarter, nothing else (depth 255,
    // the bake's cleared far plane). A plain mean would pull every coarse texel towards
    // the far plane; weighted by coverage each holds its leaves' depth. Texels over
    // nothing hold the depth of the leaves next to them (the empty quarter, next to
    // nothing within its 4 × 4 block, the covered texels' mean).
    let (w, h) = (8u32, 8u32);
    let mut albedo = vec![0u8; (w * h * 4) as usize];
    let mut depth = vec![255u8; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let leaf = if x < 4 && x % 2 == 0 && y % 2 == 0 {
                60
            } else if x >= 4 && y < 4 {
                200
            } else {
                continue;
            };
            albedo[4 * i + 3] = 255;
            depth[i] = leaf;
        }
    }
    let mips = depth_mips(&depth, &albedo, w, h, 8);
    assert_eq!(mips.len(), 2, "8 × 8 and 4 × 4, as impostor_mips stops");
    let covered = 8 + 16;
    let mean = ((8 * 60 + 16 * 200) as f64 / covered as f64).round() as u8;
    assert_eq!(mips[0][(7 * w + 7) as usize], mean, "an empty quarter takes the covered mean");
    assert_eq!(mips[0][0], 60);
    assert_eq!(mips[0][(w + 1) as usize], 60, "a gap between the near leaves takes theirs");
    assert_eq!(mips[0][(5 * w + 3) as usize], 60, "and lower down");
    let l1 = &mips[1];
    for y in 0..4u32 {
        for x in 0..4u32 {
            let want = match (x < 2, y < 2) {
                (true, _) => 60,
                (false, true) => 200,
                (false, false) => mean,
            };
            assert_eq!(l1[(y * 4 + x) as usize], want, "level 1 texel ({x}, {y})");
        }
    }
}

#[test]
fn a_texel_over_nothing_takes_the_depth_of_what_is_beside_it_in_its_own_view() {
    // Two 16 × 16 views side by side. The left one holds a vertical trunk two texels wide
    // at depth 220 (a foot seen from above, behind the views' middle) and a leaf at
    // depth 20 in its top left corner; the right one a single leaf at depth 100. Beside
    // the trunk the map must read the trunk's depth, so that a line of sight followed
    // into it from just beside the trunk lands on the trunk and not a view's width
    // away; the right view's empty texels must read its own leaf's depth, not the left
    // view's.
    let (w, h, cell) = (32u32, 16u32, 16u32);
    let mut albedo = vec![0u8; (w * h * 4) as usize];
    let mut depth = vec![255u8; (w * h) as usize];
    let mut put = |x: u32, y: u32, d: u8| {
        let i = (y * w + x) as usize;
        albedo[4 * i + 3] = 255;
        depth[i] = d;
    };
    for y in 8..16 {
        put(7, y, 220);
        put(8, y, 220);
    }
    put(0, 0, 20);
    put(24, 4, 100);
    let mips = depth_mips(&depth, &albedo, w, h, cell);
    let at = |x: u32, y: u32| mips[0][(y * w + x) as usize];
    for y in 8..16 {
        for x in [5, 6, 9, 10] {
            assert_eq!(at(x, y), 220, "texel ({x}, {y}) beside the trunk");
        }
    }
    assert_eq!(at(1, 1), 20, "beside the corner leaf");
    for (x, y) in [(16, 0), (31, 15), (20, 10)] {
        assert_eq!(at(x, y), 100, "texel ({x}, {y}) of the right view");
    }
    // The covered texels keep their own depth.
    assert_eq!((at(7, 12), at(0, 0), at(24, 4)), (220, 20, 100));
}

#[test]
fn alpha_mips_keep_the_crown_from_thinning_out_and_within_its_silhouette() {
    // Left half: isolated opaque texels (thin leaves) at 25 % density; right half empty.
    // A plain box filter turns them into alpha 64: every texel fails the alpha test.
    let (w, h) = (64u32, 64u32);
    let mut albedo = vec![0u8; (w * h * 4) as usize];
    for y in 0..h {
        for x in 0..w / 2 {
            if x % 2 == 0 && y % 2 == 0 {
                let i = ((y * w + x) * 4) as usize;
                albedo[i..i + 4].copy_from_slice(&[40, 120, 30, 255]);
            }
        }
    }
    let normal = vec![128u8; albedo.len()];
    let (mips, normals) = impostor_mips(&albedo, &normal, w, h, (1, 1));
    assert_eq!(mips.len(), normals.len());
    assert!(mips.len() >= 4);
    let share = |m: &[u8], pred: &dyn Fn(&[u8]) -> bool| {
        m.chunks(4).filter(|p| pred(p)).count() as f64 / (m.len() / 4) as f64
    };
    let level0 = share(&mips[0], &|p| p[3] >= 128);
    assert!((level0 - 0.125).abs() < 1e-9);
    for (l, m) in mips.iter().enumerate().skip(1) {
        let pass = share(m, &|p| p[3] >= 128);
        let silhouette = share(m, &|p| p[3] > 0);
        assert!(pass >= level0 - 0.01, "level {l}: {pass:.3} pass, level 0 {level0:.3}");
        assert!(pass <= silhouette + 1e-9, "level {l}: {pass:.3} pass outside the silhouette");
        // Colour is the leaves' colour, not darkened by the transparent background.
        for p in m.chunks(4).filter(|p| p[3] >= 128) {
            assert!((p[1] as i32 - 120).abs() <= 2, "level {l}: green {}", p[1]);
        }
    }
    let plain = crate::shared::box_mips(&albedo, w, h);
    assert_eq!(share(&plain[1], &|p| p[3] >= 128), 0.0, "the case a plain box filter loses");
}

#[test]
fn every_leaf_cell_keeps_its_coverage_within_ten_percent_at_every_mip_level() {
    // A crown seen from farther away samples coarser mips of the leaf atlas: what passes
    // the alpha test must stay the same share of each cluster, or far crowns thin out
    // (plain box filter) or fatten.
    for (name, _) in sylva_tree::PRESETS {
        let sp = sylva_tree::Species::preset(name).expect("preset");
        let atlas = sylva_tree::texture::leaf_atlas(&sp, 1, sylva_tree::mesh::ATLAS_SIZE);
        let (w, h) = (atlas.image.width, atlas.image.height);
        let normal = vec![128u8; atlas.image.rgba.len()];
        let (mips, _) = impostor_mips(&atlas.image.rgba, &normal, w, h, (atlas.cells, atlas.cells));
        let cells = atlas.cells;
        for (l, m) in mips.iter().enumerate() {
            let (lw, lh) = ((w >> l).max(1), (h >> l).max(1));
            let side = lw / cells;
            // Below 8 texels a cell, one texel is more than 10 % of a cluster's leaves.
            if side < 8 {
                break;
            }
            for c in 0..cells * cells {
                let (cx, cy) = (c % cells, c / cells);
                let mut pass = 0usize;
                for y in cy * side..(cy + 1) * side {
                    for x in cx * side..(cx + 1) * side {
                        pass += usize::from(m[((y * lw + x) * 4 + 3) as usize] >= 128);
                    }
                }
                let cov = pass as f32 / (side * side) as f32;
                let want = atlas.coverage[c as usize];
                assert!(
                    (cov / want - 1.0).abs() < 0.10,
                    "{name} cell {c} mip {l} ({lw}x{lh}): coverage {cov:.3} vs {want:.3}"
                );
            }
        }
    }
}
