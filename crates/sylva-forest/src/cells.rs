//! The forest's cells: a hierarchy of squares over the ground, so that a frame's passes visit
//! the squares in view and the trees in those squares, not every tree of the forest.
//!
//! **The squares.** The leaves are squares of [`LEAF_SPACINGS`] tree spacings a side (about
//! 500 trees each at the layout's density), on a grid centred on the first tree of the
//! layout (the one nearest the forest's centre). Each larger square holds 3 × 3 of the next
//! smaller ones, centred on the middle one, up to the one square that holds the forest: a
//! square's middle child is centred where it is, so the first tree stays in the middle leaf
//! of every level.
//!
//! **The trees' order.** [`Cells::new`] gives the trees in the order of a walk down the squares
//! (at each square its middle child first, then the four beside it, then the corners), and
//! within a leaf in their layout order. Every square's trees are then a contiguous range
//! of tree indices, the first tree stays tree 0, and trees near each other in the forest
//! are near each other in memory (what a frame's per-tree passes read in order).
//!
//! **Bounds.** Each square keeps the sphere that holds its trees' crown spheres (centre half
//! the tree's height up, radius 0.75 of it, as the per-tree culling takes them) and its
//! tallest tree, from which a frame bounds the crowns' shadows swept away from the sun
//! ([`Cells::visit`]). A square whose sphere the view cannot see holds no tree the per-tree
//! tests would keep, and is skipped with everything in it.

use std::ops::Range;

use sylva_core::v3::{dot, sub};

use crate::camera::{ShadowSweep, ViewCone};
use crate::scene::Placement;

/// Side of a leaf square, in tree spacings.
pub const LEAF_SPACINGS: f32 = 24.0;

/// The order of the children of a square, as (column, row) offsets from its middle: the
/// middle first, then the four beside it, then the corners.
const CHILDREN: [(i64, i64); 9] =
    [(0, 0), (1, 0), (0, 1), (-1, 0), (0, -1), (1, 1), (-1, 1), (-1, -1), (1, -1)];

/// One square of the hierarchy, over a contiguous range of trees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    /// Its trees: tree indices `first..end`.
    pub first: u32,
    /// One past its last tree.
    pub end: u32,
    /// The index of the next cell past this one's descendants (cells are stored in the walk's
    /// pre-order, so a cell's descendants follow it).
    pub skip: u32,
    /// The index of the leaf it is, among the leaves in order; `u32::MAX` for a larger square.
    pub leaf: u32,
    /// Centre of the sphere holding its trees' crowns, m.
    pub centre: [f32; 3],
    /// Radius of that sphere, m.
    pub radius: f32,
    /// Its tallest tree, m.
    pub tallest: f32,
}

impl Cell {
    /// Its trees' indices.
    pub fn trees(&self) -> Range<usize> {
        self.first as usize..self.end as usize
    }
}

/// The cell hierarchy of a forest whose trees are in the order [`Cells::new`] gives.
#[derive(Debug, Clone, Default)]
pub struct Cells {
    /// Every square that holds a tree, in pre-order (the root first).
    pub cells: Vec<Cell>,
    /// The leaves' cell indices, in order (their tree ranges tile the trees).
    pub leaves: Vec<u32>,
    /// Each leaf's trees (at the leaf's tree range) in the order of a draw per tree
    /// ([`Cells::order_by_draw`]), and the draws in that order: the trees a thinning keeps
    /// below some draw are a prefix.
    pub by_draw: Vec<u32>,
    /// See [`Cells::by_draw`].
    pub draws: Vec<f32>,
}

/// The squares a frame visits, and what it found in them.
#[derive(Debug, Clone, Default)]
pub struct Visit {
    /// The leaves in view (cell indices, ascending, so their trees are too).
    pub leaves: Vec<u32>,
    /// Cells tested against the view.
    pub cells_tested: usize,
    /// Trees in the leaves in view.
    pub trees: usize,
}

