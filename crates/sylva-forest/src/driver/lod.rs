//! The geometry LOD's continuous level per tree: the coordinate from a tree's size in the
//! image, its hysteresis and cap, the cross-fade between two levels, and the settings and
//! defaults that steer them (see the `driver` module's documentation).

/// The geometry-LOD switch and thresholds (see the `driver` module's documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodSettings {
    /// Geometry LOD on. Off: every tree at full detail (level 0), no impostors.
    pub geometry: bool,
    /// `h₀`: image-height fraction from which a tree is drawn at full detail (0.01 … 100;
    /// larger is coarser). Default [`DEFAULT_LOD_FRACTION`].
    pub fraction: f32,
    /// First level drawn as an impostor (1 … the chain's length). Default
    /// [`DEFAULT_FAR_LEVEL`].
    pub far_level: u32,
    /// Cross-fade band, in levels (0 … 1): over the last `band` of each level the tree
    /// blends into the next. Default 0.3.
    pub band: f32,
    /// Hysteresis half-width, in levels (0 … 0.5). Default 0.1.
    pub hysteresis: f32,
    /// Animation LOD on: each lane group simulates only the joints its drawn levels use.
    /// Off: every joint of every simulated tree, every step.
    pub animation: bool,
    /// Screen-space error budget of the mesh levels, pixels (0 … 64; 0: every level by
    /// [`LodSettings::fraction`]). Above 0, a tree nearer than its impostor is drawn at the
    /// coarsest mesh level whose geometric error against full detail spans at most this
    /// many pixels of the image ([`level_thresholds`]), and `fraction` places the impostor
    /// alone: a tree covering less of the image's height is one.
    pub error_budget: f32,
    /// Occlusion culling on: trees in view hidden behind nearer trunks and crown cores
    /// (`crate::occlusion`) are not drawn; like trees out of view they may still cast into
    /// the shadow map and step their trunks only. Default off
    /// (docs/decisions/0014-occlusion-culling.md).
    pub occlusion: bool,
    /// Thinning of far impostors, pixels (0 … 256; 0: off): a tree drawn as its impostor
    /// and shorter in the image than this is kept with probability about p = (its height /
    /// this)² (a fixed draw per tree; p at least [`THIN_MIN_KEEP`]), and the trees kept are drawn
    /// with `spread` times their area (wider across the line of sight; taller too as the view
    /// steepens), spread the inverse of the share kept, so that the far canopy covers the
    /// image as all its trees did (Cook, Halstead, Planck & Ryu 2007, "Stochastic
    /// simplification of aggregate detail", applied to whole trees). A tree fades out by
    /// dither as p falls past its draw (over [`THIN_BAND`] of the draws), so nothing pops.
    /// Default 0.
    pub thin_px: f32,
}

/// How far past its draw a thinned tree fades out, in draws ([`LodSettings::thin_px`]).
pub const THIN_BAND: f32 = 0.25;

/// The least p thinning takes ([`LodSettings::thin_px`]): about that share of far trees is
/// kept, each with at most about 8 times its area.
pub const THIN_MIN_KEEP: f32 = 1.0 / 8.0;

/// A tree's fixed draw for thinning, uniform in [0, 1): from its index and the scene's seed.
pub(super) fn thin_draw(tree: usize, seed: u64) -> f32 {
    tree_uniform(tree, seed ^ 0x7468_696e, 0x9e37_79b9_7f4a_7c15)
}

/// Where in the dither range a far tree fading out by thinning keeps its share, as a
/// fraction of the room left (uniform in [0, 1), fixed per tree, independent of
/// [`thin_draw`]): the dither is the screen's, so trees fading at the same place would
/// otherwise all drop the same pixels, and the ground would show through the far canopy in
/// the dither's pattern.
pub(super) fn thin_shift(tree: usize, seed: u64) -> f32 {
    tree_uniform(tree, seed ^ 0x7368_6966_7400, 0xc2b2_ae3d_27d4_eb4f)
}

