//! Honami: gusts crossing a canopy, measured from the forest's own simulation. A stand of
//! aspens in the `strong` preset blowing along +x, each tree simulated on its own (the
//! wind-field LOD off); the trunk tops' displacement recorded at 30 Hz; then, for pairs of
//! trees one behind the other along the wind (at most 4 m apart across it), the
//! correlation of the upwind tree's record with the downwind one's a lag later.
//!
//!     cargo run --release -p sylva-forest --example honami -- [SECONDS] [PICTURE.png]
//!
//! With a picture path, also draws the gusts crossing the stand: a strip of canopy along
//! the wind through the stand's middle (50 m across), downwind to the right in 6 m columns,
//! time downwards at 10 Hz for the first 60 s, each column's trees' displacement downwind
//! (about its mean, in units of its spread, over a second's running mean that hides each
//! tree's own swing) lighter, upwind darker. A gust is a light streak whose slope is its
//! travel speed.
//!
//! Prints, per band of along-wind separation, the lag of the peak correlation and its
//! value; the travel speed fitted through them against the field's convection speed U_c;
//! and the zero-lag correlation against separation, whose first minimum marks half the
//! streamwise spacing of the gusts and its next maximum the spacing, against the mixing
//! layer's 8.1 Ū(h)/Ū′(h) (Raupach, Finnigan & Brunet 1996) at the canopy top h.

use anyhow::Result;
use sylva_forest::{Forest, SceneSpec, wind_field_over};

/// Simulation and record step, s.
const DT: f32 = 1.0 / 30.0;
/// Along-wind separation bands, m.
const BAND: f32 = 7.0;
const BANDS: usize = 10;
/// Longest lag searched, s.
const MAX_LAG: f32 = 15.0;

