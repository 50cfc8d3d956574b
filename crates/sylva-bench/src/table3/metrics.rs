//! Image error against full detail (FLIP, SSIM), its floors, and the figures derived from them.

use super::*;

/// Mean FLIP error (NVIDIA's perceptual difference, 0 same … 1; through the `nv-flip`
/// crate) of `test` against `reference` at the default 67 pixels per degree.
pub(super) fn flip(test: &[u8], reference: &[u8], w: u32, h: u32) -> f64 {
    let rgb = |v: &[u8]| -> Vec<u8> { v.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &rgb(test));
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&map).mean() as f64
}

pub(super) fn ssim(a: &[u8], b: &[u8], w: u32, h: u32) -> anyhow::Result<f64> {
    use image_compare::prelude::RgbImage;
    let rgb = |v: &[u8]| -> Vec<u8> { v.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let ia = RgbImage::from_raw(w, h, rgb(a)).context("image size")?;
    let ib = RgbImage::from_raw(w, h, rgb(b)).context("image size")?;
    let s =
        image_compare::rgb_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &ia, &ib)?;
    Ok(s.score)
}

/// What the geometry LOD's image error is measured against, rest pose ([`still_error`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Still {
    /// Mean FLIP and SSIM of all LODs against full detail.
    pub(super) lod: (f64, f64),
    /// Mean FLIP and SSIM of full detail against itself seen a quarter pixel aside: how much
    /// sampling alone moves per-pixel metrics where foliage is finer than a pixel.
    pub(super) sampling: (f64, f64),
}

impl Still {
    /// FLIP and SSIM of `image`, and of `aside` (the reference a quarter pixel aside),
    /// against `reference`.
    fn of(
        image: &[u8],
        aside: &[u8],
        reference: &[u8],
        (w, h): (u32, u32),
    ) -> anyhow::Result<Still> {
        Ok(Still {
            lod: (flip(image, reference, w, h), ssim(image, reference, w, h)?),
            sampling: (flip(aside, reference, w, h), ssim(aside, reference, w, h)?),
        })
    }
}

/// `camera` turned about its eye by a quarter of a pixel's angle (image `h` pixels tall),
/// to the right.
pub(super) fn quarter_pixel_aside(camera: &Camera, h: u32) -> Camera {
    let f: [f32; 3] = std::array::from_fn(|i| camera.target[i] - camera.eye[i]);
    let dist = f.iter().map(|v| v * v).sum::<f32>().sqrt().max(1e-3);
    let right = [f[1], -f[0], 0.0];
    let rn = (right[0] * right[0] + right[1] * right[1]).sqrt().max(1e-6);
    let angle = 0.25 * camera.fov_deg.to_radians() / h.max(1) as f32;
    let shift = dist * angle.tan() / rn;
    Camera { target: std::array::from_fn(|i| camera.target[i] + right[i] * shift), ..*camera }
}

/// The geometry LOD's own image error: the forest with all LODs and at full detail
/// (geometry and animation LODs off, the same instance groups) before any step, so every
/// tree stands in its rest pose and nothing but the drawn levels differs, seen from the
/// last timed frame's camera; and, for scale, full detail against itself turned a quarter
/// pixel aside. `None` where a configuration cannot be built or the full-detail frame is
/// over `--max-image-triangles`.
pub(super) fn still_error(
    spec: &SceneSpec,
    gpu: &mut Headless,
    a: &Table3Bench,
    (w, h): (u32, u32),
) -> anyhow::Result<Option<Still>> {
    // Full detail first: where it is over the image limit, nothing is rendered.
    let specs =
        [configure(spec, a, (false, false, true))?, configure(spec, a, (true, true, true))?];
    let Some(images) = rest_frames(&specs, gpu, a, (w, h))? else { return Ok(None) };
    let [full, aside, lod] = &images[..] else { return Ok(None) };
    write_png(&a.out.join(format!("{}-still-all-LODs.png", spec.name)), w, h, lod)?;
    write_png(&a.out.join(format!("{}-still-full-detail.png", spec.name)), w, h, full)?;
    Ok(Some(Still::of(lod, aside, full, (w, h))?))
}