/// The leaf grid's column and row of the point (`x`, `y`), for leaves of `side` m centred on
/// `origin`.
fn leaf_of(x: f32, y: f32, origin: [f32; 2], side: f32) -> (i64, i64) {
    let col = ((x - origin[0]) as f64 / side as f64).round() as i64;
    let row = ((y - origin[1]) as f64 / side as f64).round() as i64;
    (col, row)
}

/// Levels above the leaves whose squares, 3^levels leaves a side and centred on the middle
/// leaf, hold every leaf within `reach` columns and rows of it.
fn levels_for(reach: i64) -> u32 {
    let mut levels = 0;
    let mut half = 0i64; // leaves from the middle to a square's edge: (3^levels − 1) / 2
    while half < reach {
        levels += 1;
        half = 3 * half + 1;
    }
    levels
}

/// The walk's key of a leaf: per level from the top, which child of its square it lies in
/// (0 … 8, [`CHILDREN`]), as the digits of a base-9 number.
fn walk_key((mut col, mut row): (i64, i64), levels: u32) -> u64 {
    let (mut key, mut place) = (0u64, 1u64);
    for _ in 0..levels {
        // Balanced ternary digit of each coordinate: −1, 0 or 1.
        let dc = (col + 1).rem_euclid(3) - 1;
        let dr = (row + 1).rem_euclid(3) - 1;
        let child = CHILDREN.iter().position(|&c| c == (dc, dr)).expect("a digit is −1, 0 or 1");
        key += child as u64 * place;
        place *= 9;
        col = (col - dc) / 3;
        row = (row - dr) / 3;
    }
    key
}

/// The digit of `key` (of `levels` digits) at `depth` levels below the top.
fn digit(key: u64, levels: u32, depth: u32) -> u64 {
    key / 9u64.pow(levels - 1 - depth) % 9
}

/// Each tree's leaf key (leaves [`leaf_side`]`(spacing)` a side on a grid centred on the first
/// tree), and the number of levels above the leaves.
fn keys(trees: &[Placement], spacing: f32) -> (Vec<u64>, u32) {
    let Some(first) = trees.first() else { return (Vec::new(), 0) };
    let side = leaf_side(spacing);
    let origin = [first.position[0], first.position[1]];
    let leaves: Vec<(i64, i64)> =
        trees.iter().map(|p| leaf_of(p.position[0], p.position[1], origin, side)).collect();
    let reach = leaves.iter().map(|&(c, r)| c.abs().max(r.abs())).max().unwrap_or(0);
    // 9²⁰ fits a u64; a square of 3²⁰ leaves a side is far beyond any layout's million trees.
    let levels = levels_for(reach).min(20);
    (leaves.iter().map(|&l| walk_key(l, levels)).collect(), levels)
}

/// Side of a leaf square for a layout of `spacing` m, m.
pub fn leaf_side(spacing: f32) -> f32 {
    (LEAF_SPACINGS * spacing).max(1.0)
}

impl Cells {
    /// The hierarchy of `trees` (placements in layout order, tree 0 the one nearest the
    /// forest's centre, for a layout of `spacing` m; each tree's crown sphere centred
    /// `h[i] / 2` above its foot with radius `0.75 h[i]`), and the order it puts the trees
    /// in: `order[k]` is the layout index of the tree that goes `k`-th, tree 0 first, ties
    /// by layout index. The cells' tree ranges are in that order.
    pub fn new(trees: &[Placement], h: &[f32], spacing: f32) -> (Cells, Vec<u32>) {
        let mut cells = Cells::default();
        let (keys, levels) = keys(trees, spacing);
        let mut order: Vec<u32> = (0..trees.len() as u32).collect();
        order.sort_unstable_by_key(|&a| (keys[a as usize], a));
        if !trees.is_empty() {
            let pick = |k: &u32| *k as usize;
            let trees: Vec<Placement> = order.iter().map(|k| trees[pick(k)]).collect();
            let h: Vec<f32> = order.iter().map(|k| h[pick(k)]).collect();
            let keys: Vec<u64> = order.iter().map(|k| keys[pick(k)]).collect();
            cells.add(&trees, &h, (&keys, levels), 0..trees.len(), 0);
        }
        (cells, order)
    }

