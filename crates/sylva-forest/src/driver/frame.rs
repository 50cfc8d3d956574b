//! Building a frame (see the `driver` module's documentation), in five passes, after one
//! more with occlusion culling on:
//!
//! 0. [`Forest::fill_occlusion`]: the trees in view near enough write their occluders into
//!    the frame's depth buffer, near to far (`crate::occlusion`).
//! 1. [`Forest::classify`]: per tree of the cells' leaves in view (`crate::cells`; a leaf
//!    the view cannot see, nor its trees' shadows, is skipped whole), a leaf at a time in
//!    parallel, whether it is in view (or casts into it), its level and cross-fade, the
//!    joints its simulation must show and step; the draws go to per-leaf lists by bucket
//!    key.
//! 2. [`FrameData::gather`]: the runs' draws into key order and their counts into the
//!    frame's figures.
//! 3. [`Forest::bucket`]: runs of equal keys into buckets, mesh buckets near to far.
//! 4. [`Forest::lay_out_palettes`]: where each drawn simulation's palettes go, then the
//!    copies.
//! 5. [`Forest::write_instances`]: one instance per draw, in runs in parallel.

mod leaves;
mod occluded;

use std::sync::atomic::Ordering;

use rayon::prelude::*;
use sylva_core::simd::prefetch;
use sylva_sway::{LANES, PaletteSlot};

use super::frame_data::*;
use super::lod::*;
use super::palettes::{Layout, copy_palettes, lay_out};
use super::regroup::Switch;
use super::{Forest, SpeciesRuntime};
use crate::camera::{Camera, ShadowBox, ShadowSweep, ViewCone, may_see_trees, may_shade_trees};
use crate::cells::Cell;
use crate::scene::Placement;
use leaves::each_leaf;

/// What stays fixed over one frame's passes: the view, the shadow's reach, the layout of
/// bucket keys and the LOD settings.
struct View {
    cone: ViewCone,
    /// With shadows on, the sun's sweep that keeps trees out of view whose shadow may fall
    /// in it.
    sweep: Option<ShadowSweep>,
    /// The shadow map's far cascade (nothing outside it takes a shadow) and the margin, two
    /// of its texels for the renderer's snapping, that a tree out of view may cast within.
    far_box: ShadowBox,
    box_margin: f32,
    /// Species (at least 1), keys of trees in view (levels 0 to the longest chain, its
    /// impostor, for each species), and all keys (those again for shadow-only draws).
    n_species: u32,
    n_keys: usize,
    all_keys: usize,
    lod: LodSettings,
    /// The animation LOD's coordinate less the geometry LOD's: the same for every tree.
    ahead: f32,
    /// The simulation time of the frame before in this view.
    previous: f64,
    /// Per species: the first level drawn as its impostor; the fraction below which a
    /// tree goes to its LOD cap; with levels by error, its levels' fraction thresholds
    /// (scratch of the `FrameData`, given back after the frame).
    far: Vec<u32>,
    past_cap: Vec<f32>,
    thresholds: Vec<Vec<f32>>,
    /// The side of a texel of the shadow map's near cascade, m.
    shadow_texel: f32,
    /// The image-height fraction below which far impostors are thinned (0: off).
    thin: f32,
    /// The least of the species' `past_cap` fractions.
    least_past_cap: f32,
    /// Whether a tree may have changed group since the frame before or still be fading
    /// between groups: the last regroup (when every switch was made) is that recent.
    regrouped: bool,
    /// Per species, with levels by error: the coarsest mesh level whose error on its
    /// largest tree spans at most `shadow_texel`, the level its trees cast their shadows
    /// with (or the level drawn, if coarser). Scratch of the `FrameData`.
    cast_floor: Vec<u32>,
}

impl View {
    /// A bucket key's species and level.
    fn split(&self, key: u32) -> (u32, u32) {
        let key = key % self.n_keys as u32;
        (key % self.n_species, key / self.n_species)
    }
}

/// Where a tree's draws go and what its simulation is asked for: the per-run lists and
/// counts, and the per-simulation maxima the runs raise together.
struct RunOut<'a> {
    run: &'a mut TreeRun,
    need_max: &'a Maxima,
    want_max: &'a Maxima,
    seen_max: &'a Maxima,
}

