//! `sylva_wind._native`: the Rust side of the Python package. Fields cross as little-endian
//! `f32` bytes (layout frame, component, z, y, x) with their grid, model and synthesis
//! settings as JSON — the serde forms of `Grid`, `WindParams` and `SynthParams`, so every
//! model parameter keeps its Rust name. The Python wrapper (`sylva_wind/__init__.py`) turns
//! them into numpy arrays.

use std::path::Path;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use serde_json::json;
use sylva_wind::stats::Welch;
use sylva_wind::synth::Method;
use sylva_wind::{Grid, Preset, SynthParams, WindError, WindField, WindParams};

/// A Rust error as a Python `ValueError` with the same message as the command line's.
fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

fn parse<T: serde::de::DeserializeOwned>(what: &str, text: &str) -> PyResult<T> {
    serde_json::from_str(text).map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

/// The field's data as bytes and its settings as JSON.
fn to_python<'py>(py: Python<'py>, f: &WindField) -> PyResult<(Bound<'py, PyBytes>, String)> {
    let bytes = le_bytes(py, &f.data)?;
    let meta = json!({
        "grid": f.grid,
        "params": f.params,
        "synth": f.synth,
        "coherence_error": f.coherence_error,
    });
    Ok((bytes, meta.to_string()))
}

/// Samples as little-endian bytes, written straight into a Python `bytes` (no copy between).
fn le_bytes<'py>(py: Python<'py>, data: &[f32]) -> PyResult<Bound<'py, PyBytes>> {
    PyBytes::new_with(py, 4 * data.len(), |buf| {
        for (b, v) in buf.chunks_exact_mut(4).zip(data) {
            b.copy_from_slice(&v.to_le_bytes());
        }
        Ok(())
    })
}

/// Names of the wind presets.
/// The documentation of every model parameter, from `sylva-wind`'s doc comments (JSON:
/// key → text; see build.rs for the keys).
#[pyfunction]
fn param_docs() -> &'static str {
    include_str!(concat!(env!("OUT_DIR"), "/param_docs.json"))
}

#[pyfunction]
fn presets() -> Vec<&'static str> {
    Preset::ALL.iter().map(|p| p.name()).collect()
}

/// A preset's model parameters as JSON.
#[pyfunction]
fn preset_params(name: &str) -> PyResult<String> {
    let p = Preset::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
        PyValueError::new_err(format!("no preset named `{name}`; presets: {}", names.join(", ")))
    })?;
    Ok(serde_json::to_string(&p.field_params()).unwrap_or_default())
}

/// The coherence speed a field takes by default with `spectrum` (its JSON name), as the
/// command line chooses it.
#[pyfunction]
fn default_coherence_speed(spectrum: &str) -> PyResult<String> {
    let s: sylva_wind::SpectrumModel = parse("spectrum", &format!("\"{spectrum}\""))?;
    Ok(serde_json::to_string(&sylva_wind::CoherenceSpeed::for_spectrum(s)).unwrap_or_default())
}

/// Model, grid and synthesis settings from their JSON, validated as the command line
/// validates them (`method` may be `"auto"`: the fastest exact method for the grid).
fn setup(params: &str, grid: &str, seed: u64, method: &str) -> PyResult<(WindParams, Grid, SynthParams)> {
    let params: WindParams = parse("params", params)?;
    let grid: Grid = parse("grid", grid)?;
    params.validate().map_err(value_error)?;
    grid.validate().map_err(value_error)?;
    let method = match method {
        "auto" => Method::fastest(&params, &grid),
        other => serde_json::from_str::<Method>(&format!("\"{other}\"")).map_err(|_| {
            PyValueError::new_err(format!(
                "method `{other}`: one of auto, separable, embedding, cholesky"
            ))
        })?,
    };
    let synth = SynthParams { seed, method };
    sylva_wind::synth::check_config(&params, &grid, synth).map_err(value_error)?;
    Ok((params, grid, synth))
}

