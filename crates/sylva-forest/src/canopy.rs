//! The wind in a forest and at its edge: the canopy profile a scene's trees make ([`Stand`]:
//! their mean height and the stand's leaf area index), the mean wind and the gusts at each
//! joint's own height ([`height_factors`], [`gust_factors`]), and the shelter a tree has
//! from the trees upwind of it ([`Shelter`], [`EdgeFactor`]): near the windward edge the
//! wind is mixed with the open ground's, the canopy's taking over with the distance into
//! the forest.
//!
//! Sources. Inside the canopy the mean speed falls exponentially (Cionco 1965), with the
//! attenuation from the leaf area (`sylva_wind::canopy_attenuation`, Harman & Finnigan
//! 2007); above it, the log law with d = ⅔h and z0 = 0.1h (Thom 1971). Upwind of the
//! forest, the log law over open flat ground, z0 = 0.03 m (the Davenport roughness class
//! "open", WMO Guide to Meteorological Instruments, 2008, Annex 5.B), meeting the forest's
//! at twice the canopy height, the top of its roughness sublayer (Raupach, Finnigan & Brunet
//! 1996 put it at 2–3 h). How much of it a tree at fetch x feels follows ForestGALES' edge
//! factor ([`EdgeFactor`]; Hale et al. 2015, fitted to the wind-tunnel bending moments of
//! Gardiner et al. 1997): its crown feels the mix of the open and the canopy wind whose
//! square, against the canopy wind's, is that factor. An isolated tree in the open wind
//! would bear several times the interior's load; measured edge trees bear 1.2–1.5 times it,
//! the flow having slowed before it reaches them.

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
    /// (Held within what a profile takes: h at most 150 m, so d at most 100 m; z0 at most
    /// 10 m.)
    pub fn profile(&self) -> Profile {
        let h = self.height.clamp(0.1, 150.0);
        Profile::Canopy {
            h,
            a: canopy_attenuation(self.lai.max(0.1), FOLIAGE_DRAG),
            z0: (0.1 * h).min(10.0),
            d: 2.0 * h / 3.0,
        }
    }
}

