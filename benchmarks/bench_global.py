"""Global identification against sdypy-EMA: error against the truth and the Cramér–Rao bound, time, and scaling.

Run ``python -m benchmarks.bench_global [--runs N] [--seeds N] [--scaling] [--plot PATH]``. Two cases:

* the benchmark case: 60 response points × 2 references (120 channels), 4000 lines over 20-400 Hz, 12 modes
  in band (a close pair among them) and one above it, 0.5 % noise of each channel's peak;
* the wide-band case: 60 × 2 on 4000 lines of 0.5 Hz (0.5-2000 Hz), 13 modes in band, among them an
  under-resolved one (47.3 Hz, ζ 0.42 %: 0.40 Hz half-power bandwidth on 0.5 Hz lines), a close pair at
  300/302.5 Hz and a weakly driven mode, and two modes above the band leaking into it.

modalbal: ``identify(frf, "global")`` (pLSCF over the orders, stabilisation, selection, joint refinement with
residual terms). sdypy-EMA (optional, when importable): LSCF at order 60 on all 120 channels as outputs of
one reference, ``select_closest_poles`` with the true frequencies (it is told where the modes are), then
``get_constants('lsfd')``. The two tools run interleaved (ours, the peer's, ours, ...) so that both see the
same load; timings are medians of ``--runs`` runs. The errors are the largest over the in-band modes, the
count of in-band modes missed (none within 0.3 %) and of modes reported that match none of the structure's
(in band, or above it within 4 of their standard errors), and the median of |error|/σ_CR, σ_CR the
Cramér–Rao standard error of the full model as the joint refinement reports it.

``--scaling``: time and peak memory of ``identify(frf, "global")`` over channels × lines × references up to 999
channels (333 outputs × 3 references) × 8192 lines, each point in a fresh process (Linux: the peak resident
memory of the call, VmHWM reset before it, above the resident memory before it, with the FRF and every module
loaded), with the slope of log time against log(channels × lines), and a plot of time against problem size
(``--plot``).
"""
from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import time
import warnings

import numpy as np

import modal

FN = np.array([35.0, 62.0, 90.0, 118.0, 150.0, 151.5, 190.0, 230.0, 265.0, 300.0, 340.0, 380.0, 430.0])
ZETA = np.array([0.02, 0.015, 0.012, 0.01, 0.01, 0.01, 0.008, 0.008, 0.007, 0.006, 0.006, 0.005, 0.005])
BAND = (20.0, 400.0)
#: the wide-band case: an under-resolved first mode, a close pair, a weakly driven mode (655 Hz), two above
WIDE_FN = np.array([47.3, 118., 205., 300., 302.5, 410., 540., 655., 790., 930., 1080., 1240., 1420., 2150., 2500.])
WIDE_ZETA = np.array([0.0042, 0.012, 0.01, 0.008, 0.008, 0.008, 0.007, 0.007, 0.006, 0.006, 0.006, 0.005, 0.005,
                      0.005, 0.005])
WIDE_BAND = (0.5, 2000.0)


def make_case(seed: int = 0, n_out: int = 60, n_lines: int = 4000):
    rng = np.random.default_rng(7)
    refs = [0, 1]
    phi = rng.normal(size=(n_out, FN.size))
    phi[refs] = rng.choice([-1, 1], size=(2, FN.size)) * rng.uniform(0.6, 1.2, size=(2, FN.size))
    phi[refs, 4], phi[refs, 5] = [1.0, 1.0], [1.0, -1.0]  # the close pair: orthogonal participation
    const = np.array([[phi[o, r] * phi[q, r] for r in range(FN.size)] for o in range(n_out) for q in refs])
    f = np.linspace(*BAND, n_lines)
    clean = modal.modal_frf(f, FN, ZETA, const, kind="accelerance",
                            response_points=[str(o) for o in range(n_out) for q in refs],
                            reference_points=[str(q) for o in range(n_out) for q in refs])
    return clean, modal.add_noise(clean, 0.005, seed=seed)


def make_wide_case(seed: int = 0, n_out: int = 60, n_lines: int = 4000, n_refs: int = 2, fn=WIDE_FN,
                   zeta=WIDE_ZETA):
    """The wide-band case (module docstring), with ``n_out`` outputs × ``n_refs`` references on ``n_lines`` lines
    of 0.5 Hz, or over 0.5-2000 Hz for another line count."""
    rng = np.random.default_rng(11)
    refs = list(range(n_refs))
    phi = rng.normal(size=(n_out, fn.size))
    phi[refs] = rng.choice([-1, 1], size=(n_refs, fn.size)) * rng.uniform(0.6, 1.2, size=(n_refs, fn.size))
    if n_refs >= 2:
        phi[refs[:2], 3], phi[refs[:2], 4] = [1.0, 1.0], [1.0, -1.0]  # the close pair: orthogonal participation
    phi[refs, 7] *= 0.2
    const = np.array([[phi[o, r] * phi[q, r] for r in range(fn.size)] for o in range(n_out) for q in refs])
    f = np.linspace(WIDE_BAND[0], WIDE_BAND[1], n_lines)
    clean = modal.modal_frf(f, fn, zeta, const, kind="accelerance",
                            response_points=[str(o) for o in range(n_out) for q in refs],
                            reference_points=[str(q) for o in range(n_out) for q in refs])
    return clean, modal.add_noise(clean, 0.005, seed=seed)


