//! Tree generation after Weber & Penn (1995), producing the skeleton of the hybrid
//! representation: every stem split into `nCurveRes` rigid segments, one joint each.
//!
//! Implemented as WP95 describes: tree scale and trunk length/radius from Scale/ScaleV,
//! 0Length and Ratio·0Scale; stem curvature (nCurve, nCurveBack for S-curves, nCurveV random,
//! negative nCurveV as a helix); base splits (0BaseSplits) and segment splits (nSegSplits
//! with the error-carrying rule) spreading clones by nSplitAngle; children (nBranches) spaced
//! along the parent above BaseSize, their length from the crown ShapeRatio (level 1) or the
//! parent's remaining length, down angles (negative nDownAngleV varying along the parent),
//! rotations (negative nRotate alternating sides); radii from Ratio/RatioPower with nTaper
//! and the trunk Flare; AttractionUp bending stems of level ≥ 2 towards the sky (> 0) or
//! down (< 0: the willow's hanging branchlets); leaves on
//! the last level, counted by Leaves·ShapeRatio(4, ·)·LeafQuality and enlarged by
//! 1/√LeafQuality; the pruning envelope (stems of level ≥ 1 that leave it are regrown
//! shorter, see [`inside_envelope`]). Taper follows WP95 for every nTaper in [0, 3], periodic
//! bulges included (see `radius_at`).
//!
//! Two bounds beyond WP95, so every seed gives a tree a forester would accept: the tree
//! scale varies below `Scale` by at most half of it ([`bounded_scale`]), and no stem of
//! level ≥ 1 reaches below [`GROUND_CLEARANCE`] (a segment that would is raised towards the
//! horizontal just enough).
//!
//! Masses: wood [`WOOD_DENSITY`], leaves [`LEAF_MASS_PER_AREA`]. Same species and seed give
//! the same tree, bit for bit.

use std::f32::consts::PI;

use sylva_core::SplitMix64 as Rng;
use sylva_core::memory::USABLE_SHARE;
use sylva_core::v3::{V3, add, cross, dot, norm, rotate, scale};

use crate::skeleton::{Joint, NO_PARENT, Skeleton, SkeletonError};
use crate::species::Species;

/// Density of green wood, kg/m³ (green hardwoods ≈ 700–1000; USDA Wood Handbook).
pub const WOOD_DENSITY: f32 = 800.0;
/// Fresh leaf mass per one-sided leaf area, kg/m² (broadleaves ≈ 0.1–0.3).
pub const LEAF_MASS_PER_AREA: f32 = 0.15;
/// Area of a leaf of length 1 and width 1 for WP95's default (elliptic) outline: π/4.
const LEAF_SHAPE_AREA: f32 = PI / 4.0;

/// WP95's crown shape ratio for `shape` at relative position `r` ∈ [0, 1].
pub fn shape_ratio(shape: u32, r: f32) -> f32 {
    let r = r.clamp(0.0, 1.0);
    match shape {
        0 => 0.2 + 0.8 * r,
        1 => 0.2 + 0.8 * (PI * r).sin(),
        2 => 0.2 + 0.8 * (0.5 * PI * r).sin(),
        3 => 1.0,
        4 => 0.5 + 0.5 * r,
        5 if r <= 0.7 => r / 0.7,
        5 => (1.0 - r) / 0.3,
        6 => 1.0 - 0.8 * r,
        7 if r <= 0.7 => 0.5 + 0.5 * r / 0.7,
        7 => 0.5 + 0.5 * (1.0 - r) / 0.3,
        _ => 1.0,
    }
}

/// Summary figures of a generated tree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeStats {
    /// Tree height (highest joint tip), m.
    pub height: f32,
    /// Trunk length, m.
    pub trunk_length: f32,
    /// Trunk base radius (before flare), m.
    pub trunk_radius: f32,
    /// Stems generated.
    pub stems: usize,
    /// Leaves generated.
    pub leaves: usize,
    /// One-sided leaf area, m².
    pub leaf_area: f32,
    /// Crown width along x and y, m: the extent of the joint tips.
    pub crown_width: [f32; 2],
    /// Crown base, m: the height at which the lowest branch that carries leaves leaves the
    /// trunk (foresters' height to the live crown; hanging twigs below it do not lower it).
    pub crown_base: f32,
}