impl Forest {
    /// Fill `out` for `camera` and an image of `aspect` = width / height. Allocates only
    /// while `out`'s arrays grow. `out` keeps the per-tree LOD history (hysteresis) of this
    /// view: use one `FrameData` per view.
    pub fn frame(&mut self, camera: &Camera, aspect: f32, out: &mut FrameData) {
        self.eye = Some(camera.eye);
        let previous = out.time;
        out.time = self.time;
        out.keys.clear();
        let fresh = out.lod_state.len() != self.trees.len();
        if fresh {
            out.lod_state.clear();
            out.lod_state.resize(self.trees.len(), f32::NAN);
        }
        // A scene holds at most a million trees (`SceneSpec` refuses more).
        debug_assert!(self.trees.len() <= TREE_BITS as usize, "too many trees to tag");
        let sims = self.lane_groups * LANES;
        out.need_max.reset(sims);
        out.want_max.reset(sims);
        out.seen_max.reset(sims);
        let mut view = self.view(camera, aspect, previous);
        self.plan_levels(&mut view, out);
        // What is known of each leaf's states holds for these levels and this view's states.
        if fresh || out.settled.len() != self.cells.leaves.len() || out.settled_far != view.far {
            // (Nothing known: each leaf's size.)
            let size = |c: &u32| self.cells.cells[*c as usize].trees().len() as u32;
            out.settled.clear();
            out.settled.extend(self.cells.leaves.iter().map(size));
            out.settled_far.clone_from(&view.far);
        }
        // The leaves whose trees or their shadows the view may see: the only trees visited.
        self.cells.visit(&view.cone, view.sweep.as_ref(), &mut out.visit);
        self.fill_occlusion(&view, camera, aspect, out);
        let mut stats = FrameStats {
            trees: self.trees.len(),
            cells_visited: out.visit.cells_tested,
            trees_visited: out.visit.trees,
            ..FrameStats::default()
        };
        let runs = self.classify(&view, out);
        out.gather(runs, view.all_keys, &mut stats);
        self.bucket(&view, camera, out, &mut stats);
        self.lay_out_palettes(out, &mut stats);
        for (a, &v) in self.want.iter_mut().zip(&out.want) {
            *a = v;
        }
        // What the trees in view show: joints beyond it that the next step drops go at
        // once, whatever trees out of view cast with them.
        for (a, m) in self.shown.iter_mut().zip(&out.seen_max.0) {
            *a = m.load(Ordering::Relaxed);
        }
        self.write_instances(&view, out);
        (out.far, out.past_cap, out.thresholds) = (view.far, view.past_cap, view.thresholds);
        out.cast_floor = view.cast_floor;
        stats.uploaded_bytes =
            4 * out.palettes.len() + std::mem::size_of::<Instance>() * out.instances.len();
        stats.sim_ms = self.last_sim_ms;
        let w = self.wind_at([0.0, 0.0, 20.0], self.time);
        out.wind = w;
        out.stats = stats;
    }

    /// What the frame's passes hold fixed for `camera`.
    fn view(&self, camera: &Camera, aspect: f32, previous: f64) -> View {
        let lod = self.lod;
        let cone = camera.cone(aspect);
        // Bucket keys: level-major, so the finest levels are drawn first.
        let n_species = self.species.len().max(1) as u32;
        let longest = self.species.iter().map(|s| s.model.lods.len()).max().unwrap_or(0);
        let n_keys = (longest + 1) * n_species as usize;
        let lighting = &self.spec.lighting;
        let sweep = if lighting.shadows { ShadowSweep::new(lighting.sun_unit()) } else { None };
        let far_box = ShadowBox::new(camera, aspect, camera.shadow_reach().1, lighting.sun_unit());
        let box_margin = 4.0 * far_box.radius / ShadowBox::TEXELS as f32;
        let all_keys = if sweep.is_some() { 2 * n_keys } else { n_keys };
        // By error, the animation simulates what is drawn (half a level ahead).
        let ahead = if lod.error_budget > 0.0 {
            0.0
        } else {
            (ANIMATION_FRACTION / lod.fraction).ln() / 3f32.ln()
        };
        // A caster's error under a texel of the near cascade does not show in the map.
        let near_box = ShadowBox::new(camera, aspect, camera.shadow_reach().0, lighting.sun_unit());
        let shadow_texel = 2.0 * near_box.radius / ShadowBox::TEXELS as f32;
        View {
            cone,
            sweep,
            far_box,
            box_margin,
            shadow_texel,
            thin: 0.0,
            least_past_cap: 0.0,
            regrouped: {
                let last = self.grouped.1;
                let fade = self.regroup_fade as f64;
                last > previous || (fade > 0.0 && self.time - last < fade)
            },
            cast_floor: Vec::new(),
            n_species,
            n_keys,
            all_keys,
            lod,
            ahead,
            previous,
            far: Vec::new(),
            past_cap: Vec::new(),
            thresholds: Vec::new(),
        }
    }

