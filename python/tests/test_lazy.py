"""A field made lazily, a block of x-columns at a time with Dask: the in-memory field's
records, bit for bit, and on a cluster a field larger than any worker's memory."""

import json
import shutil

import numpy as np
import pytest

import sylva_wind as sw

dask = pytest.importorskip("dask")
xr = pytest.importorskip("xarray")

# Several heights need the reference coherence speed, which the separable method makes
# exactly (the pair mean needs the embedding, which holds every point at once).
GRID = dict(nx=40, ny=6, spacing=3.0, heights=(8.0, 15.0, 22.0), frames=128, dt=0.1)


def test_a_lazy_field_is_the_eager_one_block_for_block():
    kw = dict(GRID, seed=5, coherence_speed="reference")
    lazy = sw.generate_lazy("strong", chunks=16, **kw)
    eager = sw.generate("strong", **kw).to_xarray()
    assert lazy.wind.data.chunks[4] == (16, 16, 8)
    # Nothing is synthesised until asked: the blocks are tasks.
    assert len(dict(lazy.wind.data.dask)) >= 3
    for block, x0 in zip(lazy.wind.data.blocks, (0, 16, 32)):
        got = np.asarray(block.compute())
        want = eager.wind.values[..., x0 : x0 + got.shape[-1]]
        assert got.dtype == np.float32
        assert np.array_equal(got.view(np.uint32), want.view(np.uint32)), f"block at x {x0}"
    xr.testing.assert_identical(lazy.compute(), eager)


def test_a_lazy_field_needs_a_method_that_makes_a_block_alone():
    # The paper's pair-mean speed on several heights: the embedding only, refused.
    with pytest.raises(ValueError, match="separable"):
        sw.generate_lazy("strong", **GRID)
    with pytest.raises(ValueError, match="chunks"):
        sw.generate_lazy("strong", chunks=0, coherence_speed="reference", **GRID)
    # One height: separable, whatever the coherence speed.
    one = dict(GRID, heights=(20.0,))
    assert sw.generate_lazy("strong", chunks=8, **one).wind.shape == (128, 3, 1, 6, 40)


def _reset_peak():
    """Start this process's peak resident memory afresh (Linux: VmHWM; a worker forked from
    a large process would otherwise report its parent's peak)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass  # not allowed here: the peak then counts from the worker's start


def _peak_rss_bytes():
    """This process's peak resident memory since the last reset, bytes."""
    with open("/proc/self/status") as f:
        line = next(l for l in f if l.startswith("VmHWM:"))
    return int(line.split()[1]) * 1024


def test_two_workers_write_a_field_four_times_their_memory_to_zarr(tmp_path):
    distributed = pytest.importorskip("distributed")
    pytest.importorskip("zarr")
    limit = 300 * 2**20
    # 3 200 columns × 64 × 2 heights × 3 components × 256 frames of float32: 1.26 GB, 4.2 ×
    # the limit, in blocks of 64 columns (25 MB).
    nx = 3200
    kw = dict(nx=nx, ny=64, spacing=4.0, heights=(10.0, 20.0), frames=256, dt=0.1)
    kw.update(seed=9, coherence_speed="reference")
    size = nx * 64 * 2 * 3 * 256 * 4
    assert size >= 4 * limit
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, memory_limit=limit, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        ds = sw.generate_lazy("strong", chunks=64, **kw)
        client.run(_reset_peak)
        ds.to_zarr(tmp_path / "big.zarr", consolidated=False, compute=True)
        peaks = list(client.run(_peak_rss_bytes).values())
    print(f"\npeak memory per worker: {[round(p / 2**20) for p in peaks]} MiB, limit {limit / 2**20:.0f} MiB, field {size / 2**20:.0f} MiB")
    assert len(peaks) == 2 and all(p < limit for p in peaks), peaks
    # The store holds the field: its last block is the one made here alone.
    back = xr.open_zarr(tmp_path / "big.zarr", consolidated=False)
    assert back.wind.shape == (256, 3, 2, 64, nx)
    model = dict(sw.default_params("strong"), coherence_speed="reference")
    grid = dict(
        xs=[4.0 * i for i in range(nx)], ys=[4.0 * j for j in range(64)], zs=[10.0, 20.0],
        frames=256, dt=0.1,
    )
    want = sw._block(json.dumps(model), json.dumps(grid), 9, "auto", nx - 64, nx)
    got = back.wind.isel(x=slice(nx - 64, nx)).values
    del back
    # The store goes now (pytest keeps the last runs' temporary folders): CI's disk is small.
    shutil.rmtree(tmp_path / "big.zarr")
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))
