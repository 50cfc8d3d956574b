//! The atlas's mip chains: colour averaged by opacity with coverage-preserving alpha, and
//! depth averaged under the leaves with gaps filled from beside them.

/// Mip chain of the views' depth map `depth` (one byte a texel, `w × h`, views `cell`
/// texels a side), down to 4 texels a side as [`impostor_mips`]'s: the mean depth of the
/// texels under each, weighted by the albedo's alpha as colour is (the depth of the leaves
/// a coarse texel shows, not of the background between them).
///
/// A texel over nothing takes the depth of the covered texels around it (pulled up a
/// pyramid of coverage-weighted means within its view, and pushed back down to the
/// texels without any): a line of sight followed into the map from a gap in the crown, or
/// from beside the trunk, reads the depth of what is next to it, and its steps land on
/// it. With one depth for every such texel (the covered texels' mean, the views' middle
/// plane) a trunk seen from above, whose foot lies metres behind that plane, was shown
/// twice where the views baked from above met its line of sight a little aside. A view
/// with nothing in it takes the covered texels' mean.
pub fn depth_mips(depth: &[u8], albedo: &[u8], w: u32, h: u32, cell: u32) -> Vec<Vec<u8>> {
    let n = (w * h) as usize;
    let mut raw: Vec<f32> = albedo.chunks(4).take(n).map(|p| p[3] as f32).collect();
    let covered: Vec<usize> = (0..n).filter(|&i| raw[i] >= 128.0).collect();
    let mean = covered.iter().map(|&i| depth[i] as f64).sum::<f64>() / covered.len().max(1) as f64;
    let fill = if covered.is_empty() { 128.0 } else { mean as f32 };
    // Pull: (depth, weight) of the covered texels under each texel, level by level, while a
    // texel stays within one view.
    let mut pull: Vec<(Vec<f32>, Vec<f32>, u32)> = vec![(
        (0..n).map(|i| if raw[i] >= 128.0 { depth[i] as f32 } else { 0.0 }).collect(),
        (0..n).map(|i| if raw[i] >= 128.0 { 1.0 } else { 0.0 }).collect(),
        w,
    )];
    let (mut cw, mut ch, mut side) = (w, h, 1u32);
    while 2 * side <= cell && cw % 2 == 0 && ch % 2 == 0 && cw > 1 && ch > 1 {
        let (nw, nh) = (cw / 2, ch / 2);
        let (d, wt, _) = pull.last().expect("level 0 is there");
        let mut nd = vec![0.0f32; (nw * nh) as usize];
        let mut nwt = vec![0.0f32; (nw * nh) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let o = (y * nw + x) as usize;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let t = ((2 * y + dy) * cw + 2 * x + dx) as usize;
                    nd[o] += d[t] * wt[t];
                    nwt[o] += wt[t];
                }
                if nwt[o] > 0.0 {
                    nd[o] /= nwt[o];
                }
            }
        }
        pull.push((nd, nwt, nw));
        (cw, ch, side) = (nw, nh, 2 * side);
    }
    // Push: from the coarsest level down, a texel without coverage takes its parent's.
    let mut parent: Option<(Vec<f32>, u32)> = None;
    for (mut d, wt, lw) in pull.into_iter().rev() {
        for (i, v) in d.iter_mut().enumerate() {
            if wt[i] > 0.0 {
                continue;
            }
            *v = match &parent {
                Some((p, pw)) => {
                    let (x, y) = (i as u32 % lw, i as u32 / lw);
                    p[((y / 2) * pw + x / 2) as usize]
                }
                None => fill,
            };
        }
        parent = Some((d, lw));
    }
    let (filled, _) = parent.expect("level 0 is there");
    let mut level: Vec<u8> = filled.iter().map(|v| v.round().clamp(0.0, 255.0) as u8).collect();
    let mut out = Vec::new();
    let (mut cw, mut ch) = (w, h);
    loop {
        out.push(level.clone());
        if cw <= 4 || ch <= 4 {
            break;
        }
        let (nw, nh) = (cw / 2, ch / 2);
        let mut next = vec![0u8; (nw * nh) as usize];
        let mut next_raw = vec![0.0f32; (nw * nh) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let texels = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .map(|(dx, dy)| ((2 * y + dy) * cw + 2 * x + dx) as usize);
                let weight: f32 = texels.iter().map(|&t| raw[t]).sum();
                let o = (y * nw + x) as usize;
                let sum: f32 = if weight > 0.0 {
                    texels.iter().map(|&t| raw[t] * level[t] as f32).sum::<f32>() / weight
                } else {
                    texels.iter().map(|&t| level[t] as f32).sum::<f32>() / 4.0
                };
                next[o] = sum.round() as u8;
                next_raw[o] = weight / 4.0;
            }
        }
        level = next;
        raw = next_raw;
        cw = nw;
        ch = nh;
    }
    out
}

