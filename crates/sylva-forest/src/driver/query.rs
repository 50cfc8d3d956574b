//! What a forest tells about itself between frames: cameras, settings, the wind, and single
//! trees (placement, palettes, sway, picking).

use sylva_sway::IDENTITY;
use sylva_wind::{NearField, OwnedPyramid};

use super::ForestError;
use super::lod::{DEFAULT_LOD_FRACTION, LodSettings};
use super::path_keys;
use super::{Forest, SceneWind, TreeInfo};
use crate::camera::Camera;
use crate::scene::{BUILTIN_PATHS, CameraKey, Placement, camera_on_path, default_camera};
use crate::wind::{steer, wind_near};

impl Forest {
    /// The scene's default viewpoint.
    pub fn default_camera(&self) -> Camera {
        default_camera(&self.spec, self.radius)
    }

    /// How long the camera path the forest follows ([`SceneSpec::path`](crate::SceneSpec::path))
    /// lasts, s: its last key's time (12 s for a path without keys), the span
    /// [`Forest::camera_at`] follows.
    pub fn path_duration(&self) -> f32 {
        self.path_keys().last().map_or(12.0, |k| k.t)
    }

    /// The camera at time `t` on the path the forest follows.
    pub fn camera_at(&self, t: f32) -> Camera {
        camera_on_path(&self.path, t, &self.default_camera())
    }

    /// The keys of the camera path the forest follows ([`SceneSpec::path`](crate::SceneSpec::path)):
    /// the fly-in (the scene's `camera_path`, or [`default_camera_path`](crate::scene::default_camera_path)), the walk and the
    /// low flight (the scene's own of those names, or [`walk_path`](crate::scene::walk_path) and
    /// [`low_flight_path`](crate::scene::low_flight_path) over this forest's terrain and tallest tree), or a named path
    /// of the scene.
    pub fn path_keys(&self) -> &[CameraKey] {
        &self.path
    }

    /// Follow camera path `name` from now on (see [`Forest::path_keys`]); an unknown name
    /// is refused, naming the paths there are.
    pub fn set_path(&mut self, name: &str) -> Result<(), ForestError> {
        if !self.spec.has_path(name) {
            let mut names: Vec<&str> = BUILTIN_PATHS.to_vec();
            names.extend(self.spec.paths.keys().map(String::as_str));
            return Err(ForestError::Path(format!("`{name}`: one of {}", names.join(", "))));
        }
        self.spec.path = name.to_string();
        self.path = path_keys(&self.spec, &self.terrain, self.radius, self.canopy);
        Ok(())
    }

    /// The height of the tallest tree above the ground, m.
    pub fn canopy_height(&self) -> f32 {
        self.canopy
    }

    /// Geometry-LOD threshold: the image-height fraction `h₀` above which a tree is drawn at
    /// full detail (larger: coarser everywhere). Clamped to 0.01 … 100.
    pub fn set_lod_fraction(&mut self, h0: f32) {
        self.lod.fraction =
            if h0.is_finite() { h0.clamp(0.01, 100.0) } else { DEFAULT_LOD_FRACTION };
    }

    /// Geometry-LOD settings; values out of range are clamped.
    pub fn set_lod(&mut self, lod: LodSettings) {
        let chain = self.species.iter().map(|s| s.model.lods.len()).min().unwrap_or(1) as u32;
        let finite = |v: f32, d: f32| if v.is_finite() { v } else { d };
        let d = LodSettings::default();
        self.lod = LodSettings {
            geometry: lod.geometry,
            fraction: finite(lod.fraction, d.fraction).clamp(0.01, 100.0),
            far_level: lod.far_level.clamp(1, chain.max(1)),
            band: finite(lod.band, d.band).clamp(0.0, 1.0),
            hysteresis: finite(lod.hysteresis, d.hysteresis).clamp(0.0, 0.5),
            animation: lod.animation,
            error_budget: finite(lod.error_budget, d.error_budget).clamp(0.0, 64.0),
            occlusion: lod.occlusion,
            thin_px: finite(lod.thin_px, d.thin_px).clamp(0.0, 256.0),
        };
    }

    /// The geometry-LOD settings in use.
    pub fn lod(&self) -> LodSettings {
        self.lod
    }

    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Live wind controls: speed multiplier (≥ 0) and extra turn of the direction, degrees.
    pub fn set_wind_control(&mut self, gain: f32, turn_deg: f32) {
        self.gain = gain.max(0.0);
        self.turn = turn_deg.to_radians();
    }

