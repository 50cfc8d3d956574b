//! Wind-field files: our compact `.swf` format, NumPy `.npy` with a JSON sidecar, and
//! TurbSim's binary full-field `.bts`.
//!
//! `.swf` (Sylva wind field), little-endian:
//!
//! | bytes | content |
//! |---|---|
//! | 0–7 | magic `SYLVAWND` |
//! | 8–11 | format version, u32 (= [`SWF_VERSION`]) |
//! | 12–15 | header length H, u32 |
//! | 16 … 16+H | header, UTF-8 JSON: grid, parameters, seed, method, per-component scale and offset |
//! | … | samples, i16, layout (frame, component, z, y, x) |
//! | last 4 | CRC-32 (IEEE) of every byte before it |
//!
//! Each component is quantised as v ≈ offset + scale·q with q ∈ [−32767, 32767] spanning its
//! min…max, so the quantisation error is at most scale/2 (reported in the header as
//! `max_error`; about 1/65534 of the component's range, e.g. 0.4 mm/s on a 25 m/s range).
//! Reading checks magic, version, sizes and checksum and names the byte offset of a fault.

pub mod atomic;
mod bts;
mod npy;
pub mod zarr;

pub use bts::{BtsField, check_bts, parse_bts, read_bts, write_bts};
pub use npy::{NpySidecar, parse_npy, read_npy, write_npy};
pub use zarr::{read_zarr, write_zarr_streaming};

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::WindError;
use crate::field::WindField;
use crate::grid::Grid;
use crate::params::WindParams;
use crate::synth::SynthParams;

/// Read a wind field by its file's extension: `.npy` (with its sidecar), `.zarr`, else
/// `.swf`. (A `.bts` holds one plane without the model: read it with [`read_bts`].)
///
/// Whatever the format, what is read is checked ([`crate::field::check_samples`]): finite
/// samples within physical bounds. A path that is not a regular file (a `.zarr` store: not
/// a folder) is refused before anything is read, so a FIFO or a device never blocks.
pub fn read_field(path: &Path) -> Result<WindField, WindError> {
    let zarr = path.extension().and_then(|e| e.to_str()) == Some("zarr");
    regular(path, zarr)?;
    // Each reader checks the samples it returns.
    match path.extension().and_then(|e| e.to_str()) {
        Some("npy") => read_npy(path),
        Some("zarr") => read_zarr(path),
        _ => read_swf(path),
    }
}

/// Refuse `path` unless it is a regular file (a folder where `folder`).
pub(crate) fn regular(path: &Path, folder: bool) -> Result<(), WindError> {
    let meta = std::fs::metadata(path).map_err(|e| WindError::io(path, e))?;
    let ok = if folder { meta.is_dir() } else { meta.is_file() };
    if ok {
        return Ok(());
    }
    let what = if folder { "a folder (a Zarr store)" } else { "a regular file" };
    Err(WindError::io(path, std::io::Error::other(format!("not {what}"))))
}

/// The CRC-32 (IEEE) of `value`'s compact JSON (`serde_json`'s, fields in declaration
/// order): what a sidecar or a store's attributes hold of themselves, computed with their
/// own checksum field set to 0.
pub(crate) fn json_crc32(value: &impl Serialize) -> Result<u32, WindError> {
    let text = serde_json::to_string(value).map_err(|e| WindError::Export(e.to_string()))?;
    Ok(crc32fast::hash(text.as_bytes()))
}

/// Magic bytes of an `.swf` file.
pub const SWF_MAGIC: &[u8; 8] = b"SYLVAWND";
/// Current `.swf` format version.
pub const SWF_VERSION: u32 = 1;
/// Largest header accepted, bytes.
const MAX_HEADER: u32 = 64 << 20;

/// The JSON header of an `.swf` file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SwfHeader {
    /// Grid and time axis.
    pub grid: Grid,
    /// Model parameters.
    pub params: WindParams,
    /// Seed and method.
    pub synth: SynthParams,
    /// Quantisation step per component (m/s per count).
    pub scale: [f64; 3],
    /// Quantisation offset per component (m/s).
    pub offset: [f64; 3],
    /// Largest quantisation error per component, scale/2 (m/s).
    pub max_error: [f64; 3],
    /// Bound on the synthesised coherence's departure from the model
    /// ([`WindField::coherence_error`]); absent in files from before it was recorded.
    #[serde(default)]
    pub coherence_error: f64,
}