    /// The cell of `range` (trees whose keys agree on their first `depth` digits) and,
    /// below it, its children; returns its index.
    fn add(
        &mut self,
        trees: &[Placement],
        h: &[f32],
        (keys, levels): (&[u64], u32),
        range: Range<usize>,
        depth: u32,
    ) -> u32 {
        let at = self.cells.len() as u32;
        let (centre, radius, tallest) = bounds(&trees[range.clone()], &h[range.clone()]);
        let is_leaf = depth == levels;
        let leaf = if is_leaf { self.leaves.len() as u32 } else { u32::MAX };
        if is_leaf {
            self.leaves.push(at);
        }
        self.cells.push(Cell {
            first: range.start as u32,
            end: range.end as u32,
            skip: 0,
            leaf,
            centre,
            radius,
            tallest,
        });
        if !is_leaf {
            let mut start = range.start;
            while start < range.end {
                let d = digit(keys[start], levels, depth);
                let end = start
                    + keys[start..range.end].partition_point(|&k| digit(k, levels, depth) == d);
                self.add(trees, h, (keys, levels), start..end, depth + 1);
                start = end;
            }
        }
        self.cells[at as usize].skip = self.cells.len() as u32;
        at
    }

    /// Each leaf's trees ordered by `draw(tree)` (ties by tree) into [`Cells::by_draw`].
    pub fn order_by_draw(&mut self, draw: impl Fn(usize) -> f32) {
        let n = self.cells.first().map_or(0, |root| root.end as usize);
        self.by_draw = (0..n as u32).collect();
        self.draws = (0..n).map(&draw).collect();
        for &l in &self.leaves {
            let span = self.cells[l as usize].trees();
            let (order, draws) = (&mut self.by_draw[span.clone()], &self.draws);
            order.sort_unstable_by(|&a, &b| {
                draws[a as usize].total_cmp(&draws[b as usize]).then(a.cmp(&b))
            });
        }
        let sorted: Vec<f32> = self.by_draw.iter().map(|&t| self.draws[t as usize]).collect();
        self.draws = sorted;
    }

    /// The leaves `cone` may see something of: those whose crowns it may see or, with a
    /// `sweep`, whose crowns' shadows swept away from the sun may reach it. Written into
    /// `visit`, without allocating once its list has grown.
    pub fn visit(&self, cone: &ViewCone, sweep: Option<&ShadowSweep>, visit: &mut Visit) {
        visit.leaves.clear();
        visit.cells_tested = 0;
        visit.trees = 0;
        let mut k = 0;
        while k < self.cells.len() {
            let cell = &self.cells[k];
            visit.cells_tested += 1;
            if may_see_cell(cone, sweep, cell) {
                if cell.leaf != u32::MAX {
                    visit.leaves.push(k as u32);
                    visit.trees += cell.trees().len();
                }
                k += 1;
            } else {
                k = cell.skip as usize;
            }
        }
    }
}

/// Whether the view may see anything of `cell`'s trees, or of their shadows swept as
/// [`Cells::visit`] takes `sweep`: the cell's sphere, or the sphere that holds it swept half
/// its tallest tree's sweep away from the sun and grown by as much (it holds every tree's
/// crown and the sphere its sweep is tested as, [`crate::camera::may_shade_trees`]). A
/// margin of a thousandth of the radius and a centimetre covers the per-tree tests'
/// rounding.
fn may_see_cell(cone: &ViewCone, sweep: Option<&ShadowSweep>, cell: &Cell) -> bool {
    let margin = 1e-3 * cell.radius + 0.01;
    let (c, r) = (cell.centre, cell.radius + margin);
    match sweep {
        None => cone.may_see(c, r),
        Some(sw) => {
            // A tree's sweep grows with its height: the tallest's is the longest.
            let (half, away) = (0.5 * sw.length(cell.tallest), sw.away);
            let swept = [c[0] + half * away[0], c[1] + half * away[1], c[2] + half * away[2]];
            cone.may_see(swept, r + half)
        }
    }
}