/// A value uniform in [0, 1) fixed by a tree's index, a salted seed and an odd multiplier
/// (24 bits of one hash).
fn tree_uniform(tree: usize, salted: u64, multiplier: u64) -> f32 {
    let h = sylva_core::rng::mix64(salted ^ (tree as u64).wrapping_mul(multiplier));
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Thinning of a far tree whose image height is `s` times the threshold and whose draw is
/// `u`: `None` where it is not drawn; else the share of its dither range it keeps (1, or
/// less as it fades out) and how much wider it is drawn.
pub fn thinning(s: f32, u: f32) -> Option<(f32, f32)> {
    // At or above the threshold (or not a number): untouched.
    if s.is_nan() || s >= 1.0 {
        return Some((1.0, 1.0));
    }
    // Kept in full below q − THIN_BAND, fading out up to q = p (1 + THIN_BAND): at the
    // threshold (p = 1) every tree is kept in full, so nothing fades or widens at once.
    let p = (s * s).max(THIN_MIN_KEEP);
    let q = p * (1.0 + THIN_BAND);
    if u >= q {
        return None;
    }
    let keep = ((q - u) / THIN_BAND).min(1.0);
    // The share of the canopy's cover kept, averaged over the draws: ∫ keep du on [0, 1).
    let (lo, hi) = ((q - THIN_BAND).clamp(0.0, 1.0), q.min(1.0));
    let cover = lo + (q * (hi - lo) - 0.5 * (hi * hi - lo * lo)) / THIN_BAND;
    Some((keep, 1.0 / cover))
}

/// Pyramid level the wind of far groups is read from: averages of 4 × 4 grid points.
pub const FAR_WIND_LEVEL: usize = 2;

/// Mesh levels coarser than drawn that trees cast their shadows with (the renderer's
/// shadow pass; a tree past the last mesh level casts its last one). Two levels: scene A's
/// image differs from one level's by 1.7 grey levels on average, for about 6 % less
/// rendering time on lavapipe. A tree drawn into the shadow map only
/// ([`Bucket::shadow_only`](super::Bucket::shadow_only)) needs just the joints of the level it casts, and
/// simulates only its trunk.
pub const SHADOW_COARSER: u32 = 2;

/// The mesh level a tree drawn at mesh level `level` of a chain of `chain` meshes casts its
/// shadow with: [`SHADOW_COARSER`] levels coarser, the last mesh at most.
pub fn shadow_level(level: u32, chain: u32) -> u32 {
    (level + SHADOW_COARSER).min(chain.saturating_sub(1))
}

/// How much finer (in levels) than it is drawn a tree is simulated, so the simulation
/// leads the camera by a frame: a tree moving closer already sways when it is first drawn
/// finer. Less margin saves joint updates but shows crowns whose sway has not built up
/// (docs/decisions/0003-lod-thresholds.md).
pub const SIM_MARGIN: f32 = 0.5;

/// Animation LOD by projected size: a tree simulates the joints of the mesh level its size
/// calls for by the default geometry rule — [`lod_coordinate`] with this h₀, half a level
/// ahead ([`SIM_MARGIN`]), every level a mesh — and never finer than the geometry LOD
/// would simulate it; the joints it draws beyond are held at rest on their parents. With
/// the geometry LOD at its defaults this is what it draws (every joint for a tree at full
/// detail); it saves work where trees are drawn finer than their size calls for (the
/// geometry LOD off, or a smaller h₀). It is not larger because twigs held at rest lack
/// the bend the wind gives them, which shows (docs/decisions/0003-lod-thresholds.md).
pub const ANIMATION_FRACTION: f32 = 0.2;

impl Default for LodSettings {
    fn default() -> LodSettings {
        LodSettings {
            geometry: true,
            fraction: DEFAULT_LOD_FRACTION,
            far_level: DEFAULT_FAR_LEVEL,
            band: 0.3,
            hysteresis: 0.1,
            animation: true,
            error_budget: 0.0,
            occlusion: false,
            thin_px: 0.0,
        }
    }
}

/// The continuous LOD coordinate of a tree covering `frac` of the image height:
/// `1 + log₃(h₀ / frac)`, clamped to ≥ 0, so level 0 (x < 1) is for trees taller than `h₀`
/// and level k for `h₀ / 3^k ≤ frac < h₀ / 3^(k−1)`. Monotone: smaller trees get larger
/// values.
pub fn lod_coordinate(frac: f32, h0: f32) -> f32 {
    (1.0 + (h0 / frac.max(1e-9)).ln() / 3f32.ln()).max(0.0)
}

/// Where a tree's LOD state stops: `far + SIM_MARGIN`. From this coordinate on a tree at
/// far level `far` is drawn at that level alone (its impostor, or its last mesh level) and
/// simulates only its trunk, whatever the coordinate's value, and the hysteresis commutes
/// with the cap (`min(hysteresis(p, x, w), cap) = min(hysteresis(min(p, cap), x, w), cap)`,
/// the clamp being monotone in `p`), so a frame built from the capped state is the frame
/// built from the uncapped one. A tree whose image fraction is surely below
/// [`past_cap_fraction`] goes to the cap without its logarithm: most of a large forest.
pub fn lod_cap(far: u32) -> f32 {
    far as f32 + SIM_MARGIN
}

/// The image-height fraction below which [`lod_coordinate`] with this `h0` is at least
/// `cap + half_width` (so that the hysteresis takes a tree to the cap at least), made smaller
/// by 10⁻³ of itself (about 10⁻³ of a level), far more than the rounding of the
/// coordinate, the fraction and this bound.
pub fn past_cap_fraction(h0: f32, cap: f32, half_width: f32) -> f32 {
    h0 * 3f32.powf(1.0 - cap - half_width) * (1.0 - 1e-3)
}

/// A tree's LOD state after a frame: the coordinate `x()` through the hysteresis of
/// `half_width`, capped at `cap` ([`lod_cap`]). `past` says the coordinate is surely at
/// least `cap + half_width`: whatever the state before, the hysteresis then gives at least
/// `cap`, so the state is the cap and `x` is not called.
pub fn next_lod_state(
    prev: f32,
    x: impl FnOnce() -> f32,
    past: bool,
    half_width: f32,
    cap: f32,
) -> f32 {
    if past { cap } else { hysteresis(prev, x(), half_width).min(cap) }
}
/// Backlash hysteresis: the previous value `prev` is kept while within `half_width` of the
/// new `x`, else dragged along with it (NaN `prev`: no history, `x` itself).
pub fn hysteresis(prev: f32, x: f32, half_width: f32) -> f32 {
    if prev.is_nan() { x } else { prev.clamp(x - half_width, x + half_width) }
}

/// Levels of a tree at continuous level `x` (levels ≥ `last` are `last`): the level, the
/// next one and the weight of the next (0 outside the band).
pub fn blend_levels(x: f32, last: u32, band: f32) -> (u32, u32, f32) {
    if x >= last as f32 {
        return (last, last, 0.0);
    }
    // The float-to-integer cast truncates and saturates (negative and NaN give 0): the
    // floor of x, clamped to 0, without a call to `floorf` where the target lacks SSE4.1.
    let level = x as u32;
    let t = x - level as f32;
    let band = band.clamp(0.0, 1.0);
    if band > 0.0 && t > 1.0 - band {
        (level, level + 1, ((t - (1.0 - band)) / band).clamp(0.0, 1.0))
    } else {
        (level, level, 0.0)
    }
}

/// Default image-height fraction above which a tree is drawn at full detail (with
/// [`DEFAULT_FAR_LEVEL`], below which it is an impostor), chosen with `sylva bench table3`
/// for the image error against full detail (docs/decisions/0003-lod-thresholds.md).
pub const DEFAULT_LOD_FRACTION: f32 = 0.2;

/// Default first level drawn as an impostor: 1, so a tree is either at full detail or an
/// impostor, cross-faded between. A scene or `--far-level` can use the mesh levels in
/// between: level 1 shows full detail's leaf cards on a third of its wood, close to full
/// detail for several times the triangles; from level 2 on the cards are thinned, which
/// the levels by screen-space error use ([`LodSettings::error_budget`];
/// docs/decisions/0003-lod-thresholds.md, 0013-lod-by-error.md).
pub const DEFAULT_FAR_LEVEL: u32 = 1;

/// Image rows a [`FrameData`](super::FrameData) assumes until its caller sets
/// [`FrameData::image_rows`](super::FrameData::image_rows): the benchmark's 768.
pub const DEFAULT_IMAGE_ROWS: u32 = 768;

/// Per level 1 … `errors.len() − 1` of a species, the image-height fraction `F_k` at or
/// below which that level's error is within `budget` pixels of an image `rows` tall: level
/// `k` may be drawn when the tree covers at most `F_k` of the image. `errors[k]` is level
/// k's error as a share of the tree's height (its geometric error over its height), so
/// that a tree of any scale covering `frac` of the image shows it as
/// `frac · rows · errors[k]` pixels. Non-increasing: a coarser level needs a smaller tree.
pub fn level_thresholds(errors: &[f32], rows: u32, budget: f32, out: &mut Vec<f32>) {
    out.clear();
    let mut last = f32::INFINITY;
    for &e in errors.iter().skip(1) {
        let f = budget / (rows as f32 * e.max(1e-9));
        last = last.min(f);
        out.push(last);
    }
}

/// The continuous LOD coordinate of a tree covering `frac` of the image, with the per-level
/// thresholds `f` of [`level_thresholds`] (f[k − 1] for level k): level 0 above `f[0]`, the
/// coarsest level k with `frac ≤ f[k − 1]` below, and between two thresholds the fraction's
/// logarithm mapped linearly onto the level's unit interval, so the coordinate is
/// continuous and non-decreasing as the tree shrinks in the image. Above `f[0]` and past
/// the last threshold it moves one level per factor 3 of size, as [`lod_coordinate`] does.
/// Levels whose thresholds coincide are passed over.
pub fn error_coordinate(frac: f32, f: &[f32]) -> f32 {
    let frac = frac.max(1e-12);
    let ln3 = 3f32.ln();
    let Some(&first) = f.first() else { return 0.0 };
    if frac > first {
        return (1.0 - (frac / first).ln() / ln3).max(0.0);
    }
    for k in 1..f.len() {
        let (hi, lo) = (f[k - 1], f[k]);
        if frac > lo {
            // Level k: between its own threshold and the next level's.
            return if hi > lo { k as f32 + (hi / frac).ln() / (hi / lo).ln() } else { k as f32 };
        }
    }
    f.len() as f32 + (f[f.len() - 1] / frac).ln() / ln3
}

/// The fraction below which [`error_coordinate`] is at least `cap + half_width`, smaller by
/// 10⁻³ of itself: the counterpart of [`past_cap_fraction`] for levels by error, the cap
/// lying past the last threshold (`cap ≥ f.len()`).
pub fn past_cap_error_fraction(f: &[f32], cap: f32, half_width: f32) -> f32 {
    let last = f.last().copied().unwrap_or(0.0);
    last * 3f32.powf(f.len() as f32 - cap - half_width) * (1.0 - 1e-3)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Averaged over the trees' draws, thinning keeps the far canopy's cover: the share of
    /// trees kept times their dither share times their spread is 1 at every size; a tree
    /// at or above the threshold is untouched; and a tree's cover changes by little between
    /// nearby sizes (no pop), falling to nothing as it is thinned out.
    #[test]
    fn thinning_keeps_the_cover_and_changes_it_gradually() {
        let draws = 20_000;
        for s in [1.5f32, 1.0, 0.9, 0.6, 0.4, 0.2, 0.05] {
            let cover: f64 = (0..draws)
                .map(|k| (k as f32 + 0.5) / draws as f32)
                .filter_map(|u| thinning(s, u))
                .map(|(keep, spread)| (keep * spread) as f64)
                .sum::<f64>()
                / draws as f64;
            assert!((cover - 1.0).abs() < 2e-3, "cover {cover} at {s} of the threshold");
            if s >= 1.0 {
                assert!((0..100).all(|k| thinning(s, k as f32 / 100.0) == Some((1.0, 1.0))));
            }
        }
        // One tree's cover (keep · spread) as it shrinks in the image, by steps of 1/1000
        // of the threshold: it moves by at most 2 % of the tree's widened cover per step.
        for u in [0.01f32, 0.2, 0.5, 0.7, 0.93, 0.999] {
            let cover = |s: f32| thinning(s, u).map_or((0.0, 1.0), |(k, w)| (k * w, w));
            let mut worst = 0.0f32;
            for k in 0..1200 {
                let s = 1.2 - k as f32 * 1e-3;
                let ((a, wa), (b, wb)) = (cover(s), cover(s - 1e-3));
                worst = worst.max((a - b).abs() / wa.max(wb));
            }
            assert!(worst < 0.02, "draw {u}: the cover jumps by {worst} of itself");
        }
        // Fewer trees, each wider: at a tenth of the threshold p is THIN_MIN_KEEP, and the
        // trees drawn (some fading) are those whose draw is below p (1 + THIN_BAND).
        let kept = (0..draws).filter(|&k| thinning(0.1, k as f32 / draws as f32).is_some());
        let share = kept.count() as f32 / draws as f32;
        assert!((share - THIN_MIN_KEEP * (1.0 + THIN_BAND)).abs() < 0.01, "kept {share}");
    }

    /// A tree's draw is uniform in [0, 1), fixed by its index and seed.
    #[test]
    fn thinning_draws_are_uniform_and_fixed() {
        let n = 100_000;
        let mut bins = [0usize; 10];
        for t in 0..n {
            let u = thin_draw(t, 7);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 10.0) as usize] += 1;
        }
        assert!(bins.iter().all(|&b| (b as f64 / n as f64 - 0.1).abs() < 0.005), "{bins:?}");
        assert_eq!(thin_draw(12, 7), thin_draw(12, 7));
        assert_ne!(thin_draw(12, 7), thin_draw(12, 8));
    }
}
