//! TurbSim binary full-field export (`.bts`), the layout OpenFAST's InflowWind reads.
//!
//! A `.bts` file is a vertical y–z plane swept by time: here the field's x = `x_index`
//! column of points, one row per height. Header (70 bytes, little-endian): i16 file id
//! (8 = periodic), i32 nz, ny, tower points (0), time steps; f32 dz, dy, dt, hub mean
//! speed, hub height, grid bottom; f32 slope and offset for u, v, w; i32 description length;
//! then the ASCII description, then per time step, per z, per y, the three components as
//! i16 with value = (count − offset)/slope; after each step's grid come its tower points
//! (none here). Needs evenly spaced y and heights.
//!
//! [`parse_bts`] reads any such file, TurbSim's own included (file id 7 or 8, with or
//! without tower points), and names the byte of the first fault.

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
    crate::field::check_samples(field)?;
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

/// Size of the fixed `.bts` header before the description, bytes.
const BTS_HEADER: usize = 70;

/// A TurbSim full-field plane as read from `.bts`: a y–z grid of points swept by time,
/// plus optional tower points below it.
#[derive(Debug, Clone, PartialEq)]
pub struct BtsField {
    /// File id 8: the field loops (periodic); 7: it does not.
    pub periodic: bool,
    /// Heights in the grid.
    pub nz: usize,
    /// Points across the wind.
    pub ny: usize,
    /// Tower points below the grid.
    pub tower_points: usize,
    /// Time steps.
    pub frames: usize,
    /// Vertical spacing, m.
    pub dz: f32,
    /// Lateral spacing, m.
    pub dy: f32,
    /// Time step, s.
    pub dt: f32,
    /// Mean speed at hub height, m/s.
    pub hub_speed: f32,
    /// Hub height, m.
    pub hub_height: f32,
    /// Height of the lowest grid row, m.
    pub z_bottom: f32,
    /// The file's free-text description.
    pub description: String,
    /// Grid velocities, m/s, layout (frame, z, y, component).
    pub grid: Vec<f32>,
    /// Tower velocities, m/s, layout (frame, tower point, component).
    pub tower: Vec<f32>,
}

impl BtsField {
    /// Velocity component `c` (0 = u, 1 = v, 2 = w) at step `t`, height row `iz`, column `iy`.
    pub fn at(&self, t: usize, c: usize, iz: usize, iy: usize) -> f32 {
        self.grid[((t * self.nz + iz) * self.ny + iy) * 3 + c]
    }

    /// Heights of the grid rows, m.
    pub fn zs(&self) -> Vec<f64> {
        (0..self.nz).map(|k| self.z_bottom as f64 + k as f64 * self.dz as f64).collect()
    }

    /// Lateral positions of the columns, m, centred on zero as TurbSim's grid is.
    pub fn ys(&self) -> Vec<f64> {
        let half = (self.ny as f64 - 1.0) / 2.0;
        (0..self.ny).map(|k| (k as f64 - half) * self.dy as f64).collect()
    }
}

/// Read a TurbSim `.bts` file.
pub fn read_bts(path: &Path) -> Result<BtsField, WindError> {
    super::regular(path, false)?;
    let bytes = std::fs::read(path).map_err(|e| WindError::io(path, e))?;
    parse_bts(&bytes)
}