impl TreeStats {
    /// Leaf area index of the crown: one-sided leaf area over the ground the crown covers
    /// (the ellipse of its widths), m²/m². Stands of temperate trees measure about 3–6 on
    /// average (Asner, Scurlock & Hicke 2003, Global Ecology and Biogeography 12, 191–205).
    pub fn leaf_area_index(&self) -> f32 {
        let ground = std::f32::consts::FRAC_PI_4 * self.crown_width[0] * self.crown_width[1];
        if ground > 0.0 { self.leaf_area / ground } else { 0.0 }
    }
}

/// A generated tree: its skeleton and figures.
#[derive(Debug, Clone)]
pub struct Tree {
    /// The joint hierarchy.
    pub skeleton: Skeleton,
    /// Summary figures.
    pub stats: TreeStats,
}

struct Gen<'a> {
    sp: &'a Species,
    rng: Rng,
    joints: Vec<Joint>,
    stems: usize,
    leaves: usize,
    leaf_area: f32,
    leaf_size: f32,
    trunk_length: f32,
    base_length: f32,
    split_error: [f32; 4],
    /// Tree scale (WP95 `scale_tree`), m: the pruning envelope's height.
    tree_scale: f32,
    /// Stem levels actually grown: `Levels`, less trailing levels of zero length.
    levels: usize,
    /// Set when growth passed `MaxJoints`: no further stem grows.
    overflow: bool,
}

/// A stem to grow: where, which way, how long and thick.
#[derive(Clone, Copy)]
struct StemSeed {
    level: usize,
    parent_joint: u32,
    origin: V3,
    dir: V3,
    /// A unit vector ⟂ dir fixing the stem's roll (the bending plane of nCurve).
    side: V3,
    length: f32,
    radius: f32,
    /// Offset of this stem along its parent, m, and the parent's length (level ≥ 1).
    offset: f32,
    parent_length: f32,
    /// First segment index to generate (clones of a split continue mid-stem).
    first_segment: u32,
    /// Share of the stem's children and leaves this piece carries: a split divides them
    /// among the clones, so splitting does not multiply the crown's density.
    share: f32,
}

/// Peak bytes per joint of a tree's growth and meshes, leaves aside: the presets measure
/// 1.1–1.9 kB (peak resident memory of `Species::model` over its joints, release build).
pub const BYTES_PER_JOINT: f64 = 2048.0;
/// Peak bytes per joint for each leaf its stem carries, up to [`LEAVES_COUNTED`]: a
/// quaking aspen with 20 000 leaves per stem measures 13.1 kB per joint against 1.85 kB
/// with its 25.
pub const BYTES_PER_LEAF: f64 = 20.0;
/// Leaves per stem counted by [`BYTES_PER_LEAF`]: past about 2 000 the leaf cards stop
/// growing in number (the aspen peaks at 55 MB with 2 000 leaves per stem and with 20 000),
/// and 700 × 20 B bounds what it measures at every count.
pub const LEAVES_COUNTED: f64 = 700.0;
/// Bytes for the bark and leaf textures, whatever the tree.
pub const FIXED_BYTES: f64 = 16e6;

impl Species {
    /// An upper bound on the joints a tree of this species grows without splits: every level
    /// carries at most nBranches children per parent stem, each of nCurveRes segments.
    pub fn joint_bound(&self) -> u64 {
        let levels = self.levels.clamp(1, 4) as usize;
        let (mut stems, mut joints) = (1.0f64, 0.0f64);
        for n in 0..levels {
            if n > 0 {
                stems *= self.level[n].branches.max(0.0) as f64;
            }
            joints += stems * self.level[n].curve_res.max(1) as f64;
        }
        joints.min(u64::MAX as f64) as u64
    }

