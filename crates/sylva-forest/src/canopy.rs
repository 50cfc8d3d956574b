//! The wind in a forest and at its edge: the canopy profile a scene's trees make ([`Stand`]:
//! their mean height and the stand's leaf area index), the wind at each joint's own height
//! ([`height_factors`]), and the shelter a tree has from the trees upwind of it
//! ([`Shelter`]): at the windward edge the wind is the open ground's, and the canopy's
//! profile takes over with the distance into the forest.
//!
//! Sources. Inside the canopy the mean speed falls exponentially (Cionco 1965), with the
//! attenuation from the leaf area (`sylva_wind::canopy_attenuation`, Harman & Finnigan
//! 2007); above it, the log law with d = ⅔h and z0 = 0.1h (Thom 1971). Upwind of the
//! forest, the log law over open flat ground, z0 = 0.03 m (the Davenport roughness class
//! "open", WMO Guide to Meteorological Instruments, 2008, Annex 5.B), meeting the forest's
//! at twice the canopy height, the top of its roughness sublayer (Raupach, Finnigan & Brunet
//! 1996 put it at 2–3 h). Across the edge the flow adjusts over a few canopy-drag lengths
//! L_c = 1/(c_d · leaf area density) = h/(c_d · LAI): Belcher, Jerram & Hunt 2003 ("Adjustment
//! of a turbulent boundary layer to a canopy of roughness elements", J. Fluid Mech. 488)
//! find the flow in the canopy decelerating over a distance of order 3 L_c. A tree's shelter
//! here is 1 − e^(−x/L_c) at fetch x, within 5 % of the interior's at 3 L_c.

use sylva_wind::{Profile, WindParams, canopy_attenuation};

/// Drag coefficient of foliage for the canopy's attenuation (Harman & Finnigan 2007 take
/// 0.2–0.25; `sylva_wind::canopy_attenuation`).
pub const FOLIAGE_DRAG: f64 = 0.2;

/// Roughness length of the open ground upwind of a forest, m: flat open grassland
/// (Davenport class "open", WMO 2008).
pub const OPEN_ROUGHNESS: f64 = 0.03;

/// The open ground's log law meets the forest's profile this many canopy heights up.
pub const BLENDING_HEIGHTS: f64 = 2.0;

/// A forest's canopy, as its wind sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stand {
    /// Canopy height h: the trees' mean height, m.
    pub height: f64,
    /// The stand's leaf area index: leaf area (one side) over the ground the forest covers.
    pub lai: f64,
}

impl Stand {
    /// The stand's mean wind profile: the log law over it (d = ⅔h, z0 = 0.1h) and the
    /// exponential law inside, continuous at h, with the attenuation of its leaf area.
    pub fn profile(&self) -> Profile {
        let h = self.height;
        Profile::Canopy {
            h,
            a: canopy_attenuation(self.lai.max(0.1), FOLIAGE_DRAG),
            z0: 0.1 * h,
            d: 2.0 * h / 3.0,
        }
    }

    /// The canopy-drag length L_c = h / (c_d · LAI), m: the e-folding distance of a tree's
    /// shelter from the windward edge inwards.
    pub fn adjustment(&self) -> f64 {
        self.height / (FOLIAGE_DRAG * self.lai.max(0.1))
    }
}

/// Mean speed at height `z` over the open ground upwind of a forest of canopy height `h` in
/// a wind of `params`, m/s: the log law of [`OPEN_ROUGHNESS`], equal to the forest's profile
/// at [`BLENDING_HEIGHTS`] · h. Below 1 m, its value at 1 m.
pub fn open_speed(params: &WindParams, h: f64, z: f64) -> f64 {
    let zb = BLENDING_HEIGHTS * h;
    let law = |z: f64| (z.max(1.0) / OPEN_ROUGHNESS).ln();
    params.mean_speed(zb) * law(z) / law(zb)
}

/// The mean speed a field of `params` synthesised on heights `zs` has at height `z`, m/s: the
/// profile's at its grid heights, linearly between them (as the field is sampled) and held
/// beyond the lowest and the highest.
pub fn field_mean(params: &WindParams, zs: &[f64], z: f64) -> f64 {
    let Some(&first) = zs.first() else { return params.mean_speed(z) };
    let last = *zs.last().unwrap_or(&first);
    if z <= first || zs.len() == 1 {
        return params.mean_speed(first);
    }
    if z >= last {
        return params.mean_speed(last);
    }
    let i = zs.partition_point(|&a| a <= z) - 1;
    let f = (z - zs[i]) / (zs[i + 1] - zs[i]);
    (1.0 - f) * params.mean_speed(zs[i]) + f * params.mean_speed(zs[i + 1])
}

