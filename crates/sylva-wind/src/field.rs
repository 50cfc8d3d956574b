//! A synthesised wind field in memory, its sampling for the animation, the eq.-8 force and
//! the wind-LOD mip pyramid.
//!
//! Storage is frame-major f32, laid out (frame, component, z, y, x), holding full
//! velocities in the wind frame: U = Ū(z) + u, V = v, W = w (paper eq. 1).
//!
//! Sampling ([`FieldView::sample`]) takes world coordinates, rotates them into the wind frame
//! (x along [`WindParams::direction_deg`]), interpolates trilinearly in space (clamped at the
//! grid's edges) and by a Catmull–Rom cubic in time, which is C1-continuous and wraps the
//! loop seamlessly, then rotates the velocity back to world axes.
//!
//! Wind LOD ([`MipPyramid`]): level l averages blocks of 2^l × 2^l grid points (per height and
//! frame); a level's points sit at the mean position of the points they average, and are
//! sampled the same way. Averaging removes the small, fast eddies far trees cannot show.

use serde::{Deserialize, Serialize};

use crate::error::WindError;
use crate::grid::Grid;
use crate::params::{AIR_DENSITY, Component, WindParams};
use crate::spectrum;
use crate::synth::{self, SynthParams};

/// Largest mean wind speed at any height, m/s: the bound a steady wind (`--wind 12`) has,
/// and what a synthesised profile or a file's mean may reach.
pub const MAX_MEAN_SPEED: f64 = 100.0;

/// Largest speed of any one sample, m/s: above the highest surface gust ever measured
/// (113 m/s, Barrow Island, 1996). A sample beyond it is a corrupt file or one in other
/// units, not wind.
pub const MAX_SAMPLE_SPEED: f64 = 150.0;

/// Check that every sample of `field` is finite and at most [`MAX_SAMPLE_SPEED`], and that
/// the mean speed of each height over its points and frames is at most
/// [`MAX_MEAN_SPEED`]; the error names the first bad sample's frame and grid point (or the
/// height). Every reader and writer runs it, so a field that passes is one the forest and
/// the sway probe can take.
pub fn check_samples(field: &WindField) -> Result<(), WindError> {
    let g = &field.grid;
    let (nx, ny, nz) = (g.nx(), g.ny(), g.nz());
    let plane = nx * ny * nz;
    let mut sums = vec![0.0f64; nz];
    for (t, frame) in field.data.chunks_exact(3 * plane).enumerate() {
        for q in 0..plane {
            let (u, v, w) = (frame[q] as f64, frame[plane + q] as f64, frame[2 * plane + q] as f64);
            let speed = (u * u + v * v + w * w).sqrt();
            if speed.is_nan() || speed > MAX_SAMPLE_SPEED {
                let (iz, iy, ix) = (q / (nx * ny), (q / nx) % ny, q % nx);
                return Err(WindError::Samples(format!(
                    "wind sample at frame {t}, point (x {ix}, y {iy}, z {iz}) = ({u}, {v}, {w}) \
                     m/s: expected finite speeds of at most {MAX_SAMPLE_SPEED} m/s"
                )));
            }
            sums[q / (nx * ny)] += u;
        }
    }
    let n = (g.frames * nx * ny).max(1) as f64;
    for (iz, s) in sums.iter().enumerate() {
        let mean = s / n;
        if mean.abs() > MAX_MEAN_SPEED {
            return Err(WindError::Samples(format!(
                "mean wind at height {} m is {mean:.1} m/s: expected at most {MAX_MEAN_SPEED} m/s",
                g.zs[iz]
            )));
        }
    }
    Ok(())
}

/// A wind field: grid, model parameters, synthesis settings and the velocity samples.
#[derive(Debug, Clone, PartialEq)]
pub struct WindField {
    /// Grid and time axis.
    pub grid: Grid,
    /// Model parameters.
    pub params: WindParams,
    /// Seed and method it was made with.
    pub synth: SynthParams,
    /// Velocities in m/s, layout (frame, component, z, y, x), `u` including Ū(z).
    pub data: Vec<f32>,
    /// Bound on how far any coherence of the synthesised CPSDM departs from the model's:
    /// 0 for the exact methods; for the embedding, what projecting the pair-mean model onto
    /// a valid covariance cost where it is not one (see [`crate::synth::Method::Embedding`]).
    pub coherence_error: f64,
}

