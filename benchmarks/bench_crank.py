"""Exact counterweight optimiser against brute-force (k, r_c, theta) grids.

Run ``python -m benchmarks.bench_crank`` (add ``--full`` for the minute-long
1001 x 1001 grid at 0.1 deg).  Case: seed 000's compressor at 2950 rpm, 1x+2x.

Columns: wall time (median of the runs), the objective the method reports, the
true peak force at the point it picked (exact inner maximum), and that peak's
excess over the exact optimum F*.  A grid's own value can sit below F*
because a coarse angle grid under-reads the side peak near 101 deg.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from balancer.compressor.crank import (
    SliderCrank,
    grid_search_counterweight,
    max_shaking_force,
    optimal_counterweight,
)

SPEED_RPM = 2950.0
MECH = SliderCrank(0.0119, 0.050, 0.096656, 0.148344)
REFERENCE_F_N = 109.522005  # reference note, 6 decimals


def _median_time(func, runs: int):
    times, result = [], None
    for _ in range(runs):
        start = time.perf_counter()
        result = func()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true",
                        help="add the 1001 x 1001 grid at 0.1 deg (about a minute or more)")
    args = parser.parse_args(argv)

    t_exact, opt = _median_time(lambda: optimal_counterweight(MECH, SPEED_RPM), 7)
    f_star = opt.max_force_n
    rows = [("exact (equal-peak root)", "-", "-", t_exact, 7, f_star, f_star)]

    r = MECH.crank_radius_m
    grids = [  # (label, n_k, n_r, theta step deg, runs)
        ("grid", 21, 21, 1.0, 5),
        ("grid", 101, 101, 0.5, 3),
        ("paper-like (k 1e-3, r_c 0.01 mm, 1 deg)", 1001, 1191, 1.0, 1),
        ("grid", 401, 401, 0.1, 1),
    ]
    if args.full:
        grids.append(("grid", 1001, 1001, 0.1, 1))
    for label, n_k, n_r, step_deg, runs in grids:
        ks = np.linspace(0.0, 1.0, n_k)
        radii = np.linspace(0.0, r, n_r) if n_r != 1191 else np.arange(n_r) * 1e-5
        theta = np.deg2rad(np.arange(0.0, 360.0, step_deg))
        t_grid, res = _median_time(
            lambda: grid_search_counterweight(MECH, SPEED_RPM, ks, radii, theta), runs)
        m_c = MECH.rotating_mass_kg + res.k * MECH.reciprocating_mass_kg
        true_peak = max_shaking_force(MECH, SPEED_RPM, m_c, res.counterweight_radius_m)
        rows.append((label, f"{n_k} x {n_r}", f"{step_deg:g}", t_grid, runs, res.max_force_n,
                     true_peak))

    print(f"seed 000 compressor, {SPEED_RPM:g} rpm, harmonics 1x+2x; exact optimum "
          f"alpha* = {opt.balance_fraction:.9f}, F* = {f_star:.9f} N "
          f"(reference {REFERENCE_F_N} N; difference {f_star - REFERENCE_F_N:+.1e} N)")
    header = (f"{'method':<42} {'k x r_c':>12} {'dtheta':>7} {'time [s]':>10} {'runs':>5} "
              f"{'reported F [N]':>15} {'true peak [N]':>14} {'excess [N]':>11}")
    print(header)
    print("-" * len(header))
    for label, grid, step, seconds, runs, reported, true_peak in rows:
        print(f"{label:<42} {grid:>12} {step:>7} {seconds:>10.4f} {runs:>5} {reported:>15.7f} "
              f"{true_peak:>14.7f} {true_peak - f_star:>11.2e}")


if __name__ == "__main__":
    main()