/// The header's quantisation, range-checked (a header edited with its checksum recomputed
/// would otherwise be taken on trust): per component a step of more than 0 and at most
/// 0.01 m/s a count (a writer's step spans a component's range over 65 534 counts, so
/// 0.01 m/s would already be a range of 655 m/s), an offset within ±100 m/s (the mean
/// wind's bound), and the largest error half the step.
fn check_quantisation(h: &SwfHeader) -> Result<(), WindError> {
    for c in 0..3 {
        let (scale, offset, err) = (h.scale[c], h.offset[c], h.max_error[c]);
        if !(scale > 0.0 && scale <= 0.01) {
            return Err(WindError::format(
                16,
                format!("header: scale[{c}] = {scale}: expected > 0 … 0.01 m/s a count"),
            ));
        }
        if offset.is_nan() || offset.abs() > crate::field::MAX_MEAN_SPEED {
            return Err(WindError::format(
                16,
                format!("header: offset[{c}] = {offset}: expected within ±100 m/s"),
            ));
        }
        let off = (err - 0.5 * scale).abs();
        if off.is_nan() || off > 1e-9 * scale.max(1e-12) + 1e-15 {
            return Err(WindError::format(
                16,
                format!("header: max_error[{c}] = {err}: expected half the scale, {}", 0.5 * scale),
            ));
        }
    }
    Ok(())
}

/// Per-component (offset, scale) spanning min…max over ±32767 counts.
pub(crate) fn quantisation(field: &WindField, levels: f64) -> ([f64; 3], [f64; 3]) {
    let n = field.grid.points();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (i, v) in field.data.iter().enumerate() {
        let c = (i / n) % 3;
        lo[c] = lo[c].min(*v as f64);
        hi[c] = hi[c].max(*v as f64);
    }
    let mut offset = [0.0; 3];
    let mut scale = [0.0; 3];
    for c in 0..3 {
        offset[c] = 0.5 * (lo[c] + hi[c]);
        scale[c] = ((hi[c] - lo[c]) / levels).max(1e-9);
    }
    (offset, scale)
}

