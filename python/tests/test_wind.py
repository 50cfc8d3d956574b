"""The Python package against the library's promises and the command line: shapes and
coordinates, determinism by seed, the same field bit for bit as `sylva wind generate`,
errors with the command line's messages, round trips through every writable format, and
the spectrum's area equal to the variance (Parseval)."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import sylva_wind as sw

#: The repository's root.
ROOT = Path(__file__).resolve().parents[2]

#: The command-line binary (the CI builds it and points here).
SYLVA = os.environ.get("SYLVA_BIN", str(Path(__file__).resolve().parents[2] / "target/debug/sylva"))


def small(seed=3, **kw):
    return sw.generate("strong", nx=6, ny=5, spacing=3.0, heights=(10.0, 20.0), frames=64, seed=seed, **kw)


def test_shape_coordinates_and_units():
    f = small()
    assert f.data.shape == (64, 3, 2, 5, 6)
    assert f.data.dtype == np.float32
    assert np.allclose(f.x, 3.0 * np.arange(6)) and np.allclose(f.y, 3.0 * np.arange(5))
    assert np.allclose(f.z, [10.0, 20.0]) and np.allclose(f.t, 0.1 * np.arange(64))
    # The mean wind blows along +x and grows with height (the log profile).
    u = f.data[:, 0]
    assert u[:, 1].mean() > u[:, 0].mean() > 0.0
    assert abs(f.data[:, 2].mean()) < 0.2 * u.mean()


def test_same_seed_same_bits_other_seed_other_field():
    a, b, c = small(3), small(3), small(4)
    assert a.data.tobytes() == b.data.tobytes()
    assert not np.array_equal(a.data, c.data)


def test_parameters_keep_their_rust_names():
    p = sw.default_params("breeze")
    assert {"u_star", "direction_deg"} <= set(p)
    f = small(u_star=0.8)
    assert f.params["u_star"] == 0.8
    with pytest.raises(ValueError, match="unknown wind parameter"):
        small(ustar=0.8)


def cli(*args):
    return subprocess.run([SYLVA, *args], capture_output=True, text=True)


def test_the_same_field_as_the_command_line_bit_for_bit(tmp_path):
    args = ["wind", "generate", "--preset", "strong", "--nx", "8", "--ny", "4", "--spacing", "2",
            "--heights", "10,20", "--frames", "64", "--seed", "5", "--method", "embedding"]
    for name in ("cli.npy", "cli.swf"):
        r = cli(*args, "--out", str(tmp_path / name))
        assert r.returncode == 0, r.stderr
    c = sw.read(tmp_path / "cli.npy")  # f32 as synthesised (.swf quantises to 16 bits)
    p = sw.generate(params=c.params, xs=c.x, ys=c.y, heights=c.z, frames=64, dt=c.grid["dt"],
                    seed=5, method="embedding")
    assert p.data.tobytes() == c.data.tobytes()
    # Written as .swf by each, the same file.
    sw.write(p, tmp_path / "py.swf")
    assert (tmp_path / "py.swf").read_bytes() == (tmp_path / "cli.swf").read_bytes()


def test_the_defaults_are_the_command_lines(tmp_path):
    # The README's example against `sylva wind generate` with the same preset, grid and seed
    # and nothing else: Python defaulted to the reference coherence speed, the command line
    # to the pair mean, and the fields differed by up to 35 m/s.
    for preset, extra in (("strong", []), ("breeze", ["--spectrum", "kaimal"])):
        r = cli("wind", "generate", "--preset", preset, "--nx", "8", "--ny", "4", "--spacing", "4",
                "--heights", "10,20", "--frames", "64", "--seed", "7", *extra,
                "--out", str(tmp_path / f"{preset}.npy"))
        assert r.returncode == 0, r.stderr
        c = sw.read(tmp_path / f"{preset}.npy")
        kw = {"spectrum": "kaimal"} if extra else {}
        p = sw.generate(preset, nx=8, ny=4, spacing=4, heights=(10, 20), frames=64, seed=7, **kw)
        assert p.params == c.params
        assert p.data.tobytes() == c.data.tobytes()


def test_bad_grid_numbers_and_methods_are_named_as_the_command_line_names_them():
    # They spoke serde: "grid: expected value at line 1 column 894", "= 0" for nx = -1, and a
    # column number for an unknown method.
    for kw, named in (({"dt": float("nan")}, "dt = nan"), ({"nx": -1}, "nx = -1"),
                      ({"spacing": 0.0}, "spacing = 0.0"), ({"heights": (10.0, float("inf"))}, "heights"),
                      ({"method": "fft"}, "method `fft`: one of auto, separable"),
                      ({"u_star": float("nan")}, "u_star = nan"),
                      ({"profile": {"kind": "log", "z0": float("inf"), "d": 10.0}}, "profile.z0 = inf")):
        with pytest.raises(ValueError) as e:
            sw.generate("breeze", **{"nx": 4, "ny": 4, "frames": 16, **kw})
        assert named in str(e.value), str(e.value)
        assert "line 1 column" not in str(e.value)


def test_a_field_larger_than_memory_is_refused_before_synthesis():
    # 2000 × 2000 points × 2048 frames: about 100 GB, refused by the command line's memory
    # check instead of attempted.
    with pytest.raises(ValueError) as e:
        sw.generate("breeze", nx=2000, ny=2000, frames=2048)
    assert "GB" in str(e.value) and "free memory" in str(e.value), str(e.value)


def test_errors_carry_the_command_lines_message(tmp_path):
    with pytest.raises(ValueError) as e:
        sw.generate("strong", nx=4, ny=4, frames=16, u_star=-1.0)
    r = cli("wind", "generate", "--preset", "strong", "--u-star", "-1", "--nx", "4", "--ny", "4",
            "--frames", "16", "--out", str(tmp_path / "x.swf"))
    assert r.returncode != 0
    assert str(e.value) in r.stderr, (str(e.value), r.stderr)
    with pytest.raises(ValueError, match="No such file"):
        sw.read(tmp_path / "missing.swf")
    bad = tmp_path / "bad.swf"
    bad.write_bytes(b"SWF1 not a field")
    with pytest.raises(ValueError):
        sw.read(bad)


def test_round_trips_through_swf_and_npy_and_bts_is_written(tmp_path):
    f = small()
    sw.write(f, tmp_path / "f.npy")
    g = sw.read(tmp_path / "f.npy")
    assert g.data.tobytes() == f.data.tobytes()
    assert g.params == f.params and g.grid == f.grid
    # .swf keeps 16 bits per value over each component's range: half a step at most.
    sw.write(f, tmp_path / "f.swf")
    g = sw.read(tmp_path / "f.swf")
    for c in range(3):
        step = (f.data[:, c].max() - f.data[:, c].min()) / 65534.0
        assert np.abs(g.data[:, c] - f.data[:, c]).max() <= 0.51 * step + 1e-6, c
    assert g.params == f.params and g.grid == f.grid
    sw.write(f, tmp_path / "f.bts", bts_x_index=2)
    assert (tmp_path / "f.bts").stat().st_size > f.data[:, :, :, :, 2].nbytes // 2
    with pytest.raises(ValueError, match=".swf, .npy or .bts"):
        sw.write(f, tmp_path / "f.txt")


def test_spectrum_area_is_the_variance():
    # Parseval: the one-sided PSD integrates to the record's variance.
    f = sw.generate("strong", nx=1, ny=1, heights=(20.0,), frames=2048, seed=9)
    freqs, p = sw.psd(f, "u", segment=256)
    record = f.data[:, 0, 0, 0, 0].astype(np.float64)
    area = np.sum(p) * (freqs[1] - freqs[0])
    assert abs(area / record.var() - 1.0) < 0.1, (area, record.var())
    with pytest.raises(ValueError, match="segment"):
        sw.psd(f, "u", segment=3)


def test_xarray_dataset_when_available():
    xr = pytest.importorskip("xarray")
    f = small()
    ds = f.to_xarray()
    assert set(ds.data_vars) == {"wind"}
    assert ds["wind"].dims == ("time", "component", "z", "y", "x")
    assert isinstance(ds, xr.Dataset) and ds.attrs["seed"] == 3
    # Components by label; coordinates with their units.
    assert np.array_equal(ds.wind.sel(component="w").values, f.data[:, 2])
    assert ds.time.attrs["units"] == "s" and ds.x.attrs["units"] == "m"
    assert ds.wind.attrs["units"] == "m/s"


def test_one_layout_in_memory_in_zarr_and_read_back(tmp_path):
    # A store written by the command line, opened by xarray itself, holds the array that
    # `read(...).to_xarray()` gives, on the same dimensions and coordinates.
    xr = pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    out = tmp_path / "f.zarr"
    r = cli("wind", "generate", "--preset", "breeze", "--nx", "40", "--ny", "6", "--heights",
            "20", "--frames", "64", "--seed", "5", "--out", str(out))
    assert r.returncode == 0, r.stderr
    ours = sw.read(out).to_xarray()
    theirs = xr.open_zarr(out, consolidated=False)
    assert theirs["wind"].dims == ours["wind"].dims
    assert np.array_equal(theirs["wind"].values, ours["wind"].values)
    for c in ("time", "z", "y", "x"):
        assert np.array_equal(theirs[c].values, ours[c].values), c
        assert theirs[c].attrs["units"] == ours[c].attrs["units"], c


def test_stats_are_the_command_lines(tmp_path):
    # The same tables as `sylva wind stats --json` on the same file, value for value.
    import json

    out = tmp_path / "s.npy"
    r = cli("wind", "generate", "--preset", "breeze", "--nx", "8", "--ny", "8", "--heights", "20",
            "--frames", "512", "--seed", "2", "--out", str(out))
    assert r.returncode == 0, r.stderr
    r = cli("wind", "stats", "--json", str(out))
    assert r.returncode == 0, r.stderr
    want = json.loads(r.stdout)
    got = sw.stats(sw.read(out))
    assert len(got) == len(want) == 1
    for g, w in zip(got[0]["components"], want[0]["components"]):
        assert g["component"] == w["component"] and g["sigma"] == w["sigma"]
        for table in ("spectrum", "coherence"):
            for key, column in g[table].items():
                assert list(column) == [row[key] for row in w[table]], (table, key)
    # The spectrum follows the model: the measured σ is within a few expected scatters.
    u = got[0]["components"][0]
    assert abs(u["sigma_error"]) < 4 * u["sigma_scatter"] + 0.02
    with pytest.raises(ValueError, match="outside the grid"):
        sw.stats(sw.read(out), height=3)


def test_every_model_parameter_and_value_carries_the_rust_documentation():
    docs = sw.PARAMETER_DOCS
    for preset in sw.PRESETS:
        params = sw.default_params(preset)
        for name, value in params.items():
            assert docs.get(name), f"no documentation for `{name}`"
            if isinstance(value, dict):  # the profile: its kind and fields
                assert docs.get(f"{name}.kind={value['kind']}"), value
                for field in value:
                    if field != "kind":
                        assert docs.get(f"{name}.{field}"), f"{name}.{field}"
            elif isinstance(value, list):  # per component u, v, w
                for field in value[0]:
                    assert docs.get(f"{name}[].{field}"), f"{name}[].{field}"
    for spectrum in ("paper", "kaimal", "von-karman"):
        assert docs.get(f"spectrum={spectrum}")
    for speed in ("reference", "pair-mean"):
        assert docs.get(f"coherence_speed={speed}")
    # The text is the Rust doc comment itself.
    source = (ROOT / "crates" / "sylva-wind" / "src" / "params.rs").read_text()
    assert "/// Friction velocity U* in m/s (> 0)." in source
    assert docs["u_star"].startswith("Friction velocity U* in m/s (> 0).")
    assert "power" in sw.describe("profile") and "z0" in sw.describe("profile")
    with pytest.raises(ValueError, match="unknown wind parameter `u_stra`"):
        sw.describe("u_stra")