/// Statistics of what a finite loop keeps of the model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Captured {
    /// Model σ of u, v, w in m/s.
    pub sigma_model: [f64; 3],
    /// σ present in the loop's discrete lines, averaged over heights, m/s.
    pub sigma_discrete: [f64; 3],
    /// Fraction of the model variance the loop holds, per component.
    pub fraction: [f64; 3],
}

/// A zeroed buffer for a field on `grid`, probed fallibly first: a field larger than the
/// machine is an error naming its size, not an allocation abort. (The probe only reserves
/// address space; the buffer itself is then allocated zeroed, page by page as it is written.)
pub(crate) fn alloc_field(grid: &Grid) -> Result<Vec<f32>, WindError> {
    let len = grid.points() * 3 * grid.frames;
    let mut probe: Vec<f32> = Vec::new();
    probe.try_reserve_exact(len).map_err(|_| {
        WindError::Unsupported(format!(
            "the field needs {:.2} GB of memory ({} points × 3 components × {} frames of f32), \
             which this machine cannot allocate; use fewer points or frames, or stream it to a \
             Zarr store",
            len as f64 * 4.0 / 1e9,
            grid.points(),
            grid.frames
        ))
    })?;
    drop(probe);
    Ok(vec![0.0f32; len])
}

impl WindField {
    /// Synthesise a field. `progress` receives the fraction done (0 … 1).
    pub fn generate(
        params: &WindParams,
        grid: &Grid,
        synth: SynthParams,
        progress: &(dyn Fn(f64) + Sync),
    ) -> Result<WindField, WindError> {
        synth::check_config(params, grid, synth)?;
        let mut data = alloc_field(grid)?;
        advise_huge_pages(&mut data);
        let coherence_error = synth::synthesize_into(params, grid, synth, &mut data, progress)?;
        Ok(WindField { grid: grid.clone(), params: params.clone(), synth, data, coherence_error })
    }

    /// Index of sample (frame, component, z, y, x) in `data`.
    #[inline]
    pub fn index(&self, t: usize, c: usize, iz: usize, iy: usize, ix: usize) -> usize {
        let g = &self.grid;
        (((t * 3 + c) * g.nz() + iz) * g.ny() + iy) * g.nx() + ix
    }

    /// The columns `cols` (x indices) of the field as a field of their own: the same model,
    /// time axis, heights and y, the x coordinates those columns have. For statistics over
    /// part of a grid (its middle against its edges, say). Panics if `cols` reaches past the
    /// grid.
    pub fn columns(&self, cols: std::ops::Range<usize>) -> WindField {
        let g = &self.grid;
        let mut grid = g.clone();
        grid.xs = g.xs[cols.clone()].to_vec();
        let mut data = Vec::with_capacity(g.frames * 3 * g.nz() * g.ny() * cols.len());
        for t in 0..g.frames {
            for c in 0..3 {
                for iz in 0..g.nz() {
                    for iy in 0..g.ny() {
                        data.extend(cols.clone().map(|ix| self.data[self.index(t, c, iz, iy, ix)]));
                    }
                }
            }
        }
        WindField {
            grid,
            params: self.params.clone(),
            synth: self.synth,
            data,
            coherence_error: self.coherence_error,
        }
    }

    /// The record of one component at one grid point (fluctuation plus mean), length `frames`.
    pub fn record(&self, c: Component, iz: usize, iy: usize, ix: usize) -> Vec<f64> {
        (0..self.grid.frames)
            .map(|t| self.data[self.index(t, c.index(), iz, iy, ix)] as f64)
            .collect()
    }

    /// What the loop captures of the model variance.
    pub fn captured(&self) -> Captured {
        captured(&self.params, &self.grid)
    }

