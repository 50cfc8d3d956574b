//! Frontal (projected) area of a tree seen from the side: the union of its segments and
//! leaves on a raster, against the sum of their own projected areas (their overlap).

use sylva_tree::Skeleton;

/// Cells along the longer side of the raster of each view.
const CELLS: usize = 512;

/// Projected areas of a tree seen from the side, m², averaged over two views (along world
/// x and along world y).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frontal {
    /// Area of the union: the tree's silhouette, gaps excluded (what a photograph against
    /// the sky measures as a crown's frontal area).
    pub union: f32,
    /// Sum of every element's projected area, overlaps counted each time.
    pub sum: f32,
}

/// Each joint's segment drawn as a flat-ended band along its projected axis (a segment seen
/// end-on shows nothing: its area is its projected length times its width), of half-width the larger
/// of its radius and its leaves spread along it (a flat leaf shows on average half its
/// one-sided area: the band's area is the segment's d·L plus half its leaf area).
pub fn frontal_area(skeleton: &Skeleton) -> Frontal {
    let joints = skeleton.joints();
    let (mut union, mut sum) = (0.0, 0.0);
    for (a, b) in [(1usize, 2usize), (0, 2)] {
        let mut lo = [f32::INFINITY; 2];
        let mut hi = [f32::NEG_INFINITY; 2];
        let mut bands = Vec::with_capacity(joints.len());
        for j in joints {
            let t = j.tip();
            let (p, q) = ([j.origin[a], j.origin[b]], [t[a], t[b]]);
            let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            let half = j.radius.max(0.25 * j.leaf_area / j.length.max(1e-3));
            sum += len * 2.0 * half;
            for c in 0..2 {
                lo[c] = lo[c].min(p[c].min(q[c]) - half);
                hi[c] = hi[c].max(p[c].max(q[c]) + half);
            }
            bands.push((p, q, half));
        }
        let h = (hi[0] - lo[0]).max(hi[1] - lo[1]) / CELLS as f32;
        if !(h > 0.0 && h.is_finite()) {
            // Nothing with an extent in this view.
            continue;
        }
        let (nu, nv) =
            (((hi[0] - lo[0]) / h).ceil() as usize + 1, ((hi[1] - lo[1]) / h).ceil() as usize + 1);
        let mut covered = vec![false; nu * nv];
        for (p, q, half) in bands {
            let d = [q[0] - p[0], q[1] - p[1]];
            let dd = (d[0] * d[0] + d[1] * d[1]).max(1e-12);
            let cell = |v: f32, c: usize| ((v - lo[c]) / h).floor().max(0.0) as usize;
            let (u0, u1) =
                (cell(p[0].min(q[0]) - half, 0), cell(p[0].max(q[0]) + half, 0).min(nu - 1));
            let (v0, v1) =
                (cell(p[1].min(q[1]) - half, 1), cell(p[1].max(q[1]) + half, 1).min(nv - 1));
            for v in v0..=v1 {
                for u in u0..=u1 {
                    let x =
                        [lo[0] + (u as f32 + 0.5) * h - p[0], lo[1] + (v as f32 + 0.5) * h - p[1]];
                    let s = (x[0] * d[0] + x[1] * d[1]) / dd;
                    let e = [x[0] - s * d[0], x[1] - s * d[1]];
                    if (0.0..=1.0).contains(&s) && e[0] * e[0] + e[1] * e[1] <= half * half {
                        covered[v * nu + u] = true;
                    }
                }
            }
        }
        union += covered.iter().filter(|&&c| c).count() as f32 * h * h;
    }
    Frontal { union: 0.5 * union, sum: 0.5 * sum }
}