impl Stand {
    /// The canopy-drag length L_c = h / (c_d · LAI), m; the canopy's flow develops over
    /// about 3 L_c of forest (Belcher, Jerram & Hunt 2003), what [`Shelter`] asks of a
    /// forest's depth along the wind.
    pub fn drag_length(&self) -> f64 {
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

/// σ_u / U* at the canopy top: the mean over the canopies Raupach, Finnigan & Brunet 1996
/// gather. Against the surface layer's 2.5 (the field's) the factor is 0.72; the gust
/// factors ([`canopy_gust`]) take it for every component, and the across-wind component
/// keeps it (σ_v = 1.44 U* against the field's 2.0: they give no σ_v).
pub const CANOPY_TOP_SIGMA_U: f64 = 1.8;

/// σ_w / U* at the canopy top: the mean over the canopies Raupach, Finnigan & Brunet 1996
/// gather (against the surface layer's 1.25, the field's: a factor 0.88).
pub const CANOPY_TOP_SIGMA_W: f64 = 1.1;

/// The vertical gusts' factor at the canopy top over the along-wind gusts':
/// ([`CANOPY_TOP_SIGMA_W`] / 1.25) / ([`CANOPY_TOP_SIGMA_U`] / 2.5) ≈ 1.22, applied to the
/// vertical fluctuation at a tree's sample by its shelter ([`Eddies::mix`]).
pub fn vertical_gust_ratio() -> f64 {
    let field = sylva_wind::spectrum::SIGMA_PER_U_STAR;
    (CANOPY_TOP_SIGMA_W / field[2]) / (CANOPY_TOP_SIGMA_U / field[0])
}

/// The gusts' size at height `z` against the field's (whose σ_u is 2.5 U* at every height,
/// `sylva_wind::spectrum::SIGMA_PER_U_STAR`): inside a canopy of height `h`,
/// [`CANOPY_TOP_SIGMA_U`] / 2.5 at the top, below it falling with the canopy's mean speed
/// `mean(z) / mean(h)` (the constant turbulence intensity of the first-order closure that
/// gives the exponential profile, Inoue 1963), above it rising linearly to the field's own
/// at 2h (the roughness sublayer's top).
pub fn canopy_gust(z: f64, h: f64, mean: impl Fn(f64) -> f64) -> f64 {
    let top = CANOPY_TOP_SIGMA_U / sylva_wind::spectrum::SIGMA_PER_U_STAR[0];
    if z <= h {
        let at_top = mean(h);
        if at_top > 0.0 { top * mean(z) / at_top } else { top }
    } else if z < 2.0 * h {
        top + (1.0 - top) * (z - h) / h
    } else {
        1.0
    }
}

/// The open ground's gusts against the field's: its friction velocity (of its log law, met
/// by the forest's at [`BLENDING_HEIGHTS`] · `h`) over the forest's U*.
pub fn open_gust(params: &WindParams, h: f64) -> f64 {
    let zb = BLENDING_HEIGHTS * h;
    let open_u_star = sylva_wind::KARMAN * params.mean_speed(zb) / (zb / OPEN_ROUGHNESS).ln();
    open_u_star / params.u_star.max(1e-9)
}

/// Per joint, the factors on a tree's gusts (its wind less the field's mean) at each
/// joint's height `heights[i]`, over the open ground (first: the open ground's friction
/// velocity over the forest's, the same at every height, its σ_u 2.5 times that) and
/// inside a canopy of height `h` (second: [`canopy_gust`]).
pub fn gust_factors(params: &WindParams, h: f64, heights: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let open = open_gust(params, h) as f32;
    let inside = heights
        .iter()
        .map(|&z| canopy_gust(z as f64, h, |z| params.mean_speed(z)) as f32)
        .collect();
    (vec![open; heights.len()], inside)
}

/// The peak factor on the gusts in a crown's peak wind, mean + k σ_u: the expected largest
/// of a 10-minute record of a response at about 0.3 Hz (a tree's sway), Davenport 1964's
/// √(2 ln νT) + 0.5772 / √(2 ln νT) with νT = 180: 3.40. ForestGALES' edge factor is on
/// the record's maximum bending moment (Gardiner et al. 1997's wind tunnel).
pub const PEAK_FACTOR: f64 = 3.40;

/// The open ground's peak wind over the canopy's at a crown `crown` m up in a forest of
/// height `h` ([`Shelter::set_ratio`]): each its mean plus [`PEAK_FACTOR`] times its
/// along-wind gusts' σ (the open ground's friction velocity's, [`open_gust`]; the canopy's,
/// [`canopy_gust`]). ForestGALES' edge factor is on the maximum bending moment, which the
/// peak wind sets, and the open ground has the faster mean but the smaller gusts.
pub fn crown_peak_ratio(params: &WindParams, h: f64, crown: f64) -> f64 {
    let sigma = sylva_wind::spectrum::SIGMA_PER_U_STAR[0] * params.u_star;
    let open = open_speed(params, h, crown) + PEAK_FACTOR * open_gust(params, h) * sigma;
    let inside = params.mean_speed(crown)
        + PEAK_FACTOR * canopy_gust(crown, h, |z| params.mean_speed(z)) * sigma;
    if inside > 1e-9 { open / inside } else { 1.0 }
}

/// ForestGALES' edge factor: a tree's maximum bending moment at fetch x from a windward edge
/// with open ground upwind, against the interior's (Hale et al. 2015, "ForestGALES 2.5",
/// fitted to Gardiner et al. 1997's wind-tunnel measurements; the form of the `fgr`
/// package's `edge_gap_factor` for a gap of over ten heights): with s = spacing / h (held
/// within 0.075 … 0.45), A = 2.7193 s − 0.061, B = 0.9701 − 1.273 s, c = 1.1127 s + 0.0311,
/// the factor is (A + B c^(x/h)) / A (1.2–1.5 at the edge, within 5 % of 1 by 3 h).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeFactor {
    a: f64,
    b: f64,
    c: f64,
    h: f64,
}

impl EdgeFactor {
    /// For a stand of mean spacing `spacing` m and canopy height `h` m.
    pub fn new(spacing: f64, h: f64) -> EdgeFactor {
        let h = h.max(0.1);
        let s = (spacing / h).clamp(0.075, 0.45);
        EdgeFactor { a: 2.7193 * s - 0.061, b: 0.9701 - 1.273 * s, c: 1.1127 * s + 0.0311, h }
    }