fn main() -> Result<()> {
    let seconds: f32 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(90.0);
    let spec = SceneSpec::from_toml(
        "honami.toml",
        "name = \"honami\"\nseed = 3\ntrees = 400\nspacing = 6.0\nterrain_amplitude = 0.0\n\
         wind = \"strong\"\nwind_direction_deg = 0.0\nscale_variation = 0.0\n\
         species = [{ name = \"quaking_aspen\" }]\n[lod]\nwind = false\n",
    )?;
    let mut forest = Forest::new(&spec)?;
    let params = wind_field_over(&spec, forest.radius, forest.stand())?.field.params;
    let u_c = params.convection_speed.unwrap_or(f64::NAN);
    // The canopy top the profile stands for, as the convection speed takes it
    // (`canopy_convection`: the canopy profile's h, or 1.5 d under a log law).
    let h = match params.profile {
        sylva_wind::Profile::Canopy { h, .. } => h,
        sylva_wind::Profile::Log { d, .. } => 1.5 * d,
        _ => forest.canopy_height() as f64,
    };
    let n = forest.trees();
    // Warm up 10 s, then record.
    for _ in 0..(10.0 / DT) as usize {
        forest.step(DT);
    }
    let frames = (seconds / DT) as usize;
    let mut rec = vec![vec![0.0f32; frames]; n];
    for f in 0..frames {
        forest.step(DT);
        for (t, r) in rec.iter_mut().enumerate() {
            r[f] = forest.trunk_top_displacement(t).unwrap_or(0.0);
        }
    }
    // Fluctuations about each tree's mean, scaled to unit variance.
    for r in rec.iter_mut() {
        let m = r.iter().sum::<f32>() / frames as f32;
        let v = r.iter().map(|x| (x - m) * (x - m)).sum::<f32>() / frames as f32;
        let s = v.sqrt().max(1e-9);
        r.iter_mut().for_each(|x| *x = (*x - m) / s);
    }
    let pos: Vec<[f32; 3]> = (0..n).map(|t| forest.placement(t).expect("tree").position).collect();
    if let Some(path) = std::env::args().nth(2) {
        strip_picture(&path, &pos, &rec)?;
    }
    let lags = (MAX_LAG / DT) as usize;
    let mut sum = vec![vec![0.0f64; lags + 1]; BANDS];
    let (mut pairs, mut sep) = (vec![0usize; BANDS], vec![0.0f64; BANDS]);
    for a in 0..n {
        for b in 0..n {
            let (ds, dn) = (pos[b][0] - pos[a][0], (pos[b][1] - pos[a][1]).abs());
            if ds <= 0.0 || dn > 4.0 {
                continue;
            }
            let k = (ds / BAND) as usize;
            if k >= BANDS {
                continue;
            }
            pairs[k] += 1;
            sep[k] += ds as f64;
            for (lag, s) in sum[k].iter_mut().enumerate() {
                let m = frames - lag;
                let c: f32 = (0..m).map(|i| rec[a][i] * rec[b][i + lag]).sum();
                *s += (c / m as f32) as f64;
            }
        }
    }
    println!(
        "U_c {u_c:.2} m/s; canopy top h {h:.1} m (trees up to {:.1} m); {n} trees, {seconds} s at {:.0} Hz",
        forest.canopy_height(),
        1.0 / DT
    );
    let (mut sxx, mut sxy) = (0.0f64, 0.0f64);
    let mut zero_lag = Vec::new();
    for k in 0..BANDS {
        if pairs[k] == 0 {
            continue;
        }
        let ds = sep[k] / pairs[k] as f64;
        let r: Vec<f64> = sum[k].iter().map(|s| s / pairs[k] as f64).collect();
        let (peak, best) =
            r.iter().enumerate().fold((0, f64::MIN), |b, (i, &v)| if v > b.1 { (i, v) } else { b });
        let lag = peak as f64 * DT as f64;
        println!(
            "separation {ds:5.1} m ({:4} pairs): peak correlation {best:+.3} at lag {lag:5.2} s \
             (Δx / U_c = {:5.2} s); at lag 0 {:+.3}",
            pairs[k],
            ds / u_c,
            r[0]
        );
        zero_lag.push((ds, r[0]));
        if lag > 0.0 {
            sxx += ds * ds;
            sxy += ds * lag;
        }
    }
    let speed = sxx / sxy.max(1e-9);
    println!("travel speed fitted through the peaks: {speed:.2} m/s, {:.2} × U_c", speed / u_c);
    // The mixing layer's spacing from the profile's shear at h.
    let spacing = sylva_forest::canopy::mixing_layer_spacing(&params, h);
    // A train of gusts Λ apart correlates with itself at lag 0 as cos(2π d/Λ) decays: the
    // first minimum at Λ/2, the next maximum at Λ (each refined by a parabola through the
    // band and its neighbours).
    let vertex = |k: usize| {
        let (x0, x1, x2) = (zero_lag[k - 1].0, zero_lag[k].0, zero_lag[k + 1].0);
        let (y0, y1, y2) = (zero_lag[k - 1].1, zero_lag[k].1, zero_lag[k + 1].1);
        let d = (x0 - x1) * (x0 - x2) * (x1 - x2);
        let a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / d;
        let b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / d;
        if a.abs() > 1e-12 { (-b / (2.0 * a)).clamp(x0, x2) } else { x1 }
    };
    let inner = 1..zero_lag.len().saturating_sub(1);
    let low = inner.clone().find(|&k| {
        zero_lag[k].1 < 0.0
            && zero_lag[k].1 <= zero_lag[k - 1].1
            && zero_lag[k].1 <= zero_lag[k + 1].1
    });
    let high = low.and_then(|l| {
        inner.clone().find(|&k| {
            k > l && zero_lag[k].1 >= zero_lag[k - 1].1 && zero_lag[k].1 >= zero_lag[k + 1].1
        })
    });
    match low {
        Some(l) => println!(
            "streamwise spacing of the gusts: {:.1} m from the zero-lag correlation's first \
             minimum (at Λ/2), {} from its next maximum (at Λ); 8.1 Ū(h)/Ū′(h) = {spacing:.1} m",
            2.0 * vertex(l),
            high.map_or("none within the bands".to_string(), |k| format!("{:.1} m", vertex(k)))
        ),
        None => println!(
            "the zero-lag correlation has no minimum below zero within {:.0} m; \
             8.1 Ū(h)/Ū′(h) = {spacing:.1} m",
            BAND * BANDS as f32
        ),
    }
    Ok(())
}