/// Mip chains of the baked albedo and normals (`w × h`, RGBA8), down to 4 texels a side.
/// Colour and normals average weighted by the albedo's alpha (transparent texels take the
/// opaque mean, so filtering at an edge does not pull in black); each level's alpha is
/// rescaled so that the share of texels at or above 128 (the alpha test) equals level 0's,
/// in each of `tiles.0 × tiles.1` equal tiles (an atlas's cells or views) on its own, down
/// to tiles of one texel.
pub fn impostor_mips(
    albedo: &[u8],
    normal: &[u8],
    w: u32,
    h: u32,
    tiles: (u32, u32),
) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
    let n = (w * h) as usize;
    let opaque = |img: &[u8], i: usize| img[4 * i + 3] >= 128;
    let covered = (0..n).filter(|&i| opaque(albedo, i)).count();
    let (tx, ty) = (tiles.0.clamp(1, w.max(1)), tiles.1.clamp(1, h.max(1)));
    // Texel indices of tile t of a `lw × lh` level, row-major tiles.
    let tile = |t: u32, lw: u32, lh: u32| -> Vec<usize> {
        let (sw, sh) = ((lw / tx).max(1), (lh / ty).max(1));
        let (x0, y0) = ((t % tx) * sw, (t / tx) * sh);
        (y0..(y0 + sh).min(lh))
            .flat_map(|y| (x0..(x0 + sw).min(lw)).map(move |x| (y * lw + x) as usize))
            .collect()
    };
    // Level-0 coverage of each tile.
    let coverage: Vec<f64> = (0..tx * ty)
        .map(|t| {
            let texels = tile(t, w, h);
            let k = texels.iter().filter(|&&i| opaque(albedo, i)).count();
            k as f64 / texels.len().max(1) as f64
        })
        .collect();
    // Mean opaque colour and normal fill the transparent texels.
    let mut mean = [[0.0f64; 4]; 2];
    for i in (0..n).filter(|&i| opaque(albedo, i)) {
        for c in 0..4 {
            mean[0][c] += albedo[4 * i + c] as f64;
            mean[1][c] += normal[4 * i + c] as f64;
        }
    }
    let fill = |m: [f64; 4]| -> [u8; 4] {
        let k = covered.max(1) as f64;
        [(m[0] / k) as u8, (m[1] / k) as u8, (m[2] / k) as u8, (m[3] / k) as u8]
    };
    let (fa, fn_) = (fill(mean[0]), fill(mean[1]));
    let mut a0 = albedo.to_vec();
    let mut n0 = normal.to_vec();
    for i in (0..n).filter(|&i| !opaque(albedo, i)) {
        a0[4 * i..4 * i + 3].copy_from_slice(&fa[..3]);
        n0[4 * i..4 * i + 4].copy_from_slice(&fn_);
    }
    // Raw (box-filtered, unscaled) alpha per level, and the outputs.
    let mut raw: Vec<f32> = albedo.chunks(4).map(|p| p[3] as f32).collect();
    let (mut albedo_out, mut normal_out) = (vec![a0], vec![n0]);
    let (mut cw, mut ch) = (w, h);
    while cw > 4 && ch > 4 {
        let (nw, nh) = (cw / 2, ch / 2);
        let (pa, pn) = (&albedo_out[albedo_out.len() - 1], &normal_out[normal_out.len() - 1]);
        let mut next_raw = vec![0.0f32; (nw * nh) as usize];
        let mut na = vec![0u8; (nw * nh * 4) as usize];
        let mut nn = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let texels = [
                    (2 * x, 2 * y),
                    (2 * x + 1, 2 * y),
                    (2 * x, 2 * y + 1),
                    (2 * x + 1, 2 * y + 1),
                ]
                .map(|(xx, yy)| (yy * cw + xx) as usize);
                let weight: f32 = texels.iter().map(|&t| raw[t]).sum();
                let o = (y * nw + x) as usize;
                next_raw[o] = weight / 4.0;
                for c in 0..3 {
                    let avg = |img: &[u8]| {
                        if weight > 0.0 {
                            texels.iter().map(|&t| raw[t] * img[4 * t + c] as f32).sum::<f32>()
                                / weight
                        } else {
                            texels.iter().map(|&t| img[4 * t + c] as f32).sum::<f32>() / 4.0
                        }
                    };
                    na[4 * o + c] = avg(pa).round() as u8;
                    nn[4 * o + c] = avg(pn).round() as u8;
                }
                nn[4 * o + 3] =
                    (texels.iter().map(|&t| pn[4 * t + 3] as f32).sum::<f32>() / 4.0).round() as u8;
            }
        }
        // Alpha scale keeping each tile's alpha-tested coverage: the raw value at the
        // tile's coverage quantile maps to 128.
        for t in 0..tx * ty {
            // Rank by raw alpha (ties broken by a hash of the texel, so equal values do not
            // all pass or all fail together); the first `k` pass the test.
            let mut ranked = tile(t, nw, nh);
            let tie = |o: usize| (o as u32).wrapping_mul(0x9e37_79b9).rotate_left(13);
            ranked.sort_by(|&a, &b| next_raw[b].total_cmp(&next_raw[a]).then(tie(a).cmp(&tie(b))));
            let k =
                ((coverage[t as usize] * ranked.len() as f64).round() as usize).min(ranked.len());
            let at_quantile = if k > 0 { next_raw[ranked[k - 1]].max(1.0) } else { 255.0 };
            let scale = 128.0 / at_quantile;
            for (rank, &o) in ranked.iter().enumerate() {
                let a = (next_raw[o] * scale).round();
                na[4 * o + 3] = if rank < k { a.clamp(128.0, 255.0) } else { a.min(127.0) } as u8;
            }
        }
        raw = next_raw;
        albedo_out.push(na);
        normal_out.push(nn);
        cw = nw;
        ch = nh;
    }
    (albedo_out, normal_out)
}