/// Per joint, the factors on a tree's wind (sampled `sample_z` m above its foot from a field
/// of `params` on heights `zs`) that make the mean wind at each joint's height `heights[i]`
/// the open ground's (first) and the canopy's (second) profile: U(z_i) / Ū_field(sample_z).
/// `None` where the field is still at the sample point.
pub fn height_factors(
    params: &WindParams,
    zs: &[f64],
    sample_z: f64,
    h: f64,
    heights: &[f32],
) -> Option<(Vec<f32>, Vec<f32>)> {
    let at_sample = field_mean(params, zs, sample_z);
    if !(at_sample > 1e-6 && at_sample.is_finite()) {
        return None;
    }
    let factor = |u: f64| (u / at_sample) as f32;
    let open = heights.iter().map(|&z| factor(open_speed(params, h, z as f64))).collect();
    let inside = heights.iter().map(|&z| factor(params.mean_speed(z as f64))).collect();
    Some((open, inside))
}

/// Each point's shelter from the wind by the trees upwind of it: 0 at a forest's windward
/// edge, 1 − e^(−x/L) at fetch x (the distance upwind through the forest to its edge).
/// The forest is the cells of a grid that hold a tree; a gap of empty cells shorter than a
/// canopy height is crossed (a clearing narrower than that does not let the open wind in).
#[derive(Debug, Clone)]
pub struct Shelter {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    /// Per cell: the fetch, m (0 for empty cells).
    fetch: Vec<f32>,
    /// Per cell: whether a tree stands in it.
    occupied: Vec<bool>,
    length: f64,
}

