"""Global identification against sdypy-EMA: error against the truth and the Cramér–Rao bound, and time.

Run ``python -m benchmarks.bench_global [--runs N] [--seeds N]``. The case is the
issue's: 60 response points × 2 references (120 channels), 4000 lines, 12 modes in
band (a close pair among them) and one above it, 0.5 % noise of each channel's peak.
modalbal: ``identify(frf, "global")`` (pLSCF over the orders, stabilisation,
selection, joint refinement with residual terms). sdypy-EMA (optional, when
importable): LSCF at order 60 on all 120 channels as outputs of one reference,
``select_closest_poles`` with the true frequencies (it is told where the modes
are), then ``get_constants('lsfd')``. Timings are medians of ``--runs`` runs; the
errors are the largest over the modes and the median of |error|/σ_CR, where σ_CR
is the Cramér–Rao standard error of the full model at the truth, as the joint
refinement reports it (its covariance is the inverse Fisher information).
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


def time_runs(fn, runs):
    times, out = [], None
    for _ in range(runs):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), max(times), out


def errors(found_f, found_z, sigma_f=None, sigma_z=None):
    in_band = FN < BAND[1]
    idx = [int(np.argmin(np.abs(found_f - f))) for f in FN[in_band]]
    fe = np.abs(found_f[idx] / FN[in_band] - 1)
    ze = np.abs(found_z[idx] / ZETA[in_band] - 1)
    missed = int(np.sum(fe > 3e-3))
    z = None
    if sigma_f is not None:
        z = (np.abs(found_f[idx] - FN[in_band]) / sigma_f[idx], np.abs(found_z[idx] - ZETA[in_band]) / sigma_z[idx])
    return fe.max(), ze.max(), missed, z


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=3, help="noise seeds for the error columns")
    args = parser.parse_args(argv)
    clean, noisy = make_case()
    print(f"Case: {noisy.n_channels} channels (60 outputs x 2 references), {noisy.n_freq} lines, "
          f"{int(np.sum(FN < BAND[1]))} modes in band (close pair 150/151.5 Hz), 0.5 % noise; "
          f"median of {args.runs} runs [min-max]; errors over {args.seeds} noise seeds (worst).\n")
    print("| tool | time s | max fn err | max ζ err | modes missed | median fn err/σ_CR | median ζ err/σ_CR |")
    print("|---|---|---|---|---|---|---|")

    def ours(data):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return modal.identify(data, "global")

    t, lo, hi, _ = time_runs(lambda: ours(noisy), args.runs)
    rows = []
    for seed in range(args.seeds):
        _, data = make_case(seed)
        result = ours(data)
        f = np.array([m.natural_frequency_hz for m in result])
        z = np.array([m.damping_ratio for m in result])
        sf = np.array([m.std.natural_frequency_hz for m in result])
        sz = np.array([m.std.damping_ratio for m in result])
        rows.append(errors(f, z, sf, sz))
    zf = np.concatenate([r[3][0] for r in rows])
    zz = np.concatenate([r[3][1] for r in rows])
    print(f"| modalbal global | {t:.3f} [{lo:.3f}-{hi:.3f}] | {max(r[0] for r in rows):.1e} | "
          f"{max(r[1] for r in rows):.1e} | {max(r[2] for r in rows)} | {np.median(zf):.2f} | {np.median(zz):.2f} |")
    try:
        import sdypy.EMA as ema
    except Exception:  # noqa: BLE001
        print("| sdypy-EMA | not installed (optional: pip install sdypy-EMA) | | | | | |")
        return

    def peer(data):
        model = ema.Model(data.channels, data.frequency_hz, lower=BAND[0], upper=BAND[1], pol_order_high=60,
                          frf_form="accelerance")
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.get_poles(show_progress=False)
            model.select_closest_poles(list(FN[FN < BAND[1]]))
            model.get_constants(method="lsfd")
        return model

    try:
        t, lo, hi, _ = time_runs(lambda: peer(noisy), args.runs)
        rows = []
        for seed in range(args.seeds):
            _, data = make_case(seed)
            model = peer(data)
            rows.append(errors(np.asarray(model.nat_freq, float), np.asarray(model.nat_xi, float)))
        print(f"| sdypy-EMA {getattr(ema, '__version__', '?')} LSCF+LSFD (order 60, told the frequencies) | "
              f"{t:.3f} [{lo:.3f}-{hi:.3f}] | {max(r[0] for r in rows):.1e} | {max(r[1] for r in rows):.1e} | "
              f"{max(r[2] for r in rows)} | | |")
    except Exception as exc:  # noqa: BLE001
        print(f"| sdypy-EMA | failed: {type(exc).__name__}: {str(exc)[:80]} | | | | | |")


if __name__ == "__main__":
    main()
