"""Min-max balancing: cutting-plane LPs (the toolkit) against one LP on a fixed polygon.

Run ``python -m benchmarks.bench_influence``.  Random complex influence matrices
(n readings x p planes, seed 0).  The fixed polygon replaces ``|v| <= t`` by K
half-planes per reading (K = 64 and 512); its worst residual can exceed the optimum by
up to ``1 / cos(pi / K) - 1`` (1.2e-3 and 1.9e-5).  Columns: wall time (median of 3),
worst residual relative to the cutting-plane answer, and the cutting-plane certificate
(relative gap between its true worst residual and the LP lower bound).
"""
from __future__ import annotations

import math
import statistics
import time

import numpy as np
from scipy.optimize import linprog

from balancer.influence import correction


def polygon_minmax(a: np.ndarray, b: np.ndarray, k: int) -> np.ndarray:
    """One LP with k fixed directions per reading; returns u."""
    n, p = a.shape
    phi = np.arange(k) * 2 * math.pi / k
    rot = np.exp(-1j * phi)[:, None, None] * a[None, :, :]  # (k, n, p)
    rows = np.concatenate([rot.real, -rot.imag, -np.ones((k, n, 1))], axis=2).reshape(k * n, 2 * p + 1)
    rhs = -(np.exp(-1j * phi)[:, None] * b[None, :]).real.reshape(-1)
    cost = np.zeros(2 * p + 1)
    cost[-1] = 1.0
    x = linprog(cost, A_ub=rows, b_ub=rhs, bounds=[(None, None)] * (2 * p + 1), method="highs").x
    return x[:p] + 1j * x[p:2 * p]


def _median(func, runs=3):
    times, out = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = func()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main(argv: list[str] | None = None) -> None:
    rng = np.random.default_rng(0)
    print(f"{'n x p':>10} {'method':<22} {'time [s]':>9} {'worst / cutting-plane':>22} {'gap':>9}")
    for n, p in [(10, 3), (40, 4), (200, 8), (1000, 20)]:
        a = rng.normal(size=(n, p)) + 1j * rng.normal(size=(n, p))
        b = rng.normal(size=n) + 1j * rng.normal(size=n)
        t_cp, res = _median(lambda: correction(a, b, method="minmax"))
        ref = res.worst_residual
        print(f"{n:>5} x {p:<3} {'cutting planes':<22} {t_cp:>9.4f} {1.0:>22.7f} {res.minmax_gap:>9.1e}")
        for k in (64, 512):
            if n * k > 300_000:
                continue
            t_poly, u = _median(lambda: polygon_minmax(a, b, k), 1)
            worst = float(np.max(np.abs(a @ u + b)))
            print(f"{'':>10} {f'polygon K={k}':<22} {t_poly:>9.4f} {worst / ref:>22.7f} {'':>9}")
        t_ls, ls = _median(lambda: correction(a, b))
        print(f"{'':>10} {'least squares':<22} {t_ls:>9.4f} {ls.worst_residual / ref:>22.7f} {'':>9}")


if __name__ == "__main__":
    main()
