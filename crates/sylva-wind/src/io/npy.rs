//! NumPy `.npy` export (format 1.0, little-endian f32, C order) with a JSON sidecar.
//!
//! Shape (frames, 3, ny, nx) for one height, (frames, 3, nz, ny, nx) for several; velocities
//! in m/s in the wind frame, `u` including Ū(z). The sidecar (`same name.json`) holds every
//! number needed to recompute the model spectra and coherence without Sylva: U*, heights,
//! mean speeds, grid coordinates and spacings, dt, the Table-1/Table-2 constants, the
//! seed and method.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::WindError;
use crate::field::{Captured, WindField};
use crate::grid::Grid;
use crate::params::{CoherenceSpeed, WindParams};
use crate::synth::{self, SynthParams};

/// The JSON sidecar of an `.npy` export.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NpySidecar {
    /// Shape of the array.
    pub shape: Vec<usize>,
    /// Axis names, outermost first.
    pub axes: Vec<String>,
    /// Friction velocity U*, m/s.
    pub u_star: f64,
    /// Heights, m.
    pub heights: Vec<f64>,
    /// Ū at each height, m/s.
    pub mean_speeds: Vec<f64>,
    /// Which speed divides the separations in eq. 5: `"reference"` (one speed for every
    /// pair, `coherence_speed`) or `"pair-mean"` (the paper's (Ū_j + Ū_k)/2 of
    /// `mean_speeds`, per pair of heights).
    #[serde(default = "reference_model")]
    pub coherence_model: String,
    /// The one speed in eq. 5's denominator with the reference model, m/s; null with the
    /// pair mean.
    pub coherence_speed: Option<f64>,
    /// Taylor advection: gusts at every height travel at `advection_speed` (m/s), with
    /// phase origin at x = `advection_origin_x` (m); both null when advection is off.
    #[serde(default)]
    pub advection_origin_x: Option<f64>,
    /// The convection speed U_c every height advects at, m/s; null when advection is off.
    #[serde(default)]
    pub advection_speed: Option<f64>,
    /// Bound on the synthesised coherence's departure from the model (0 when exact).
    #[serde(default)]
    pub coherence_error: f64,
    /// Regular spacing along x and y in m (null where uneven; see `grid`).
    pub spacing: [Option<f64>; 2],
    /// Time step, s.
    pub dt: f64,
    /// Full grid (coordinates of every axis).
    pub grid: Grid,
    /// Full model parameters, spectrum and coherence constants included.
    pub params: WindParams,
    /// Seed and method.
    pub synth: SynthParams,
    /// Variance captured by the loop.
    pub captured: Captured,
    /// CRC-32 (IEEE) of the `.npy` file's data bytes (after its header), so a reader can
    /// detect corruption; `.npy` itself carries no checksum.
    pub data_crc32: u32,
    /// CRC-32 (IEEE) of this sidecar itself: of its compact JSON (`serde_json`'s, fields in
    /// this order) with this field 0, so an edited grid, time step or parameter is refused
    /// rather than trusted ([`NpySidecar::checksum`]).
    pub sidecar_crc32: u32,
}

impl NpySidecar {
    /// The CRC-32 [`NpySidecar::sidecar_crc32`] holds for this sidecar's other fields.
    pub fn checksum(&self) -> Result<u32, WindError> {
        super::json_crc32(&NpySidecar { sidecar_crc32: 0, ..self.clone() })
    }

    /// Check the fields that repeat the grid and parameters for readers without Sylva
    /// (shape, heights, mean speeds, spacing, `dt`) against them: the checksum covers the
    /// text, this its sense.
    fn check_consistent(&self, name: &str) -> Result<(), WindError> {
        let g = &self.grid;
        let bad = |field: &str, what: String| {
            Err(WindError::format(0, format!("{name}: `{field}` {what}")))
        };
        if self.shape != npy_shape(g) {
            return bad("shape", format!("{:?} is not the grid's {:?}", self.shape, npy_shape(g)));
        }
        if self.heights != g.zs {
            return bad("heights", format!("{:?} are not the grid's {:?}", self.heights, g.zs));
        }
        if self.dt != g.dt {
            return bad("dt", format!("{} is not the grid's {}", self.dt, g.dt));
        }
        let spacing = [Grid::regular_spacing(&g.xs), Grid::regular_spacing(&g.ys)];
        if self.spacing != spacing {
            return bad("spacing", format!("{:?} is not the grid's {spacing:?}", self.spacing));
        }
        if self.u_star != self.params.u_star {
            return bad(
                "u_star",
                format!("{} is not the parameters' {}", self.u_star, self.params.u_star),
            );
        }
        let means: Vec<f64> = g.zs.iter().map(|&z| self.params.mean_speed(z)).collect();
        if self.mean_speeds.len() != means.len()
            || self
                .mean_speeds
                .iter()
                .zip(&means)
                .any(|(a, b)| (a - b).abs() > 1e-9 * b.abs().max(1.0))
        {
            return bad(
                "mean_speeds",
                format!("{:?} are not the model's {means:?}", self.mean_speeds),
            );
        }
        Ok(())
    }
}

