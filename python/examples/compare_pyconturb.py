"""Sylva's wind field next to PyConTurb's, on the same grid and the same model.

Both tools synthesise Gaussian turbulence by the spectral representation (Veers 1988): for
every frequency a coherence matrix is factored and random phases are coloured by it.
PyConTurb does it on a y–z plane of points for wind-turbine loads; Sylva on a 3-D grid for
a forest. Here both are given one model:

* mean wind: power law, Ū = 10 m/s at the grid's height z = 20 m;
* spectrum: the Kaimal form of IEC 61400-1 (ed. 3) with L = (8.1, 2.7, 0.66) · 0.7 z — Sylva's
  ``spectrum="kaimal"``, PyConTurb's ``kaimal_spectrum``;
* σ_u : σ_v : σ_w = 2.5 : 2.0 : 1.25 U*, U* = 1 m/s (PyConTurb's ``constant_sig``);
* coherence: Davenport's exp(−C f Δy / Ū) with Sylva's constants C_y for u, v, w (eq. 5 of
  the paper), given to PyConTurb as a coherence callable.

The grid is a lateral line of points (one height, one x: the plane PyConTurb simulates)
over a loop of ``frames`` steps of ``dt``. Both fields are then measured with one estimator
(scipy's Welch, Hann window, half overlap) against the model: σ, the spectrum in log bands
and the co-coherence at several separations, plus the time each tool took. Run:

    pip install pyconturb matplotlib scipy   # next to the sylva_wind wheel
    python python/examples/compare_pyconturb.py [--points 64] [--frames 4096] [--plot out.png]

It prints a Markdown table (the one in docs/guide/python.md) and, with ``--plot``, draws the
spectra and coherences.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy import signal

import sylva_wind as sw

COMPONENTS = ("u", "v", "w")
U_STAR = 1.0
SIGMA = (2.5 * U_STAR, 2.0 * U_STAR, 1.25 * U_STAR)
Z = 20.0
U_MEAN = 10.0
# Davenport decay constants per lateral separation (Sylva's defaults, the paper's Table 2).
C_Y = tuple(c["cy"] for c in sw.default_params()["coherence"])


def kaimal(comp: int, f: np.ndarray) -> np.ndarray:
    """One-sided Kaimal spectrum (IEC 61400-1 ed. 3), (m/s)²/Hz."""
    length = 0.7 * min(Z, 60.0) * (8.1, 2.7, 0.66)[comp]
    x = f * length / U_MEAN
    return SIGMA[comp] ** 2 * 4.0 * x / (1.0 + 6.0 * x) ** (5.0 / 3.0) / f


def davenport(comp: int, f: np.ndarray, dy: float) -> np.ndarray:
    return np.exp(-C_Y[comp] * f * dy / U_MEAN)


def sylva_field(
    ys: np.ndarray, frames: int, dt: float, seed: int, method: str = "auto"
) -> tuple[np.ndarray, float]:
    """(t, component, point) from sylva_wind, and the seconds it took. ``auto`` picks the
    separable synthesis for this grid (exponential coherence on a line: its Cholesky factor
    is an AR(1) recursion, O(n) a frequency); ``cholesky`` factors the dense matrix at
    every frequency, as PyConTurb does."""
    start = time.perf_counter()
    field = sw.generate(
        "breeze",
        xs=[0.0],
        ys=ys.tolist(),
        heights=(Z,),
        frames=frames,
        dt=dt,
        seed=seed,
        method=method,
        u_star=U_STAR,
        spectrum="kaimal",
        profile={"kind": "power", "u_ref": U_MEAN, "z_ref": Z, "alpha": 0.2},
    )
    took = time.perf_counter() - start
    return field.data[:, :, 0, :, 0].astype(np.float64), took


def pyconturb_field(ys: np.ndarray, frames: int, dt: float, seed: int) -> tuple[np.ndarray, float]:
    """(t, component, point) from PyConTurb with the same model, and the seconds it took."""
    from pyconturb import gen_spat_grid, gen_turb
    from pyconturb.sig_models import constant_sig
    from pyconturb.spectral_models import kaimal_spectrum
    from pyconturb.wind_profiles import power_profile

    spat = gen_spat_grid(ys, [Z])

    def coherence(icomp, freq, r, **_):
        # The f = 0 line is never synthesised (no mean in the fluctuations); coherence 0
        # there keeps PyConTurb's Cholesky factor of that (unused) line defined.
        coh = np.exp(-C_Y[icomp] * freq * np.abs(r) / U_MEAN)
        return np.where(freq > 0.0, coh, 0.0)

    start = time.perf_counter()
    turb = gen_turb(
        spat,
        T=frames * dt,
        nt=frames,
        coh_model=coherence,
        wsp_func=power_profile,
        sig_func=constant_sig,
        spec_func=kaimal_spectrum,
        u_ref=U_MEAN,
        z_ref=Z,
        alpha=0.2,
        sig_vals=SIGMA,
        comps=(0, 1, 2),
        seed=seed,
        nf_chunk=64,
    )
    took = time.perf_counter() - start
    out = np.empty((frames, 3, len(ys)))
    for c, name in enumerate(COMPONENTS):
        out[:, c, :] = turb[[f"{name}_p{i}" for i in range(len(ys))]].to_numpy()
    return out, took


def measure(data: np.ndarray, ys: np.ndarray, dt: float, segment: int, steps=(1, 2, 4, 8)):
    """σ, spectrum and co-coherence of a (t, component, point) field against the model."""
    fs = 1.0 / dt
    n = data.shape[2]
    res = {}
    for c in range(3):
        rec = data[:, c, :] - data[:, c, :].mean(axis=0)
        f, pxx = signal.welch(rec, fs=fs, window="hann", nperseg=segment, axis=0)
        # Leave out DC and Nyquist: neither tool puts energy there.
        f, pxx = f[1:-1], pxx[1:-1].mean(axis=1)
        model = kaimal(c, f)
        # Variance the loop can hold (frequencies from 1/T to Nyquist).
        ff = np.arange(1, data.shape[0] // 2) / (data.shape[0] * dt)
        sigma_discrete = np.sqrt(np.sum(kaimal(c, ff)) / (data.shape[0] * dt))
        # Spectrum in log bands: ratio measured / model; error in dB.
        edges = np.geomspace(f[0], f[-1], 13)
        band = np.digitize(f, edges[1:-1])
        ratio = np.array([pxx[band == b].mean() / model[band == b].mean() for b in range(12)])
        coh = []
        for s in steps:
            if s >= n:
                continue
            cxy = np.zeros_like(f, dtype=complex)
            sxx = np.zeros_like(f)
            syy = np.zeros_like(f)
            for i in range(n - s):
                _, p = signal.csd(rec[:, i], rec[:, i + s], fs=fs, window="hann", nperseg=segment)
                _, a = signal.welch(rec[:, i], fs=fs, window="hann", nperseg=segment)
                _, b = signal.welch(rec[:, i + s], fs=fs, window="hann", nperseg=segment)
                cxy += p[1:-1]
                sxx += a[1:-1]
                syy += b[1:-1]
            cocoh = cxy.real / np.sqrt(sxx * syy)
            dy = s * (ys[1] - ys[0])
            target = davenport(c, f, dy)
            # Where the model's coherence is worth measuring (above 0.05).
            keep = target > 0.05
            coh.append(
                {
                    "dy": dy,
                    "f": f,
                    "measured": cocoh,
                    "model": target,
                    "rms": float(np.sqrt(np.mean((cocoh[keep] - target[keep]) ** 2))),
                }
            )
        res[COMPONENTS[c]] = {
            "sigma": float(rec.std()),
            "sigma_discrete": float(sigma_discrete),
            "mean": float(data[:, c, :].mean()),
            "f": f,
            "psd": pxx,
            "model": model,
            "band_db": 10.0 * np.log10(ratio),
            "coherence": coh,
        }
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=64, help="points along y (default 64)")
    ap.add_argument("--spacing", type=float, default=2.0, help="m between points (default 2)")
    ap.add_argument("--frames", type=int, default=4096, help="frames in the loop (default 4096)")
    ap.add_argument("--dt", type=float, default=0.1, help="s between frames (default 0.1)")
    ap.add_argument("--segment", type=int, default=512, help="Welch segment (default 512)")
    ap.add_argument("--seed", type=int, default=1, help="first seed (default 1)")
    ap.add_argument("--seeds", type=int, default=4, help="seeds to average over (default 4)")
    ap.add_argument("--plot", help="write a figure of spectra and coherences (needs matplotlib)")
    args = ap.parse_args()

    ys = np.arange(args.points) * args.spacing
    tools = {
        "Sylva": sylva_field,
        "Sylva (cholesky)": lambda *a: sylva_field(*a, method="cholesky"),
        "PyConTurb": pyconturb_field,
    }
    runs = {name: [] for name in tools}  # per seed: (measures, seconds)
    for seed in range(args.seed, args.seed + args.seeds):
        for name, make in tools.items():
            data, took = make(ys, args.frames, args.dt, seed)
            runs[name].append((measure(data, ys, args.dt, args.segment), took))

    def avg(name, get):
        return float(np.mean([get(m) for m, _ in runs[name]]))

    print(
        f"{args.points} points {args.spacing:g} m apart along y at z = {Z:g} m, "
        f"{args.frames} frames of {args.dt:g} s, Ū = {U_MEAN:g} m/s, U* = {U_STAR:g} m/s; "
        f"means over seeds {args.seed}…{args.seed + args.seeds - 1}\n"
    )
    print("| | " + " | ".join(tools) + " |")
    print("|---" * (len(tools) + 1) + "|")
    print(
        "| synthesis time, s (median) | "
        + " | ".join(f"{np.median([t for _, t in runs[n]]):.3f}" for n in tools)
        + " |"
    )
    first = runs["Sylva"][0][0]
    for comp in COMPONENTS:
        print(
            f"| σ_{comp} / the loop's model σ ({first[comp]['sigma_discrete']:.3f} m/s) | "
            + " | ".join(f"{avg(n, lambda m: m[comp]['sigma'] / m[comp]['sigma_discrete']):.3f}"
                         for n in tools)
            + " |"
        )
        # Bias of the spectrum: the band errors averaged over seeds, the largest of them.
        print(
            f"| spectrum of {comp}: largest mean band error, dB (12 log bands) | "
            + " | ".join(
                f"{np.max(np.abs(np.mean([m[comp]['band_db'] for m, _ in runs[n]], axis=0))):.2f}"
                for n in tools
            )
            + " |"
        )
        for i, row in enumerate(first[comp]["coherence"]):
            print(
                f"| co-coherence of {comp} at Δy = {row['dy']:g} m: RMS error | "
                + " | ".join(f"{avg(n, lambda m: m[comp]['coherence'][i]['rms']):.3f}"
                             for n in tools)
                + " |"
            )
    measured = {name: runs[name][0][0] for name in tools}

    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 3, figsize=(13, 7), constrained_layout=True)
        styles = {"Sylva": "-", "PyConTurb": "--"}
        fields = styles
        for c, comp in enumerate(COMPONENTS):
            ax = axes[0, c]
            for name in fields:
                r = measured[name][comp]
                ax.loglog(r["f"], r["f"] * r["psd"], styles[name], label=name)
            r = measured["Sylva"][comp]
            ax.loglog(r["f"], r["f"] * r["model"], "k:", label="Kaimal model")
            ax.set(title=f"{comp}: f·S(f), seed {args.seed}", xlabel="f, Hz", ylabel="(m/s)²")
            ax.legend()
            ax = axes[1, c]
            for i, row in enumerate(measured["Sylva"][comp]["coherence"][:3]):
                colour = f"C{i}"
                for name in fields:
                    rr = measured[name][comp]["coherence"][i]
                    ax.plot(rr["f"], rr["measured"], styles[name], color=colour,
                            label=f"{name}, Δy {row['dy']:g} m")
                ax.plot(row["f"], row["model"], ":", color="k")
            ax.set(title=f"{comp}: co-coherence (dotted: Davenport)", xlabel="f, Hz",
                   xlim=(0, 1.0), ylim=(-0.2, 1.0))
            ax.legend(fontsize=7)
        fig.savefig(args.plot, dpi=90)
        print(f"\nwrote {args.plot}")


if __name__ == "__main__":
    main()