    /// Current wind controls (gain, turn in degrees).
    pub fn wind_control(&self) -> (f32, f32) {
        (self.gain, self.turn.to_degrees())
    }

    /// The wind grid: points per side and their spacing, m.
    pub fn wind_grid(&self) -> (usize, f64) {
        let xs = &self.wind.field().grid.xs;
        let spacing = if xs.len() > 1 { xs[1] - xs[0] } else { 0.0 };
        (xs.len(), spacing)
    }

    /// The near field read around the camera, if the scene's field is coarser than its
    /// trees (see [`wind_field`](crate::wind::wind_field)).
    pub fn near_field(&self) -> Option<&NearField> {
        self.near.as_ref()
    }

    /// One line on the wind's resolution: the grid, and the near tile if there is one.
    pub fn wind_summary(&self) -> String {
        let (n, dx) = self.wind_grid();
        let mut line = format!("wind grid {n}×{n} at {dx:.1} m");
        if let Some(near) = &self.near {
            line += &format!(
                ", near tile {m}×{m} at {:.1} m within {:.0} m of the camera",
                near.spacing(),
                near.reach(),
                m = near.points()
            );
        }
        line
    }

    /// Number of trees.
    pub fn trees(&self) -> usize {
        self.trees.len()
    }

    /// Each tree's crown as seen from above: trunk position x, y and the crown's radius, m
    /// (the species' leaf clusters at full detail: the distance from the trunk within which
    /// 90 % of them hang, plus half a card, times the tree's scale).
    pub fn crowns(&self) -> Vec<[f32; 3]> {
        let radii = self.crown_radii();
        self.trees
            .iter()
            .map(|(p, _)| [p.position[0], p.position[1], radii[p.species as usize] * p.scale])
            .collect()
    }

    /// Per species: the crown radius of the unscaled tree (see [`Forest::crowns`]), m.
    pub(super) fn crown_radii(&self) -> Vec<f32> {
        self.species.iter().map(|s| super::build::crown_radius(&s.model)).collect()
    }

    /// The `n` trees nearest the forest's centre (the origin, over the ground), nearest
    /// first: the first `n` of the scene's layout. (Tree indices follow the forest's cells,
    /// `crate::cells`: tree 0 is the nearest, the others go square by square.)
    pub fn nearest_centre(&self, n: usize) -> Vec<usize> {
        let d2 = |t: usize| {
            let p = self.trees[t].0.position;
            p[0] * p[0] + p[1] * p[1]
        };
        let mut all: Vec<usize> = (0..self.trees.len()).collect();
        let by = |a: &usize, b: &usize| d2(*a).total_cmp(&d2(*b)).then(a.cmp(b));
        if n < all.len() {
            all.select_nth_unstable_by(n, by);
            all.truncate(n);
        }
        all.sort_unstable_by(by);
        all
    }

    /// Placement of tree `t` (species, trunk base, yaw, scale), if there is such a tree.
    pub fn placement(&self, t: usize) -> Option<Placement> {
        self.trees.get(t).map(|&(p, _)| p)
    }

    /// Palettes (rest → animated, tree space) of joints `joints` of tree `t`'s simulation
    /// — its instance group's — in its species' joint numbering ([`SpeciesRuntime::model`](super::SpeciesRuntime::model),
    /// in LOD order). Empty for an unknown tree; a joint past the skeleton reads identity.
    pub fn tree_palettes(&self, t: usize, joints: &[usize]) -> Vec<sylva_sway::Palette> {
        let Some(&(p, g)) = self.trees.get(t) else { return Vec::new() };
        let s = &self.species[p.species as usize];
        let n = s.batch.species().len();
        // Joints beyond what the lane simulates show their anchors' palettes.
        let lane = s.lane_of[g as usize] as usize;
        joints.iter().map(|&j| if j < n { s.batch.palette(lane, j) } else { IDENTITY }).collect()
    }

    /// Replace the wind (e.g. one [`wind_field`](crate::wind::wind_field) synthesised in the background for a changed
    /// scene wind); time, sway state and live controls carry on.
    pub fn set_wind_field(&mut self, wind: SceneWind) {
        self.wind = OwnedPyramid::new(wind.field);
        self.near = wind.near;
        self.apply_height_factors();
    }