    /// A sampling view of the full-resolution field.
    pub fn view(&self) -> FieldView<'_> {
        FieldView {
            xs: &self.grid.xs,
            ys: &self.grid.ys,
            zs: &self.grid.zs,
            frames: self.grid.frames,
            dt: self.grid.dt,
            dir: self.params.direction(),
            data: &self.data,
        }
    }
}

/// Ask the kernel to back a large, not yet touched buffer with transparent huge pages:
/// the first write then faults once per 2 MiB instead of once per 4 KiB, which is a large
/// part of the cost of filling a fresh multi-gigabyte field. Advice only: any failure is
/// harmless and ignored.
fn advise_huge_pages(data: &mut [f32]) {
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = data.as_mut_ptr() as usize;
        let end = start + std::mem::size_of_val(data);
        let (a, b) = (start.next_multiple_of(HUGE), end / HUGE * HUGE);
        if b > a {
            // SAFETY: [a, b) lies inside `data`, which we own; MADV_HUGEPAGE changes no
            // contents and no mapping, only how the kernel backs it.
            unsafe { libc::madvise(a as *mut libc::c_void, b - a, libc::MADV_HUGEPAGE) };
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = data;
}

/// What a loop on `grid` captures of the model variance of `params`.
pub fn captured(params: &WindParams, grid: &Grid) -> Captured {
    let mut out = Captured { sigma_model: [0.0; 3], sigma_discrete: [0.0; 3], fraction: [0.0; 3] };
    for comp in Component::ALL {
        let c = comp.index();
        let model = spectrum::model_variance(params, comp);
        let disc = grid
            .zs
            .iter()
            .map(|&z| spectrum::discrete_variance(params, comp, z, grid.frames, grid.dt))
            .sum::<f64>()
            / grid.nz() as f64;
        out.sigma_model[c] = model.sqrt();
        out.sigma_discrete[c] = disc.sqrt();
        out.fraction[c] = disc / model;
    }
    out
}

/// Eq. 8: aerodynamic drag per unit drag area (C_d·A = 1 m²), F = ½ ρ |T| T in N, for a
/// relative air velocity T in m/s. Multiply by the body's C_d·A.
#[inline]
pub fn drag(t: [f64; 3]) -> [f64; 3] {
    let m = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
    let k = 0.5 * AIR_DENSITY * m;
    [k * t[0], k * t[1], k * t[2]]
}

/// A borrowed, sampleable field of one resolution level.
#[derive(Debug, Clone, Copy)]
pub struct FieldView<'a> {
    xs: &'a [f64],
    ys: &'a [f64],
    zs: &'a [f64],
    frames: usize,
    dt: f64,
    dir: [f64; 2],
    data: &'a [f32],
}

/// Position of `v` on a sorted axis: (lower index, fraction to the next), clamped; a NaN
/// lies at the axis's start (no comparison holds for it, and the search below would
/// return the index before the first).
#[inline]
pub(crate) fn locate(axis: &[f64], v: f64) -> (usize, f64) {
    let n = axis.len();
    if n == 1 || v <= axis[0] || v.is_nan() {
        return (0, 0.0);
    }
    if v >= axis[n - 1] {
        return (n - 2, 1.0);
    }
    let i = axis.partition_point(|&a| a <= v) - 1;
    (i, (v - axis[i]) / (axis[i + 1] - axis[i]))
}

