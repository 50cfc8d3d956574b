"""Stochastic wind fields from Sylva's ``sylva-wind``: synthesise, read, write, analyse.

A field is three velocity components on a rectilinear grid over a looping time axis,
synthesised from wind-engineering spectra (Kaimal, von Kármán) and coherence (Davenport)
with a mean profile (log or power law). The same Rust library runs the command line
(``sylva wind generate``), so a field made here with the same model, grid, seed and method
is the same field, bit for bit.

>>> import sylva_wind as sw
>>> f = sw.generate("strong", nx=16, ny=16, heights=(10.0, 20.0), frames=256, seed=3)
>>> f.data.shape            # (t, component, z, y, x), float32, m/s
(256, 3, 2, 16, 16)
>>> freqs, psd = sw.psd(f, "u", z=1)

Model parameters keep their Rust names (``sw.default_params()`` lists them) and their Rust
documentation: ``sw.describe("u_star")`` or ``sw.PARAMETER_DOCS`` give meaning, unit and
range. Errors from the library are raised as ``ValueError`` with the command line's message.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field as _field
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

from . import _native

__all__ = [
    "Field",
    "PRESETS",
    "COMPONENTS",
    "default_params",
    "describe",
    "PARAMETER_DOCS",
    "generate",
    "generate_lazy",
    "read",
    "write",
    "psd",
    "stats",
]

#: Names of the wind presets (calm, breeze, strong, storm).
PRESETS: Tuple[str, ...] = tuple(_native.presets())

#: The documentation of every model parameter, taken from the Rust doc comments of
#: ``sylva-wind`` when the package is built. Keys: ``u_star`` (a top-level parameter),
#: ``profile.z0`` (a field of a profile kind), ``profile.kind=log`` (a kind),
#: ``spectrum=kaimal`` and ``coherence_speed=pair-mean`` (values),
#: ``spectrum_constants[].a`` and ``coherence[].cy`` (fields of the per-component entries).
PARAMETER_DOCS: Dict[str, str] = json.loads(_native.param_docs())

#: Velocity components, in the order of the data's axis 1.
COMPONENTS: Tuple[str, ...] = ("u", "v", "w")


@dataclass
class Field:
    """A wind field: ``data[t, c, z, y, x]`` in m/s (``u`` includes the mean wind), the grid
    (``xs``, ``ys``, ``zs`` in m, ``frames``, ``dt`` in s), the model ``params`` and the
    synthesis settings (``seed``, ``method``)."""

    data: np.ndarray
    grid: Dict[str, Any]
    params: Dict[str, Any]
    synth: Dict[str, Any]
    coherence_error: float = 0.0
    _meta: Dict[str, Any] = _field(default_factory=dict, repr=False)

    @property
    def t(self) -> np.ndarray:
        """Times of the frames, s."""
        return np.arange(self.grid["frames"]) * self.grid["dt"]

    @property
    def x(self) -> np.ndarray:
        """Along-wind coordinates, m."""
        return np.asarray(self.grid["xs"])

    @property
    def y(self) -> np.ndarray:
        """Lateral coordinates, m."""
        return np.asarray(self.grid["ys"])

    @property
    def z(self) -> np.ndarray:
        """Heights above ground, m."""
        return np.asarray(self.grid["zs"])

    def to_xarray(self):
        """The field as an ``xarray.Dataset`` laid out as Sylva's Zarr stores are, so that
        ``xarray.open_zarr(path, consolidated=False)`` on a store of the same field gives the same array: the
        variable ``wind`` over ``(time, component, z, y, x)`` in m/s (``u`` includes the
        mean wind), the coordinates ``time`` (s), ``z``, ``y``, ``x`` (m) with their units,
        ``component`` labelled ``u``, ``v``, ``w`` (``ds.wind.sel(component="u")``), and
        the model and synthesis settings as attributes (needs the ``xarray`` package)."""
        import xarray as xr

        coords = {
            "time": ("time", self.t, {"units": "s"}),
            "component": ("component", list(COMPONENTS)),
            "z": ("z", self.z, {"units": "m"}),
            "y": ("y", self.y, {"units": "m"}),
            "x": ("x", self.x, {"units": "m"}),
        }
        wind = (("time", "component", "z", "y", "x"), self.data, {"units": "m/s"})
        attrs = {f"param_{k}": json.dumps(v) for k, v in self.params.items()}
        attrs.update({"seed": self.synth["seed"], "method": self.synth["method"]})
        return xr.Dataset({"wind": wind}, coords=coords, attrs=attrs)

    def _meta_json(self) -> str:
        return json.dumps(
            {
                "grid": self.grid,
                "params": self.params,
                "synth": self.synth,
                "coherence_error": self.coherence_error,
            }
        )


def _field_from(native: Tuple[bytes, str]) -> Field:
    data, meta = native
    m = json.loads(meta)
    g = m["grid"]
    shape = (g["frames"], 3, len(g["zs"]), len(g["ys"]), len(g["xs"]))
    array = np.frombuffer(data, dtype="<f4").reshape(shape)
    return Field(array, g, m["params"], m["synth"], m["coherence_error"])


def describe(name: str) -> str:
    """The documentation of a model parameter or value (a key of ``PARAMETER_DOCS``; a
    top-level name such as ``"profile"`` also lists its fields and kinds)."""
    below = [k for k in PARAMETER_DOCS if k != name and k.startswith((name + ".", name + "[]", name + "="))]
    if name not in PARAMETER_DOCS and not below:
        raise ValueError(f"unknown wind parameter `{name}`; known: {sorted(PARAMETER_DOCS)}")
    lines = [f"{name}: {PARAMETER_DOCS[name]}"] if name in PARAMETER_DOCS else []
    lines += [f"  {k}: {PARAMETER_DOCS[k]}" for k in below]
    return "\n".join(lines)


def default_params(preset: str = "breeze") -> Dict[str, Any]:
    """A preset's model parameters for a field (Rust ``WindParams`` names and values): the
    same as ``sylva wind generate --preset NAME`` takes, the paper's pair-mean coherence
    speed with the paper's spectrum included."""
    return json.loads(_native.preset_params(preset))