    /// An upper bound on the memory, bytes, that growing this species' tree and building
    /// its meshes, LOD chain and textures takes at its peak: per joint of
    /// [`Species::joint_bound`], [`BYTES_PER_JOINT`] plus [`BYTES_PER_LEAF`] for each of up to
    /// [`LEAVES_COUNTED`] leaves a stem of the species' largest tree carries, and
    /// [`FIXED_BYTES`] for the textures.
    pub fn memory_estimate(&self) -> f64 {
        let largest = bounded_scale(self.scale, self.scale_v, 1.0);
        let factor = f64::from(leaf_count_factor(self.scale, largest));
        let leaves = (self.leaves.abs() as f64 * factor).min(LEAVES_COUNTED);
        self.joint_bound() as f64 * (BYTES_PER_JOINT + BYTES_PER_LEAF * leaves) + FIXED_BYTES
    }

    /// Refuse a species whose [`Species::memory_estimate`] is over `usable` bytes (what
    /// [`Species::generate`] checks against the usable share of the free memory).
    pub fn check_memory(&self, usable: f64) -> Result<(), SkeletonError> {
        let need = self.memory_estimate();
        if need > usable {
            return Err(SkeletonError::TooMuchMemory {
                need_gb: need / 1e9,
                usable_gb: usable / 1e9,
                joints: self.joint_bound(),
            });
        }
        Ok(())
    }

    /// Generate the tree of this species for `seed`. Refused, before anything grows, when
    /// [`Species::joint_bound`] exceeds `MaxJoints` or [`Species::memory_estimate`] the usable
    /// share of the free memory, and stopped when growth passes `MaxJoints` (splits can
    /// multiply stems beyond the bound).
    pub fn generate(&self, seed: u64) -> Result<Tree, SkeletonError> {
        let bound = self.joint_bound();
        if bound > self.max_joints as u64 {
            return Err(SkeletonError::TooManyJoints {
                joints: bound,
                max: self.max_joints,
                how: "nBranches and nCurveRes allow up to this many",
            });
        }
        if let Some(free) = sylva_core::memory::available_memory() {
            self.check_memory(USABLE_SHARE * free)?;
        }
        let mut rng = Rng::new(seed ^ 0x5175_a000_0000_0000);
        let sp = self;
        let tree_scale = bounded_scale(sp.scale, sp.scale_v, rng.sym());
        let l0 = &sp.level[0];
        let trunk_length = (l0.length + l0.length_v * rng.sym()).max(0.01) * tree_scale.max(0.1);
        let trunk_radius =
            trunk_length * sp.ratio * (sp.scale0 + sp.scale0_v * rng.sym()).max(0.01);
        let mut g = Gen {
            sp,
            rng,
            joints: Vec::new(),
            stems: 0,
            leaves: 0,
            leaf_area: 0.0,
            leaf_size: sp.leaf_scale / sp.leaf_quality.sqrt(),
            trunk_length,
            base_length: sp.base_size * trunk_length,
            split_error: [0.0; 4],
            tree_scale: tree_scale.max(0.1),
            levels: (1..sp.levels.clamp(1, 4) as usize)
                .take_while(|&n| sp.level[n].length + sp.level[n].length_v > 0.0)
                .count()
                + 1,
            overflow: false,
        };
        let seed = StemSeed {
            level: 0,
            parent_joint: NO_PARENT,
            origin: [0.0; 3],
            dir: [0.0, 0.0, 1.0],
            side: [1.0, 0.0, 0.0],
            length: trunk_length,
            radius: trunk_radius,
            offset: 0.0,
            parent_length: trunk_length,
            first_segment: 0,
            share: 1.0,
        };
        g.stem(seed);
        if g.overflow {
            return Err(SkeletonError::TooManyJoints {
                joints: g.joints.len() as u64,
                max: sp.max_joints,
                how: "splits multiplied the stems: growth stopped at the limit",
            });
        }
        let height = g.joints.iter().map(|j| j.tip()[2]).fold(0.0, f32::max);
        let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
        for t in g.joints.iter().map(Joint::tip) {
            for c in 0..2 {
                lo[c] = lo[c].min(t[c]);
                hi[c] = hi[c].max(t[c]);
            }
        }
        let crown_base = crown_base(&g.joints);
        let stats = TreeStats {
            crown_base,
            height,
            trunk_length,
            trunk_radius,
            stems: g.stems,
            leaves: g.leaves,
            leaf_area: g.leaf_area,
            crown_width: [hi[0] - lo[0], hi[1] - lo[1]],
        };
        Ok(Tree { skeleton: Skeleton::new(g.joints)?, stats })
    }
}