/// The sphere that holds the crown spheres of `trees` (heights `h`): its centre the middle
/// of their bounding box, its radius the farthest crown's reach from it; and the tallest.
fn bounds(trees: &[Placement], h: &[f32]) -> ([f32; 3], f32, f32) {
    let crown =
        |p: &Placement, h: f32| ([p.position[0], p.position[1], p.position[2] + 0.5 * h], 0.75 * h);
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for (p, &h) in trees.iter().zip(h) {
        let (c, r) = crown(p, h);
        for k in 0..3 {
            lo[k] = lo[k].min(c[k] - r);
            hi[k] = hi[k].max(c[k] + r);
        }
    }
    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
    let radius = trees.iter().zip(h).fold(0.0f32, |m, (p, &h)| {
        let (c, r) = crown(p, h);
        let d = sub(c, centre);
        m.max(dot(d, d).sqrt() + r)
    });
    let tallest = h.iter().copied().fold(0.0, f32::max);
    (centre, radius, tallest)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f32, y: f32) -> Placement {
        Placement { position: [x, y, 0.0], yaw: 0.0, scale: 1.0, species: 0 }
    }

    #[test]
    fn the_walk_keeps_the_first_tree_first_and_each_square_contiguous() {
        // A grid of trees 7 m apart over 1.4 km, listed nearest the middle first.
        let mut trees: Vec<Placement> = (-100..=100)
            .flat_map(|i| (-100..=100).map(move |j| at(7.0 * i as f32 + 0.3, 7.0 * j as f32)))
            .collect();
        trees.sort_by(|a, b| {
            let d = |p: &Placement| p.position[0].powi(2) + p.position[1].powi(2);
            d(a).total_cmp(&d(b))
        });
        let h = vec![20.0; trees.len()];
        let (cells, order) = Cells::new(&trees, &h, 7.0);
        assert_eq!(order[0], 0, "the centre tree stays tree 0");
        let mut seen = vec![false; trees.len()];
        order.iter().for_each(|&i| seen[i as usize] = true);
        assert!(seen.iter().all(|&s| s), "a permutation");
        let ordered: Vec<Placement> = order.iter().map(|&i| trees[i as usize]).collect();
        // Leaves tile the trees in order; every tree lies in its leaf's square and within
        // every enclosing cell's sphere.
        let side = leaf_side(7.0);
        let mut next = 0;
        for &l in &cells.leaves {
            let cell = cells.cells[l as usize];
            assert_eq!(cell.first as usize, next, "leaves tile the trees in order");
            next = cell.end as usize;
            let (c0, r0) = leaf_of(
                ordered[cell.first as usize].position[0],
                ordered[cell.first as usize].position[1],
                [ordered[0].position[0], ordered[0].position[1]],
                side,
            );
            for p in &ordered[cell.trees()] {
                let leaf = leaf_of(p.position[0], p.position[1], [0.3, 0.0], side);
                assert_eq!(leaf, (c0, r0), "a leaf holds one square's trees");
            }
        }
        assert_eq!(next, ordered.len());
        for cell in &cells.cells {
            for p in &ordered[cell.trees()] {
                let c = [p.position[0], p.position[1], 10.0];
                let d = dot(sub(c, cell.centre), sub(c, cell.centre)).sqrt();
                assert!(d + 15.0 <= cell.radius * (1.0 + 1e-6), "a crown outside its cell");
            }
            // Children tile their parent's trees.
            if cell.leaf == u32::MAX {
                let start = cells.cells.iter().position(|c| c == cell).expect("in the list") + 1;
                let (mut k, mut covered) = (start, cell.first);
                while k < cell.skip as usize {
                    assert_eq!(cells.cells[k].first, covered);
                    covered = cells.cells[k].end;
                    k = cells.cells[k].skip as usize;
                }
                assert_eq!(covered, cell.end, "children tile their parent");
            }
        }
        // 1.4 km in 168 m leaves: 9 columns (3² leaves a side), two levels above the leaves.
        assert_eq!(cells.leaves.len(), 81);
        assert_eq!(cells.cells.len(), 1 + 9 + 81);
    }
}