def generate(
    preset: str = "breeze",
    *,
    nx: int = 64,
    ny: int = 64,
    spacing: float = 4.0,
    heights: Sequence[float] = (20.0,),
    xs: Optional[Iterable[float]] = None,
    ys: Optional[Iterable[float]] = None,
    frames: int = 2048,
    dt: float = 0.1,
    seed: int = 1,
    method: str = "auto",
    params: Optional[Dict[str, Any]] = None,
    **overrides: Any,
) -> Field:
    """Synthesise a field.

    The model is ``params`` if given, else the preset's; keyword ``overrides`` replace single
    parameters by their Rust names (``u_star=1.8``, ``direction_deg=30``, …). The grid is
    ``nx × ny`` points ``spacing`` m apart from the origin (or the coordinates ``xs``,
    ``ys``), at ``heights`` m, over ``frames`` frames ``dt`` s apart (the field loops every
    ``frames · dt`` s). ``method`` is ``"auto"`` (the fastest exact method for the grid),
    ``"separable"``, ``"embedding"`` or ``"cholesky"``. The GIL is released during
    synthesis.
    """
    model, grid = _model_and_grid(locals(), overrides)
    return _field_from(_native.generate(json.dumps(model), json.dumps(grid), int(seed), method))


def _model_and_grid(a: Dict[str, Any], overrides: Dict[str, Any]) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """The model and grid of ``generate``'s arguments ``a``, checked in the command line's
    words."""
    spacing, dt, heights, xs, ys = a["spacing"], a["dt"], a["heights"], a["xs"], a["ys"]
    nx, ny, frames, params, preset = a["nx"], a["ny"], a["frames"], a["params"], a["preset"]
    # The grid's numbers checked here, in the command line's words (JSON cannot carry NaN).
    for name, value in (("spacing", spacing), ("dt", dt)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value}: expected a finite number > 0")
    for name, n in (("nx", nx), ("ny", ny), ("frames", frames)):
        if not (isinstance(n, int) and n >= 1):
            raise ValueError(f"{name} = {n}: expected a whole number ≥ 1")
    for name, values in (("heights", heights), ("xs", xs), ("ys", ys)):
        if values is not None and not all(math.isfinite(float(v)) for v in values):
            raise ValueError(f"{name}: expected finite numbers, got {list(values)}")
    model = dict(params) if params is not None else default_params(preset)
    unknown = [k for k in overrides if k not in model]
    if unknown:
        raise ValueError(f"unknown wind parameter(s) {unknown}; known: {sorted(model)}")
    model.update(overrides)
    for name, value in _numbers(model):
        if not math.isfinite(value):
            raise ValueError(f"{name} = {value}: expected a finite number")
    # A spectrum chosen here without a coherence speed takes the command line's for it.
    if params is None and "spectrum" in overrides and "coherence_speed" not in overrides:
        spectrum = json.dumps(model["spectrum"]).strip('"')
        model["coherence_speed"] = json.loads(_native.default_coherence_speed(spectrum))
    grid = {
        "xs": list(xs) if xs is not None else [spacing * i for i in range(nx)],
        "ys": list(ys) if ys is not None else [spacing * j for j in range(ny)],
        "zs": [float(h) for h in heights],
        "frames": int(frames),
        "dt": float(dt),
    }
    return model, grid