impl Shelter {
    /// The shelter of a forest of trees at `feet` (x, y, m), in a wind blowing towards
    /// `direction_deg` (counter-clockwise from +x), on cells of `cell` m, with the e-folding
    /// length `length` m and gaps up to `gap` m crossed. Fetches are followed up to six
    /// lengths (shelter 0.998), farther counts as that.
    pub fn new(feet: &[[f32; 2]], direction_deg: f64, cell: f64, length: f64, gap: f64) -> Shelter {
        let cell = cell.max(0.5);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in feet {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k] as f64);
                hi[k] = hi[k].max(p[k] as f64);
            }
        }
        if feet.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        let origin = [lo[0] - cell, lo[1] - cell];
        let count = |k: usize| ((hi[k] - lo[k]) / cell).floor() as usize + 3;
        let (nx, ny) = (count(0), count(1));
        let mut s = Shelter {
            origin,
            cell,
            nx,
            ny,
            fetch: vec![0.0; nx * ny],
            occupied: vec![false; nx * ny],
            length: length.max(1e-3),
        };
        for p in feet {
            if let Some(c) = s.cell_of(p[0] as f64, p[1] as f64) {
                s.occupied[c] = true;
            }
        }
        let (sn, cs) = direction_deg.to_radians().sin_cos();
        let (step, most) = (0.5 * cell, 6.0 * s.length);
        for iy in 0..ny {
            for ix in 0..nx {
                let c = iy * nx + ix;
                if !s.occupied[c] {
                    continue;
                }
                let x = s.origin[0] + (ix as f64 + 0.5) * cell;
                let y = s.origin[1] + (iy as f64 + 0.5) * cell;
                // Walk upwind until the forest ends: a run of empty cells longer than `gap`,
                // or the grid's edge.
                let (mut d, mut edge, mut empty_from) = (0.0, most, None);
                while d < most {
                    d += step;
                    let inside = s.cell_of(x - cs * d, y - sn * d).map(|c| s.occupied[c]);
                    match inside {
                        Some(true) => empty_from = None,
                        Some(false) => {
                            let from = *empty_from.get_or_insert(d);
                            if d - from > gap {
                                edge = from;
                                break;
                            }
                        }
                        None => {
                            edge = empty_from.unwrap_or(d);
                            break;
                        }
                    }
                }
                s.fetch[c] = edge.min(most) as f32;
            }
        }
        s
    }

    fn cell_of(&self, x: f64, y: f64) -> Option<usize> {
        let fx = (x - self.origin[0]) / self.cell;
        let fy = (y - self.origin[1]) / self.cell;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (ix, iy) = (fx as usize, fy as usize);
        (ix < self.nx && iy < self.ny).then_some(iy * self.nx + ix)
    }

    /// The fetch at (x, y), m: how far the wind has blown through the forest to get there
    /// (0 outside it).
    pub fn fetch(&self, x: f64, y: f64) -> f64 {
        self.cell_of(x, y).map_or(0.0, |c| self.fetch[c] as f64)
    }

    /// The shelter at (x, y): 1 − e^(−fetch / length).
    pub fn at(&self, x: f64, y: f64) -> f32 {
        1.0 - (-self.fetch(x, y) / self.length).exp() as f32
    }

    /// The ground the forest covers: its cells' area, m².
    pub fn area(&self) -> f64 {
        self.occupied.iter().filter(|&&o| o).count() as f64 * self.cell * self.cell
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(n: usize, spacing: f32) -> Vec<[f32; 2]> {
        (0..n * n).map(|k| [(k % n) as f32 * spacing, (k / n) as f32 * spacing]).collect()
    }

    #[test]
    fn fetch_grows_from_the_windward_edge_across_the_forest() {
        // 40 × 40 trees 5 m apart, wind along +x: the fetch is the distance from x = 0.
        let s = Shelter::new(&square(40, 5.0), 0.0, 10.0, 1000.0, 15.0);
        for x in [0.0, 50.0, 100.0, 150.0, 190.0] {
            let f = s.fetch(x, 100.0);
            assert!((f - x).abs() <= 12.0, "fetch {f} m at x = {x} m");
        }
        // Wind along −x: the edge is the other side.
        let s = Shelter::new(&square(40, 5.0), 180.0, 10.0, 1000.0, 15.0);
        assert!(s.fetch(190.0, 100.0) < 12.0 && s.fetch(0.0, 100.0) > 180.0);
        // The shelter rises from 0 at the edge towards 1 inside.
        let s = Shelter::new(&square(40, 5.0), 0.0, 10.0, 30.0, 15.0);
        assert!(s.at(1.0, 100.0) < 0.3 && s.at(150.0, 100.0) > 0.99, "{}", s.at(1.0, 100.0));
    }

    #[test]
    fn a_clearing_narrower_than_the_gap_is_crossed_and_a_wide_one_is_an_edge() {
        // Two stands along x with a 10 m gap, then with a 60 m gap between them.
        for (gap, crossed) in [(10.0f32, true), (60.0, false)] {
            let mut feet = square(20, 5.0);
            feet.extend(square(20, 5.0).iter().map(|p| [p[0] + 95.0 + gap, p[1]]));
            let s = Shelter::new(&feet, 0.0, 5.0, 1000.0, 15.0);
            let f = s.fetch(100.0 + gap as f64 + 10.0, 50.0);
            if crossed {
                assert!(f > 100.0, "gap {gap} m: fetch {f}");
            } else {
                assert!(f < 25.0, "gap {gap} m: fetch {f}");
            }
        }
    }

    #[test]
    fn the_open_profile_meets_the_forests_at_twice_the_canopy_height_and_is_faster_below() {
        let stand = Stand { height: 15.0, lai: 3.0 };
        let p = WindParams { profile: stand.profile(), ..Default::default() };
        p.validate().expect("valid profile");
        let zb = BLENDING_HEIGHTS * 15.0;
        assert!((open_speed(&p, 15.0, zb) - p.mean_speed(zb)).abs() < 1e-9);
        for z in [2.0, 5.0, 10.0, 15.0, 20.0] {
            assert!(open_speed(&p, 15.0, z) > p.mean_speed(z), "z {z}");
        }
        // A denser stand shelters sooner.
        assert!(Stand { lai: 6.0, ..stand }.adjustment() < stand.adjustment());
    }

    #[test]
    fn factors_bring_the_field_mean_to_the_profile_at_every_height() {
        let stand = Stand { height: 15.0, lai: 3.0 };
        let p = WindParams { profile: stand.profile(), ..Default::default() };
        let zs = [8.0, 22.0];
        let heights = [1.0f32, 4.0, 7.5, 10.5, 15.0, 18.0];
        let (open, inside) = height_factors(&p, &zs, 10.5, 15.0, &heights).expect("factors");
        let at = field_mean(&p, &zs, 10.5);
        for (k, &z) in heights.iter().enumerate() {
            let want = p.mean_speed(z as f64);
            assert!((inside[k] as f64 * at - want).abs() < 1e-5 * want.max(1.0), "z {z}");
            let want = open_speed(&p, 15.0, z as f64);
            assert!((open[k] as f64 * at - want).abs() < 1e-5 * want.max(1.0), "z {z}");
        }
    }
}