    /// The factor at fetch `x` m.
    pub fn at(&self, x: f64) -> f64 {
        (self.a + self.b * self.c.powf(x.max(0.0) / self.h)) / self.a
    }
}

/// Fetches beyond this many canopy heights count as the interior's.
pub const INTERIOR_HEIGHTS: f64 = 10.0;

/// Each point's shelter from the wind by the trees upwind of it, from its fetch x (the
/// distance along the wind from the forest's upwind-most tree, straight upwind of the
/// point, to the point): 1 deep inside; nearer the edge, the mix of the open ground's wind
/// (shelter 0) and the canopy's (1) whose square, at the crown's height, is the
/// [`EdgeFactor`] times the canopy's.
/// The forest is the cells of a grid that hold a tree; a gap of empty cells shorter than a
/// canopy height is crossed (a clearing narrower than that does not let the open wind in).
#[derive(Debug, Clone)]
pub struct Shelter {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    /// The wind's direction (cos, sin).
    along: [f64; 2],
    /// Per cell: where the forest upwind of it begins, as a distance along the wind.
    edge: Vec<f64>,
    /// Per cell: where the forest downwind of it ends, as a distance along the wind.
    rear: Vec<f64>,
    /// The depth of forest along the wind that develops the canopy's flow, m.
    deep: f64,
    /// Per cell: whether a tree stands in it.
    occupied: Vec<bool>,
    factor: EdgeFactor,
    /// The open ground's peak wind over the canopy's at the crown's height.
    ratio: f64,
    /// Longest fetch followed, m.
    most: f64,
}

/// The grid of cells `cell` m wide over trees at `feet`, one empty cell beyond them on every
/// side: its origin and its cells along x and y.
fn cells(feet: &[[f32; 2]], cell: f64) -> ([f64; 2], usize, usize) {
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
    let count = |k: usize| ((hi[k] - lo[k]) / cell).floor() as usize + 3;
    ([lo[0] - cell, lo[1] - cell], count(0), count(1))
}

/// The ground trees at `feet` cover, m²: the area of the cells `cell` m wide that hold one
/// (the grid [`Shelter`] finds the forest on).
pub fn covered_area(feet: &[[f32; 2]], cell: f64) -> f64 {
    let cell = cell.max(0.5);
    let (origin, nx, ny) = cells(feet, cell);
    let mut occupied = vec![false; nx * ny];
    for p in feet {
        let ix = ((p[0] as f64 - origin[0]) / cell) as usize;
        let iy = ((p[1] as f64 - origin[1]) / cell) as usize;
        if ix < nx && iy < ny {
            occupied[iy * nx + ix] = true;
        }
    }
    occupied.iter().filter(|&&o| o).count() as f64 * cell * cell
}

impl Shelter {
    /// The shelter of a forest of trees at `feet` (x, y, m), in a wind blowing towards
    /// `direction_deg` (counter-clockwise from +x), on cells of `cell` m, with the edge
    /// factor `factor`, gaps up to `gap` m crossed, the open wind's peak `ratio` times
    /// the canopy's at the crown ([`Shelter::set_ratio`]), and `deep` m of forest along the wind
    /// needed for the canopy's flow ([`Shelter::at`]). Fetches are followed up to
    /// [`INTERIOR_HEIGHTS`] canopy heights.
    pub fn new(
        feet: &[[f32; 2]],
        direction_deg: f64,
        cell: f64,
        factor: EdgeFactor,
        gap: f64,
        (ratio, deep): (f64, f64),
    ) -> Shelter {
        let cell = cell.max(0.5);
        let (origin, nx, ny) = cells(feet, cell);
        let (sn, cs) = direction_deg.to_radians().sin_cos();
        let mut s = Shelter {
            origin,
            cell,
            nx,
            ny,
            along: [cs, sn],
            edge: vec![f64::NEG_INFINITY; nx * ny],
            rear: vec![f64::INFINITY; nx * ny],
            deep: deep.max(1e-3),
            occupied: vec![false; nx * ny],
            factor,
            ratio,
            most: INTERIOR_HEIGHTS * factor.h,
        };
        // Per cell, its upwind-most tree's distance along the wind.
        let mut first = vec![f64::INFINITY; nx * ny];
        for p in feet {
            let (x, y) = (p[0] as f64, p[1] as f64);
            if let Some(c) = s.cell_of(x, y) {
                s.occupied[c] = true;
                first[c] = first[c].min(s.downwind(x, y));
            }
        }
        // Per cell, its downwind-most tree's distance along the wind.
        let mut last_tree = vec![f64::NEG_INFINITY; nx * ny];
        for p in feet {
            let (x, y) = (p[0] as f64, p[1] as f64);
            if let Some(c) = s.cell_of(x, y) {
                last_tree[c] = last_tree[c].max(s.downwind(x, y));
            }
        }
        for iy in 0..ny {
            for ix in 0..nx {
                let c = iy * nx + ix;
                if !s.occupied[c] {
                    continue;
                }
                let x = s.origin[0] + (ix as f64 + 0.5) * cell;
                let y = s.origin[1] + (iy as f64 + 0.5) * cell;
                // Upwind to the edge (the last occupied cell's upwind-most tree), downwind to
                // the forest's end (the last occupied cell's downwind-most tree).
                s.edge[c] = s.walk(x, y, -1.0, gap).map_or(f64::NEG_INFINITY, |k| first[k]);
                s.rear[c] = s.walk(x, y, 1.0, gap).map_or(f64::INFINITY, |k| last_tree[k]);
            }
        }
        s
    }

    /// From (x, y), along the wind (`sense` 1) or against it (−1), the last occupied cell
    /// before the forest ends (a run of empty cells longer than `gap`, or the grid's edge);
    /// `None` when it goes on past the longest fetch followed.
    fn walk(&self, x: f64, y: f64, sense: f64, gap: f64) -> Option<usize> {
        let [cs, sn] = self.along;
        let mut last = self.cell_of(x, y)?;
        let (mut d, mut empty_from) = (0.0, None);
        while d < self.most + self.cell {
            d += 0.5 * self.cell;
            match self
                .cell_of(x + sense * cs * d, y + sense * sn * d)
                .map(|k| (k, self.occupied[k]))
            {
                Some((k, true)) => {
                    empty_from = None;
                    last = k;
                }
                Some((_, false)) => {
                    let from = *empty_from.get_or_insert(d);
                    if d - from > gap {
                        return Some(last);
                    }
                }
                None => return Some(last),
            }
        }
        None
    }