/// Parse the bytes of a TurbSim `.bts` file; every size is checked against the file's
/// length before anything is allocated. (About 120 lines: the header's fields in file
/// order, each checked where it is read.)
pub fn parse_bts(bytes: &[u8]) -> Result<BtsField, WindError> {
    if bytes.len() < BTS_HEADER {
        return Err(WindError::format(
            bytes.len() as u64,
            format!("file ends inside the {BTS_HEADER}-byte .bts header"),
        ));
    }
    let i32_at =
        |o: usize| i32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let f32_at =
        |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let periodic = match i16::from_le_bytes([bytes[0], bytes[1]]) {
        7 => false,
        8 => true,
        id => {
            return Err(WindError::format(
                0,
                format!("file id {id}: not a TurbSim .bts file (7 or 8 expected)"),
            ));
        }
    };
    let count = |o: usize, name: &str, min: i32| -> Result<usize, WindError> {
        let v = i32_at(o);
        if v < min {
            return Err(WindError::format(
                o as u64,
                format!("{name} = {v}: at least {min} expected"),
            ));
        }
        Ok(v as usize)
    };
    let nz = count(2, "nz", 1)?;
    let ny = count(6, "ny", 1)?;
    let tower_points = count(10, "tower points", 0)?;
    let frames = count(14, "time steps", 1)?;
    let names = ["dz", "dy", "dt", "hub speed", "hub height", "grid bottom"];
    let mut h = [0.0f32; 6];
    for (k, v) in h.iter_mut().enumerate() {
        *v = f32_at(18 + 4 * k);
        let positive = k <= 2;
        if !v.is_finite() || (positive && *v <= 0.0) {
            let want = if positive { "a finite value > 0" } else { "a finite value" };
            return Err(WindError::format(
                (18 + 4 * k) as u64,
                format!("{} = {v}: {want} expected", names[k]),
            ));
        }
    }
    let mut slope = [0.0f64; 3];
    let mut offset = [0.0f64; 3];
    for c in 0..3 {
        let (so, oo) = (42 + 8 * c, 46 + 8 * c);
        let (s, o) = (f32_at(so), f32_at(oo));
        if !s.is_finite() || s == 0.0 {
            return Err(WindError::format(
                so as u64,
                format!("slope of component {c} = {s}: a finite non-zero value expected"),
            ));
        }
        if !o.is_finite() {
            return Err(WindError::format(
                oo as u64,
                format!("offset of component {c} = {o}: a finite value expected"),
            ));
        }
        // Every count must map to a finite f32 velocity.
        let reach = (32768.0 + (o as f64).abs()) / (s as f64).abs();
        if reach >= f32::MAX as f64 {
            return Err(WindError::format(
                so as u64,
                format!("slope of component {c} = {s:e} maps counts beyond the range of f32"),
            ));
        }
        (slope[c], offset[c]) = (s as f64, o as f64);
    }
    let nchar = count(66, "description length", 0)?;
    let data_start =
        BTS_HEADER.checked_add(nchar).filter(|&e| e <= bytes.len()).ok_or_else(|| {
            WindError::format(
                66,
                format!("description of {nchar} bytes runs past the end of the file"),
            )
        })?;
    let description = String::from_utf8_lossy(&bytes[BTS_HEADER..data_start]).into_owned();
    let need = (nz as u128 * ny as u128 + tower_points as u128) * frames as u128 * 6;
    let have = (bytes.len() - data_start) as u128;
    if need != have {
        return Err(WindError::format(
            // The first byte missing or in excess.
            (data_start as u128 + need.min(have)) as u64,
            format!(
                "data holds {have} bytes; {frames} steps of {nz}×{ny} grid and {tower_points} \
                 tower points need {need}"
            ),
        ));
    }
    let per_step = nz * ny + tower_points;
    let mut grid = Vec::with_capacity(frames * nz * ny * 3);
    let mut tower = Vec::with_capacity(frames * tower_points * 3);
    for (k, q) in bytes[data_start..].chunks_exact(6).enumerate() {
        let out = if k % per_step < nz * ny { &mut grid } else { &mut tower };
        for c in 0..3 {
            let count = i16::from_le_bytes([q[2 * c], q[2 * c + 1]]) as f64;
            out.push(((count - offset[c]) / slope[c]) as f32);
        }
    }
    Ok(BtsField {
        periodic,
        nz,
        ny,
        tower_points,
        frames,
        dz: h[0],
        dy: h[1],
        dt: h[2],
        hub_speed: h[3],
        hub_height: h[4],
        z_bottom: h[5],
        description,
        grid,
        tower,
    })
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
        let dir = sylva_testkit::TempDir::new("sylva-bts");
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

        // The library's reader agrees with the independent one, value for value.
        let b = parse_bts(&bytes).expect("parse");
        assert!(b.periodic);
        assert_eq!((b.nz, b.ny, b.tower_points, b.frames), (2, 4, 0, 16));
        assert_eq!(b.zs(), f.grid.zs);
        assert_eq!(b.ys(), vec![-3.0, -1.0, 1.0, 3.0]);
        assert!(b.description.contains("seed"));
        let mut k = 0;
        for t in 0..16 {
            for iz in 0..2 {
                for iy in 0..4 {
                    for c in 0..3 {
                        assert_eq!(b.at(t, c, iz, iy), vals[k][c] as f32);
                    }
                    k += 1;
                }
            }
        }
    }

    /// A file in TurbSim's own layout with tower points, built by hand: the tower's values
    /// follow each step's grid.
    #[test]
    fn tower_points_and_non_periodic_files_are_read() {
        let mut b = Vec::new();
        b.extend_from_slice(&7i16.to_le_bytes());
        for v in [1i32, 2, 1, 2] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [5.0f32, 4.0, 0.05, 10.0, 90.0, 80.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for _ in 0..3 {
            b.extend_from_slice(&100.0f32.to_le_bytes()); // slope: 100 counts per m/s
            b.extend_from_slice(&0.0f32.to_le_bytes());
        }
        b.extend_from_slice(&0i32.to_le_bytes());
        // Two steps, each: grid (z 0: y 0, y 1), then one tower point.
        for t in 0..2i16 {
            for p in 0..3i16 {
                for c in 0..3i16 {
                    b.extend_from_slice(&(1000 * t + 100 * p + c).to_le_bytes());
                }
            }
        }
        let f = parse_bts(&b).expect("parse");
        assert!(!f.periodic);
        assert_eq!((f.grid.len(), f.tower.len()), (2 * 2 * 3, 2 * 3));
        assert_eq!(f.at(1, 2, 0, 1), 11.02); // step 1, point 1, w: count 1102 / 100
        assert_eq!(f.tower[3], 12.0); // step 1's tower point, u: count 1200 / 100
        assert_eq!(f.zs(), vec![80.0]);
    }

    #[test]
    fn damaged_headers_are_refused_naming_the_byte() {
        let f = small();
        let dir = sylva_testkit::TempDir::new("sylva-bts2");
        let p = dir.join("f.bts");
        write_bts(&f, 0, &p).expect("write");
        let good = std::fs::read(&p).expect("read");
        let err = |b: &[u8]| parse_bts(b).expect_err("damaged").to_string();
        assert!(err(&good[..40]).contains("byte 40"));
        let mut b = good.clone();
        b[0] = 3;
        assert!(err(&b).contains("file id 3"));
        let mut b = good.clone();
        b[2..6].copy_from_slice(&(-1i32).to_le_bytes());
        assert!(err(&b).contains("byte 2") && err(&b).contains("nz = -1"));
        let mut b = good.clone();
        b[26..30].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(err(&b).contains("dt = NaN"));
        let mut b = good.clone();
        b[42..46].copy_from_slice(&0.0f32.to_le_bytes());
        assert!(err(&b).contains("slope of component 0"));
        // A subnormal slope would turn counts into infinite velocities (found by fuzz/run).
        b[42..46].copy_from_slice(&1e-40f32.to_le_bytes());
        assert!(err(&b).contains("beyond the range"));
        let mut b = good.clone();
        b[66..70].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(err(&b).contains("past the end"));
        // A grid far larger than the file is refused before allocating.
        let mut b = good.clone();
        b[6..10].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(err(&b).contains("need"));
        assert!(err(&good[..good.len() - 1]).contains("need"));
        // Sizes whose product overflows 64 bits (found by fuzz/run bts) are refused too.
        let mut b = good.clone();
        for o in [2, 6, 14] {
            b[o..o + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        }
        assert!(err(&b).contains("need"));
    }
}