/// The array's shape for `g`: (frames, 3, ny, nx) for one height, with nz after the
/// component for several.
fn npy_shape(g: &Grid) -> Vec<usize> {
    if g.nz() == 1 {
        vec![g.frames, 3, g.ny(), g.nx()]
    } else {
        vec![g.frames, 3, g.nz(), g.ny(), g.nx()]
    }
}

/// The `shape` tuple of an `.npy` header dictionary, as numbers; `None` if it has none that
/// parses.
fn header_shape(dict: &str) -> Option<Vec<usize>> {
    let rest = &dict[dict.find("'shape':")? + "'shape':".len()..];
    let open = rest.find('(')?;
    let close = rest.find(')')?;
    if close < open {
        return None;
    }
    rest[open + 1..close]
        .split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| t.parse().ok())
        .collect()
}

fn reference_model() -> String {
    "reference".into()
}

fn sidecar_path(path: &Path) -> PathBuf {
    path.with_extension("json")
}

/// Write `field` to `path` (`.npy`) and its sidecar next to it (`.json`).
///
/// The array and its sidecar are written under one lock ([`super::atomic::lock_beside`]):
/// two writers of the same path leave one of their pairs, never a mix.
pub fn write_npy(field: &WindField, path: &Path) -> Result<(), WindError> {
    crate::field::check_samples(field)?;
    let _pair = super::atomic::lock_beside(path).map_err(|e| WindError::io(path, e))?;
    let g = &field.grid;
    let shape = npy_shape(g);
    let axes = if g.nz() == 1 {
        vec!["frame", "component", "y", "x"]
    } else {
        vec!["frame", "component", "z", "y", "x"]
    };
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let mut dict =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({},), }}", dims.join(", "));
    // Pad so that magic(6) + version(2) + len(2) + dict + '\n' is a multiple of 64.
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    // Streamed in blocks through a temporary file: the peak memory is the field plus one
    // block, not a second copy, and the previous file stays whole until this one is.
    let mut w = super::atomic::AtomicFile::create(path).map_err(|e| WindError::io(path, e))?;
    let mut crc = crc32fast::Hasher::new();
    let io = |e| WindError::io(path, e);
    w.write_all(b"\x93NUMPY\x01\x00").map_err(io)?;
    w.write_all(&(dict.len() as u16).to_le_bytes()).map_err(io)?;
    w.write_all(dict.as_bytes()).map_err(io)?;
    let mut block = Vec::with_capacity(4 << 16);
    for chunk in field.data.chunks(1 << 16) {
        block.clear();
        for v in chunk {
            block.extend_from_slice(&v.to_le_bytes());
        }
        crc.update(&block);
        w.write_all(&block).map_err(io)?;
    }
    w.commit().map_err(io)?;
    let data_crc32 = crc.finalize();
    let mut side = NpySidecar {
        shape,
        axes: axes.into_iter().map(String::from).collect(),
        u_star: field.params.u_star,
        heights: g.zs.clone(),
        mean_speeds: g.zs.iter().map(|&z| field.params.mean_speed(z)).collect(),
        coherence_model: field.params.coherence_speed.name().into(),
        coherence_speed: (field.params.coherence_speed == CoherenceSpeed::Reference)
            .then(|| synth::reference_speed(&field.params, g)),
        advection_origin_x: field.params.advection.then(|| g.x_mid()),
        advection_speed: field.params.advection.then(|| synth::convection_speed(&field.params, g)),
        coherence_error: field.coherence_error,
        spacing: [Grid::regular_spacing(&g.xs), Grid::regular_spacing(&g.ys)],
        dt: g.dt,
        grid: g.clone(),
        params: field.params.clone(),
        synth: field.synth,
        captured: field.captured(),
        data_crc32,
        sidecar_crc32: 0,
    };
    side.sidecar_crc32 = side.checksum()?;
    let sp = sidecar_path(path);
    let json = serde_json::to_string_pretty(&side).map_err(|e| WindError::Export(e.to_string()))?;
    // Written after the array: an interruption between the two leaves the previous sidecar,
    // whose checksum then refuses the new array instead of misreading it.
    super::atomic::write_atomic(&sp, json.as_bytes()).map_err(|e| WindError::io(&sp, e))
}