/// The thinning of far impostors' own image error (with `--thin-px` or the scene's `[lod]
/// thin_px`): all LODs with the thinning against all LODs without it (every far tree its own
/// impostor), both before any step, seen from the last timed frame's camera; and, for
/// scale, the frame without thinning against itself a quarter pixel aside. `None` with the
/// thinning off or a frame over `--max-image-triangles`.
pub(super) fn thinning_error(
    spec: &SceneSpec,
    gpu: &mut Headless,
    a: &Table3Bench,
    (w, h): (u32, u32),
) -> anyhow::Result<Option<Still>> {
    let thinned = configure(spec, a, (true, true, true))?;
    if thinned.lod.thin_px <= 0.0 {
        return Ok(None);
    }
    let mut whole = thinned.clone();
    whole.lod.thin_px = 0.0;
    let Some(images) = rest_frames(&[whole, thinned], gpu, a, (w, h))? else { return Ok(None) };
    let [whole, aside, thin] = &images[..] else { return Ok(None) };
    write_png(&a.out.join(format!("{}-still-thinned.png", spec.name)), w, h, thin)?;
    write_png(&a.out.join(format!("{}-still-every-impostor.png", spec.name)), w, h, whole)?;
    Ok(Some(Still::of(thin, aside, whole, (w, h))?))
}

/// The frames of `specs` before any step (every tree in its rest pose), each from the last
/// timed frame's camera, the first also turned a quarter pixel aside (after it): `None`
/// where a forest cannot be built or a frame is over `--max-image-triangles`.
fn rest_frames(
    specs: &[SceneSpec],
    gpu: &mut Headless,
    a: &Table3Bench,
    (w, h): (u32, u32),
) -> anyhow::Result<Option<Vec<Vec<u8>>>> {
    let mut images = Vec::new();
    for (k, spec) in specs.iter().enumerate() {
        let Ok(mut forest) = Forest::new(spec) else { return Ok(None) };
        // The last timed frame's camera: the path's end (its start when one frame is run).
        let last = if a.warmup + a.frames > 1 { forest.path_duration() } else { 0.0 };
        let camera = forest.camera_at(last);
        let mut frame = FrameData::with_rows(h);
        forest.frame(&camera, w as f32 / h as f32, &mut frame);
        if frame.stats.triangles as f64 > a.max_image_triangles {
            return Ok(None);
        }
        images.push(gpu.render(&frame, &camera)?);
        if k == 0 {
            let aside = quarter_pixel_aside(&camera, h);
            forest.frame(&aside, w as f32 / h as f32, &mut frame);
            images.push(gpu.render(&frame, &aside)?);
        }
    }
    Ok(Some(images))
}

/// What to read a scene's image error against: one frame of motion at full detail, the
/// geometry LOD alone with nothing moving, and sampling alone.
pub(super) struct Floor {
    pub(super) scene: String,
    /// Mean FLIP between two consecutive full-detail frames.
    pub(super) motion: Option<f64>,
    /// The geometry LOD's error and the sampling floor, rest pose ([`still_error`]).
    pub(super) still: Option<Still>,
    /// The thinning's error against every far tree drawn, and its sampling floor
    /// ([`thinning_error`]).
    pub(super) thinning: Option<Still>,
}

/// The lowest and highest of the rounds' CPU speed-ups (`off[r] / on[r]`, round by round);
/// `None` with fewer than two rounds.
pub(super) fn speed_up_range(on: &[f64], off: &[f64]) -> Option<(f64, f64)> {
    if on.len() < 2 || on.len() != off.len() {
        return None;
    }
    let ratios = on.iter().zip(off).map(|(a, b)| b / a);
    Some(ratios.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| (lo.min(r), hi.max(r))))
}

/// "A 0.123, B —": one figure per scene, a dash where there is none.
pub(super) fn per_scene(floors: &[Floor], figure: impl Fn(&Floor) -> Option<String>) -> String {
    floors
        .iter()
        .map(|f| format!("{} {}", f.scene, figure(f).unwrap_or_else(|| "—".into())))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Mean FLIP and SSIM as the Markdown writes them.
pub(super) fn flip_ssim((flip, ssim): (f64, f64)) -> String {
    format!("FLIP {flip:.3} / SSIM {ssim:.3}")
}