def errors(found_f, found_z, sigma_f=None, sigma_z=None, fn=FN, zeta=ZETA, band=BAND):
    """(max fn error, max ζ error, in-band modes missed, modes matching none, (fn z-scores, ζ z-scores) or None)."""
    in_band = fn < band[1]
    idx = [int(np.argmin(np.abs(found_f - f))) for f in fn[in_band]]
    fe = np.abs(found_f[idx] / fn[in_band] - 1)
    ze = np.abs(found_z[idx] / zeta[in_band] - 1)
    missed = int(np.sum(fe > 3e-3))
    above = fn[~in_band]
    invented = 0
    for j, f in enumerate(found_f):
        if j in idx:
            continue
        width = 4 * sigma_f[j] if sigma_f is not None and np.isfinite(sigma_f[j]) else 0.02 * f
        if not (f > band[1] and above.size and np.min(np.abs(above - f)) <= width):
            invented += 1
    z = None
    if sigma_f is not None:
        z = (np.abs(found_f[idx] - fn[in_band]) / sigma_f[idx], np.abs(found_z[idx] - zeta[in_band]) / sigma_z[idx])
    return fe.max(), ze.max(), missed, invented, z


def ours(data):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return modal.identify(data, "global")


def peer_model(ema, data, fn, band):
    model = ema.Model(data.channels, data.frequency_hz, lower=band[0], upper=band[1], pol_order_high=60,
                      frf_form="accelerance")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.get_poles(show_progress=False)
        model.select_closest_poles(list(fn[fn < band[1]]))
        model.get_constants(method="lsfd")
    return model


def interleaved(functions, runs):
    """Run each function once per round, ``runs`` rounds: (median, min, max) of each one's times."""
    times = [[] for _ in functions]
    for _ in range(runs):
        for k, fn in enumerate(functions):
            start = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - start)
    return [(statistics.median(t), min(t), max(t)) for t in times]


def compare(name, make, fn, zeta, band, runs, seeds, ema):
    _, noisy = make(0)
    functions = [lambda: ours(noisy)]
    if ema is not None:
        functions.append(lambda: peer_model(ema, noisy, fn, band))
    timing = interleaved(functions, runs)
    rows = []
    for seed in range(seeds):
        _, data = make(seed)
        result = ours(data)
        f = np.array([m.natural_frequency_hz for m in result])
        z = np.array([m.damping_ratio for m in result])
        sf = np.array([m.std.natural_frequency_hz for m in result])
        sz = np.array([m.std.damping_ratio for m in result])
        rows.append(errors(f, z, sf, sz, fn, zeta, band))
    zf = np.concatenate([r[4][0] for r in rows])
    zz = np.concatenate([r[4][1] for r in rows])
    t, lo, hi = timing[0]
    print(f"| {name} | modalbal global | {t:.3f} [{lo:.3f}-{hi:.3f}] | {max(r[0] for r in rows):.1e} | "
          f"{max(r[1] for r in rows):.1e} | {max(r[2] for r in rows)} | {max(r[3] for r in rows)} | "
          f"{np.median(zf):.2f} | {np.median(zz):.2f} |")
    if ema is None:
        print(f"| {name} | sdypy-EMA | not installed (optional: pip install sdypy-EMA) | | | | | | |")
        return
    rows = []
    for seed in range(seeds):
        _, data = make(seed)
        model = peer_model(ema, data, fn, band)
        rows.append(errors(np.asarray(model.nat_freq, float), np.asarray(model.nat_xi, float), fn=fn, zeta=zeta,
                           band=band))
    t, lo, hi = timing[1]
    print(f"| {name} | sdypy-EMA {getattr(ema, '__version__', '?')} LSCF+LSFD (order 60, told the frequencies) | "
          f"{t:.3f} [{lo:.3f}-{hi:.3f}] | {max(r[0] for r in rows):.1e} | {max(r[1] for r in rows):.1e} | "
          f"{max(r[2] for r in rows)} | {max(r[3] for r in rows)} | | |")


#: the scaling grid: (outputs, references, lines)
SCALING_GRID = ((12, 1, 1024), (4, 3, 1024), (120, 1, 1024), (40, 3, 1024), (999, 1, 1024), (333, 3, 1024),
                (12, 1, 8192), (40, 3, 8192), (333, 3, 8192))