    /// The level a tree of `species` drawn at mesh level `level` casts its shadow with,
    /// no finer than it is drawn (its joints are then a prefix of the drawn ones): by
    /// fraction [`shadow_level`]; by error the coarsest level whose error fits a texel of
    /// the shadow map's near cascade (`View::cast_floor`), whatever finer level the
    /// camera's error budget picked.
    fn cast_level(&self, view: &View, species: u32, level: u32) -> u32 {
        let chain = self.species[species as usize].model.lods.len() as u32;
        if view.lod.error_budget > 0.0 {
            level.max(view.cast_floor[species as usize])
        } else {
            shadow_level(level, chain)
        }
    }

    /// Per species, where its impostor starts and where its LOD state stops; with levels by
    /// error, the thresholds of its mesh levels, the impostor's the fraction's. A mesh
    /// level whose error keeps it until the tree is small enough for its impostor is not
    /// used: the impostor starts before it, so the level coordinate stays continuous.
    fn plan_levels(&self, view: &mut View, out: &mut FrameData) {
        let lod = view.lod;
        let rows = if out.image_rows == 0 { DEFAULT_IMAGE_ROWS } else { out.image_rows };
        let (mut far, mut past_cap, mut thresholds) = (
            std::mem::take(&mut out.far),
            std::mem::take(&mut out.past_cap),
            std::mem::take(&mut out.thresholds),
        );
        far.clear();
        past_cap.clear();
        let mut cast_floor = std::mem::take(&mut out.cast_floor);
        cast_floor.clear();
        // Only levels by error cast by the texel (`cast_level`).
        if lod.error_budget > 0.0 {
            let largest = 1.0 + self.spec.scale_variation;
            cast_floor.extend(self.species.iter().map(|sp| {
                let height = sp.model.tree.stats.height * largest;
                let meshes = sp.level_error.len().min(sp.model.lods.len());
                let fine = |k: &usize| sp.level_error[*k] * height <= view.shadow_texel;
                (0..meshes).take_while(fine).last().unwrap_or(0) as u32
            }));
        }
        view.cast_floor = cast_floor;
        view.thin = if lod.geometry && lod.thin_px > 0.0 { lod.thin_px / rows as f32 } else { 0.0 };
        thresholds.resize_with(self.species.len(), Vec::new);
        for (sp, f) in self.species.iter().zip(thresholds.iter_mut()) {
            let chain_far = lod.far_level.min(sp.model.lods.len() as u32);
            if lod.error_budget > 0.0 {
                let mesh = &sp.level_error[..(chain_far as usize).min(sp.level_error.len())];
                level_thresholds(mesh, rows, lod.error_budget, f);
                // Levels past the fraction go; equal thresholds are parted by 10⁻³ of
                // themselves, so each level keeps an interval of its own.
                let used = f.iter().take_while(|&&t| t > lod.fraction).count();
                f.truncate(used);
                for k in 1..f.len() {
                    f[k] = f[k].min(f[k - 1] * (1.0 - 1e-3)).max(lod.fraction);
                }
                f.push(lod.fraction);
                let here = f.len() as u32;
                far.push(here);
                past_cap.push(past_cap_error_fraction(f, lod_cap(here), lod.hysteresis));
            } else {
                f.clear();
                far.push(chain_far);
                past_cap.push(past_cap_fraction(lod.fraction, lod_cap(chain_far), lod.hysteresis));
            }
        }
        view.least_past_cap = past_cap.iter().copied().fold(f32::INFINITY, f32::min);
        (view.far, view.past_cap, view.thresholds) = (far, past_cap, thresholds);
    }

    /// Whether a tree of `species` at `level` is drawn as its impostor.
    fn impostor(&self, view: &View, species: u32, level: u32) -> bool {
        view.lod.geometry && level >= view.far[species as usize]
    }

    /// Thinning of tree `i` (crown centre `c`, height `h`) drawn from level `level` on:
    /// `None` where it is left out, else the share of its dither range it keeps and how
    /// much wider it is drawn ([`thinning`]; (1, 1) where it is not a far impostor).
    fn thinned(
        &self,
        view: &View,
        i: usize,
        c: [f32; 3],
        h: f32,
        level: u32,
        species: u32,
    ) -> Option<(f32, f32)> {
        if view.thin <= 0.0 || !self.impostor(view, species, level) {
            return Some((1.0, 1.0));
        }
        // By distance: a tree beside or behind the eye (its depth small) is near, not far.
        let s = view.cone.size_fraction(c, h) / view.thin;
        thinning(s, thin_draw(i, self.spec.seed))
    }

