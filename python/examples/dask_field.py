"""A field made lazily on a Dask cluster against the same field made in memory.

    python python/examples/dask_field.py [COLUMNS ...]

For each number of x-columns (default 1600 and 3200; 64 × 2 points a column, 256 frames,
the ``strong`` preset at the reference coherence speed): the eager field in this process
(``generate``, all cores), then the lazy one (``generate_lazy``, blocks of 128 columns) on a
``LocalCluster`` of 2 single-threaded workers with 300 MiB each, reduced to one sum so that
only the synthesis is timed, and written to a Zarr store; prints the times, their ratio and
each worker's peak memory (its process's peak resident set, VmHWM, reset before the
lazy field). Needs the ``distributed``
extra.
"""

import sys
import tempfile
import time

import distributed
import numpy as np

import sylva_wind as sw


def reset_peak():
    """Start this process's peak resident memory afresh (Linux: VmHWM; a worker forked from
    a large process would otherwise report its parent's peak)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass  # not allowed here: the peak then counts from the worker's start


def peak_rss_mib():
    """This process's peak resident memory since the last reset, MiB."""
    with open("/proc/self/status") as f:
        line = next(l for l in f if l.startswith("VmHWM:"))
    return int(line.split()[1]) / 1024


def main(columns):
    for nx in columns:
        kw = dict(nx=nx, ny=64, spacing=4.0, heights=(10.0, 20.0), frames=256, dt=0.1)
        kw.update(seed=9, coherence_speed="reference")
        size = nx * 64 * 2 * 3 * 256 * 4 / 2**20
        t0 = time.perf_counter()
        eager = sw.generate("strong", **kw)
        eager_sum = float(eager.data.sum(dtype=np.float64))
        t_eager = time.perf_counter() - t0
        del eager
        with distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, memory_limit=300 * 2**20, dashboard_address=None
        ) as cluster, distributed.Client(cluster) as client:
            ds = sw.generate_lazy("strong", chunks=128, **kw)
            client.run(reset_peak)
            t0 = time.perf_counter()
            lazy_sum = float(ds.wind.data.sum(dtype=np.float64).compute())
            t_lazy = time.perf_counter() - t0
            with tempfile.TemporaryDirectory() as d:
                t0 = time.perf_counter()
                ds.to_zarr(f"{d}/f.zarr", consolidated=False)
                t_zarr = time.perf_counter() - t0
            peaks = [round(p) for p in client.run(peak_rss_mib).values()]
        assert abs(lazy_sum - eager_sum) <= 1e-9 * abs(eager_sum), (lazy_sum, eager_sum)
        print(
            f"{nx} columns, {size:.0f} MiB: eager {t_eager:.2f} s (one process), "
            f"lazy {t_lazy:.2f} s (2 workers), ratio {t_lazy / t_eager:.2f}; "
            f"to Zarr {t_zarr:.2f} s; worker peaks {peaks} MiB of 300"
        )


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1600, 3200])