def _numbers(value: Any, name: str = "") -> Iterable[Tuple[str, float]]:
    """Every float in a model, with its name as the library's errors give it
    (``profile.z0``, ``coherence[1].cy``): JSON cannot carry NaN, so they are checked here."""
    if isinstance(value, float):
        yield name, value
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _numbers(v, f"{name}.{k}" if name else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _numbers(v, f"{name}[{i}]")


def generate_lazy(
    preset: str = "breeze",
    *,
    nx: int = 64,
    ny: int = 64,
    spacing: float = 4.0,
    heights: Sequence[float] = (20.0,),
    xs: Optional[Iterable[float]] = None,
    ys: Optional[Iterable[float]] = None,
    frames: int = 2048,
    dt: float = 0.1,
    seed: int = 1,
    method: str = "auto",
    params: Optional[Dict[str, Any]] = None,
    chunks: int = 32,
    **overrides: Any,
):
    """The field ``generate`` makes with the same arguments, as a lazy ``xarray.Dataset``
    laid out as ``Field.to_xarray()`` (``wind`` over ``(time, component, z, y, x)``, m/s),
    whose ``x`` axis is a Dask array in blocks of ``chunks`` columns (needs the ``dask``
    extra: ``pip install sylva-wind[dask]``).

    Nothing is synthesised until a block is computed; each block is then made on its own,
    on whichever worker computes it, and equals the in-memory field's columns bit for bit:
    the synthesis runs the x recursion of each frequency line over the columns before the
    block from the same counter-based phases (no FFT there), which carries its state into
    the block exactly. A block costs its share of the field plus that phase sweep, and
    holds ``frames × 3 × len(heights) × ny × chunks`` float32 values. So
    ``ds.to_zarr(path)`` on a ``dask.distributed`` cluster writes a field no single machine
    could hold, each worker holding a few blocks at a time.

    Only the separable method can make a block alone (the embedding and the dense Cholesky
    hold every point's coefficients at once): one height, or the reference coherence speed
    (``coherence_speed="reference"``) on several; anything else is refused with a
    ``ValueError``.
    """
    import dask
    import dask.array as da
    import xarray as xr

    if not (isinstance(chunks, int) and chunks >= 1):
        raise ValueError(f"chunks = {chunks}: expected a whole number ≥ 1 of x-columns")
    model, grid = _model_and_grid(locals(), overrides)
    model_json, grid_json = json.dumps(model), json.dumps(grid)
    meta = json.loads(_native.plan_blocks(model_json, grid_json, int(seed), method))
    g = meta["grid"]
    shape = (g["frames"], 3, len(g["zs"]), len(g["ys"]))
    blocks = []
    for x0 in range(0, len(g["xs"]), chunks):
        x1 = min(x0 + chunks, len(g["xs"]))
        block = dask.delayed(_block, pure=True)(model_json, grid_json, int(seed), method, x0, x1)
        blocks.append(da.from_delayed(block, shape=shape + (x1 - x0,), dtype=np.float32))
    wind = da.concatenate(blocks, axis=4)
    field = Field(wind, g, meta["params"], meta["synth"], 0.0)
    return field.to_xarray()


def _block(model_json: str, grid_json: str, seed: int, method: str, x0: int, x1: int) -> np.ndarray:
    """Columns ``x0 .. x1`` of a field, (t, component, z, y, x) float32: one block of
    ``generate_lazy``, made wherever it runs."""
    g = json.loads(grid_json)
    data = _native.generate_columns(model_json, grid_json, seed, method, x0, x1)
    shape = (g["frames"], 3, len(g["zs"]), len(g["ys"]), x1 - x0)
    return np.frombuffer(data, dtype="<f4").reshape(shape)


def read(path: str) -> Field:
    """Read a ``.swf``, ``.npy`` (with its ``.json`` sidecar) or ``.zarr`` field."""
    return _field_from(_native.read(str(path)))


def write(field: Field, path: str, *, bts_x_index: int = 0) -> None:
    """Write ``field`` as ``.swf``, ``.npy`` (with its sidecar) or TurbSim ``.bts`` (the y–z
    plane at x index ``bts_x_index``), by the path's extension. Written atomically."""
    data = np.ascontiguousarray(field.data, dtype="<f4").tobytes()
    _native.write(str(path), data, field._meta_json(), bts_x_index)


def psd(
    field: Field, component: str = "u", z: int = 0, y: int = 0, x: int = 0, segment: int = 256
) -> Tuple[np.ndarray, np.ndarray]:
    """Welch power spectral density of one component's record at one grid point (Hann
    window, segments of ``segment`` frames with half overlap, wrapping the loop): the
    frequencies in Hz and the PSD in (m/s)²/Hz — the estimator ``sylva wind stats`` uses."""
    if component not in COMPONENTS:
        raise ValueError(f"component `{component}`: one of {COMPONENTS}")
    record = field.data[:, COMPONENTS.index(component), z, y, x].astype(np.float64)
    freqs, values = _native.psd(record.tolist(), float(field.grid["dt"]), int(segment))
    return np.asarray(freqs), np.asarray(values)


def stats(
    field: Field, *, height: Optional[int] = None, segment: Optional[int] = None
) -> List[Dict[str, Any]]:
    """What ``sylva wind stats --json`` reports, per height (every height, or the index
    ``height``): per component ``u``, ``v``, ``w`` the measured σ against the model's and
    the discrete target's with its expected scatter, and two tables as numpy arrays — the
    auto-spectrum against eq. 4 in log bands (``spectrum``: a column per field) and the
    co-coherence against eq. 5 at several separations (``coherence``). ``segment`` is the
    Welch segment length (default: the command line's)."""
    data = np.ascontiguousarray(field.data, dtype="<f4").tobytes()
    rows = json.loads(_native.stats(data, field._meta_json(), segment, height))
    for row in rows:
        for comp in row["components"]:
            for table in ("spectrum", "coherence"):
                entries = comp[table]
                keys = entries[0].keys() if entries else []
                comp[table] = {k: _column([e[k] for e in entries]) for k in keys}
    return rows


def _column(values: List[Any]) -> Any:
    """A table column as a numpy array, or as the list itself where its entries differ in
    shape (a column of per-row lists of varying length)."""
    try:
        return np.asarray(values)
    except ValueError:
        return values