/// Where the lowest leafy branch leaves the trunk, m (`TreeStats::crown_base`): each joint
/// off the trunk takes the height at which its first-order branch starts (joints in parent
/// order, so a parent's is known first); a trunk with no leafy branch gives its height.
fn crown_base(joints: &[Joint]) -> f32 {
    let mut on_trunk = vec![true; joints.len()];
    let mut start = vec![f32::INFINITY; joints.len()];
    let mut base = f32::INFINITY;
    for (i, j) in joints.iter().enumerate() {
        if j.parent != NO_PARENT {
            let p = j.parent as usize;
            if on_trunk[p] {
                on_trunk[i] = j.continues;
                start[i] = if j.continues { f32::INFINITY } else { j.origin[2] };
            } else {
                on_trunk[i] = false;
                start[i] = start[p];
            }
        }
        if j.leaf_area > 0.0 && !on_trunk[i] {
            base = base.min(start[i]);
        }
    }
    if base.is_finite() { base } else { joints.iter().map(|j| j.tip()[2]).fold(0.0, f32::max) }
}

/// Height above the ground below which no stem of level ≥ 1 may reach, m.
pub const GROUND_CLEARANCE: f32 = 0.3;
/// Below `Scale` the sampled tree scale varies by at most this fraction of `Scale`.
pub const MAX_SHRINK: f32 = 0.5;

/// WP95's tree scale `Scale + ScaleV·r` for r ∈ [−1, 1), with the downward variation
/// limited to [`MAX_SHRINK`]·Scale: WP95's black oak (Scale = ScaleV = 10 m) would otherwise
/// give trees of any height down to nothing (a 2.4 m bush at seed 1). Upward variation is
/// WP95's.
pub fn bounded_scale(scale: f32, scale_v: f32, r: f32) -> f32 {
    if r >= 0.0 { scale + scale_v * r } else { scale + scale_v.min(MAX_SHRINK * scale) * r }
}

/// How many more leaves a twig of a tree grown to `tree_scale` carries than one of the
/// species' nominal `scale`: (tree_scale / scale)². WP95's branch counts are the same at
/// every size, so a tree twice as tall has as many twigs over four times the ground; with
/// its leaves at their true size, a fixed `Leaves` would leave it a quarter of the leaf
/// area index (a 20 m black oak at 0.4 where the 7 m one has 3.7). Open-grown crowns of a
/// species keep their leaf area index as they grow, so the count grows with the crown's
/// area instead.
fn leaf_count_factor(scale: f32, tree_scale: f32) -> f32 {
    if scale > 0.0 { (tree_scale / scale).powi(2) } else { 1.0 }
}