    /// Distance of (x, y) along the wind.
    fn downwind(&self, x: f64, y: f64) -> f64 {
        x * self.along[0] + y * self.along[1]
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
    /// (0 outside it and at the windward edge's first trees; at most [`INTERIOR_HEIGHTS`]
    /// canopy heights).
    pub fn fetch(&self, x: f64, y: f64) -> f64 {
        match self.cell_of(x, y) {
            Some(c) if self.occupied[c] => {
                (self.downwind(x, y) - self.edge[c]).clamp(0.0, self.most)
            }
            _ => 0.0,
        }
    }

    /// The depth of forest along the wind through (x, y), m: from its windward edge to its
    /// downwind end (0 outside it).
    pub fn depth(&self, x: f64, y: f64) -> f64 {
        match self.cell_of(x, y) {
            Some(c) if self.occupied[c] => (self.rear[c] - self.edge[c]).max(0.0),
            _ => 0.0,
        }
    }

    /// The shelter at (x, y): the mix whose peak wind at the crown (mean and gusts, both
    /// mixed linearly by the shelter), squared, is the edge factor at its fetch times the
    /// canopy's (1 where the open wind's peak is no faster than the canopy's),
    /// times the share of `deep` the forest's depth there reaches: a clump shorter along the
    /// wind than the canopy's flow needs to develop stays in the open wind.
    pub fn at(&self, x: f64, y: f64) -> f32 {
        let depth = (self.depth(x, y) / self.deep).min(1.0);
        if self.ratio <= 1.0 + 1e-9 {
            return depth as f32;
        }
        let r = self.factor.at(self.fetch(x, y)).sqrt();
        (((self.ratio - r) / (self.ratio - 1.0)).clamp(0.0, 1.0) * depth) as f32
    }

    /// The open ground's peak wind over the canopy's at the crown's height, for the field's
    /// profile ([`crown_peak_ratio`]).
    pub fn set_ratio(&mut self, ratio: f64) {
        self.ratio = if ratio.is_finite() { ratio } else { 1.0 };
    }

    /// The edge factor in use.
    pub fn edge_factor(&self) -> EdgeFactor {
        self.factor
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The eddies are gusts of unit variance whose along-wind correlation falls to its
    /// minimum half a mixing-layer spacing away and rises again a spacing away.
    #[test]
    fn eddies_have_unit_variance_and_the_mixing_layer_spacing() {
        let stand = Stand { height: 17.5, lai: 3.0 };
        let p = WindParams { profile: stand.profile(), ..Default::default() };
        let eddies = Eddies::new(&p, stand.height, EDDY_SHARE, 5);
        let spacing = mixing_layer_spacing(&p, stand.height);
        assert!((eddies.spacing() - spacing).abs() < 1e-9 * spacing);
        // Samples 1 m apart along the wind over many tiles and across-wind lines.
        let line = |y: f64| -> Vec<f64> {
            (0..4000).map(|x| eddies.at(x as f64, y, 0.0) as f64).collect()
        };
        // Across the wind, lines through every row of the tile (four spacings wide).
        let across = 4.0 * spacing / 64.0;
        let lines: Vec<Vec<f64>> = (0..64).map(|k| line(across * k as f64)).collect();
        let var = lines.iter().flatten().map(|v| v * v).sum::<f64>() / (64.0 * 4000.0);
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
        let corr = |lag: usize| {
            let s: f64 = lines
                .iter()
                .map(|l| l.iter().zip(&l[lag..]).map(|(a, b)| a * b).sum::<f64>())
                .sum();
            s / (64.0 * (4000 - lag) as f64) / var
        };
        let r: Vec<f64> = (0..(1.5 * spacing) as usize).map(corr).collect();
        let low = (1..r.len() - 1).find(|&k| r[k] < r[k - 1] && r[k] <= r[k + 1]).expect("minimum");
        let high = (low + 1..r.len() - 1).find(|&k| r[k] > r[k - 1] && r[k] >= r[k + 1]);
        assert!(r[low] < -0.3, "a train of gusts anticorrelates half a spacing on: {}", r[low]);
        assert!(
            (2.0 * low as f64 / spacing - 1.0).abs() < 0.25,
            "minimum at {low} m, Λx {spacing}"
        );
        let high = high.expect("maximum");
        assert!((high as f64 / spacing - 1.0).abs() < 0.25, "maximum at {high} m, Λx {spacing}");
    }

    /// The canopy's turbulence by shelter: at the windward edge (shelter 0) the field's wind
    /// unchanged; deeper in, the eddies take their share of the along-wind variance while
    /// that variance stays the field's, the across-wind gusts stay the field's and the
    /// vertical ones grow to σ_w / σ_u = 1.1 / 1.8 at the canopy top (Raupach, Finnigan &
    /// Brunet 1996) once the gust factors common to all components are applied.
    #[test]
    fn canopy_turbulence_grows_with_shelter_and_keeps_the_along_wind_variance() {
        let stand = Stand { height: 17.5, lai: 3.0 };
        let p = WindParams { profile: stand.profile(), direction_deg: 30.0, ..Default::default() };
        let eddies = Eddies::new(&p, stand.height, EDDY_SHARE, 9);
        let d = p.direction();
        let mean = p.mean_speed(0.7 * stand.height);
        let sigma = sylva_wind::spectrum::SIGMA_PER_U_STAR.map(|s| s * p.u_star);
        let mut rng = sylva_core::rng::SplitMix64::new(3);
        let mut gauss = || {
            let (a, b) = (rng.unit_f64().max(1e-12), rng.unit_f64());
            (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
        };
        // Field winds: mean along d, independent gusts of the field's sizes, at points
        // and times spread over many eddies.
        let samples: Vec<([f64; 3], [f64; 3], f64)> = (0..40_000)
            .map(|k| {
                let (u, v, w) = (sigma[0] * gauss(), sigma[1] * gauss(), sigma[2] * gauss());
                let wind = [(mean + u) * d[0] - v * d[1], (mean + u) * d[1] + v * d[0], w];
                let at = [(k % 200) as f64 * 7.3, (k / 200) as f64 * 5.1, 12.0];
                (wind, at, k as f64 * 0.37)
            })
            .collect();
        let moments = |x: f64| {
            let mut m = [0.0f64; 3];
            for (wind, at, t) in &samples {
                let o = eddies.mix(*wind, *at, *t, mean, x);
                let along = o[0] * d[0] + o[1] * d[1] - mean;
                let across = -o[0] * d[1] + o[1] * d[0];
                m[0] += along * along;
                m[1] += across * across;
                m[2] += o[2] * o[2];
            }
            m.map(|v| (v / samples.len() as f64).sqrt())
        };
        for (wind, at, t) in samples.iter().take(100) {
            let o = eddies.mix(*wind, *at, *t, mean, 0.0);
            assert!((0..3).all(|c| (o[c] - wind[c]).abs() < 1e-9), "the edge: the field's wind");
        }
        let field = moments(0.0);
        for x in [0.5, 1.0] {
            let m = moments(x);
            assert!((m[0] / field[0] - 1.0).abs() < 0.03, "along-wind σ at {x}: {m:?} {field:?}");
            assert!((m[1] / field[1] - 1.0).abs() < 1e-9, "across-wind σ at {x}");
            let want = 1.0 + x * (vertical_gust_ratio() - 1.0);
            assert!((m[2] / field[2] - want).abs() < 1e-9, "vertical σ at {x}");
        }
        // Deep inside, with the gust factor every component takes at the top (0.72):
        let top = CANOPY_TOP_SIGMA_U / sylva_wind::spectrum::SIGMA_PER_U_STAR[0];
        let m = moments(1.0);
        assert!((top * m[0] / p.u_star - 1.8).abs() < 0.06, "σ_u {}", top * m[0] / p.u_star);
        assert!((top * m[2] / p.u_star - 1.1).abs() < 0.04, "σ_w {}", top * m[2] / p.u_star);
    }

    /// The eddies travel downwind at the convection speed: a point moving with them sees
    /// the same gust a moment later, a fixed point another; over many lifetimes they are
    /// replaced.
    #[test]
    fn eddies_travel_at_the_convection_speed_and_live_a_few_spacings() {
        let stand = Stand { height: 17.5, lai: 3.0 };
        let p = WindParams {
            profile: stand.profile(),
            convection_speed: Some(12.0),
            ..Default::default()
        };
        let eddies = Eddies::new(&p, stand.height, EDDY_SHARE, 9);
        let spacing = eddies.spacing();
        let lag = 0.25 * spacing / 12.0; // a quarter spacing of travel
        let pts: Vec<(f64, f64, f64)> =
            (0..2000).map(|k| (3.1 * k as f64, 11.0 * (k % 13) as f64, 0.37 * k as f64)).collect();
        let corr = |f: &dyn Fn(f64, f64, f64) -> (f32, f32)| {
            let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
            for &(x, y, t) in &pts {
                let (a, b) = f(x, y, t);
                ab += (a * b) as f64;
                aa += (a * a) as f64;
                bb += (b * b) as f64;
            }
            ab / (aa * bb).sqrt()
        };
        let moving = corr(&|x, y, t| (eddies.at(x, y, t), eddies.at(x + 12.0 * lag, y, t + lag)));
        let fixed = corr(&|x, y, t| (eddies.at(x, y, t), eddies.at(x, y, t + lag)));
        let later = corr(&|x, y, t| {
            (eddies.at(x, y, t), eddies.at(x + 12.0 * 30.0 * lag, y, t + 30.0 * lag))
        });
        assert!(moving > 0.9, "with the eddies: {moving}");
        assert!(fixed < 0.3, "a quarter spacing later at a fixed point: {fixed}");
        assert!(later.abs() < 0.15, "after seven spacings of travel: {later}");
    }

    fn square(n: usize, spacing: f32) -> Vec<[f32; 2]> {
        (0..n * n).map(|k| [(k % n) as f32 * spacing, (k / n) as f32 * spacing]).collect()
    }

    #[test]
    fn fetch_grows_from_the_windward_edge_across_the_forest() {
        // 40 × 40 trees 5 m apart, wind along +x: the fetch is the distance from x = 0.
        // The ground it covers: 20 × 20 cells of 10 m hold its trees.
        assert_eq!(covered_area(&square(40, 5.0), 10.0), 40_000.0);
        let far = EdgeFactor::new(5.0, 100.0);
        let s = Shelter::new(&square(40, 5.0), 0.0, 10.0, far, 15.0, (3.0, 1.0));
        for x in [0.0, 50.0, 100.0, 150.0, 190.0] {
            let f = s.fetch(x, 100.0);
            assert!((f - x).abs() < 1e-9, "fetch {f} m at x = {x} m");
        }
        // Wind along −x: the edge is the other side.
        let s = Shelter::new(&square(40, 5.0), 180.0, 10.0, far, 15.0, (3.0, 1.0));
        assert!(s.fetch(195.0, 100.0) < 1e-9 && (s.fetch(0.0, 100.0) - 195.0).abs() < 1e-9);
        // The shelter rises towards 1 inside: a 15 m stand, the open wind 3 times the
        // canopy's at the crown; at the edge the crown's wind squared is the edge factor
        // times the interior's.
        let f = EdgeFactor::new(5.0, 15.0);
        let s = Shelter::new(&square(40, 5.0), 0.0, 10.0, f, 15.0, (3.0, 1.0));
        let mix = |x: f64| {
            let sh = s.at(x, 100.0) as f64;
            ((1.0 - sh) * 3.0 + sh).powi(2)
        };
        assert!((mix(0.0) - f.at(0.0)).abs() < 1e-5 && f.at(0.0) > 1.2, "{}", f.at(0.0));
        assert!(s.at(0.0, 100.0) < s.at(15.0, 100.0) && s.at(150.0, 100.0) > 0.9999);
    }

    #[test]
    fn a_clump_shorter_than_the_canopy_flow_needs_stays_in_the_open_wind() {
        // A stand 195 m deep along the wind, and a clump of 4 × 4 trees 15 m deep, both
        // asking 100 m of forest: the stand's middle is sheltered, the clump's trees keep
        // 15 % of it at most.
        let f = EdgeFactor::new(5.0, 15.0);
        let stand = Shelter::new(&square(40, 5.0), 0.0, 10.0, f, 15.0, (3.0, 100.0));
        assert!((stand.depth(100.0, 100.0) - 195.0).abs() < 1e-9);
        assert!(stand.at(100.0, 100.0) > 0.99);
        let clump = Shelter::new(&square(4, 5.0), 0.0, 10.0, f, 15.0, (3.0, 100.0));
        assert!((clump.depth(10.0, 10.0) - 15.0).abs() < 1e-9);
        for x in [0.0, 5.0, 10.0, 15.0] {
            assert!(clump.at(x, 7.0) <= 0.15, "{} at x {x}", clump.at(x, 7.0));
        }
    }

    #[test]
    fn a_clearing_narrower_than_the_gap_is_crossed_and_a_wide_one_is_an_edge() {
        // Two stands along x with a 10 m gap, then with a 60 m gap between them.
        for (gap, crossed) in [(10.0f32, true), (60.0, false)] {
            let mut feet = square(20, 5.0);
            feet.extend(square(20, 5.0).iter().map(|p| [p[0] + 95.0 + gap, p[1]]));
            let s = Shelter::new(&feet, 0.0, 5.0, EdgeFactor::new(5.0, 100.0), 15.0, (3.0, 1.0));
            let f = s.fetch(100.0 + gap as f64 + 10.0, 50.0);
            if crossed {
                assert!((f - 110.0 - gap as f64).abs() < 1e-9, "gap {gap} m: fetch {f}");
            } else {
                assert!((f - 15.0).abs() < 1e-9, "gap {gap} m: fetch {f}");
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
        // ForestGALES' factor: larger at the edge of a denser stand (its interior is the
        // more sheltered), 1 deep inside.
        let (dense, sparse) = (EdgeFactor::new(3.0, 15.0), EdgeFactor::new(6.0, 15.0));
        assert!(dense.at(0.0) > sparse.at(0.0) && sparse.at(0.0) > 1.3, "{}", sparse.at(0.0));
        assert!((sparse.at(10.0 * 15.0) - 1.0).abs() < 1e-3);
    }

    #[test]
    fn every_stand_a_scene_can_hold_makes_a_valid_profile() {
        for height in [0.05, 0.5, 15.0, 90.0, 150.0, 400.0] {
            for lai in [0.0, 0.5, 3.0, 40.0] {
                let p =
                    WindParams { profile: Stand { height, lai }.profile(), ..Default::default() };
                p.validate().unwrap_or_else(|e| panic!("h {height} m, LAI {lai}: {e}"));
            }
        }
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

/// Streamwise spacing of a canopy's mixing-layer eddies, m: Λx = 8.1 Ū(h)/Ū′(h), the shear
/// taken across ±5 cm of the canopy top `h` of the field `params` (Raupach, Finnigan &
/// Brunet 1996, from plane mixing layers and a dozen canopies).
pub fn mixing_layer_spacing(params: &WindParams, h: f64) -> f64 {
    let shear = (params.mean_speed(h + 0.05) - params.mean_speed(h - 0.05)) / 0.1;
    8.1 * params.mean_speed(h) / shear.max(1e-9)
}

/// Share of the along-wind gusts' variance at the canopy top carried by the mixing-layer
/// eddies, the rest by the field's gusts (a choice: Raupach, Finnigan & Brunet 1996 find
/// the canopy-top spectra peaked at the eddies' passing frequency, and most of the
/// momentum carried by them; the share is not measured as such).
pub const EDDY_SHARE: f64 = 0.5;

/// Tile points per side of [`Eddies`].
const EDDY_TILE: usize = 64;
/// The tile is this many streamwise spacings across.
const EDDY_SPACINGS: f64 = 4.0;
/// Independent tiles the eddies cycle through, each placed anew at every turn.
const EDDY_TILES: usize = 4;
/// An eddy's lifetime, in streamwise spacings travelled (a choice: the eddies are replaced
/// as they travel, so gusts decorrelate over a few spacings instead of staying frozen).
const EDDY_LIFE_SPACINGS: f64 = 2.0;

/// The canopy's mixing-layer eddies (Raupach, Finnigan & Brunet 1996): along-wind gusts of
/// streamwise spacing Λx carried downwind at the convection speed U_c — the waves that
/// cross a crop or a forest as honami. Periodic tiles four spacings across, drawn once from
/// a seed: sums of plane waves with wavelengths within about ±25 % of Λx along the wind and
/// a spanwise spread that makes each gust about a third of Λx wide; unit variance; sampled
/// bilinearly at (x − U_c t) along the wind. The eddies live about two spacings of travel:
/// every 2 Λx / U_c one tile fades into the next (cos/sin weights, which keep the variance),
/// each placed at a fresh offset.
#[derive(Debug, Clone, PartialEq)]
pub struct Eddies {
    /// [`EDDY_TILES`] tiles of [`EDDY_TILE`]² values.
    values: Vec<f32>,
    /// Tile step, m.
    step: f64,
    /// Convection speed, m/s, and the mean wind's direction (unit, horizontal).
    speed: f64,
    dir: [f64; 2],
    /// Standard deviation of the eddies' along-wind gust deep in the canopy, m/s, and their
    /// share of the along-wind gusts' variance there.
    sigma: f64,
    share: f64,
    /// Seconds from one tile to the next, and the seed of their offsets.
    life: f64,
    seed: u64,
}

impl Eddies {
    /// The eddies of a canopy of height `h` in the field `params` (its convection speed, or
    /// 1.8 Ū(h) where it has none; its direction; its σ_u = 2.5 U*), with `share` of the
    /// canopy-top gust variance, drawn from `seed`.
    pub fn new(params: &WindParams, h: f64, share: f64, seed: u64) -> Eddies {
        let spacing = mixing_layer_spacing(params, h).clamp(1.0, 1.0e4);
        let side = EDDY_SPACINGS * spacing;
        let n = EDDY_TILE;
        let mut rng = sylva_core::rng::SplitMix64::new(seed ^ 0x6564_6469_6573);
        let mut values = vec![0.0f32; EDDY_TILES * n * n];
        for tile in values.chunks_mut(n * n) {
            // Plane waves (i, j) cycles per tile: i about EDDY_SPACINGS along the wind.
            let mut waves = Vec::new();
            for i in 2..=6i32 {
                for j in -6..=6i32 {
                    let along = i as f64 - EDDY_SPACINGS;
                    let across = j as f64 / 2.0;
                    let a = (-0.5 * (along * along + across * across)).exp();
                    waves.push((i as f64, j as f64, a, std::f64::consts::TAU * rng.unit_f64()));
                }
            }
            // Unit variance: a cosine of amplitude A has variance A²/2.
            let norm = (waves.iter().map(|w| 0.5 * w.2 * w.2).sum::<f64>()).sqrt();
            for (k, v) in tile.iter_mut().enumerate() {
                let (u, w) = ((k % n) as f64 / n as f64, (k / n) as f64 / n as f64);
                let s: f64 = waves
                    .iter()
                    .map(|&(i, j, a, p)| a * (std::f64::consts::TAU * (i * u + j * w) + p).cos())
                    .sum();
                *v = (s / norm) as f32;
            }
        }
        let speed = params.convection_speed.unwrap_or(1.8 * params.mean_speed(h)).max(0.1);
        let share = share.clamp(0.0, 1.0);
        Eddies {
            values,
            step: side / n as f64,
            speed,
            dir: params.direction(),
            sigma: 2.5 * params.u_star * share.sqrt(),
            share,
            life: EDDY_LIFE_SPACINGS * spacing / speed,
            seed,
        }
    }

    /// Tile `turn` (of the endless sequence) at tile coordinates (u, v), bilinearly.
    fn tile_at(&self, turn: i64, u: f64, v: f64) -> f32 {
        let n = EDDY_TILE;
        let h =
            sylva_core::rng::mix64(self.seed ^ (turn as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let tile = &self.values[(h as usize % EDDY_TILES) * n * n..][..n * n];
        let (ou, ov) = (((h >> 16) & 0xffff) as f64, ((h >> 32) & 0xffff) as f64);
        let (u, v) = (u + ou * n as f64 / 65_536.0, v + ov * n as f64 / 65_536.0);
        let (fu, fv) = (u.floor(), v.floor());
        let (du, dv) = ((u - fu) as f32, (v - fv) as f32);
        let wrap = |c: f64| (c.rem_euclid(n as f64) as usize).min(n - 1);
        let (i0, j0) = (wrap(fu), wrap(fv));
        let (i1, j1) = ((i0 + 1) % n, (j0 + 1) % n);
        let at = |i: usize, j: usize| tile[j * n + i];
        let lo = at(i0, j0) + (at(i1, j0) - at(i0, j0)) * du;
        let hi = at(i0, j1) + (at(i1, j1) - at(i0, j1)) * du;
        lo + (hi - lo) * dv
    }

    /// The eddies' unit along-wind gust at ground point (`x`, `y`) m and time `t` s.
    pub fn at(&self, x: f64, y: f64, t: f64) -> f32 {
        let along = x * self.dir[0] + y * self.dir[1] - self.speed * t;
        let across = -x * self.dir[1] + y * self.dir[0];
        let (u, v) = (along / self.step, across / self.step);
        let age = t / self.life;
        let turn = age.floor();
        let (sn, cs) = (std::f64::consts::FRAC_PI_2 * (age - turn)).sin_cos();
        let turn = turn as i64;
        (cs as f32) * self.tile_at(turn, u, v) + (sn as f32) * self.tile_at(turn + 1, u, v)
    }
    /// The canopy's turbulence at point `p` and time `t` for a tree of shelter `shelter`
    /// (0 at the windward edge … 1 deep inside, [`Shelter::at`]), from the field's wind `w`
    /// there about its mean `mean` m/s. The mixing-layer eddies grow with the shelter: they
    /// take `share · shelter` of the along-wind gusts' variance (the field's along-wind
    /// fluctuation kept at √(1 − share · shelter), the eddies' gust added at
    /// √shelter of their size), so the along-wind variance stays the field's; the
    /// across-wind fluctuation is the field's; the vertical one is raised by
    /// 1 + shelter · ([`vertical_gust_ratio`] − 1), so that with the gust factors the
    /// sway takes for every component ([`canopy_gust`]) σ_w at the canopy top is
    /// [`CANOPY_TOP_SIGMA_W`] U*.
    pub fn mix(&self, w: [f64; 3], p: [f64; 3], t: f64, mean: f64, shelter: f64) -> [f64; 3] {
        let x = shelter.clamp(0.0, 1.0);
        let d = self.dir;
        let (du, dv) = (w[0] - d[0] * mean, w[1] - d[1] * mean);
        // The fluctuation along the mean wind and across it.
        let (along, across) = (du * d[0] + dv * d[1], -du * d[1] + dv * d[0]);
        let keep = (1.0 - self.share * x).sqrt();
        let along = mean + keep * along + x.sqrt() * self.sigma * self.at(p[0], p[1], t) as f64;
        [
            along * d[0] - across * d[1],
            along * d[1] + across * d[0],
            (1.0 + x * (vertical_gust_ratio() - 1.0)) * w[2],
        ]
    }

    /// The streamwise spacing the eddies were drawn with, m.
    pub fn spacing(&self) -> f64 {
        self.step * EDDY_TILE as f64 / EDDY_SPACINGS
    }
}