_SCALING_POINT = """
import sys, time, warnings
import numpy as np
import modal
from benchmarks.bench_global import WIDE_BAND, WIDE_FN, WIDE_ZETA, make_wide_case
n_out, n_refs, n_lines = map(int, sys.argv[1:4])
fn, zeta = WIDE_FN[WIDE_FN > 100], WIDE_ZETA[WIDE_FN > 100]
warnings.simplefilter("ignore")
_, small = make_wide_case(0, n_out=4, n_lines=1024, n_refs=1, fn=fn, zeta=zeta)
modal.identify(small, "global")  # every module imported before the measurement
_, noisy = make_wide_case(0, n_out=n_out, n_lines=n_lines, n_refs=n_refs, fn=fn, zeta=zeta)


def status(field):
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith(field)) / 1e3


with open("/proc/self/clear_refs", "w") as f:
    f.write("5")  # resets the peak resident memory (VmHWM) to the current
before = status("VmRSS:")
start = time.perf_counter()
result = modal.identify(noisy, "global")
elapsed = time.perf_counter() - start
peak = status("VmHWM:")
found = np.array([m.natural_frequency_hz for m in result])
in_band = fn[fn < WIDE_BAND[1]]
hits = sum(np.min(np.abs(found / f - 1)) < 3e-3 for f in in_band)
print(elapsed, peak - before, hits, in_band.size)
"""


def scaling(plot=None):
    """Time and peak memory of identify(frf, "global") over the grid (each point in a fresh process: its peak
    resident memory during the call above the resident memory before it, with the FRF), the slope, the plot."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    print("\n| outputs x references | channels | lines | channels x lines | time s | peak memory MB (above the FRF) "
          "| modes found / in band |")
    print("|---|---|---|---|---|---|---|")
    sizes, times, memory, refs = [], [], [], []
    for n_out, n_refs, n_lines in SCALING_GRID:
        out = subprocess.run([sys.executable, "-c", _SCALING_POINT, str(n_out), str(n_refs), str(n_lines)],
                             capture_output=True, text=True, cwd=root, env={**os.environ}, check=True)
        elapsed, peak, hits, n_in = out.stdout.split()
        size = n_out * n_refs * n_lines
        sizes.append(size)
        times.append(float(elapsed))
        memory.append(max(float(peak), 1.0))
        refs.append(n_refs)
        print(f"| {n_out} x {n_refs} | {n_out * n_refs} | {n_lines} | {size:.2e} | {float(elapsed):.2f} | "
              f"{float(peak):.0f} | {hits} / {n_in} |", flush=True)
    slope_t = np.polyfit(np.log(sizes), np.log(times), 1)[0]
    slope_m = np.polyfit(np.log(sizes), np.log(memory), 1)[0]
    print(f"\nSlope of log time against log(channels x lines): {slope_t:.2f}; of log peak memory: {slope_m:.2f}.")
    if plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        sizes_a, times_a, refs_a = np.array(sizes, float), np.array(times), np.array(refs)
        for n_refs, marker in ((1, "o"), (3, "s")):
            ax.loglog(sizes_a[refs_a == n_refs], times_a[refs_a == n_refs], marker, label=f"{n_refs} reference(s)")
        grid = np.geomspace(sizes_a.min(), sizes_a.max(), 20)
        fit = np.polyfit(np.log(sizes_a), np.log(times_a), 1)
        ax.loglog(grid, np.exp(np.polyval(fit, np.log(grid))), "k--", label=f"slope {fit[0]:.2f}")
        ax.set_xlabel("channels x lines")
        ax.set_ylabel("identify(frf, 'global') time, s")
        ax.legend()
        fig.tight_layout()
        fig.savefig(plot, dpi=100)
        plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=3, help="noise seeds for the error columns")
    parser.add_argument("--scaling", action="store_true", help="time and memory over channels x lines x references")
    parser.add_argument("--plot", default=None, help="with --scaling: write the plot of time against size here")
    args = parser.parse_args(argv)
    try:
        import sdypy.EMA as ema
    except Exception:  # noqa: BLE001
        ema = None
    print(f"Median of {args.runs} interleaved runs [min-max]; errors over {args.seeds} noise seeds (worst); "
          "'invented': reported modes matching none of the structure's.\n")
    print("| case | tool | time s | max fn err | max ζ err | modes missed | invented | median fn err/σ_CR | "
          "median ζ err/σ_CR |")
    print("|---|---|---|---|---|---|---|---|---|")
    compare("benchmark (20-400 Hz)", make_case, FN, ZETA, BAND, args.runs, args.seeds, ema)
    compare("wide band (0.5-2000 Hz)", make_wide_case, WIDE_FN, WIDE_ZETA, WIDE_BAND, args.runs, args.seeds, ema)
    if args.scaling:
        scaling(args.plot)


if __name__ == "__main__":
    main()
