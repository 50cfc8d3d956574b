//! The canopy wind on a forest's simulations: the stand its trees make, each tree's
//! shelter by its fetch from the windward edge, and each species' joints' height factors
//! (see [`crate::canopy`]).

use sylva_tree::WIND_SAMPLE_HEIGHT;

use super::{Forest, SpeciesRuntime};
use crate::canopy::{
    EDDY_SHARE, Eddies, EdgeFactor, Shelter, Stand, canopy_gust, covered_area, crown_peak_ratio,
    field_mean, gust_factors, height_factors, open_gust, open_speed,
};
use crate::scene::{Placement, SceneSpec, WindSource};
use crate::wind::{steer, wind_near};

/// The canopy wind of a scene's trees, where the scene has it on (`canopy_wind`, default on
/// with a preset or a wind file; a steady wind is the same everywhere): the stand (mean
/// height, leaf area over the ground its trees cover) and the shelter on a grid of cells
/// two spacings wide, gaps up to a canopy height crossed, with ForestGALES' edge factor for
/// the stand's mean spacing, and three canopy-drag lengths of forest along the wind needed
/// for the canopy's flow.
pub(super) fn canopy_of(
    spec: &SceneSpec,
    trees: &[(Placement, u32)],
    species: &[SpeciesRuntime],
) -> Option<(Stand, Shelter)> {
    let on = spec.canopy_wind.unwrap_or(true);
    let steady = matches!(spec.wind_source(), Ok(WindSource::Steady(_)));
    if !on || steady || trees.is_empty() {
        return None;
    }
    let stats = |p: &Placement| &species[p.species as usize].model.tree.stats;
    let n = trees.len() as f64;
    let height = trees.iter().map(|(p, _)| (stats(p).height * p.scale) as f64).sum::<f64>() / n;
    let leaves: f64 =
        trees.iter().map(|(p, _)| (stats(p).leaf_area * p.scale * p.scale) as f64).sum();
    let feet: Vec<[f32; 2]> = trees.iter().map(|(p, _)| [p.position[0], p.position[1]]).collect();
    let (cell, direction) = (2.0 * spec.spacing as f64, spec.wind_direction_deg as f64);
    let ground = covered_area(&feet, cell).max(1.0);
    let stand = Stand { height, lai: leaves / ground };
    // The factor for the stand's mean spacing; the open-to-canopy ratio comes with the field.
    let edge = EdgeFactor::new((ground / n).sqrt(), height);
    // The canopy's flow needs about three canopy-drag lengths of forest to develop.
    let deep = 3.0 * stand.drag_length();
    let shelter = Shelter::new(&feet, direction, cell, edge, height, (1.0, deep));
    Some((stand, shelter))
}

impl Forest {
    /// The stand whose canopy wind the forest simulates (`None` with the canopy wind off).
    pub fn stand(&self) -> Option<Stand> {
        self.canopy_wind.as_ref().map(|c| c.0)
    }

    /// Tree `t`'s shelter from the wind: 0 at the windward edge … 1 deep inside the forest
    /// (`None` with the canopy wind off or no such tree).
    pub fn shelter_of(&self, t: usize) -> Option<f32> {
        let (_, shelter) = self.canopy_wind.as_ref()?;
        let p = self.trees.get(t)?.0.position;
        Some(shelter.at(p[0] as f64, p[1] as f64))
    }

    /// Tree `t`'s fetch: how far the wind has blown through the forest to reach it, m
    /// (`None` with the canopy wind off or no such tree).
    pub fn fetch_of(&self, t: usize) -> Option<f64> {
        let (_, shelter) = self.canopy_wind.as_ref()?;
        let p = self.trees.get(t)?.0.position;
        Some(shelter.fetch(p[0] as f64, p[1] as f64))
    }