    /// Pass 1: the trees of the leaves in view, a leaf at a time, the leaves in parallel.
    /// Each fills its own keys, merged afterwards in leaf order (so in tree order), and
    /// raises the per-simulation maxima (which do not depend on order), so the frame is the
    /// same for any number of threads. Returns the number of leaves (runs) visited.
    fn classify(&self, view: &View, out: &mut FrameData) -> usize {
        let runs = out.visit.leaves.len();
        if out.runs.len() < runs {
            out.runs.resize_with(runs, TreeRun::default);
        }
        let (past_cap, thresholds) = (&view.past_cap, &view.thresholds);
        let (need_max, want_max, seen_max) = (&out.need_max, &out.want_max, &out.seen_max);
        let occlusion = &out.occlusion;
        let cells: &[Cell] = &self.cells.cells;
        let one_leaf = |run: &mut TreeRun, states: &mut [f32], settled: &mut u32, cell: &Cell| {
            let (first, n) = (cell.first as usize, states.len());
            let trees = &self.trees[first..first + n];
            if run.by_key.len() < view.all_keys {
                run.by_key.resize_with(view.all_keys, Vec::new);
            }
            run.by_key.iter_mut().for_each(Vec::clear);
            run.seen.resize(n, false);
            run.shade.resize(n, false);
            let (cr, span) = (&self.crowns, first..first + n);
            let (cx, cy) = (&cr.x[span.clone()], &cr.y[span.clone()]);
            let (cz, ch) = (&cr.z[span.clone()], &cr.h[span]);
            // One tree of the leaf, `k` its index in it: the crown's height and centre, as the
            // culling took them.
            let classify_at = |k: usize, state: &mut f32, to: &mut RunOut<'_>| {
                let (p, g) = &trees[k];
                let h = ch[k];
                let c = [cx[k], cy[k], cz[k] + 0.5 * h];
                let tree = Tree { i: first + k, p, group: *g, c, h };
                self.classify_tree(view, (past_cap, thresholds), &tree, k, state, to);
            };
            // A leaf wholly in view and far: the trees past the thinning's last keep are
            // decided at once, the others classified alone, in tree order.
            if let Some(kept) = self.thinned_out(view, cell) {
                self.settle_far_leaf(view, cell, kept, (states, settled), run);
                let kept_trees = std::mem::take(&mut run.kept);
                let mut to = RunOut { run, need_max, want_max, seen_max };
                for (n, &t) in kept_trees.iter().enumerate() {
                    // The kept trees lie apart in the leaf: ask for a later one's data now.
                    if let Some(&ahead) = kept_trees.get(n + PREFETCH_AHEAD) {
                        let k = ahead as usize - first;
                        prefetch(trees, k);
                        prefetch(states, k);
                        for a in [cx, cy, cz, ch] {
                            prefetch(a, k);
                        }
                    }
                    let k = t as usize - first;
                    classify_at(k, &mut states[k], &mut to);
                }
                to.run.kept = kept_trees;
                return;
            }
            *settled = n as u32;
            // With occlusion culling on, pass 0 has culled this leaf already.
            if !view.lod.occlusion {
                may_see_trees(&view.cone, cx, cy, cz, ch, &mut run.seen[..n]);
            }
            let occluded = if view.lod.occlusion {
                self.hide_occluded(occlusion, trees, cz, ch, &mut run.seen[..n])
            } else {
                0
            };
            match &view.sweep {
                Some(sw) => may_shade_trees(
                    &view.cone,
                    sw,
                    cx,
                    cy,
                    cz,
                    ch,
                    &run.seen[..n],
                    &mut run.shade[..n],
                ),
                None => run.shade[..n].fill(false),
            }
            run.stats = FrameStats { occluded, ..FrameStats::default() };
            let mut to = RunOut { run, need_max, want_max, seen_max };
            for (k, state) in states.iter_mut().enumerate() {
                classify_at(k, state, &mut to);
            }
        };
        let leaves = (&out.visit.leaves[..], cells);
        let slices = (&mut out.runs[..runs], &mut out.lod_state[..], &mut out.settled[..]);
        each_leaf(slices, (0, 0), leaves, &one_leaf);
        runs
    }

    /// One tree of pass 1 (`k` its index in its run): culled, or its level, cross-fade and
    /// simulation's needs recorded and its draws (one per level and instance group) listed.
    fn classify_tree(
        &self,
        view: &View,
        (past_cap, thresholds): (&[f32], &[Vec<f32>]),
        tree: &Tree<'_>,
        k: usize,
        state: &mut f32,
        to: &mut RunOut<'_>,
    ) {
        let (lod, cone) = (view.lod, &view.cone);
        let (p, i, c, h) = (tree.p, tree.i, tree.c, tree.h);
        let sp = &self.species[p.species as usize];
        // Out of view: kept for the shadow map only where its swept crown may reach the
        // view.
        let shadow_only = !to.run.seen[k];
        if shadow_only {
            let Some(sw) = view.sweep.filter(|_| to.run.shade[k]) else { return };
            let (r, len) = (0.75 * h, sw.length(h));
            if !(view.far_box.may_take(c, r, len, view.box_margin)
                && cone.may_see_shadow(c, r, sw.away, len))
            {
                return;
            }
        }
        // A far tree in view, surely at its impostor alone, that the thinning leaves out:
        // its LOD state goes to the cap as below (so the levels are those without the
        // thinning), and nothing more of it is computed.
        let far_level = view.far[p.species as usize];
        // (`view.thin` is 0 without the geometry LOD.)
        let surely_far = !shadow_only
            && view.thin > 0.0
            && cone.fraction_below(c, h, past_cap[p.species as usize]);
        if surely_far && self.thinned(view, i, c, h, far_level, p.species).is_none() {
            let x = lod_cap(far_level);
            if !state.is_nan() && *state as u32 != x as u32 {
                to.run.stats.level_changes += 1;
            }
            *state = x;
            to.run.stats.thinned += 1;
            return;
        }
        let key_base = if shadow_only { view.n_keys as u32 } else { 0 };
        let far = view.far[p.species as usize];
        // Joints level `l` draws (a prefix in LOD order).
        let joints = |l: u32| {
            if lod.geometry && l >= far { sp.order.trunk } else { sp.order.prefix[l as usize] }
        };
        // Joints a tree out of view casts its shadow at level `l` with.
        let casts = |l: u32| {
            if lod.geometry && l >= far {
                sp.order.trunk
            } else {
                sp.order.prefix[self.cast_level(view, p.species, l) as usize]
            }
        };
        let frac = || cone.screen_fraction(c, h);
        let (a, b, sim, x) = if lod.geometry {
            let before = *state;
            let x = next_lod_state(
                before,
                || {
                    if lod.error_budget > 0.0 {
                        error_coordinate(frac(), &thresholds[p.species as usize])
                    } else {
                        lod_coordinate(frac(), lod.fraction)
                    }
                },
                cone.fraction_below(c, h, past_cap[p.species as usize]),
                lod.hysteresis,
                lod_cap(far),
            );
            // Levels as `blend_levels` takes them (both are ≥ 0).
            if !before.is_nan() && before as u32 != x as u32 {
                to.run.stats.level_changes += 1;
            }
            *state = x;
            let (a, b, _) = blend_levels(x, far, lod.band);
            (a, b, blend_levels((x - SIM_MARGIN).max(0.0), far, 0.0).0, x)
        } else {
            (0, 0, 0, f32::NAN)
        };
        // A far impostor the thinning leaves out is not drawn, as if out of view (a tree
        // surely far was decided above: it is at the cap, level `far_level`, and kept).
        if !shadow_only && !surely_far && self.thinned(view, i, c, h, a, p.species).is_none() {
            to.run.stats.thinned += 1;
            return;
        }
        // Joints to simulate: the geometry's choice half a level ahead, or coarser by
        // projected size (the joints it draws beyond are held, shown at rest on their
        // parents).
        let moving = if lod.geometry && sim >= far {
            sp.order.trunk
        } else {
            // With the geometry LOD on, from its coordinate (and so its hysteresis), so the
            // two agree wherever their thresholds do.
            let by_size = if x.is_nan() {
                lod_coordinate(frac(), ANIMATION_FRACTION)
            } else {
                x + view.ahead
            } - SIM_MARGIN;
            let level = sim.max(by_size.max(0.0) as u32) as usize;
            sp.order.prefix[level.min(sp.order.prefix.len() - 1)]
        };
        // The tree's group, and the one it is fading out of after a regroup (none long after
        // the last regroup: its switch is not read then).
        let sw = if view.regrouped { self.switches[i] } else { Switch::NONE };
        let switch = sw.fading(self.time, self.regroup_fade);
        to.run.stats.group_changes +=
            (!shadow_only && sw.from != u32::MAX && sw.at > view.previous && sw.at <= self.time)
                as usize;
        for (group, old) in [(tree.group, false)].into_iter().chain(switch.map(|(_, f)| (f, true)))
        {
            let own = sp.lane_base * LANES + sp.lane_of[group as usize] as usize;
            // A tree cast only into the shadow map needs the joints of the level it casts
            // and simulates nothing of its own beyond the trunk (every lane steps that), and
            // what it shows does not hold joints the simulation drops: as it leaves the
            // view, its crown's joints go at once, as when it was culled whole, and its
            // shadow bends with the trunk alone (they blend in from rest when it comes back,
            // as for any tree entering the view). This keeps lane groups of far trees
            // stepping their trunks only (docs/decisions/0004-shadow-casters.md).
            let (need, want) = if shadow_only {
                (casts(a), sp.order.trunk)
            } else {
                to.seen_max.raise(own, joints(a) as u32);
                (joints(a), moving)
            };
            to.need_max.raise(own, need as u32);
            to.want_max.raise(own, want as u32);
            for level in a..=b {
                to.run.by_key[(key_base + level * view.n_species + p.species) as usize].push(
                    i as u32
                        | if switch.is_some() { REGROUPING } else { 0 }
                        | if old { OLD_GROUP } else { 0 },
                );
            }
        }
        let stats = &mut to.run.stats;
        if shadow_only {
            stats.shadow_only += 1;
            return;
        }
        stats.drawn += 1;
        stats.regrouping += switch.is_some() as usize;
        stats.fading += (a != b) as usize;
        stats.impostors += (lod.geometry && b >= far) as usize;
    }

    /// Pass 3: the draws into buckets. A run of equal keys is one species at one level, one
    /// bucket (impostors are bucketed as level `chain`, one past the last mesh). Within each
    /// bucket drawn as meshes, the trees nearest the camera first (the impostors, two
    /// triangles each, are left in tree order).
    fn bucket(&self, view: &View, camera: &Camera, out: &mut FrameData, stats: &mut FrameStats) {
        out.buckets.clear();
        let mut run = 0;
        while run < out.keys.len() {
            let key = out.keys[run].0;
            let end = run + out.keys[run..].iter().take_while(|k| k.0 == key).count();
            let (species, level) = view.split(key);
            let shadow_only = key as usize >= view.n_keys;
            let sp = &self.species[species as usize];
            let far = self.impostor(view, species, level);
            let bucket_lod = if far { sp.model.lods.len() as u32 } else { level };
            let count = (end - run) as u32;
            match out.buckets.last_mut() {
                Some(b)
                    if b.species == species
                        && b.lod == bucket_lod
                        && b.shadow_only == shadow_only =>
                {
                    b.count += count
                }
                _ => {
                    stats.draw_calls += if shadow_only {
                        0
                    } else if far {
                        1
                    } else {
                        2
                    };
                    out.buckets.push(Bucket {
                        species,
                        lod: bucket_lod,
                        shadow_lod: if far {
                            bucket_lod
                        } else {
                            self.cast_level(view, species, level)
                        },
                        first: run as u32,
                        count,
                        shadow_only,
                    })
                }
            }
            if !shadow_only {
                stats.triangles +=
                    (end - run) * if far { 2 } else { sp.model.lods[level as usize].triangles() };
            }
            if !far {
                self.sort_near_first(camera.eye, out, run..end);
            }
            run = end;
        }
    }

    /// The draws `range` of a mesh bucket, nearest `eye` first, through the (squared
    /// distance, tree) pairs of the distance-sort scratch: no allocation once it has grown.
    /// Squared distances are non-negative, so their bits order as they do; equal distances
    /// go by tree, then the old group's draw after the new one's: a total order.
    fn sort_near_first(&self, eye: [f32; 3], out: &mut FrameData, range: std::ops::Range<usize>) {
        out.sorted.clear();
        out.sorted.extend(out.keys[range.clone()].iter().map(|&(_, tagged)| {
            let p = self.trees[(tagged & TREE_BITS) as usize].0.position;
            ((0..3).map(|k| (p[k] - eye[k]).powi(2)).sum::<f32>().to_bits(), tagged)
        }));
        out.sorted.sort_unstable_by_key(|&(d, tagged)| (d, tagged & !REGROUPING));
        for (k, &(_, tagged)) in out.keys[range].iter_mut().zip(&out.sorted) {
            k.1 = tagged;
        }
    }

    /// Pass 4: palettes of the simulations that are drawn, the prefix of joints their
    /// finest drawn level uses (a contiguous run: the batch lays palettes out joint-major).
    /// First where each lane group's go and how they are laid out, then the copies, lane
    /// groups in parallel over disjoint parts of the buffer. Written over the last frame's
    /// palettes: only growth is zero-filled.
    fn lay_out_palettes(&self, out: &mut FrameData, stats: &mut FrameStats) {
        out.slots.clear();
        out.slots.resize(self.lane_groups * LANES, PaletteSlot::default());
        out.copies.clear();
        let mut len = 0;
        for (si, s) in self.species.iter().enumerate() {
            for k in 0..s.batch.groups() {
                let Some(copy) = lay_out(s, si, k, &out.need, len) else { continue };
                let sims = s.lane_base * LANES + k * LANES..;
                let slots = &mut out.slots[sims][..copy.used as usize];
                match copy.kind {
                    Layout::Rows => {
                        // Each simulation's own prefix, in a row.
                        let mut at = len;
                        let need = &out.need[s.lane_base * LANES + k * LANES..][..slots.len()];
                        for (&m, slot) in need.iter().zip(slots.iter_mut()) {
                            *slot = PaletteSlot { base: at as u32, stride: 1 };
                            at += 12 * (m as usize).min(s.batch.species().len());
                        }
                    }
                    Layout::Rest | Layout::Lanes => {
                        for (l, slot) in slots.iter_mut().enumerate() {
                            *slot = PaletteSlot { base: (len + l) as u32, stride: copy.used };
                        }
                    }
                }
                len += copy.len;
                out.copies.push(copy);
            }
            add_species_figures(stats, s);
        }
        let buf = overwrite(&mut out.palettes, len);
        copy_palettes(&self.species, &out.need, &out.slots, &out.copies, buf);
        out.palettes.truncate(len);
    }

    /// Pass 5: one instance per draw, in runs of [`INSTANCE_RUN`] in parallel.
    fn write_instances(&self, view: &View, out: &mut FrameData) {
        let (keys, states, slots) = (&out.keys, &out.lod_state, &out.slots);
        let instances = overwrite(&mut out.instances, keys.len());
        instances.par_chunks_mut(INSTANCE_RUN).zip(keys.par_chunks(INSTANCE_RUN)).for_each(
            |(instances, keys)| {
                // The key of the draws before (a bucket's draws are consecutive).
                let mut bucket: Option<KeyOf<'_>> = None;
                for (n, (instance, &(key, tagged))) in instances.iter_mut().zip(keys).enumerate() {
                    // The trees of a bucket lie far apart in memory: ask for a later draw's
                    // data now, so it has arrived when its turn comes.
                    if let Some(&(_, ahead)) = keys.get(n + PREFETCH_AHEAD) {
                        self.prefetch_tree((ahead & TREE_BITS) as usize, states);
                    }
                    let of = match bucket {
                        Some(b) if b.key == key => b,
                        _ => {
                            let (species, level) = view.split(key);
                            let sp = &self.species[species as usize];
                            let last = view.far[species as usize];
                            let far = self.impostor(view, species, level);
                            *bucket.insert(KeyOf { key, species, level, sp, last, far })
                        }
                    };
                    *instance = self.instance(view, &of, tagged, states, slots);
                }
            },
        );
        out.instances.truncate(out.keys.len());
    }

    /// Ask the memory system for what [`Forest::instance`] reads of tree `i` (a hint: it
    /// changes no result).
    #[inline(always)]
    fn prefetch_tree(&self, i: usize, states: &[f32]) {
        let cr = &self.crowns;
        prefetch(&self.trees, i);
        prefetch(states, i);
        for a in [&cr.x, &cr.y, &cr.z, &cr.h] {
            prefetch(a, i);
        }
    }

    /// The instance of one draw: tree `tagged` in bucket `of`.
    fn instance(
        &self,
        view: &View,
        of: &KeyOf<'_>,
        tagged: u32,
        states: &[f32],
        slots: &[PaletteSlot],
    ) -> Instance {
        let KeyOf { species, level, sp, last, far, .. } = *of;
        let lod = &view.lod;
        let i = (tagged & TREE_BITS) as usize;
        let (p, now) = self.trees[i];
        // Share of the dither range this draw's group keeps: after a regroup the old group's
        // draws keep [0, 1 − v) and the new one's [1 − v, 1).
        let fading = if tagged & REGROUPING != 0 {
            self.switches[i].fading(self.time, self.regroup_fade)
        } else {
            None
        };
        let (g, lo, hi) = match fading {
            Some((v, from)) if tagged & OLD_GROUP != 0 => (from, 0.0, 1.0 - v),
            Some((v, _)) => (now, 1.0 - v, 1.0),
            None => (now, 0.0, 1.0),
        };
        let group = &sp.groups[g as usize];
        // Within the group's share, two levels split it as [lo, lo + (1 − w)(hi − lo)) and
        // the rest; a range reaching 1 is written open to 2.
        let w = if lod.geometry {
            let (a, b, w) = blend_levels(states[i], last, lod.band);
            match (a == b, level == a) {
                (true, _) => None,
                (false, true) => Some((true, w)),
                (false, false) => Some((false, w)),
            }
        } else {
            None
        };
        let (lo, hi) = match w {
            None => (lo, hi),
            Some((true, w)) => (lo, lo + (1.0 - w) * (hi - lo)),
            Some((false, w)) => (lo + (1.0 - w) * (hi - lo), hi),
        };
        // A far impostor kept by the thinning: fading out over the last of its range, and
        // wider. Only a tree in view drawn at its impostor alone (as pass 1 thinned it).
        let shadow_only = of.key as usize >= view.n_keys;
        let (keep, spread) = match (far, w) {
            (true, None) if view.thin > 0.0 && !shadow_only => {
                let cr = &self.crowns;
                let h = cr.h[i];
                let c = [cr.x[i], cr.y[i], cr.z[i] + 0.5 * h];
                self.thinned(view, i, c, h, level, species).unwrap_or((1.0, 1.0))
            }
            _ => (1.0, 1.0),
        };
        let (lo, hi) = if keep < 1.0 {
            let kept = keep * (hi - lo);
            // Alone in its range [0, 1) (no regroup's fade), it keeps its share at its own
            // place in it (`thin_shift`), so fading trees drop different pixels.
            let lo =
                if fading.is_none() { thin_shift(i, self.spec.seed) * (1.0 - kept) } else { lo };
            (lo, lo + kept)
        } else {
            (lo, hi)
        };
        let fade = [lo, if hi >= 1.0 { 2.0 } else { hi }];
        Instance {
            position: p.position,
            yaw: group.yaw,
            scale: p.scale,
            palette: slots[sp.lane_base * LANES + sp.lane_of[g as usize] as usize],
            leaf_phase: group.leaf.phase,
            leaf_amplitude: group.leaf.amplitude,
            fade,
            lean: group.lean,
            tilt: group.tilt,
            spread,
            tag: if far { 15 } else { level.min(14) } | (species.min(15) << 4) | (g << 8),
        }
    }
}