impl Gen<'_> {
    /// `dir` for a segment of length `len` from `pos`, raised just enough that its end stays
    /// [`GROUND_CLEARANCE`] above the ground (limbs and hanging branchlets rest on it
    /// rather than passing through); unchanged when it already does.
    fn above_ground(&self, pos: V3, dir: V3, len: f32) -> V3 {
        let min_z = ((GROUND_CLEARANCE - pos[2]) / len.max(1e-6)).clamp(-1.0, 1.0);
        if dir[2] >= min_z {
            return dir;
        }
        let h = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
        let flat = if h > 1e-6 { [dir[0] / h, dir[1] / h] } else { [1.0, 0.0] };
        let k = (1.0 - min_z * min_z).max(0.0).sqrt();
        [flat[0] * k, flat[1] * k, min_z]
    }

    /// Radius at relative position z ∈ [0, 1] along a stem of base radius `r0` and length
    /// `length`, by WP95's taper: nTaper in [0, 1) a cone narrowing to (1 − nTaper) r0,
    /// [1, 2) a cone ending in a rounded tip, [2, 3] periodic bulges of depth nTaper − 2
    /// (spherical segments of the local radius); the trunk adds Flare near the ground.
    fn radius_at(&self, level: usize, r0: f32, length: f32, z: f32) -> f32 {
        let taper = self.sp.level[level].taper.clamp(0.0, 3.0);
        let unit = if taper < 1.0 {
            taper
        } else if taper < 2.0 {
            2.0 - taper
        } else {
            0.0
        };
        let taper_z = r0 * (1.0 - unit * z);
        let mut r = if taper < 1.0 {
            taper_z
        } else {
            let z2 = (1.0 - z) * length;
            let depth = if taper < 2.0 || z2 < taper_z { 1.0 } else { taper - 2.0 };
            let z3 = if taper < 2.0 {
                z2
            } else {
                let period = 2.0 * taper_z.max(1e-6);
                (z2 - period * (z2 / period + 0.5).floor()).abs()
            };
            if taper < 2.0 && z3 >= taper_z {
                taper_z
            } else {
                let d = z3 - taper_z;
                (1.0 - depth) * taper_z + depth * (taper_z * taper_z - d * d).max(0.0).sqrt()
            }
        };
        if level == 0 {
            let y = (1.0 - 8.0 * z).max(0.0);
            r *= 1.0 + self.sp.flare * (100f32.powf(y) - 1.0) / 100.0;
        }
        r.max(0.001 * r0).max(1e-4)
    }

    /// Grow one stem from `s`: its segments, children, leaves and splits, in Weber & Penn's
    /// order (the random draws must come in that order for a seed to grow the same tree).
    fn stem(&mut self, s: StemSeed) {
        if self.overflow {
            return;
        }
        let lp = self.sp.level[s.level];
        let res = lp.curve_res.max(1);
        let seg_len = s.length / res as f32;
        self.stems += 1;
        let mut dir = s.dir;
        let side = s.side;
        let mut pos = s.origin;
        let mut parent = s.parent_joint;
        // Children of this stem, spaced along it. Leaves grow on the last level that has
        // stems (a last level of zero length leaves them on the one above).
        let last_level = s.level + 1 >= self.levels;
        let children = if last_level { 0.0 } else { self.child_count(&s) };
        let leaves = if last_level { self.leaf_count(&s) } else { 0.0 };
        let (start, span) = if s.level == 0 {
            (self.base_length, (s.length - self.base_length).max(0.0))
        } else {
            (0.0, s.length)
        };
        let mut rot_acc = self.rng.sym() * PI;
        let n_children = children.round() as usize;
        let n_leaves = leaves.round() as usize;
        // A clone continues mid-stem: it carries only the children and leaves of the
        // segments it grows.
        let clone_start = s.first_segment as f32 * seg_len;
        let mut next_child = (0..n_children)
            .take_while(|&k| start + span * (k as f32 + 0.5) / (n_children as f32) < clone_start)
            .count();
        let mut next_leaf = (s.first_segment as usize * n_leaves) / res as usize;
        let mut share = s.share;
        let mut leaf_carry = 0.0f32;
        for seg in s.first_segment..res {
            dir = self.segment_direction(&s, seg, dir, (pos, seg_len));
            let z0 = seg as f32 / res as f32;
            let r = self.radius_at(s.level, s.radius, s.length, z0 + 0.5 / res as f32);
            let leaf_here = {
                let upto = ((seg + 1) as usize * n_leaves) / res as usize;
                let n = upto.saturating_sub(next_leaf) as f32 * share + leaf_carry;
                next_leaf = upto;
                leaf_carry = n - n.floor();
                n.floor() as usize
            };
            let area = leaf_here as f32
                * self.leaf_size
                * self.leaf_size
                * self.sp.leaf_scale_x
                * LEAF_SHAPE_AREA;
            self.leaves += leaf_here;
            self.leaf_area += area;
            if self.joints.len() >= self.sp.max_joints as usize {
                self.overflow = true;
                return;
            }
            self.joints.push(Joint {
                parent,
                origin: pos,
                axis: dir,
                length: seg_len,
                radius: r,
                own_mass: WOOD_DENSITY * PI * r * r * seg_len,
                leaf_area: area,
                leaf_mass: LEAF_MASS_PER_AREA * area,
                continues: seg > s.first_segment || s.first_segment > 0,
            });
            let me = (self.joints.len() - 1) as u32;
            // Children whose offset falls on this segment.
            let seg_start = seg as f32 * seg_len;
            while next_child < n_children {
                let off = start + span * (next_child as f32 + 0.5) / n_children as f32;
                if off >= seg_start + seg_len && seg + 1 < res {
                    break;
                }
                // Thinning by the share: child k is kept when ⌊(k+1)·share⌋ > ⌊k·share⌋.
                let k = next_child as f32;
                if ((k + 1.0) * share).floor() > (k * share).floor() {
                    let at = add(pos, scale(dir, (off - seg_start).clamp(0.0, seg_len)));
                    self.child(&s, me, at, dir, side, off, &mut rot_acc, next_child);
                }
                next_child += 1;
            }
            pos = add(pos, scale(dir, seg_len));
            parent = me;
            dir = self.split(&s, seg, (pos, dir), me, &mut share);
        }
    }

    /// The direction of segment `seg` of stem `s`, turned from the last segment's `dir`:
    /// its curvature (nCurve, nCurveBack, nCurveV or a helix), the pull towards or away from
    /// the vertical (AttractionUp), and kept above the ground from `pos` over `seg_len`.
    fn segment_direction(
        &mut self,
        s: &StemSeed,
        seg: u32,
        mut dir: V3,
        (pos, seg_len): (V3, f32),
    ) -> V3 {
        let lp = self.sp.level[s.level];
        let res = lp.curve_res.max(1);
        let side = s.side;
        // Random curvature per stem; a negative nCurveV makes a helix (constant twist).
        let curve_v = lp.curve_v.abs().to_radians();
        let helix = lp.curve_v < 0.0;
        let helix_step = if helix { curve_v / res as f32 } else { 0.0 };
        // Curvature of this segment.
        let half = res as f32 / 2.0;
        let bend = if lp.curve_back == 0.0 {
            lp.curve / res as f32
        } else if (seg as f32) < half {
            lp.curve / half
        } else {
            lp.curve_back / half
        };
        let mut angle = bend.to_radians();
        if !helix {
            angle += curve_v / res as f32 * self.rng.sym();
        }
        if seg > 0 || s.level == 0 {
            let axis = norm(cross(dir, side));
            if seg > 0 {
                dir = norm(rotate(dir, axis, angle));
            }
            if helix {
                dir = norm(rotate(dir, s.dir, helix_step));
            }
        }
        if s.level >= 2 && self.sp.attraction_up != 0.0 {
            // WP95: bend towards (AttractionUp > 0) or away from (< 0) the vertical in
            // proportion to the segment's declination. A positive angle about
            // dir × z turns `dir` towards +z; the turn stops at the vertical (up or
            // down) instead of passing it.
            let decl = dir[2].clamp(-1.0, 1.0).acos();
            let horiz = norm(cross(dir, [0.0, 0.0, 1.0]));
            if dot(horiz, horiz) > 0.5 {
                let up = (self.sp.attraction_up * decl / res as f32).clamp(-0.5, 0.5);
                let up = up.clamp(-(PI - decl), decl);
                dir = norm(rotate(dir, horiz, up));
            }
        }
        if s.level >= 1 {
            dir = self.above_ground(pos, dir, seg_len);
        }
        dir
    }

    /// After segment `seg` of stem `s` ends at `pos` going `dir`: its splits (base splits on
    /// the trunk's first segment, else nSegSplits with the error carried along the level),
    /// each clone grown as a stem of its own with its `share` of children and leaves, and the
    /// direction the original goes on in (bent the other way by half the split angle).
    fn split(
        &mut self,
        s: &StemSeed,
        seg: u32,
        (pos, mut dir): (V3, V3),
        me: u32,
        share: &mut f32,
    ) -> V3 {
        let lp = self.sp.level[s.level];
        let res = lp.curve_res.max(1);
        let side = s.side;
        // Splits: base splits on the trunk's first segment, else the error-carrying rule.
        let splits = if s.level == 0 && seg == 0 && self.sp.base_splits > 0 {
            self.sp.base_splits as f32
        } else {
            let want = lp.seg_splits + self.split_error[s.level];
            let n = want.round();
            self.split_error[s.level] = want - n;
            n
        };
        if splits >= 1.0 && seg + 1 < res {
            let clones = splits as usize;
            *share /= clones as f32 + 1.0;
            let spread = (lp.split_angle + lp.split_angle_v * self.rng.sym()).to_radians();
            for c in 0..clones {
                let around =
                    2.0 * PI * (c as f32 + 1.0) / (clones as f32 + 1.0) + self.rng.sym() * 0.3;
                let axis = norm(rotate(norm(cross(dir, side)), dir, around));
                let cdir = norm(rotate(dir, axis, spread));
                let clone = StemSeed {
                    origin: pos,
                    dir: cdir,
                    side: norm(cross(axis, cdir)),
                    parent_joint: me,
                    first_segment: seg + 1,
                    radius: s.radius / (clones as f32 + 1.0).sqrt(),
                    share: *share,
                    ..*s
                };
                self.stem(clone);
            }
            // The original bends the other way by half the angle.
            let axis = norm(cross(dir, side));
            dir = norm(rotate(dir, axis, -0.5 * spread));
        }
        dir
    }

    fn child_count(&mut self, s: &StemSeed) -> f32 {
        // WP95: the trunk carries 1Branches; a first-level branch carries fewer the shorter
        // it is relative to its largest possible length; deeper stems fewer the nearer
        // they sit to their parent's tip.
        let lc = self.sp.level[s.level + 1];
        let factor = match s.level {
            0 => 1.0,
            1 => {
                let max_len = self.sp.level[1].length.max(1e-3);
                0.2 + 0.8 * (s.length / s.parent_length / max_len).min(1.0)
            }
            _ => 1.0 - 0.5 * s.offset / s.parent_length,
        };
        lc.branches * factor.max(0.0)
    }

    fn leaf_count(&mut self, s: &StemSeed) -> f32 {
        let l = self.sp.leaves.abs() * leaf_count_factor(self.sp.scale, self.tree_scale);
        let r = if s.parent_length > 0.0 { s.offset / s.parent_length } else { 1.0 };
        l * shape_ratio(4, r) * self.sp.leaf_quality
    }

    #[allow(clippy::too_many_arguments)]
    fn child(
        &mut self,
        s: &StemSeed,
        joint: u32,
        at: V3,
        dir: V3,
        side: V3,
        off: f32,
        rot_acc: &mut f32,
        k: usize,
    ) {
        let lc = self.sp.level[s.level + 1];
        let len_max = lc.length + lc.length_v * self.rng.sym();
        let length = if s.level == 0 {
            let r = (self.trunk_length - off) / (self.trunk_length - self.base_length).max(1e-3);
            s.length * len_max * shape_ratio(self.sp.shape, r)
        } else {
            len_max * (s.length - 0.6 * off)
        };
        if length <= 1e-3 {
            return;
        }
        let r_parent_here = self.radius_at(s.level, s.radius, s.length, off / s.length);
        let radius =
            (s.radius * (length / s.length).powf(self.sp.ratio_power)).min(r_parent_here).max(1e-4);
        // Rotation about the parent: nRotate per child, or for a negative nRotate children
        // alternating sides (180° apart), each pair advanced by |nRotate|.
        let angle = if lc.rotate >= 0.0 {
            *rot_acc += (lc.rotate + lc.rotate_v * self.rng.sym()).to_radians();
            *rot_acc
        } else {
            let pair = (k / 2) as f32 * lc.rotate.abs() + if k % 2 == 1 { 180.0 } else { 0.0 };
            *rot_acc + (pair + lc.rotate_v * self.rng.sym()).to_radians()
        };
        let down = if lc.down_angle_v >= 0.0 {
            lc.down_angle + lc.down_angle_v * self.rng.sym()
        } else {
            let r = (s.length - off)
                / (s.length - if s.level == 0 { self.base_length } else { 0.0 }).max(1e-3);
            lc.down_angle + lc.down_angle_v * (1.0 - 2.0 * shape_ratio(0, r))
        };
        let perp = norm(rotate(side, dir, angle));
        let tilt_axis = norm(cross(dir, perp));
        let cdir = norm(rotate(dir, tilt_axis, down.to_radians()));
        let cside = norm(cross(tilt_axis, cdir));
        let seed = StemSeed {
            level: s.level + 1,
            parent_joint: joint,
            origin: at,
            dir: cdir,
            side: if dot(cside, cside) > 0.5 { cside } else { perp },
            length,
            radius,
            offset: off,
            parent_length: s.length,
            first_segment: 0,
            share: 1.0,
        };
        if self.sp.prune_ratio <= 0.0 {
            self.stem(seed);
            return;
        }
        // Pruning (WP95): a stem that leaves the envelope is regenerated shorter — the
        // longest fraction that fits, found by bisection, each try from the same random
        // state — and its final length is blended by PruneRatio.
        let snap = self.snapshot();
        self.stem(seed);
        if self.inside_since(snap.joints) {
            return;
        }
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..6 {
            let mid = 0.5 * (lo + hi);
            self.restore(&snap);
            self.stem(StemSeed { length: length * mid, ..seed });
            if self.inside_since(snap.joints) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        self.restore(&snap);
        let pruned = length * (lo + (1.0 - self.sp.prune_ratio.min(1.0)) * (1.0 - lo));
        if pruned > 1e-3 {
            self.stem(StemSeed { length: pruned, ..seed });
        }
    }

    fn snapshot(&self) -> Snapshot {
        Snapshot {
            joints: self.joints.len(),
            rng: self.rng.clone(),
            stems: self.stems,
            leaves: self.leaves,
            leaf_area: self.leaf_area,
            split_error: self.split_error,
        }
    }

    fn restore(&mut self, s: &Snapshot) {
        self.joints.truncate(s.joints);
        self.rng = s.rng.clone();
        self.stems = s.stems;
        self.leaves = s.leaves;
        self.leaf_area = s.leaf_area;
        self.split_error = s.split_error;
    }

    /// Whether every segment tip from joint `from` on lies inside the pruning envelope.
    fn inside_since(&self, from: usize) -> bool {
        self.joints[from..].iter().all(|j| inside_envelope(self.sp, self.tree_scale, j.tip()))
    }
}