impl FieldView<'_> {
    /// Number of grid points (x, y, z) at this level.
    pub fn shape(&self) -> [usize; 3] {
        [self.xs.len(), self.ys.len(), self.zs.len()]
    }

    /// Velocity in world axes (m/s) at world position `p` (m) and time `t` (s, any value:
    /// the loop wraps).
    pub fn sample(&self, p: [f64; 3], t: f64) -> [f64; 3] {
        let [c, s] = self.dir;
        let xw = p[0] * c + p[1] * s;
        let yw = -p[0] * s + p[1] * c;
        let w = self.sample_wind_frame([xw, yw, p[2]], t);
        [w[0] * c - w[1] * s, w[0] * s + w[1] * c, w[2]]
    }

    /// Velocity (U, V, W) in the wind frame at wind-frame position `q`.
    pub fn sample_wind_frame(&self, q: [f64; 3], t: f64) -> [f64; 3] {
        let (ix, fx) = locate(self.xs, q[0]);
        let (iy, fy) = locate(self.ys, q[1]);
        let (iz, fz) = locate(self.zs, q[2]);
        let (nx, ny, nz) = (self.xs.len(), self.ys.len(), self.zs.len());
        let m = self.frames;
        let u = (t / self.dt).rem_euclid(m as f64);
        let t1 = (u.floor() as usize).min(m - 1);
        let a = u - t1 as f64;
        // Catmull–Rom weights for frames t1−1, t1, t1+1, t1+2.
        let a2 = a * a;
        let a3 = a2 * a;
        let wt = [
            0.5 * (-a3 + 2.0 * a2 - a),
            0.5 * (3.0 * a3 - 5.0 * a2 + 2.0),
            0.5 * (-3.0 * a3 + 4.0 * a2 + a),
            0.5 * (a3 - a2),
        ];
        let frames = [(t1 + m - 1) % m, t1, (t1 + 1) % m, (t1 + 2) % m];
        let mut corners = [(0usize, 0.0f64); 8];
        let mut n = 0;
        for (dz, wz) in [(0, 1.0 - fz), (1, fz)] {
            for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
                for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
                    let (x, y, z) =
                        ((ix + dx).min(nx - 1), (iy + dy).min(ny - 1), (iz + dz).min(nz - 1));
                    corners[n] = ((z * ny + y) * nx + x, wx * wy * wz);
                    n += 1;
                }
            }
        }
        let pts = nx * ny * nz;
        let mut out = [0.0; 3];
        for (f, wf) in frames.into_iter().zip(wt) {
            for (c, o) in out.iter_mut().enumerate() {
                let base = (f * 3 + c) * pts;
                let v: f64 = corners.iter().map(|&(i, w)| self.data[base + i] as f64 * w).sum();
                *o += wf * v;
            }
        }
        out
    }
}

/// One coarse level of the pyramid.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    xs: Vec<f64>,
    ys: Vec<f64>,
    data: Vec<f32>,
}

/// Mip pyramid of a field for the wind LOD: level l averages 2^l × 2^l points.
#[derive(Debug, Clone)]
pub struct MipPyramid<'a> {
    base: &'a WindField,
    coarse: Vec<Level>,
}

impl<'a> MipPyramid<'a> {
    /// Build every level down to a single point across (each halves nx and ny, rounding up:
    /// an odd last point is averaged alone).
    pub fn new(field: &'a WindField) -> MipPyramid<'a> {
        MipPyramid { base: field, coarse: coarsen(field) }
    }

    /// Number of levels, the full-resolution field included.
    pub fn levels(&self) -> usize {
        self.coarse.len() + 1
    }

    /// A sampling view of level `l` (clamped to the coarsest level).
    pub fn level(&self, l: usize) -> FieldView<'_> {
        if l == 0 {
            return self.base.view();
        }
        let lv = &self.coarse[(l - 1).min(self.coarse.len() - 1)];
        FieldView { xs: &lv.xs, ys: &lv.ys, data: &lv.data, ..self.base.view() }
    }
}