    /// The wind at world point `p` (m) now, as the trees feel it (live controls applied).
    pub fn wind_sample(&self, p: [f64; 3]) -> [f32; 3] {
        self.wind_at(p, self.time)
    }

    /// How far tree `t`'s trunk top has moved from rest, m (its instance group's sway).
    pub fn trunk_top_displacement(&self, t: usize) -> Option<f32> {
        let &(p, _) = self.trees.get(t)?;
        let sk = &self.species[p.species as usize].model.tree.skeleton;
        let top = sk.trunk_top();
        let rest = sk.joints()[top].tip();
        let m = self.tree_palettes(t, &[top]);
        let moved = sylva_sway::transform(m.first()?, rest);
        let d: f32 = (0..3).map(|i| (moved[i] - rest[i]).powi(2)).sum::<f32>().sqrt();
        Some(d * p.scale)
    }

    /// What a viewer shows of tree `t`.
    pub fn tree_info(&self, t: usize) -> Option<TreeInfo> {
        let &(p, g) = self.trees.get(t)?;
        let s = &self.species[p.species as usize];
        let stats = &s.model.tree.stats;
        Some(TreeInfo {
            species: s.name.clone(),
            height: stats.height * p.scale,
            dbh: s.model.tree.skeleton.dbh() * p.scale,
            trunk_frequency: s.batch.species().spring(0).frequency,
            group: g,
            group_size: self
                .trees
                .iter()
                .filter(|&&(q, h)| q.species == p.species && h == g)
                .count(),
        })
    }

    /// The tree the ray from `origin` along `dir` (world) hits first: one whose axis it
    /// passes within its crown's radius ([`Forest::crowns`]) above a third of its height,
    /// or within a fifth of its height lower down (the trunk), in front of the origin; the
    /// closest such along the ray. The crown stands as a cylinder about the trunk.
    pub fn pick(&self, origin: [f32; 3], dir: [f32; 3]) -> Option<usize> {
        let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        if n.is_nan() || n <= 0.0 {
            return None;
        }
        let d = [dir[0] / n, dir[1] / n, dir[2] / n];
        let radii = self.crown_radii();
        let mut best: Option<(f32, usize)> = None;
        for (i, (p, _)) in self.trees.iter().enumerate() {
            let h = self.species[p.species as usize].model.tree.stats.height * p.scale;
            // Closest approach of the ray and the trunk segment (base to base + h ẑ).
            let w =
                [origin[0] - p.position[0], origin[1] - p.position[1], origin[2] - p.position[2]];
            let b = d[2];
            let (dd, e) = (d[0] * w[0] + d[1] * w[1] + d[2] * w[2], w[2]);
            let den = 1.0 - b * b;
            let (s, z) = if den > 1e-6 {
                let s = (b * e - dd) / den;
                (s, (e + s * b).clamp(0.0, h))
            } else {
                (-dd, 0.5 * h)
            };
            let s = s.max(0.0);
            let q = [origin[0] + s * d[0], origin[1] + s * d[1], origin[2] + s * d[2]];
            let gap = ((q[0] - p.position[0]).powi(2)
                + (q[1] - p.position[1]).powi(2)
                + (q[2] - p.position[2] - z).powi(2))
            .sqrt();
            let reach = if z >= h / 3.0 {
                (radii[p.species as usize] * p.scale).max(0.2 * h)
            } else {
                0.2 * h
            };
            if gap <= reach && s > 0.0 && best.is_none_or(|(bs, _)| s < bs) {
                best = Some((s, i));
            }
        }
        best.map(|(_, i)| i)
    }

    /// Leaf flutter of tree `t` (its instance group's), as the renderer draws it; `None`
    /// for an unknown tree.
    pub fn tree_leaves(&self, t: usize) -> Option<sylva_sway::LeafSway> {
        let &(p, g) = self.trees.get(t)?;
        self.species[p.species as usize].groups.get(g as usize).map(|g| g.leaf)
    }

    pub(super) fn wind_at(&self, p: [f64; 3], t: f64) -> [f32; 3] {
        let w = wind_near(self.wind.level(0), self.near.as_ref(), self.near_centre(), p, t).0;
        steer(w, self.gain, self.turn)
    }

    /// Where the near field is centred: the last frame's camera (before any frame, the
    /// camera the groups were formed for).
    pub(super) fn near_centre(&self) -> [f32; 3] {
        self.eye.unwrap_or(self.grouped.0)
    }
}
