//! An impostor's outline per elevation row: the trapezoid around what its views show, so
//! its quad covers no more pixels than it must.

use super::OUTLINE_PER_ROW;

/// The trapezoid an impostor is drawn as, from its views' coverage (`albedo`, RGBA8,
/// `w × h`, `views × rows` cells of `cell` texels a side), in a cell's coordinates (x across
/// 0 … 1, y down 0 … 1): for each elevation row `r`, the smallest trapezoid with horizontal
/// top and bottom that holds every texel any view of row `r` or `r + 1` covers (an
/// instance between the two shows either), as its left and right sides `x = a + s·y`,
/// `[a_left, s_left, a_right, s_right]`, then `[y_top, y_bottom, 0, 0]`. Still two
/// triangles a tree, as the square of the cells was, but a conifer's is nearly a triangle
/// and every tree's ends where its crown and trunk end. The shader clamps it to the square
/// it replaces and does not widen it (what a coarse mip's texel spreads past the outline
/// shows in a few hundred pixels of scene D's frame, each by a few levels: far.wgsl).
pub fn outline(albedo: &[u8], w: u32, h: u32, views: u32, rows: u32, cell: u32) -> Vec<[f32; 4]> {
    let (views, rows, cell) = (views.max(1), rows.max(1), cell.max(1));
    // Per row and texel row of a cell: the covered columns' range over all the row's views.
    let mut spans = vec![None::<(u32, u32)>; (rows * cell) as usize];
    for r in 0..rows {
        for y in 0..cell {
            let ty = r * cell + y;
            if ty >= h {
                continue;
            }
            let span = &mut spans[ty as usize];
            for k in 0..views {
                for x in 0..cell {
                    let tx = k * cell + x;
                    if tx >= w || albedo[((ty * w + tx) * 4 + 3) as usize] == 0 {
                        continue;
                    }
                    *span = Some(span.map_or((x, x), |(a, b)| (a.min(x), b.max(x))));
                }
            }
        }
    }
    let mut out = Vec::with_capacity(rows as usize * OUTLINE_PER_ROW);
    for r in 0..rows {
        // The texel rows covered in row r or the next, with their covered range (texel
        // edges, in a cell's units): (y top, y bottom, x left, x right).
        let pair = [r, (r + 1).min(rows - 1)];
        let covered: Vec<[f32; 4]> = (0..cell)
            .filter_map(|y| {
                let both = pair.map(|r| spans[(r * cell + y) as usize]);
                let (a, b) =
                    both.into_iter().flatten().reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
                let c = cell as f32;
                Some([y as f32 / c, (y + 1) as f32 / c, a as f32 / c, (b + 1) as f32 / c])
            })
            .collect();
        let (Some(first), Some(last)) = (covered.first(), covered.last()) else {
            // Nothing covered: the whole cell.
            out.extend([[0.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 0.0]]);
            continue;
        };
        let (top, bottom) = (first[0], last[1]);
        let mid = 0.5 * (top + bottom);
        // Each side: of the slopes tried, the one whose line, moved out to the last covered
        // texel, lies innermost at mid-height (the trapezoid's area is its height times
        // its width there). A texel row is held where its top and bottom corners are.
        let side = |left: bool| {
            (-200..=200)
                .map(|i| {
                    let slope = i as f32 * 0.01;
                    let offsets = covered.iter().flat_map(|c| {
                        let x = if left { c[2] } else { c[3] };
                        [x - slope * c[0], x - slope * c[1]]
                    });
                    let a = if left {
                        offsets.fold(f32::INFINITY, f32::min)
                    } else {
                        offsets.fold(f32::NEG_INFINITY, f32::max)
                    };
                    (a, slope)
                })
                .max_by(|p, q| {
                    let at = |(a, s): (f32, f32)| if left { a + s * mid } else { -(a + s * mid) };
                    at(*p).total_cmp(&at(*q))
                })
                .unwrap_or((0.0, 0.0))
        };
        let (l, rt) = (side(true), side(false));
        out.extend([[l.0, l.1, rt.0, rt.1], [top, bottom, 0.0, 0.0]]);
    }
    out
}