/// Generator state to roll back to when a pruned stem is regrown.
struct Snapshot {
    joints: usize,
    rng: Rng,
    stems: usize,
    leaves: usize,
    leaf_area: f32,
    split_error: [f32; 4],
}

/// WP95's pruning envelope: a point at height z and distance r from the trunk axis is
/// inside when r / H < PruneWidth · f(ratio), ratio = (H − z) / (H (1 − BaseSize)) in
/// [0, 1], f = (ratio / PruneWidthPeak)^PrunePowerHigh below the peak and
/// ((1 − ratio) / (1 − PruneWidthPeak))^PrunePowerLow above it; H is the tree scale.
pub fn inside_envelope(sp: &Species, height: f32, p: [f32; 3]) -> bool {
    let ratio = (height - p[2]) / (height * (1.0 - sp.base_size)).max(1e-6);
    if !(0.0..=1.0).contains(&ratio) {
        return false;
    }
    let peak = sp.prune_width_peak.clamp(1e-3, 1.0 - 1e-3);
    let f = if ratio < peak {
        (ratio / peak).powf(sp.prune_power_high)
    } else {
        ((1.0 - ratio) / (1.0 - peak)).powf(sp.prune_power_low)
    };
    (p[0] * p[0] + p[1] * p[1]).sqrt() / height < sp.prune_width * f
}

#[cfg(test)]
mod tests;
