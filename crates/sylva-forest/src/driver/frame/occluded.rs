//! Pass 0 of a frame with occlusion culling on, and its test in pass 1: the trees in view
//! near enough write their occluders, near to far; a tree whose bounds they hide is culled
//! (`crate::occlusion`).

use rayon::prelude::*;
use sylva_core::v3::{dot, sub};

use super::{FrameData, TreeRun, View};
use crate::camera::{Camera, may_see_trees};
use crate::driver::Forest;
use crate::scene::Placement;

impl Forest {
    /// Pass 0, with occlusion culling on: the trees in view that cover enough of the image
    /// (a run at a time, in parallel) write their occluders into the frame's depth buffer,
    /// near to far.
    pub(super) fn fill_occlusion(
        &self,
        view: &View,
        camera: &Camera,
        aspect: f32,
        out: &mut FrameData,
    ) {
        // Off, the buffer is neither filled nor read.
        if !view.lod.occlusion {
            return;
        }
        out.occlusion.reset(camera, aspect);
        // Each species' occluder measured once, on the first frame that culls (one species
        // after the other, each measurement parallel in itself), before the passes read it.
        for s in &self.species {
            s.occluder();
        }
        let runs = out.visit.leaves.len();
        if out.runs.len() < runs {
            out.runs.resize_with(runs, TreeRun::default);
        }
        let cot = 1.0 / (0.5 * camera.fov_deg.to_radians()).tan();
        let (buffer, forward) = (&out.occlusion, camera.forward());
        out.runs[..runs].par_iter_mut().zip(out.visit.leaves.par_iter()).for_each(
            |(run, &leaf)| {
                let span = self.cells.cells[leaf as usize].trees();
                let (first, n) = (span.start, span.len());
                let trees = &self.trees[span];
                run.occluders.clear();
                run.seen.resize(n, false);
                let (cr, span) = (&self.crowns, first..first + n);
                let (cx, cy) = (&cr.x[span.clone()], &cr.y[span.clone()]);
                let (cz, ch) = (&cr.z[span.clone()], &cr.h[span]);
                may_see_trees(&view.cone, cx, cy, cz, ch, &mut run.seen[..n]);
                for (k, (p, _)) in trees.iter().enumerate() {
                    let side = self.species[p.species as usize].occluder().smallest_side();
                    if !run.seen[k] || side <= 0.0 {
                        continue;
                    }
                    let w = dot(sub(p.position, camera.eye), forward);
                    if buffer.worth_writing(side * p.scale, w, cot) {
                        run.occluders.push((first + k) as u32);
                    }
                }
            },
        );
        // Near to far (ties by tree), so each pixel's light falls in depth order.
        let order = &mut out.occluder_order;
        order.clear();
        for run in &out.runs[..runs] {
            order.extend(run.occluders.iter().map(|&i| {
                let p = &self.trees[i as usize].0;
                let o = self.species[p.species as usize].occluder();
                (out.occlusion.tree_depth(o, p.position, p.scale), i)
            }));
        }
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(depth, i) in order.iter() {
            let p = &self.trees[i as usize].0;
            let o = self.species[p.species as usize].occluder();
            out.occlusion.add_tree(o, p.position, p.scale, depth);
        }
    }

    /// Of a run's trees in view (`seen`), those whose bounds `buffer` hides are marked out
    /// of view; returns how many.
    pub(super) fn hide_occluded(
        &self,
        buffer: &crate::occlusion::DepthBuffer,
        trees: &[(Placement, u32)],
        z: &[f32],
        h: &[f32],
        seen: &mut [bool],
    ) -> usize {
        let mut hidden = 0;
        for (k, (p, _)) in trees.iter().enumerate() {
            if !seen[k] {
                continue;
            }
            let o = self.species[p.species as usize].occluder();
            // The tree's bounds at rest, widened by a tenth of its height for its sway.
            let r = o.bound_radius * p.scale + 0.1 * h[k];
            let (x, y) = (p.position[0], p.position[1]);
            let lo = [x - r, y - r, z[k] + o.bound_bottom * p.scale - 0.1];
            let hi = [x + r, y + r, z[k] + o.bound_top * p.scale + 0.1 * h[k]];
            if buffer.hides_box(lo, hi) {
                seen[k] = false;
                hidden += 1;
            }
        }
        hidden
    }
}