    /// The wind tree `t` feels `z` m above its foot at time `time` s (world axes, m/s, live
    /// controls applied): its instance group's sample of the field with the canopy's
    /// eddies and vertical gusts by its group's shelter ([`crate::canopy::Eddies::mix`]),
    /// its mean and its gusts each times the canopy wind's factor for that height and that
    /// shelter, as its simulation takes it (on the field's finest level) (the same at every height with the canopy wind off). `None`: no
    /// such tree.
    pub fn tree_wind(&self, t: usize, z: f64, time: f64) -> Option<[f32; 3]> {
        let &(p, g) = self.trees.get(t)?;
        let s = self.species.get(p.species as usize)?;
        let sample = s.groups.get(g as usize)?.sample;
        let Some((stand, shelter)) = &self.canopy_wind else {
            return Some(self.wind_at(sample, time));
        };
        let field = self.wind.field();
        let (params, zs) = (&field.params, &field.grid.zs);
        let at_sample =
            field_mean(params, zs, WIND_SAMPLE_HEIGHT * s.model.tree.stats.height as f64);
        let x = shelter.at(sample[0], sample[1]) as f64;
        let raw =
            wind_near(self.wind.level(0), self.near.as_ref(), self.near_centre(), sample, time).0;
        let raw = match &self.eddies {
            Some(e) => e.mix(raw, sample, time, at_sample, x),
            None => raw,
        };
        let w = steer(raw, self.gain, self.turn);
        let h = stand.height;
        let here = (1.0 - x) * open_speed(params, h, z) + x * params.mean_speed(z);
        let m = if at_sample > 1e-6 { (here / at_sample) as f32 } else { 1.0 };
        let inside = canopy_gust(z, h, |z| params.mean_speed(z));
        let gust = ((1.0 - x) * open_gust(params, h) + x * inside) as f32;
        let mean = self.mean_wind(at_sample);
        Some(std::array::from_fn(|c| m * mean[c] + gust * (w[c] - mean[c])))
    }

    /// The field's mean wind of speed `speed` m/s, in world axes, live controls applied.
    pub(super) fn mean_wind(&self, speed: f64) -> [f32; 3] {
        let (sn, cs) = self.wind.field().params.direction_deg.to_radians().sin_cos();
        steer([speed * cs, speed * sn, 0.0], self.gain, self.turn)
    }

    /// Give every species' simulation the height factors of the current wind field: the
    /// mean wind at each joint the profile's at its height, in the open and inside, and the
    /// gusts the canopy's size there; and the field's mean speed where it samples.
    pub(super) fn apply_height_factors(&mut self) {
        let field = self.wind.field();
        let (params, zs) = (&field.params, &field.grid.zs);
        self.eddies = None;
        if let Some((stand, shelter)) = &mut self.canopy_wind {
            let crown = WIND_SAMPLE_HEIGHT * stand.height;
            shelter.set_ratio(crown_peak_ratio(params, stand.height, crown));
            let seed = self.spec.seed ^ field.synth.seed;
            self.eddies = Some(Eddies::new(params, stand.height, EDDY_SHARE, seed));
        }
        let canopy = &self.canopy_wind;
        for s in &mut self.species {
            s.mean_speed = 0.0;
            // Without the canopy wind (or where the field is still), no factors: the same
            // wind at every joint.
            let _ = s.batch.set_wind_heights(&[], &[]);
            let Some((stand, _)) = canopy else { continue };
            let centres: Vec<f32> =
                s.batch.species().pressure_centres().iter().map(|c| c[2]).collect();
            let sample = WIND_SAMPLE_HEIGHT * s.model.tree.stats.height as f64;
            let Some((open, inside)) = height_factors(params, zs, sample, stand.height, &centres)
            else {
                continue;
            };
            // Finite and non-negative by construction: a profile's speeds are.
            let _ = s.batch.set_wind_heights(&open, &inside);
            let (open, inside) = gust_factors(params, stand.height, &centres);
            let _ = s.batch.set_gust_heights(&open, &inside);
            s.mean_speed = field_mean(params, zs, sample) as f32;
        }
    }
}