/// How many draws ([`Forest::write_instances`]) or kept trees of a far leaf (pass 1) ahead
/// the frame asks for a tree's data.
const PREFETCH_AHEAD: usize = 12;

/// One tree as pass 1 takes it: its index, placement and instance group, and its crown's
/// centre and height as the culling took them.
struct Tree<'a> {
    i: usize,
    p: &'a Placement,
    group: u32,
    c: [f32; 3],
    h: f32,
}

/// A species' simulation figures, added to the frame's.
fn add_species_figures(stats: &mut FrameStats, s: &SpeciesRuntime) {
    stats.simulated += s.groups.len();
    stats.coarse_wind += s.coarse_wind;
    stats.near_wind += s.near_wind;
    stats.joints += s.batch.joint_updates();
    stats.state_bytes += s.batch.stored_bytes();
    stats.state_capped += s.capped;
}

impl FrameData {
    /// Pass 2: the per-simulation maxima the runs raised into `need` and `want`, the runs'
    /// counts into `stats`, and their draws into (level, species) order, trees in order
    /// within each: key by key, each run's draws of that key in run order, as a stable sort
    /// of the runs' draws by key would put them.
    fn gather(&mut self, runs: usize, all_keys: usize, stats: &mut FrameStats) {
        self.need.clear();
        self.need.extend(self.need_max.0.iter().map(|m| m.load(Ordering::Relaxed)));
        self.want.clear();
        self.want.extend(self.want_max.0.iter().map(|m| m.load(Ordering::Relaxed)));
        for run in &self.runs[..runs] {
            let r = &run.stats;
            stats.level_changes += r.level_changes;
            stats.group_changes += r.group_changes;
            stats.drawn += r.drawn;
            stats.shadow_only += r.shadow_only;
            stats.occluded += r.occluded;
            stats.regrouping += r.regrouping;
            stats.fading += r.fading;
            stats.impostors += r.impostors;
            stats.thinned += r.thinned;
            stats.thinned_by_leaf += r.thinned_by_leaf;
        }
        for k in 0..all_keys {
            for run in &self.runs[..runs] {
                self.keys.extend(run.by_key[k].iter().map(|&tagged| (k as u32, tagged)));
            }
        }
    }
}