/// Synthesise a field: model, grid and synthesis settings as JSON (`method` may be
/// `"auto"`: the fastest exact method for the grid). The GIL is released while it runs.
#[pyfunction]
fn generate<'py>(
    py: Python<'py>,
    params: &str,
    grid: &str,
    seed: u64,
    method: &str,
) -> PyResult<(Bound<'py, PyBytes>, String)> {
    let (params, grid, synth) = setup(params, grid, seed, method)?;
    let method = synth.method;
    // The command line's memory check: the field and the synthesis's working memory within
    // three quarters of what the machine has free.
    let need = sylva_wind::synth::memory_estimate(&grid, method);
    if let Some(free) = sylva_core::memory::available_memory() {
        let usable = sylva_core::memory::USABLE_SHARE * free;
        if need > usable {
            return Err(PyValueError::new_err(format!(
                "this field needs about {:.2} GB ({} points × 3 components × {} frames, method \
                 {}), more than the {:.2} GB usable of this machine's free memory; reduce \
                 frames, nx/ny or heights, or make it lazily, a block at a time \
                 (generate_lazy)",
                need / 1e9,
                grid.points(),
                grid.frames,
                method.name(),
                usable / 1e9
            )));
        }
    }
    let field = py
        .allow_threads(|| WindField::generate(&params, &grid, synth, &|_| {}))
        .map_err(value_error)?;
    to_python(py, &field)
}

/// The settings of a field to be made a block of x-columns at a time (JSON as `generate`
/// gives them, without data): refused unless the method can make a block alone.
#[pyfunction]
fn plan_blocks(params: &str, grid: &str, seed: u64, method: &str) -> PyResult<String> {
    let (params, grid, synth) = setup(params, grid, seed, method)?;
    if synth.method != Method::Separable {
        return Err(PyValueError::new_err(format!(
            "a lazy field is made a block of x-columns at a time, which needs the separable \
             method (the reference coherence speed, or one height); the {} method holds \
             every point's coefficients at once: pass coherence_speed=\"reference\" or one \
             height",
            synth.method.name()
        )));
    }
    let meta = json!({ "grid": grid, "params": params, "synth": synth, "coherence_error": 0.0 });
    Ok(meta.to_string())
}

/// The x-columns `x0 .. x1` of a field, laid out (frame, component, z, y, column) as
/// little-endian f32 bytes: the whole field's records there, bit for bit. The GIL is
/// released while it runs.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn generate_columns<'py>(
    py: Python<'py>,
    params: &str,
    grid: &str,
    seed: u64,
    method: &str,
    x0: usize,
    x1: usize,
) -> PyResult<Bound<'py, PyBytes>> {
    let (params, grid, synth) = setup(params, grid, seed, method)?;
    let data = py
        .allow_threads(|| sylva_wind::synth::synthesize_columns(&params, &grid, synth, x0..x1))
        .map_err(value_error)?;
    // Written straight into the Python bytes: a block is held twice at most, not three times.
    le_bytes(py, &data)
}

/// Read a field file: `.swf`, `.npy` (with its sidecar) or a `.zarr` store.
#[pyfunction]
fn read<'py>(py: Python<'py>, path: &str) -> PyResult<(Bound<'py, PyBytes>, String)> {
    let p = Path::new(path);
    let field = py.allow_threads(|| sylva_wind::io::read_field(p)).map_err(value_error)?;
    to_python(py, &field)
}

/// Write a field (bytes and JSON settings as `read` gives them) by the path's extension:
/// `.swf`, `.npy` (with its sidecar) or `.bts` (the y–z plane at x index `bts_x_index`).
#[pyfunction]
#[pyo3(signature = (path, data, meta, bts_x_index = 0))]
fn write(py: Python<'_>, path: &str, data: &[u8], meta: &str, bts_x_index: usize) -> PyResult<()> {
    let field = from_python(data, meta)?;
    let p = Path::new(path);
    let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    py.allow_threads(|| match ext.as_str() {
        "swf" => sylva_wind::io::write_swf(&field, p),
        "npy" => sylva_wind::io::write_npy(&field, p),
        "bts" => sylva_wind::io::write_bts(&field, bts_x_index, p),
        _ => Err(WindError::Export(format!(
            "{path}: write .swf, .npy or .bts (a .zarr store comes from `sylva wind generate`)"
        ))),
    })
    .map_err(value_error)
}

