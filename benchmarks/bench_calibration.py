"""Calibration of the reported standard errors: z = error / reported std over noise seeds (issue 21).

Run ``python -m benchmarks.bench_calibration [--seeds N] [--methods M ...]``.

For every method × FRF kind on an SDOF driving point (1 % noise, 12 lines per half-power
band, ±4 widths), and on a two-mode, three-channel case (mobility, 10 lines per band;
channel 0 the driving point), prints per quantity the standard deviation of z (1 when
calibrated), its mean (0 when unbiased) and the fraction of 2σ intervals that hold the
truth (0.954). The modal constant has one standard error for the complex value: its RMS
|z| (1 when calibrated). The same cases as ``tests/calibration/test_calibration.py``, which asserts
SD within ±0.15, |mean| ≤ 0.3 and coverage within ±0.044 at 200 seeds.

Works on any checkout whose ``modal.identify`` has the methods (run with
``PYTHONPATH=<other checkout>`` to measure another version).
"""
from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import modal
from modal.synthetic import add_noise, modal_frf, sdof_frf

METHODS = ("halfpower", "circle", "nls", "global")
KINDS = ("receptance", "mobility", "accelerance")
REAL = ("natural_frequency_hz", "damping_ratio", "stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
SHORT = {"natural_frequency_hz": "fn", "damping_ratio": "ζ", "stiffness_n_per_m": "k", "damping_n_s_per_m": "c",
         "mass_kg": "m", "modal_constant": "A"}


def sdof_case(kind: str):
    """SDOF driving point: m = 2 kg, k = 1e5 N/m, ζ = 0.01, 12 lines per half-power band, ±4 widths."""
    m, k, zeta = 2.0, 1e5, 0.01
    wn = np.sqrt(k / m)
    fn = wn / (2 * np.pi)
    c = 2 * zeta * m * wn
    df = 2 * zeta * fn / 12
    f = fn + (np.arange(-48, 49) + 0.37) * df
    truth = {"natural_frequency_hz": [fn], "damping_ratio": [zeta], "modal_constant": [[1 / m]],
             "stiffness_n_per_m": [k], "damping_n_s_per_m": [c], "mass_kg": [m]}
    return sdof_frf(f, m, k, c, kind=kind), truth


def multi_case(kind: str = "mobility"):
    """Two modes (100, 180 Hz), three channels, channel 0 the driving point (constants 1/m_r)."""
    fn, zeta, mass = np.array([100.0, 180.0]), np.array([0.01, 0.0055]), np.array([2.0, 1.25])
    const = np.array([1 / mass, [0.35, -0.6], [-0.5, 0.45]])
    df = 2 * zeta[0] * fn[0] / 10
    f = np.arange(94.0, 187.0, df) + 0.37 * df
    frf = modal_frf(f, fn, zeta, const, kind=kind, response_points=["1", "2", "3"], reference_points=["1", "1", "1"])
    wn = 2 * np.pi * fn
    truth = {"natural_frequency_hz": fn, "damping_ratio": zeta, "modal_constant": const.T,
             "stiffness_n_per_m": mass * wn**2, "damping_n_s_per_m": 2 * zeta * mass * wn, "mass_kg": mass}
    return frf, truth


def z_scores(method: str, clean, truth, seeds: int) -> dict[str, np.ndarray]:
    """z of every quantity over the seeds (all modes; k, c, m of channel 0, the driving point)."""
    out: dict[str, list] = {q: [] for q in (*REAL, "modal_constant")}
    options = {"max_order": 12} if method == "global" else {}
    for seed in range(seeds):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.identify(add_noise(clean, 0.01, seed=seed), method, **options)
        if len(result) != len(truth["natural_frequency_hz"]):
            continue
        for r, mode in enumerate(result):
            for q in REAL:
                value = np.atleast_1d(getattr(mode, q))[0]
                out[q].append((value - truth[q][r]) / np.atleast_1d(getattr(mode.std, q))[0])
            const = np.atleast_1d(mode.modal_constant)
            out["modal_constant"].extend(np.abs(const - truth["modal_constant"][r]) / np.atleast_1d(mode.std.modal_constant))
    return {q: np.asarray(v, float) for q, v in out.items()}


def row(method: str, label: str, z: dict[str, np.ndarray], seconds: float) -> str:
    cells = []
    for q in REAL:
        a = z[q][np.isfinite(z[q])]
        cells.append(f"{np.std(a):.2f} / {np.mean(a):+.2f} / {np.mean(np.abs(a) <= 2):.3f}" if a.size else "n/a")
    a = z["modal_constant"][np.isfinite(z["modal_constant"])]
    cells.append(f"{np.sqrt(np.mean(a**2)):.2f}" if a.size else "n/a")
    return f"| {method} | {label} | " + " | ".join(cells) + f" | {seconds:.1f} |"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_calibration", description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=200, help="noise seeds per cell (default 200)")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    parser.add_argument("--no-multi", action="store_true", help="skip the two-mode three-channel case")
    args = parser.parse_args(argv)
    print(f"Calibration over {args.seeds} seeds, 1 % noise: per quantity SD of z / mean of z / 2σ coverage "
          "(calibrated: 1 / 0 / 0.954); A: RMS |z| of the complex modal constant; CPU s for the cell.\n")
    print("| method | case | fn | ζ | k | c | m | A (RMS) | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    cases = [(f"SDOF {kind}", lambda kind=kind: sdof_case(kind)) for kind in KINDS]
    if not args.no_multi:
        cases.append(("2 modes × 3 channels, mobility", multi_case))
    for method in args.methods:
        for label, make in cases:
            clean, truth = make()
            start = time.process_time()
            try:
                z = z_scores(method, clean, truth, args.seeds)
            except Exception as exc:  # noqa: BLE001 - a method that fails on a case is reported
                print(f"| {method} | {label} | failed: {type(exc).__name__}: {str(exc)[:60]} | | | | | | |")
                continue
            print(row(method, label, z, time.process_time() - start), flush=True)


if __name__ == "__main__":
    main()
