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
//! parameters, seed and method, mean speeds, the coherence model and the advection origin.
//!
//! The store is written into a temporary folder beside the destination and renamed into
//! place when complete; an interrupted run leaves any previous store intact.

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
    let (group, array) = metadata(params, grid, synth_params)?;
    write_file(&tmp.join("zarr.json"), group.as_bytes())?;
    write_file(&tmp.join("wind/zarr.json"), array.as_bytes())?;
    let times: Vec<f64> = (0..m).map(|t| t as f64 * grid.dt).collect();
    for (name, values) in [("time", &times), ("z", &grid.zs), ("y", &grid.ys), ("x", &grid.xs)] {
        write_coordinate(&tmp, name, values)?;
    }
    // Each block of columns becomes one chunk, written frame by frame in C order
    // (frame, z·y, 32 columns), through a small buffer of frames.
    const TILE: usize = 16;
    let mut buf: Vec<u8> = Vec::with_capacity(TILE * np * EMIT_COLUMNS * 4);
    let mut tile: Vec<f32> = Vec::with_capacity(TILE * np * EMIT_COLUMNS);
    let mut emit = |comp: Component, x0: usize, cols: usize, rec: &[f32]| {
        let path = tmp.join(chunk_key(comp.index(), x0 / EMIT_COLUMNS));
        let mut f = AtomicFile::create(&path).map_err(|e| WindError::io(&path, e))?;
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
            f.write_all(&buf).map_err(|e| WindError::io(&path, e))?;
        }
        f.commit().map_err(|e| WindError::io(&path, e))
    };
    synth::synthesize_streaming(params, grid, synth_params, &mut emit, progress)?;
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

/// A 1-D float64 coordinate array `name` in one chunk.
fn write_coordinate(root: &Path, name: &str, values: &[f64]) -> Result<(), WindError> {
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
    write_file(&dir.join("c/0"), &bytes)
}

/// The group's and the `wind` array's metadata.
fn metadata(
    params: &WindParams,
    grid: &Grid,
    synth: SynthParams,
) -> Result<(String, String), WindError> {
    let attrs = ZarrAttributes {
        grid: grid.clone(),
        params: params.clone(),
        synth,
        mean_speeds: grid.zs.iter().map(|&z| params.mean_speed(z)).collect(),
        coherence_model: params.coherence_speed.name().into(),
        advection_origin_x: params.advection.then(|| grid.x_mid()),
    };
    let group = serde_json::json!({
        "zarr_format": 3,
        "node_type": "group",
        "attributes": {"sylva": attrs}
    });
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
    let text = |v: &serde_json::Value| {
        serde_json::to_string_pretty(v).map_err(|e| WindError::Export(e.to_string()))
    };
    Ok((text(&group)?, text(&meta)?))
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
    let attrs: ZarrAttributes = serde_json::from_value(group["attributes"]["sylva"].clone())
        .map_err(|e| bad(format!("the group's attributes.sylva: {e}")))?;
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
            let path = dir.join(chunk_key(c, xb));
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
    Ok(WindField {
        grid: attrs.grid,
        params: attrs.params,
        synth: attrs.synth,
        data,
        coherence_error: 0.0,
    })
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