/// Read an `.npy` written by [`write_npy`] together with its sidecar.
pub fn read_npy(path: &Path) -> Result<WindField, WindError> {
    let bytes = std::fs::read(path).map_err(|e| WindError::io(path, e))?;
    let sp = sidecar_path(path);
    let side_text = std::fs::read_to_string(&sp).map_err(|e| WindError::io(&sp, e))?;
    parse_npy(&bytes, &side_text, &sp.display().to_string())
}

/// Parse an `.npy` array and the text of its sidecar (named `sidecar_name` in errors).
pub fn parse_npy(
    bytes: &[u8],
    side_text: &str,
    sidecar_name: &str,
) -> Result<WindField, WindError> {
    let side: NpySidecar = serde_json::from_str(side_text).map_err(|e| WindError::Format {
        offset: 0,
        reason: format!("{sidecar_name}: line {}: {e}", e.line()),
    })?;
    let crc = side.checksum()?;
    if crc != side.sidecar_crc32 {
        return Err(WindError::format(
            0,
            format!(
                "{sidecar_name}: sidecar checksum {crc:08x} differs from its `sidecar_crc32` \
                 {:08x}: the sidecar was edited or is corrupt",
                side.sidecar_crc32
            ),
        ));
    }
    side.grid.validate().map_err(|e| WindError::format(0, format!("{sidecar_name}: {e}")))?;
    side.params.validate().map_err(|e| WindError::format(0, format!("{sidecar_name}: {e}")))?;
    side.check_consistent(sidecar_name)?;
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(WindError::format(0, "not a .npy file (bad magic)"));
    }
    if bytes[6] != 1 {
        return Err(WindError::format(
            6,
            format!("npy version {}.{} is not supported (1.0 is)", bytes[6], bytes[7]),
        ));
    }
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let start = 10 + hlen;
    if bytes.len() < start {
        return Err(WindError::format(bytes.len() as u64, "file ends inside the npy header"));
    }
    let dict = String::from_utf8_lossy(&bytes[10..start]);
    if !dict.contains("'<f4'") || dict.contains("'fortran_order': True") {
        return Err(WindError::format(10, "array is not little-endian f32 in C order"));
    }
    match header_shape(&dict) {
        Some(shape) if shape == side.shape => {}
        Some(shape) => {
            return Err(WindError::format(
                10,
                format!("the npy header's shape {shape:?} is not the sidecar's {:?}", side.shape),
            ));
        }
        None => return Err(WindError::format(10, "the npy header has no shape that parses")),
    }
    let count = side.grid.points() * 3 * side.grid.frames;
    let need = start + 4 * count;
    if bytes.len() != need {
        return Err(WindError::format(
            bytes.len().min(need) as u64,
            format!(
                "data holds {} bytes, the sidecar's grid needs {}",
                bytes.len() - start,
                4 * count
            ),
        ));
    }
    let crc = crc32fast::hash(&bytes[start..]);
    if crc != side.data_crc32 {
        return Err(WindError::format(
            start as u64,
            format!(
                "data checksum {crc:08x} differs from the sidecar's {:08x}: the file is corrupt",
                side.data_crc32
            ),
        ));
    }
    let data = bytes[start..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let field = WindField {
        grid: side.grid,
        params: side.params,
        synth: side.synth,
        data,
        coherence_error: side.coherence_error,
    };
    crate::field::check_samples(&field)?;
    Ok(field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::tests::small;

    #[test]
    fn npy_round_trip_is_exact_and_truncation_is_refused() {
        let f = small();
        let dir = sylva_testkit::TempDir::new("sylva-npy");
        let p = dir.join("f.npy");
        write_npy(&f, &p).expect("write");
        let bytes = std::fs::read(&p).expect("read");
        assert_eq!((10 + u16::from_le_bytes([bytes[8], bytes[9]]) as usize) % 64, 0);
        let g = read_npy(&p).expect("read back");
        assert_eq!(g, f);
        let side = std::fs::read_to_string(p.with_extension("json")).expect("sidecar");
        assert!(side.contains("\"u_star\"") && side.contains("\"mean_speeds\""));
        std::fs::write(&p, &bytes[..bytes.len() - 3]).expect("truncate");
        assert!(read_npy(&p).expect_err("truncated").to_string().contains("needs"));
        let mut flipped = bytes.clone();
        let last = flipped.len() - 1;
        flipped[last] ^= 0x01;
        std::fs::write(&p, &flipped).expect("flip");
        assert!(read_npy(&p).expect_err("bit flip").to_string().contains("checksum"));
        let mut v2 = bytes;
        v2[6] = 2;
        std::fs::write(&p, &v2).expect("version");
        assert!(read_npy(&p).expect_err("version 2").to_string().contains("version 2"));
    }
}
