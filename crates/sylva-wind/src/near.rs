//! A fine tile of the field for the trees near a moving viewpoint (the wind-field LOD's
//! finest level).
//!
//! A field covering a large forest at a spacing that resolves its trees would not fit in
//! memory (50 000 trees 7 m apart: 230² points, 0.65 GB at 512 frames). The forest's field
//! is therefore coarse, and a tree between its grid points reads a bilinear mix of partly
//! coherent records: neighbouring trees move alike, and the mix has less variance than any
//! record (half of it in the middle of a cell whose corners are uncorrelated). A
//! [`NearField`] is a second realisation of the same model (same spectra, coherence, mean
//! profile, heights and loop) on a small square grid at the tree spacing. It tiles the
//! plane periodically in the wind frame and is read only within [`NearField::reach`] of a
//! centre (the camera):
//!
//! * **weight** ([`NearField::weight`]): 1 within `reach − band`, falling smoothly (a
//!   smoothstep) to 0 at `reach`, so a tree passes from one field to the other over seconds
//!   as the camera moves rather than in one frame;
//! * **blend** ([`NearField::blend`]): the mean profile plus the two fluctuations weighted
//!   by `1 − w` and `w` and divided by √((1 − w)² + w²). The realisations are independent,
//!   so the variance passes from the coarse field's to the tile's as w goes from 0 to 1
//!   (at w = ½ it is the average of the two), without the dip a plain linear mix would
//!   make (a quarter of their sum at w = ½); the mean stays the profile's.
//!
//! The tile's period is (n − 1) grid steps along each axis: the value at the last point is
//! followed by the first one's, a seam fixed in space (two neighbouring trees across it feel
//! uncorrelated winds, as trees far apart do; nothing jumps in time). The tile is at least
//! twice `reach` wide, so the neighbourhood of the centre holds at most one seam a side.

use crate::error::WindError;
use crate::field::{WindField, locate};
use crate::grid::Grid;
use crate::params::WindParams;
use crate::synth::SynthParams;

/// A fine, periodic realisation of the wind model read near a moving centre.
#[derive(Debug, Clone)]
pub struct NearField {
    tile: WindField,
    reach: f64,
    band: f64,
}

impl NearField {
    /// Synthesise a tile of `points × points` grid points `spacing` m apart on heights
    /// `zs`, with the loop `frames × dt` (use the coarse field's heights and loop, and a
    /// seed other than its own). Read within `reach` m of the centre, fading out over the
    /// last `band` m; `reach` is clamped to half the tile's period and `band` to `reach`.
    #[allow(clippy::too_many_arguments)]
    pub fn generate(
        params: &WindParams,
        points: usize,
        spacing: f64,
        zs: &[f64],
        frames: usize,
        dt: f64,
        synth: SynthParams,
        reach: f64,
        band: f64,
    ) -> Result<NearField, WindError> {
        let grid = Grid::regular(points, points, spacing, zs, frames, dt);
        let tile = WindField::generate(params, &grid, synth, &|_| {})?;
        let half = 0.5 * spacing * (points.max(2) - 1) as f64;
        let reach = reach.clamp(0.0, half);
        Ok(NearField { tile, reach, band: band.clamp(0.0, reach) })
    }

    /// The tile (one period of the near field), in the wind frame.
    pub fn tile(&self) -> &WindField {
        &self.tile
    }

    /// Grid points per side.
    pub fn points(&self) -> usize {
        self.tile.grid.nx()
    }

    /// Grid spacing, m.
    pub fn spacing(&self) -> f64 {
        let xs = &self.tile.grid.xs;
        if xs.len() > 1 { xs[1] - xs[0] } else { 0.0 }
    }

    /// Distance from the centre beyond which the near field is not read, m.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// Width of the fade at the edge of the reach, m.
    pub fn band(&self) -> f64 {
        self.band
    }

    /// Weight of the near field at horizontal distance `d` (m) from the centre: 1 within
    /// `reach − band`, 0 from `reach` on, a smoothstep between.
    pub fn weight(&self, d: f64) -> f64 {
        let inner = self.reach - self.band;
        if d <= inner {
            return 1.0;
        }
        if d >= self.reach || self.band <= 0.0 {
            return 0.0;
        }
        let s = (self.reach - d) / self.band;
        s * s * (3.0 - 2.0 * s)
    }

    /// Velocity in world axes (m/s) of the periodic tile at world point `p` and time `t`.
    pub fn sample(&self, p: [f64; 3], t: f64) -> [f64; 3] {
        let g = &self.tile.grid;
        let [c, s] = self.tile.params.direction();
        let wrap = |v: f64, axis: &[f64]| {
            let period = axis[axis.len() - 1] - axis[0];
            if period > 0.0 { axis[0] + (v - axis[0]).rem_euclid(period) } else { axis[0] }
        };
        let xw = wrap(p[0] * c + p[1] * s, &g.xs);
        let yw = wrap(-p[0] * s + p[1] * c, &g.ys);
        let w = self.tile.view().sample_wind_frame([xw, yw, p[2]], t);
        [w[0] * c - w[1] * s, w[0] * s + w[1] * c, w[2]]
    }

    /// Mean velocity in world axes at height `z` as the samplers see it (the mean profile
    /// at the grid's heights, interpolated linearly between them and held beyond).
    pub fn mean(&self, z: f64) -> [f64; 3] {
        let zs = &self.tile.grid.zs;
        let u = |i: usize| self.tile.params.mean_speed(zs[i.min(zs.len() - 1)]);
        // The samplers' own interpolation along the heights.
        let (i, f) = locate(zs, z);
        let speed = u(i) + f * (u(i + 1) - u(i));
        let [c, s] = self.tile.params.direction();
        [speed * c, speed * s, 0.0]
    }

    /// The wind at `p`, `t` given `coarse`, the coarse field's velocity there (same model,
    /// heights and direction), and the near weight `w` ∈ [0, 1]: the mean plus the two
    /// fluctuations mixed without losing variance (see the module notes).
    pub fn blend(&self, coarse: [f64; 3], p: [f64; 3], t: f64, w: f64) -> [f64; 3] {
        let w = w.clamp(0.0, 1.0);
        if w <= 0.0 {
            return coarse;
        }
        let fine = self.sample(p, t);
        if w >= 1.0 {
            return fine;
        }
        let m = self.mean(p[2]);
        let norm = ((1.0 - w) * (1.0 - w) + w * w).sqrt();
        std::array::from_fn(|i| {
            m[i] + ((1.0 - w) * (coarse[i] - m[i]) + w * (fine[i] - m[i])) / norm
        })
    }
}