/// Columns of the strip picture, m; its half-width across the wind, m; its time step, in
/// record frames (10 Hz); its length, s; pixels per column.
const COLUMN: f32 = 6.0;
const STRIP: f32 = 25.0;
const EVERY: usize = 3;
const PICTURE_SECONDS: f32 = 60.0;
const COLUMN_PX: usize = 8;
/// Running mean of the picture's records, frames (1 s).
const SMOOTH: usize = 30;

/// The strip of canopy over time (see the module's documentation) as an RGB PNG at `path`,
/// from the trees at `pos` and their normalised records `rec`.
fn strip_picture(path: &str, pos: &[[f32; 3]], rec: &[Vec<f32>]) -> Result<()> {
    let y_mid = pos.iter().map(|p| p[1]).sum::<f32>() / pos.len().max(1) as f32;
    let strip: Vec<usize> = (0..pos.len()).filter(|&t| (pos[t][1] - y_mid).abs() < STRIP).collect();
    let x0 = strip.iter().map(|&t| pos[t][0]).fold(f32::INFINITY, f32::min);
    let x1 = strip.iter().map(|&t| pos[t][0]).fold(f32::NEG_INFINITY, f32::max);
    anyhow::ensure!(x1 > x0, "no trees in the strip");
    let columns = ((x1 - x0) / COLUMN) as usize + 1;
    let frames = rec.first().map_or(0, Vec::len);
    let rows = (frames / EVERY).min((PICTURE_SECONDS / DT) as usize / EVERY);
    let (width, height) = (columns * COLUMN_PX, rows);
    // Per column and picture row: its trees' mean record, over the running mean.
    let mean_at = |c: usize, f: usize| {
        let members: Vec<usize> =
            strip.iter().copied().filter(|&t| ((pos[t][0] - x0) / COLUMN) as usize == c).collect();
        if members.is_empty() {
            return None;
        }
        let (a, b) = (f.saturating_sub(SMOOTH / 2), (f + SMOOTH / 2).min(frames));
        let sum: f32 = members.iter().map(|&t| rec[t][a..b].iter().sum::<f32>()).sum();
        Some(sum / (members.len() * (b - a)) as f32)
    };
    let mut rgb = vec![0u8; width * height * 3];
    for row in 0..rows {
        let values: Vec<Option<f32>> = (0..columns).map(|c| mean_at(c, row * EVERY)).collect();
        for c in 0..columns {
            // A column without trees takes its neighbours' mean.
            let v = values[c].or_else(|| {
                let near: Vec<f32> = [c.wrapping_sub(1), c + 1]
                    .iter()
                    .filter_map(|&k| values.get(k).copied().flatten())
                    .collect();
                (!near.is_empty()).then(|| near.iter().sum::<f32>() / near.len() as f32)
            });
            // Canopy green, lighter where the column bends downwind (a gust), darker where
            // it swings back.
            let light = 0.5 + 0.3 * v.unwrap_or(0.0).clamp(-1.5, 1.5);
            let colour = [60.0 + 150.0 * light, 110.0 + 140.0 * light, 40.0 + 80.0 * light];
            for x in c * COLUMN_PX..(c + 1) * COLUMN_PX {
                let i = (row * width + x) * 3;
                for k in 0..3 {
                    rgb[i + k] = colour[k].clamp(0.0, 255.0) as u8;
                }
            }
        }
    }
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut e = png::Encoder::new(file, width as u32, height as u32);
    e.set_color(png::ColorType::Rgb);
    e.set_depth(png::BitDepth::Eight);
    e.write_header()?.write_image_data(&rgb)?;
    println!(
        "wrote {path}: {columns} columns of {COLUMN} m (downwind to the right), {rows} rows of {:.1} s",
        EVERY as f32 * DT
    );
    Ok(())
}