/// The statistics `sylva wind stats --json` prints, as JSON: per height (all, or
/// `height_index`), per component σ against the model with its expected scatter, the
/// auto-spectrum against eq. 4 in log bands and the co-coherence against eq. 5.
#[pyfunction]
#[pyo3(signature = (data, meta, segment = None, height_index = None))]
fn stats(
    py: Python<'_>,
    data: &[u8],
    meta: &str,
    segment: Option<usize>,
    height_index: Option<usize>,
) -> PyResult<String> {
    let field = from_python(data, meta)?;
    let nz = field.grid.nz();
    let heights: Vec<usize> = match height_index {
        Some(h) if h >= nz => {
            return Err(PyValueError::new_err(format!(
                "height index {h} is outside the grid ({nz} heights, so 0 … {})",
                nz - 1
            )));
        }
        Some(h) => vec![h],
        None => (0..nz).collect(),
    };
    let fields = [field];
    let rows: Vec<sylva_wind::stats::FieldStats> = py.allow_threads(|| {
        heights.iter().map(|&h| sylva_wind::stats::ensemble_stats_at(&fields, segment, h)).collect()
    });
    serde_json::to_string(&rows).map_err(value_error)
}

/// A field from the bytes and JSON settings `read` and `generate` give.
fn from_python(data: &[u8], meta: &str) -> PyResult<WindField> {
    #[derive(serde::Deserialize)]
    struct Meta {
        grid: Grid,
        params: WindParams,
        synth: SynthParams,
        #[serde(default)]
        coherence_error: f64,
    }
    let m: Meta = parse("meta", meta)?;
    m.grid.validate().map_err(value_error)?;
    let want = m.grid.points() * 3 * m.grid.frames;
    if data.len() != 4 * want {
        return Err(PyValueError::new_err(format!(
            "data holds {} bytes; the grid needs {} values of 4 bytes",
            data.len(),
            want
        )));
    }
    let values = data.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]));
    Ok(WindField {
        grid: m.grid,
        params: m.params,
        synth: m.synth,
        data: values.collect(),
        coherence_error: m.coherence_error,
    })
}

/// Welch power spectral density of a record sampled every `dt` s, in segments of
/// `segment` samples (Hann window, half overlap): (frequencies in Hz, PSD in (m/s)²/Hz).
#[pyfunction]
fn psd(
    py: Python<'_>,
    record: Vec<f64>,
    dt: f64,
    segment: usize,
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(PyValueError::new_err(format!("dt = {dt}: must be finite and > 0")));
    }
    if segment < 4 || segment > record.len() || !segment.is_multiple_of(2) {
        return Err(PyValueError::new_err(format!(
            "segment = {segment}: an even number of samples, 4 … {} (the record's length)",
            record.len()
        )));
    }
    Ok(py.allow_threads(|| {
        let w = Welch::new(segment, dt);
        let s = w.spectra(&record);
        (w.freqs(), w.psd([&s]))
    }))
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(presets, m)?)?;
    m.add_function(wrap_pyfunction!(param_docs, m)?)?;
    m.add_function(wrap_pyfunction!(preset_params, m)?)?;
    m.add_function(wrap_pyfunction!(default_coherence_speed, m)?)?;
    m.add_function(wrap_pyfunction!(generate, m)?)?;
    m.add_function(wrap_pyfunction!(plan_blocks, m)?)?;
    m.add_function(wrap_pyfunction!(generate_columns, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(psd, m)?)?;
    m.add_function(wrap_pyfunction!(stats, m)?)?;
    Ok(())
}