/// Write `field` as `.swf`.
pub fn write_swf(field: &WindField, path: &Path) -> Result<(), WindError> {
    crate::field::check_samples(field)?;
    let (offset, scale) = quantisation(field, 65534.0);
    let header = SwfHeader {
        grid: field.grid.clone(),
        params: field.params.clone(),
        synth: field.synth,
        scale,
        offset,
        max_error: scale.map(|s| 0.5 * s),
        coherence_error: field.coherence_error,
    };
    let json = serde_json::to_vec(&header).map_err(|e| WindError::Export(e.to_string()))?;
    let n = field.grid.points();
    // Streamed in blocks through a temporary file: peak memory one block, and the previous
    // file stays whole until the new one is complete.
    let io = |e| WindError::io(path, e);
    let mut f = atomic::AtomicFile::create(path).map_err(io)?;
    let mut crc = crc32fast::Hasher::new();
    let mut head = Vec::with_capacity(16 + json.len());
    head.extend_from_slice(SWF_MAGIC);
    head.extend_from_slice(&SWF_VERSION.to_le_bytes());
    head.extend_from_slice(&(json.len() as u32).to_le_bytes());
    head.extend_from_slice(&json);
    crc.update(&head);
    f.write_all(&head).map_err(io)?;
    let mut block = Vec::with_capacity(2 << 16);
    for (k, chunk) in field.data.chunks(1 << 16).enumerate() {
        block.clear();
        for (i, v) in chunk.iter().enumerate() {
            let c = ((k << 16) + i) / n % 3;
            let x = ((*v as f64 - offset[c]) / scale[c]).clamp(-32767.0, 32767.0);
            // Round half away from zero without a libm call (`as` truncates toward zero).
            let q = (x + 0.5f64.copysign(x)) as i16;
            block.extend_from_slice(&q.to_le_bytes());
        }
        crc.update(&block);
        f.write_all(&block).map_err(io)?;
    }
    f.write_all(&crc.finalize().to_le_bytes()).map_err(io)?;
    f.commit().map_err(io)
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

/// Read an `.swf` file.
pub fn read_swf(path: &Path) -> Result<WindField, WindError> {
    let bytes = std::fs::read(path).map_err(|e| WindError::io(path, e))?;
    parse_swf(&bytes)
}

/// Parse the bytes of an `.swf` file.
pub fn parse_swf(bytes: &[u8]) -> Result<WindField, WindError> {
    if bytes.len() < 16 {
        return Err(WindError::format(bytes.len() as u64, "file ends inside the 16-byte preamble"));
    }
    if &bytes[..8] != SWF_MAGIC {
        return Err(WindError::format(0, "not a Sylva wind file (magic is not SYLVAWND)"));
    }
    let version = u32_at(bytes, 8);
    if version != SWF_VERSION {
        return Err(WindError::format(
            8,
            format!("format version {version} is not supported (this build reads {SWF_VERSION})"),
        ));
    }
    let hlen = u32_at(bytes, 12);
    if hlen > MAX_HEADER {
        return Err(WindError::format(12, format!("header length {hlen} is implausible")));
    }
    let hend = 16 + hlen as usize;
    if bytes.len() < hend + 4 {
        return Err(WindError::format(
            bytes.len() as u64,
            format!("file ends inside the header (which ends at byte {hend})"),
        ));
    }
    // Checksum before trusting anything in the header.
    let body = &bytes[..bytes.len() - 4];
    let stored = u32_at(bytes, bytes.len() - 4);
    let header: Result<SwfHeader, _> = serde_json::from_slice(&bytes[16..hend]);
    let header = match header {
        Ok(h) => h,
        Err(e) => {
            let reason = if crc32fast::hash(body) != stored {
                format!(
                    "header does not parse ({e}) and the checksum does not match: the file is corrupt or truncated"
                )
            } else {
                format!("header does not parse: {e}")
            };
            return Err(WindError::format(16 + e.column() as u64, reason));
        }
    };
    header.grid.validate().map_err(|e| WindError::format(16, format!("header: {e}")))?;
    header.params.validate().map_err(|e| WindError::format(16, format!("header: {e}")))?;
    let count = header.grid.points() * 3 * header.grid.frames;
    let expected = hend as u64 + 2 * count as u64 + 4;
    if (bytes.len() as u64) < expected {
        return Err(WindError::format(
            bytes.len() as u64,
            format!("file is truncated: {count} samples need {expected} bytes"),
        ));
    }
    if bytes.len() as u64 > expected {
        return Err(WindError::format(expected, "trailing bytes after the checksum"));
    }
    let crc = crc32fast::hash(body);
    if crc != stored {
        return Err(WindError::format(
            (bytes.len() - 4) as u64,
            format!(
                "checksum mismatch (stored {stored:08x}, computed {crc:08x}): the file is corrupt"
            ),
        ));
    }
    check_quantisation(&header)?;
    let n = header.grid.points();
    let data = bytes[hend..hend + 2 * count]
        .chunks_exact(2)
        .enumerate()
        .map(|(i, b)| {
            let c = (i / n) % 3;
            (header.offset[c] + header.scale[c] * i16::from_le_bytes([b[0], b[1]]) as f64) as f32
        })
        .collect();
    let field = WindField {
        grid: header.grid,
        params: header.params,
        synth: header.synth,
        data,
        coherence_error: header.coherence_error,
    };
    crate::field::check_samples(&field)?;
    Ok(field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::Method;

    pub(crate) fn small() -> WindField {
        let grid = Grid::regular(5, 4, 2.0, &[12.0, 20.0], 16, 0.1);
        WindField::generate(
            &WindParams::default(),
            &grid,
            SynthParams { seed: 5, method: Method::Separable },
            &|_| {},
        )
        .expect("valid setup")
    }

    fn bytes_of(f: &WindField) -> Vec<u8> {
        let dir = sylva_testkit::TempDir::new("sylva-swf");
        let p = dir.join("f.swf");
        write_swf(f, &p).expect("write");
        std::fs::read(&p).expect("read back")
    }

    #[test]
    fn swf_round_trip_within_the_stated_quantisation_error() {
        let f = small();
        let bytes = bytes_of(&f);
        let g = parse_swf(&bytes).expect("parse");
        assert_eq!(g.grid, f.grid);
        assert_eq!(g.params, f.params);
        let (_, scale) = quantisation(&f, 65534.0);
        let n = f.grid.points();
        for (i, (a, b)) in f.data.iter().zip(&g.data).enumerate() {
            let c = (i / n) % 3;
            assert!(((a - b) as f64).abs() <= 0.5 * scale[c] + 1e-6, "sample {i}: {a} vs {b}");
        }
    }

    #[test]
    fn truncated_flipped_and_wrong_version_files_are_refused() {
        let bytes = bytes_of(&small());
        for cut in [0, 7, 15, 40, bytes.len() / 2, bytes.len() - 1] {
            let e = parse_swf(&bytes[..cut]).expect_err("truncated file must fail");
            assert!(matches!(e, WindError::Format { .. }), "cut {cut}: {e}");
        }
        let mut flipped = bytes.clone();
        let mid = bytes.len() - 50;
        flipped[mid] ^= 0x10;
        let e = parse_swf(&flipped).expect_err("bit flip must fail");
        assert!(e.to_string().contains("checksum"), "{e}");
        let mut v2 = bytes.clone();
        v2[8] = 2;
        let e = parse_swf(&v2).expect_err("wrong version must fail");
        assert!(e.to_string().contains("version 2"), "{e}");
        let mut magic = bytes;
        magic[0] = b'X';
        assert!(parse_swf(&magic).expect_err("bad magic").to_string().contains("magic"));
    }
}