/// The coarse levels of `field`'s pyramid: each halves nx and ny (rounding up: an odd
/// last point is averaged alone), down to a single point across.
fn coarsen(field: &WindField) -> Vec<Level> {
    let g = &field.grid;
    let mut coarse: Vec<Level> = Vec::new();
    let (mut xs, mut ys) = (g.xs.clone(), g.ys.clone());
    while xs.len() > 1 || ys.len() > 1 {
        let src: &[f32] = coarse.last().map_or(&field.data, |l| &l.data);
        let half = |a: &[f64]| -> Vec<f64> {
            a.chunks(2).map(|c| c.iter().sum::<f64>() / c.len() as f64).collect()
        };
        let (nxs, nys) = (half(&xs), half(&ys));
        let (nx, ny, nz) = (xs.len(), ys.len(), g.nz());
        let (mx, my) = (nxs.len(), nys.len());
        let mut data = vec![0.0f32; g.frames * 3 * nz * my * mx];
        for (plane_out, plane_in) in data.chunks_mut(my * mx).zip(src.chunks(ny * nx)) {
            for j in 0..my {
                for i in 0..mx {
                    let mut sum = 0.0f64;
                    let mut cnt = 0.0;
                    for y in 2 * j..(2 * j + 2).min(ny) {
                        for x in 2 * i..(2 * i + 2).min(nx) {
                            sum += plane_in[y * nx + x] as f64;
                            cnt += 1.0;
                        }
                    }
                    plane_out[j * mx + i] = (sum / cnt) as f32;
                }
            }
        }
        coarse.push(Level { xs: nxs.clone(), ys: nys.clone(), data });
        xs = nxs;
        ys = nys;
    }
    coarse
}

/// A [`MipPyramid`] that owns its field (for holders that keep both, such as a forest).
#[derive(Debug, Clone)]
pub struct OwnedPyramid {
    field: WindField,
    coarse: Vec<Level>,
}

impl OwnedPyramid {
    /// Build every level of `field`'s pyramid (see [`MipPyramid::new`]).
    pub fn new(field: WindField) -> OwnedPyramid {
        let coarse = coarsen(&field);
        OwnedPyramid { field, coarse }
    }

    /// The full-resolution field.
    pub fn field(&self) -> &WindField {
        &self.field
    }

    /// Number of levels, the full-resolution field included.
    pub fn levels(&self) -> usize {
        self.coarse.len() + 1
    }

    /// A sampling view of level `l` (0: the field; clamped to the coarsest level).
    pub fn level(&self, l: usize) -> FieldView<'_> {
        match l.checked_sub(1).and_then(|k| self.coarse.get(k).or(self.coarse.last())) {
            Some(lv) => FieldView { xs: &lv.xs, ys: &lv.ys, data: &lv.data, ..self.field.view() },
            None => self.field.view(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::Method;

    fn small(seed: u64) -> WindField {
        let grid = Grid::regular(8, 6, 3.0, &[20.0], 64, 0.1);
        let synth = SynthParams { seed, method: Method::Separable };
        WindField::generate(&WindParams::default(), &grid, synth, &|_| {}).expect("valid setup")
    }

    #[test]
    fn sampling_at_grid_points_and_frames_returns_the_stored_values() {
        let f = small(1);
        let v = f.view();
        let (ix, iy, t) = (5, 2, 17);
        let got = v.sample([ix as f64 * 3.0, iy as f64 * 3.0, 20.0], t as f64 * 0.1);
        for c in 0..3 {
            let want = f.data[f.index(t, c, 0, iy, ix)] as f64;
            assert!((got[c] - want).abs() < 1e-5, "component {c}: {} vs {want}", got[c]);
        }
    }

    /// A position that is not a number (a tree on ground whose height came out NaN) reads
    /// the grid's first point, as one before the grid does, instead of an index before the
    /// first one.
    #[test]
    fn sampling_at_a_position_that_is_not_a_number_reads_the_grids_edge() {
        let f = small(4);
        let v = f.view();
        for p in [[f64::NAN, 4.0, 20.0], [5.0, f64::NAN, 20.0], [5.0, 4.0, f64::NAN]] {
            let got = v.sample_wind_frame(p, 0.3);
            let mut edge = p;
            edge.iter_mut().filter(|c| c.is_nan()).for_each(|c| *c = -1e6);
            let want = v.sample_wind_frame(edge, 0.3);
            assert!(v.sample(p, 0.3).iter().all(|c| c.is_finite()), "world axes, at {p:?}");
            assert_eq!(got, want, "at {p:?}");
            assert!(got.iter().all(|c| c.is_finite()), "at {p:?}: {got:?}");
        }
        assert_eq!(locate(&[0.0, 1.0, 2.0], f64::NAN), (0, 0.0));
    }

    #[test]
    fn sampling_is_periodic_and_c1_in_time() {
        let f = small(2);
        let v = f.view();
        let p = [7.3, 4.1, 20.0];
        let period = f.grid.period();
        let a = v.sample(p, 1.234);
        let b = v.sample(p, 1.234 + 3.0 * period);
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-9);
        }
        // C1: the one-sided derivatives at a frame time agree (Catmull–Rom), including the
        // loop seam at t = 0.
        for t0 in [0.0, 0.5, period - 0.1] {
            let h = 1e-5;
            let d_left = (v.sample(p, t0)[0] - v.sample(p, t0 - h)[0]) / h;
            let d_right = (v.sample(p, t0 + h)[0] - v.sample(p, t0)[0]) / h;
            assert!(
                (d_left - d_right).abs() < 1e-2 * (1.0 + d_left.abs()),
                "{d_left} vs {d_right}"
            );
        }
    }

