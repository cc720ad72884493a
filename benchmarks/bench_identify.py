"""Identification benchmark: run time against error, and error against the Cramér–Rao bound.

Run ``python -m benchmarks.bench_identify [--trials N] [--quick]``.

Tables:

1. SDOF receptance, fn = 100 Hz, every method over damping ζ, noise p (σ = p·max|H|)
   and resolution L (lines per half-power bandwidth): median |relative error| of
   ωn and ζ, the same divided by the CRLB (1 = efficient), and µs per fit.
2. 1000 channels × 3 modes × 2001 lines (accelerance, 1 % noise): run time and
   errors per method (sdypy-EMA's LSCF needs 2.8–7 s here; see modal_peers.md).
"""
from __future__ import annotations

import argparse
import platform
import time
import warnings

import numpy as np

import modal
from modal import identify
from modal.model import cramer_rao_sdof
from modal.synthetic import add_noise, modal_frf

METHODS = ("halfpower", "circle", "nls")


def sdof_grid(trials: int, zetas, noises, resolutions):
    rows = []
    fn = 100.0
    for zeta in zetas:
        for p in noises:
            for lines in resolutions:
                bw = 2 * zeta * fn
                df = bw / lines
                half = max(3, 5 / lines) * bw
                errs = {m: [] for m in METHODS}
                times = {m: [] for m in METHODS}
                rng = np.random.default_rng(0)
                crlb = None
                for trial in range(trials):
                    offset = rng.uniform()
                    f = fn + (np.arange(-np.ceil(half / df), np.ceil(half / df) + 1) + offset) * df
                    f = f[f > 0]
                    clean = modal_frf(f, [fn], [zeta], [1.0])
                    frf = add_noise(clean, p, seed=trial) if p > 0 else clean
                    if crlb is None and p > 0:
                        sigma = p * np.abs(clean.response).max()
                        c = cramer_rao_sdof(2 * np.pi * f, 2 * np.pi * fn, zeta, 1.0, 0, sigma, offset=True)
                        crlb = np.array([c[0] / (2 * np.pi * fn), c[1] / zeta])
                    for method in METHODS:
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore")
                            t0 = time.perf_counter()
                            try:
                                mode = identify(frf, method, bands_hz=[(f[0], f[-1])])[0]
                                e = (mode.natural_frequency_hz / fn - 1, mode.damping_ratio / zeta - 1)
                            except modal.ModalError:
                                e = (np.nan, np.nan)
                            times[method].append(time.perf_counter() - t0)
                        errs[method].append(e)
                for method in METHODS:
                    e = np.abs(np.array(errs[method]))
                    med = np.nanmedian(e, axis=0)
                    ratio = med / (0.6745 * crlb) if crlb is not None else [np.nan, np.nan]
                    rows.append((zeta, p, lines, method, med[0], ratio[0], med[1], ratio[1],
                                 1e6 * np.median(times[method])))
    return rows


def many_channels(repeats: int = 3):
    rng = np.random.default_rng(1)
    fn = np.array([50.0, 120.0, 300.0])
    zeta = np.array([0.01, 0.02, 0.03])
    A = rng.standard_normal((1000, 3)) + 0.05j * rng.standard_normal((1000, 3))
    f = np.linspace(0, 400, 2001)
    frf = add_noise(modal_frf(f, fn, zeta, A, kind="accelerance"), 0.01, seed=2)
    rows = []
    for method in METHODS:
        times = []
        for _ in range(repeats):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t0 = time.perf_counter()
                result = identify(frf, method)
                times.append(time.perf_counter() - t0)
        fn_err = max(abs(m.natural_frequency_hz / fn[i] - 1) for i, m in enumerate(result))
        z_err = [abs(m.damping_ratio / zeta[i] - 1) for i, m in enumerate(result)]
        rows.append((method, np.median(times), np.min(times), np.max(times), fn_err, *z_err))
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=50)
    parser.add_argument("--quick", action="store_true", help="smaller grid")
    args = parser.parse_args(argv)
    print(f"# identification benchmark — {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}, numpy {np.__version__}, {time.strftime('%Y-%m-%d')}")
    zetas = (0.01, 0.2) if args.quick else (0.001, 0.01, 0.05, 0.2)
    noises = (0.0, 0.01) if args.quick else (0.0, 0.001, 0.01, 0.05)
    resolutions = (3, 10) if args.quick else (1, 3, 10, 100)
    print(f"\n## SDOF, {args.trials} trials per cell: median |rel. error| and error/CRLB (1 = efficient)\n")
    print("| zeta | noise | L | method | fn err | fn/CRLB | zeta err | zeta/CRLB | us/fit |")
    print("|---|---|---|---|---|---|---|---|---|")
    for row in sdof_grid(args.trials, zetas, noises, resolutions):
        z, p, L, m, fe, fr, ze, zr, us = row
        print(f"| {z:g} | {p:g} | {L:g} | {m} | {fe:.2e} | {fr:.2f} | {ze:.2e} | {zr:.2f} | {us:.0f} |")
    print("\n## 1000 channels x 3 modes x 2001 lines, accelerance, 1 % noise (median of 3 runs)\n")
    print("| method | median s | min s | max s | max fn err | zeta err 1% mode | 2% mode | 3% mode |")
    print("|---|---|---|---|---|---|---|---|")
    for method, med, lo, hi, fe, *ze in many_channels():
        print(f"| {method} | {med:.3f} | {lo:.3f} | {hi:.3f} | {fe:.1e} | " + " | ".join(f"{z:.1e}" for z in ze) + " |")


if __name__ == "__main__":
    main()
