//! TurbSim binary full-field export (`.bts`), the layout OpenFAST's InflowWind reads.
//!
//! A `.bts` file is a vertical y–z plane swept by time: here the field's x = `x_index`
//! column of points, one row per height. Header (70 bytes, little-endian): i16 file id
//! (8 = periodic), i32 nz, ny, tower points (0), time steps; f32 dz, dy, dt, hub mean
//! speed, hub height, grid bottom; f32 slope and offset for u, v, w; i32 description length;
//! then the ASCII description, then per time step, per z, per y, the three components as
//! i16 with value = (count − offset)/slope. Needs evenly spaced y and heights.

use std::path::Path;

use crate::error::WindError;
use crate::field::WindField;
use crate::grid::Grid;

/// Check that the x = `x_index` plane of a field on `grid` can be written as `.bts`: call it
/// before synthesising, so a wrong column or uneven axes fail at once. Returns (dy, dz).
pub fn check_bts(grid: &Grid, x_index: usize) -> Result<(f64, f64), WindError> {
    if x_index >= grid.nx() {
        return Err(WindError::Export(format!(
            "--bts-x-index {x_index} is outside the grid (nx = {}, so 0 … {})",
            grid.nx(),
            grid.nx() - 1
        )));
    }
    if grid.nz() > i32::MAX as usize || grid.ny() > i32::MAX as usize {
        return Err(WindError::Export("the y–z plane is too large for TurbSim's i32 sizes".into()));
    }
    if grid.frames > i32::MAX as usize {
        return Err(WindError::Export("too many frames for TurbSim's i32 step count".into()));
    }
    let dy = Grid::regular_spacing(&grid.ys).ok_or_else(|| {
        WindError::Export("TurbSim needs evenly spaced y coordinates (see --ys)".into())
    })?;
    let dz = Grid::regular_spacing(&grid.zs).ok_or_else(|| {
        WindError::Export(format!("TurbSim needs evenly spaced heights (got {:?} m)", grid.zs))
    })?;
    Ok((dy, dz))
}

/// Write the x = `x_index` plane of `field` as TurbSim `.bts`.
pub fn write_bts(field: &WindField, x_index: usize, path: &Path) -> Result<(), WindError> {
    let g = &field.grid;
    let (dy, dz) = check_bts(g, x_index)?;
    let (nz, ny) = (g.nz(), g.ny());
    let at = |t: usize, c: usize, iz: usize, iy: usize| {
        field.data[field.index(t, c, iz, iy, x_index)] as f64
    };
    // Scale each component over ±32767 counts, as TurbSim does (count = slope·v + offset).
    let mut slope = [0.0f64; 3];
    let mut offset = [0.0f64; 3];
    for c in 0..3 {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for t in 0..g.frames {
            for iz in 0..nz {
                for iy in 0..ny {
                    lo = lo.min(at(t, c, iz, iy));
                    hi = hi.max(at(t, c, iz, iy));
                }
            }
        }
        let range = (hi - lo).max(1e-6);
        slope[c] = 65534.0 / range;
        offset[c] = -32767.0 - slope[c] * lo;
    }
    let hub = g.zs[nz / 2];
    let desc = format!(
        "Sylva wind field, seed {}, U* {} m/s, periodic loop of {} s",
        field.synth.seed,
        field.params.u_star,
        g.period()
    );
    let mut b = Vec::with_capacity(70 + desc.len() + g.frames * nz * ny * 6);
    b.extend_from_slice(&8i16.to_le_bytes());
    for v in [nz as i32, ny as i32, 0, g.frames as i32] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for v in [dz, dy, g.dt, field.params.mean_speed(hub), hub, g.zs[0]] {
        b.extend_from_slice(&(v as f32).to_le_bytes());
    }
    for c in 0..3 {
        b.extend_from_slice(&(slope[c] as f32).to_le_bytes());
        b.extend_from_slice(&(offset[c] as f32).to_le_bytes());
    }
    b.extend_from_slice(&(desc.len() as i32).to_le_bytes());
    b.extend_from_slice(desc.as_bytes());
    for t in 0..g.frames {
        for iz in 0..nz {
            for iy in 0..ny {
                for c in 0..3 {
                    // The f32 header values are what readers use: quantise with them.
                    let (s, o) = (slope[c] as f32 as f64, offset[c] as f32 as f64);
                    let q = (s * at(t, c, iz, iy) + o).round().clamp(-32768.0, 32767.0) as i16;
                    b.extend_from_slice(&q.to_le_bytes());
                }
            }
        }
    }
    super::atomic::write_atomic(path, &b).map_err(|e| WindError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::tests::small;

    /// An independent reader following the published layout.
    fn read(bytes: &[u8]) -> (Vec<i32>, Vec<f32>, Vec<[f64; 3]>) {
        let i32_at =
            |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let f32_at =
            |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let ints: Vec<i32> = (0..4).map(|k| i32_at(2 + 4 * k)).collect();
        let floats: Vec<f32> = (0..12).map(|k| f32_at(18 + 4 * k)).collect();
        let nchar = i32_at(66) as usize;
        let mut o = 70 + nchar;
        let mut vals = Vec::new();
        while o + 6 <= bytes.len() {
            let mut v = [0.0; 3];
            for (c, vc) in v.iter_mut().enumerate() {
                let q = i16::from_le_bytes([bytes[o + 2 * c], bytes[o + 2 * c + 1]]) as f64;
                *vc = (q - floats[7 + 2 * c] as f64) / floats[6 + 2 * c] as f64;
            }
            vals.push(v);
            o += 6;
        }
        (ints, floats, vals)
    }

    #[test]
    fn bts_holds_the_plane_within_its_quantisation() {
        let f = small();
        let dir = std::env::temp_dir().join(format!("sylva-bts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join("f.bts");
        write_bts(&f, 2, &p).expect("write");
        let bytes = std::fs::read(&p).expect("read");
        assert_eq!(i16::from_le_bytes([bytes[0], bytes[1]]), 8);
        let (ints, floats, vals) = read(&bytes);
        assert_eq!(ints, vec![2, 4, 0, 16]);
        assert_eq!(floats[0], 8.0); // dz
        assert_eq!(floats[1], 2.0); // dy
        assert_eq!(vals.len(), 16 * 2 * 4);
        let mut k = 0;
        for t in 0..16 {
            for iz in 0..2 {
                for iy in 0..4 {
                    for c in 0..3 {
                        let want = f.data[f.index(t, c, iz, iy, 2)] as f64;
                        let tol = 1.0 / floats[6 + 2 * c] as f64;
                        assert!((vals[k][c] - want).abs() <= tol, "t {t} z {iz} y {iy} c {c}");
                    }
                    k += 1;
                }
            }
        }
        assert!(write_bts(&f, 9, &p).is_err());
    }
}