    #[test]
    fn direction_rotates_the_mean_wind() {
        let mut f = small(3);
        f.params.direction_deg = 90.0;
        let v = f.view();
        let mut mean = [0.0; 3];
        for t in 0..64 {
            let s = v.sample([0.0, 10.0, 20.0], t as f64 * 0.1);
            for c in 0..3 {
                mean[c] += s[c] / 64.0;
            }
        }
        // Blowing towards +y: the mean is along +y, not x.
        assert!(mean[1] > 3.0 && mean[0].abs() < 1.5, "{mean:?}");
    }

    #[test]
    fn eq8_drag_is_half_rho_speed_times_velocity() {
        let f = drag([3.0, 4.0, 0.0]);
        assert!((f[0] - 0.5 * 1.2 * 5.0 * 3.0).abs() < 1e-12);
        assert!((f[1] - 0.5 * 1.2 * 5.0 * 4.0).abs() < 1e-12);
        // Quadratic in speed.
        let g = drag([6.0, 8.0, 0.0]);
        assert!((g[0] / f[0] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn an_owned_pyramid_samples_as_the_borrowed_one() {
        let f = small(9);
        let owned = OwnedPyramid::new(f.clone());
        let pyr = MipPyramid::new(&f);
        assert_eq!(owned.levels(), pyr.levels());
        for l in 0..=pyr.levels() {
            for k in 0..20 {
                let p = [1.0 + 0.9 * k as f64, 2.0 + 0.6 * k as f64, 20.0];
                let t = 0.137 * k as f64;
                assert_eq!(owned.level(l).sample(p, t), pyr.level(l).sample(p, t), "level {l}");
            }
        }
    }

    #[test]
    fn mip_levels_average_blocks_of_points() {
        let f = small(4);
        let pyr = MipPyramid::new(&f);
        assert_eq!(pyr.levels(), 4); // 8×6 → 4×3 → 2×2 → 1×1
        let l1 = pyr.level(1);
        assert_eq!(l1.shape(), [4, 3, 1]);
        // Level-1 point (1, 2) at frame 5 averages points x 2..4, y 4..6 of level 0.
        let t = 5;
        let want: f64 = (4..6)
            .flat_map(|y| (2..4).map(move |x| (x, y)))
            .map(|(x, y)| f.data[f.index(t, 0, 0, y, x)] as f64)
            .sum::<f64>()
            / 4.0;
        let got = l1.sample_wind_frame([7.5, 13.5, 20.0], t as f64 * 0.1)[0];
        assert!((got - want).abs() < 1e-4, "{got} vs {want}");
        // Averaging keeps the mean and lowers the variance.
        let var = |lv: FieldView<'_>| {
            let s: Vec<f64> = (0..64)
                .map(|t| lv.sample_wind_frame([10.0, 7.0, 20.0], t as f64 * 0.1)[1])
                .collect();
            let m = s.iter().sum::<f64>() / 64.0;
            s.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 64.0
        };
        assert!(var(pyr.level(3)) < var(pyr.level(0)));
    }
}
