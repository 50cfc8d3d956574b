//! Zarr v3 export, streamed: wind fields larger than memory, in a layout xarray, zarr-python
//! and other chunked-array tools read directly.
//!
//! The store is a folder holding a group (`zarr.json` at its root) with the array `wind` of
//! shape (frames, 3, nz, ny, nx), float32 little-endian, C order, dimension names
//! `time, component, z, y, x`, velocities in m/s in the wind frame with Ū(z) in `u`, and
//! the 1-D coordinate arrays `time` (s), `z`, `y`, `x` (m), so `xarray.open_zarr` gives a
//! dataset with labelled axes. Chunks
//! are (frames, 1, nz, ny, 32): exactly the block of x-columns the separable synthesis
//! finishes at a time, so each chunk is written once, as soon as it is ready, and the
//! working memory stays one block whatever the field's size. Chunk keys use the default
//! `c/…` encoding with `/`; the codec is `bytes` (uncompressed). The last chunk along x is
//! padded to 32 columns with the fill value 0, as Zarr requires.
//!
//! The group's `attributes.sylva` holds what `.swf` headers and `.npy` sidecars hold: grid,
//! parameters, seed and method, mean speeds, the coherence model and the advection origin;
//! and the store's manifest, the CRC-32 of every chunk, with a checksum of the attributes
//! themselves. The group's `zarr.json` is written last, once every chunk's checksum is known.
//!
//! The store is written into a temporary folder beside the destination and renamed into
//! place when complete; an interrupted run leaves any previous store intact.

use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::atomic::AtomicFile;
use crate::error::WindError;
use crate::field::WindField;
use crate::grid::Grid;
use crate::params::{Component, WindParams};
use crate::synth::{self, EMIT_COLUMNS, SynthParams};

/// What `attributes.sylva` of a store records.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ZarrAttributes {
    /// Grid and time axis.
    pub grid: Grid,
    /// Model parameters.
    pub params: WindParams,
    /// Seed and method.
    pub synth: SynthParams,
    /// Ū at each height, m/s.
    pub mean_speeds: Vec<f64>,
    /// `"reference"` or `"pair-mean"` (see the `.npy` sidecar).
    pub coherence_model: String,
    /// Advection phase origin x_c, m; null when advection is off.
    pub advection_origin_x: Option<f64>,
    /// The convection speed U_c every height advects at, m/s; null when advection is off.
    #[serde(default)]
    pub advection_speed: Option<f64>,
    /// The store's manifest: the CRC-32 (IEEE) of every chunk file, keyed by its path in
    /// the store (`wind/c/0/1/0/0/3`, `x/c/0`, …). The reader checks each chunk it reads
    /// against it.
    pub checksums: BTreeMap<String, u32>,
    /// CRC-32 of these attributes themselves: of their compact JSON with this field 0
    /// ([`ZarrAttributes::checksum`]), so an edited grid or manifest is refused.
    pub attributes_crc32: u32,
}

impl ZarrAttributes {
    /// The CRC-32 [`ZarrAttributes::attributes_crc32`] holds for the other fields.
    pub fn checksum(&self) -> Result<u32, WindError> {
        super::json_crc32(&ZarrAttributes { attributes_crc32: 0, ..self.clone() })
    }
}

