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