/// A chunk's key in the manifest: its path in the store with `/` separators.
fn manifest_key(path: &Path) -> String {
    path.iter().map(|p| p.to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// Removes a partial store unless it was moved into place.
struct PartialDir(Option<PathBuf>);

impl Drop for PartialDir {
    fn drop(&mut self) {
        if let Some(d) = self.0.take() {
            // Best effort: an interrupted or failed write leaves nothing behind.
            let _ = std::fs::remove_dir_all(d);
        }
    }
}

fn chunk_key(comp: usize, xb: usize) -> PathBuf {
    ["wind", "c", "0", &comp.to_string(), "0", "0", &xb.to_string()].iter().collect()
}

/// Synthesise a field straight into a Zarr v3 store at `dir`, never holding the whole
/// field: peak memory [`synth::streaming_memory_estimate`]. The separable method only.
pub fn write_zarr_streaming(
    params: &WindParams,
    grid: &Grid,
    synth_params: SynthParams,
    dir: &Path,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<(), WindError> {
    synth::check_config(params, grid, synth_params)?;
    let name = dir
        .file_name()
        .ok_or_else(|| WindError::Export(format!("{} names no folder", dir.display())))?;
    let tmp =
        dir.with_file_name(format!(".{}.partial-{}", name.to_string_lossy(), std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let mut guard = PartialDir(Some(tmp.clone()));
    let (np, m) = (grid.nz() * grid.ny(), grid.frames);
    for c in 0..3 {
        let d = tmp.join("wind/c/0").join(c.to_string()).join("0/0");
        std::fs::create_dir_all(&d).map_err(|e| WindError::io(&d, e))?;
    }
    write_file(&tmp.join("wind/zarr.json"), array_metadata(grid)?.as_bytes())?;
    let mut checksums = BTreeMap::new();
    let times: Vec<f64> = (0..m).map(|t| t as f64 * grid.dt).collect();
    for (name, values) in [("time", &times), ("z", &grid.zs), ("y", &grid.ys), ("x", &grid.xs)] {
        checksums.insert(format!("{name}/c/0"), write_coordinate(&tmp, name, values)?);
    }
    // Each block of columns becomes one chunk, written frame by frame in C order
    // (frame, z·y, 32 columns), through a small buffer of frames.
    const TILE: usize = 16;
    let mut buf: Vec<u8> = Vec::with_capacity(TILE * np * EMIT_COLUMNS * 4);
    let mut tile: Vec<f32> = Vec::with_capacity(TILE * np * EMIT_COLUMNS);
    let mut emit = |comp: Component, x0: usize, cols: usize, rec: &[f32]| {
        let key = chunk_key(comp.index(), x0 / EMIT_COLUMNS);
        let path = tmp.join(&key);
        let mut f = AtomicFile::create(&path).map_err(|e| WindError::io(&path, e))?;
        let mut crc = crc32fast::Hasher::new();
        for t0 in (0..m).step_by(TILE) {
            let tn = (t0 + TILE).min(m) - t0;
            // Read each record's run of `tn` frames (contiguous), scatter into the tile.
            tile.clear();
            tile.resize(tn * np * EMIT_COLUMNS, 0.0);
            for b in 0..cols {
                for p in 0..np {
                    let run = &rec[(b * np + p) * m + t0..(b * np + p) * m + t0 + tn];
                    for (dt, v) in run.iter().enumerate() {
                        tile[(dt * np + p) * EMIT_COLUMNS + b] = *v;
                    }
                }
            }
            buf.clear();
            for v in &tile {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            crc.update(&buf);
            f.write_all(&buf).map_err(|e| WindError::io(&path, e))?;
        }
        checksums.insert(manifest_key(&key), crc.finalize());
        f.commit().map_err(|e| WindError::io(&path, e))
    };
    synth::synthesize_streaming(params, grid, synth_params, &mut emit, progress)?;
    // The group, with the manifest, last: a store is complete when it has its root.
    let group = group_metadata(params, grid, synth_params, checksums)?;
    write_file(&tmp.join("zarr.json"), group.as_bytes())?;
    // Into place: the previous store (if any) goes only once the new one is complete.
    let old = dir.with_file_name(format!(".{}.old-{}", name.to_string_lossy(), std::process::id()));
    if dir.exists() {
        std::fs::rename(dir, &old).map_err(|e| WindError::io(dir, e))?;
    }
    std::fs::rename(&tmp, dir).map_err(|e| WindError::io(dir, e))?;
    guard.0 = None;
    if old.exists() {
        let _ = std::fs::remove_dir_all(&old);
    }
    Ok(())
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), WindError> {
    super::atomic::write_atomic(path, bytes).map_err(|e| WindError::io(path, e))
}

/// A 1-D float64 coordinate array `name` in one chunk; returns the chunk's CRC-32.
fn write_coordinate(root: &Path, name: &str, values: &[f64]) -> Result<u32, WindError> {
    let dir = root.join(name);
    std::fs::create_dir_all(dir.join("c")).map_err(|e| WindError::io(&dir, e))?;
    let units = if name == "time" { "s" } else { "m" };
    let meta = serde_json::json!({
        "zarr_format": 3,
        "node_type": "array",
        "shape": [values.len()],
        "data_type": "float64",
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [values.len()]}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "fill_value": 0.0,
        "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}],
        "dimension_names": [name],
        "attributes": {"units": units}
    });
    let text = serde_json::to_string_pretty(&meta).map_err(|e| WindError::Export(e.to_string()))?;
    write_file(&dir.join("zarr.json"), text.as_bytes())?;
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    write_file(&dir.join("c/0"), &bytes)?;
    Ok(crc32fast::hash(&bytes))
}

/// The group's metadata: `attributes.sylva` with the store's manifest.
fn group_metadata(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
    checksums: BTreeMap<String, u32>,
) -> Result<String, WindError> {
    let mut attrs = ZarrAttributes {
        grid: grid.clone(),
        params: params.clone(),
        synth,
        mean_speeds: grid.zs.iter().map(|&z| params.mean_speed(z)).collect(),
        coherence_model: params.coherence_speed.name().into(),
        advection_origin_x: params.advection.then(|| grid.x_mid()),
        advection_speed: params.advection.then(|| synth::convection_speed(params, grid)),
        checksums,
        attributes_crc32: 0,
    };
    attrs.attributes_crc32 = attrs.checksum()?;
    let group = serde_json::json!({
        "zarr_format": 3,
        "node_type": "group",
        "attributes": {"sylva": attrs}
    });
    serde_json::to_string_pretty(&group).map_err(|e| WindError::Export(e.to_string()))
}

/// The `wind` array's metadata.
fn array_metadata(grid: &Grid) -> Result<String, WindError> {
    let meta = serde_json::json!({
        "zarr_format": 3,
        "node_type": "array",
        "shape": [grid.frames, 3, grid.nz(), grid.ny(), grid.nx()],
        "data_type": "float32",
        "chunk_grid": {
            "name": "regular",
            "configuration": {"chunk_shape": [grid.frames, 1, grid.nz(), grid.ny(), EMIT_COLUMNS]}
        },
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "fill_value": 0.0,
        "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}],
        "dimension_names": ["time", "component", "z", "y", "x"],
        "attributes": {"units": "m/s", "components": ["u", "v", "w"]}
    });
    serde_json::to_string_pretty(&meta).map_err(|e| WindError::Export(e.to_string()))
}

/// Read a store written by [`write_zarr_streaming`] into memory.
pub fn read_zarr(dir: &Path) -> Result<WindField, WindError> {
    let json = |p: PathBuf| -> Result<serde_json::Value, WindError> {
        let text = std::fs::read_to_string(&p).map_err(|e| WindError::io(&p, e))?;
        serde_json::from_str(&text).map_err(|e| WindError::Format {
            offset: 0,
            reason: format!("{}: line {}: {e}", p.display(), e.line()),
        })
    };
    let group = json(dir.join("zarr.json"))?;
    let mp = dir.join("wind/zarr.json");
    let meta = json(mp.clone())?;
    let bad = |reason: String| WindError::Format {
        offset: 0,
        reason: format!("{}: {reason}", mp.display()),
    };
    let gp = dir.join("zarr.json");
    let attrs: ZarrAttributes = serde_json::from_value(group["attributes"]["sylva"].clone())
        .map_err(|e| bad(format!("the group's attributes.sylva: {e}")))?;
    let crc = attrs.checksum()?;
    if crc != attrs.attributes_crc32 {
        return Err(WindError::Format {
            offset: 0,
            reason: format!(
                "{}: attributes.sylva's checksum {crc:08x} differs from its attributes_crc32 \
                 {:08x}: the store's attributes were edited or are corrupt",
                gp.display(),
                attrs.attributes_crc32
            ),
        });
    }
    // Every chunk file against the manifest: the coordinates here, the wind as it is read.
    let check = |key: &str, bytes: &[u8]| -> Result<(), WindError> {
        let path = dir.join(key);
        let Some(&want) = attrs.checksums.get(key) else {
            return Err(WindError::Format {
                offset: 0,
                reason: format!("{}: the store's manifest has no checksum for it", path.display()),
            });
        };
        let got = crc32fast::hash(bytes);
        if got != want {
            return Err(WindError::Format {
                offset: 0,
                reason: format!(
                    "{}: chunk checksum {got:08x} differs from the manifest's {want:08x}: the \
                     chunk is corrupt",
                    path.display()
                ),
            });
        }
        Ok(())
    };
    for name in ["time", "z", "y", "x"] {
        let key = format!("{name}/c/0");
        let path = dir.join(&key);
        let bytes = std::fs::read(&path).map_err(|e| WindError::io(&path, e))?;
        check(&key, &bytes)?;
    }
    attrs.grid.validate().map_err(|e| bad(e.to_string()))?;
    attrs.params.validate().map_err(|e| bad(e.to_string()))?;
    let g = &attrs.grid;
    let (nz, ny, nx, m) = (g.nz(), g.ny(), g.nx(), g.frames);
    let want_shape = serde_json::json!([m, 3, nz, ny, nx]);
    if meta["shape"] != want_shape {
        return Err(bad(format!("shape {} does not match the grid's {want_shape}", meta["shape"])));
    }
    let chunk = serde_json::json!([m, 1, nz, ny, EMIT_COLUMNS]);
    if meta["chunk_grid"]["configuration"]["chunk_shape"] != chunk
        || meta["data_type"] != "float32"
        || meta["codecs"]
            != serde_json::json!([{"name": "bytes", "configuration": {"endian": "little"}}])
    {
        return Err(bad(format!(
            "only float32 little-endian uncompressed chunks of shape {chunk} are read"
        )));
    }
    let np = nz * ny;
    let n = g.points();
    // A store larger than this machine's memory is refused by size, not aborted on.
    let mut data = crate::field::alloc_field(g)?;
    let per_chunk = m * np * EMIT_COLUMNS * 4;
    let mut bytes = Vec::with_capacity(per_chunk);
    for c in 0..3 {
        for xb in 0..nx.div_ceil(EMIT_COLUMNS) {
            let key = chunk_key(c, xb);
            let path = dir.join(&key);
            bytes.clear();
            std::fs::File::open(&path)
                .and_then(|mut f| f.read_to_end(&mut bytes))
                .map_err(|e| WindError::io(&path, e))?;
            if bytes.len() != per_chunk {
                return Err(WindError::Format {
                    offset: bytes.len().min(per_chunk) as u64,
                    reason: format!(
                        "{}: chunk holds {} bytes, the grid needs {per_chunk}",
                        path.display(),
                        bytes.len()
                    ),
                });
            }
            check(&manifest_key(&key), &bytes)?;
            for (k, v) in bytes.chunks_exact(4).enumerate() {
                let b = k % EMIT_COLUMNS;
                let x = xb * EMIT_COLUMNS + b;
                if x >= nx {
                    continue;
                }
                let (p, t) = ((k / EMIT_COLUMNS) % np, k / (EMIT_COLUMNS * np));
                data[(t * 3 + c) * n + p * nx + x] = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
            }
        }
    }
    let field = WindField {
        grid: attrs.grid,
        params: attrs.params,
        synth: attrs.synth,
        data,
        coherence_error: 0.0,
    };
    crate::field::check_samples(&field)?;
    Ok(field)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Method, Preset};

    #[test]
    fn a_streamed_store_reads_back_as_the_field_made_in_memory() {
        let dir = sylva_testkit::TempDir::new("sylva-zarr");
        let store = dir.join("w.zarr");
        // 70 columns: two full chunks of 32 and a padded one.
        let grid = Grid::regular(70, 5, 3.0, &[15.0, 25.0], 64, 0.1);
        let params = Preset::Strong.params();
        let sp = SynthParams { seed: 9, method: Method::Separable };
        write_zarr_streaming(&params, &grid, sp, &store, &|_| {}).expect("stream");
        let back = read_zarr(&store).expect("read");
        let made = WindField::generate(&params, &grid, sp, &|_| {}).expect("in memory");
        assert_eq!(back.grid, made.grid);
        assert!(back.data.iter().zip(&made.data).all(|(a, b)| a.to_bits() == b.to_bits()));
        // Writing again replaces it whole, leaving no partial or old folder.
        write_zarr_streaming(&params, &grid, sp, &store, &|_| {}).expect("again");
        let leftovers = std::fs::read_dir(&dir)
            .expect("list")
            .filter(|e| e.as_ref().is_ok_and(|e| e.file_name().to_string_lossy().starts_with('.')))
            .count();
        assert_eq!(leftovers, 0);
        // A cut chunk is refused with its path.
        let chunk = store.join("wind/c/0/1/0/0/2");
        let bytes = std::fs::read(&chunk).expect("chunk");
        super::super::atomic::write_atomic(&chunk, &bytes[..bytes.len() - 4]).expect("cut");
        let e = read_zarr(&store).expect_err("cut chunk").to_string();
        assert!(e.contains("wind/c/0/1/0/0/2") && e.contains("bytes"), "{e}");
    }

    /// Metadata that claims a field far larger than the store (and than this machine's
    /// memory), consistent in every key: refused with an error, never an allocation abort.
    #[test]
    fn a_store_claiming_an_enormous_field_is_refused_not_aborted() {
        let dir = sylva_testkit::TempDir::new("sylva-zarr-big");
        let store = dir.join("w.zarr");
        let grid = Grid::regular(40, 4, 3.0, &[20.0], 16, 0.1);
        let sp = SynthParams { seed: 1, method: Method::Separable };
        write_zarr_streaming(&WindParams::default(), &grid, sp, &store, &|_| {}).expect("store");
        // 100 000 × 10 000 points × 3 × 12 frames: 3.6·10¹⁰ values (144 GB), inside the
        // grid's cap of 4·10¹⁰.
        let edit = |rel: &str, f: &dyn Fn(&mut serde_json::Value)| {
            let p = store.join(rel);
            let mut v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&p).expect("read")).expect("json");
            f(&mut v);
            crate::io::atomic::write_atomic(&p, v.to_string().as_bytes()).expect("write");
        };
        let (nx, ny, frames) = (100_000usize, 10_000usize, 12usize);
        edit("zarr.json", &|v| {
            let g = &mut v["attributes"]["sylva"]["grid"];
            g["xs"] = (0..nx).map(|i| i as f64).collect::<Vec<_>>().into();
            g["ys"] = (0..ny).map(|i| i as f64).collect::<Vec<_>>().into();
            g["frames"] = frames.into();
            // The attributes' checksum recomputed, as a hostile edit would.
            let a = &mut v["attributes"]["sylva"];
            let mut attrs: ZarrAttributes = serde_json::from_value(a.clone()).expect("attributes");
            attrs.attributes_crc32 = attrs.checksum().expect("checksum");
            *a = serde_json::to_value(attrs).expect("json");
        });
        edit("wind/zarr.json", &|v| {
            v["shape"] = serde_json::json!([frames, 3, 1, ny, nx]);
            v["chunk_grid"]["configuration"]["chunk_shape"] =
                serde_json::json!([frames, 1, 1, ny, EMIT_COLUMNS]);
        });
        let e = read_zarr(&store).expect_err("enormous field").to_string();
        // Refused by size where the machine cannot allocate it, else by the first chunk.
        assert!(e.contains("GB of memory") || e.contains("chunk holds"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
