"""Batches of FRF files (``modal batch``): files per second against one process looping, scaling with workers.

Run ``python -m benchmarks.bench_batch [--files N] [--lines N] [--runs N] [--workers 1 2 4]``.
The files are UFF 58 driving-point mobilities with two modes and 0.1 % noise, fitted with the
default options (method auto: band-wise NLS). Rows:

- one process looping: :func:`modal.batch.fitone.fit_one` over the files in this process (no Dask,
  no archive): the baseline; and the same loop writing the same archive at the end (one
  :func:`modal.archive.write_archive` of every result: what the batch's archive costs per file);
- ``fit_files(..., workers=N, out=...)`` on the embedded LocalCluster (start of the cluster,
  hashing, fitting, per-file parts, archive and table; a fresh archive every run);
- the rerun of the same batch (every file reused: no cluster is started);
- a scheduler with N workers already running (``client=`` an open client): the batch without the
  cluster's start, as on an existing cluster.

Then the ball-balancer studies of :mod:`balancer.adb.montecarlo` (Monte-Carlo probability of
stable operation, chunked stability map) in this process against a local cluster with the same
chunks (same numbers, checked).

Times are medians of ``--runs`` runs with the [min–max] spread; files/s = files / median. The
machine's cores and load are printed: workers beyond the free cores cannot scale.
"""
from __future__ import annotations

import argparse
import logging
import os
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from modal.archive import write_archive
from modal.batch import fit_files, find_files
from modal.batch.cluster import default_workers
from modal.batch.fitone import fit_one
from modal.fitting import FitOptions
from modal.io import write_frf
from modal.synthetic import add_noise, modal_frf


def make_files(folder: Path, n: int, n_lines: int) -> list[str]:
    rng = np.random.default_rng(0)
    freq = np.linspace(20.0, 200.0, n_lines)
    for index in range(n):
        fn = [60.0 + 20.0 * rng.random(), 130.0 + 20.0 * rng.random()]
        frf = modal_frf(freq, fn, [0.02, 0.02], [1.0, 0.7], kind="mobility", response_points=["1+Z"],
                        reference_points=["1+Z"])
        write_frf(add_noise(frf, 1e-3, seed=index), folder / f"f{index:04d}.uff")
    return find_files(folder)


def timed(fn, runs: int) -> tuple[float, float, float]:
    samples = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - start)
    return statistics.median(samples), min(samples), max(samples)


def row(label: str, n_files: int, t: tuple[float, float, float], base: float) -> str:
    med, lo, hi = t
    return f"| {label} | {med:.2f} [{lo:.2f}–{hi:.2f}] | {n_files / med:.1f} | {base / med:.2f} |"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_batch", description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=200, help="files per batch (default 200)")
    parser.add_argument("--lines", type=int, default=801, help="frequency lines per file (default 801)")
    parser.add_argument("--runs", type=int, default=3, help="repetitions per row (default 3)")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2, 4], help="local workers (default 1 2 4)")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    logging.getLogger("distributed").setLevel(logging.ERROR)
    print(f"cores available: {default_workers()}, load average before: "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "files"
        folder.mkdir()
        files = make_files(folder, args.files, args.lines)
        n = len(files)
        options = FitOptions()
        loop = timed(lambda: [fit_one(p, options) for p in files], args.runs)
        print(f"\n{n} files, {args.lines} lines, 2 modes each (UFF 58, method auto → nls)\n")
        print("| run | wall time (s) | files/s | speed-up vs loop |")
        print("|---|---|---|---|")
        print(row("one process looping (fit_one, no archive)", n, loop, loop[0]))
        counter = iter(range(10**6))

        def loop_archive() -> None:
            fits = [fit_one(p, options) for p in files]
            write_archive(Path(tmp) / f"loop{next(counter)}.h5", {"files": fits})

        print(row("one process looping + one write_archive of all results", n, timed(loop_archive, args.runs),
                  loop[0]))

        def fresh(workers: int) -> None:
            out = Path(tmp) / f"run{next(counter)}.h5"
            result = fit_files(folder, out=out, workers=workers)
            assert result.fitted == n, result.failed

        for workers in args.workers:
            print(row(f"local cluster, {workers} worker(s), incl. its start", n, timed(lambda: fresh(workers),
                                                                                       args.runs), loop[0]))
        out = Path(tmp) / "rerun.h5"
        first = timed(lambda: fit_files(folder, out=out, workers=args.workers[-1]), 1)
        rerun = timed(lambda: fit_files(folder, out=out), args.runs)
        assert fit_files(folder, out=out).reused == n
        print(row(f"rerun, every file reused (first run {first[0]:.2f} s)", n, rerun, loop[0]))
        from distributed import Client, LocalCluster

        for workers in args.workers:
            with LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None,
                              silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
                def running() -> None:
                    target = Path(tmp) / f"run{next(counter)}.h5"
                    assert fit_files(folder, out=target, client=client).fitted == n

                print(row(f"running scheduler + {workers} worker(s) (client=)", n, timed(running, args.runs),
                          loop[0]))
    studies(args.runs, args.workers)
    print(f"\nload average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


def studies(runs: int, worker_counts: list[int]) -> None:
    """Monte-Carlo stability probability and a chunked stability map, here and on local clusters."""
    from distributed import Client, LocalCluster

    from balancer.adb import ADBParameters, ParameterStd
    from balancer.adb.montecarlo import chunked_stability_map, stability_probability

    params = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
    wn = params.natural_frequency_rad_s
    std = ParameterStd(k=200.0, c=1.0, M=0.02)
    speeds = np.linspace(0.5, 6.0, 50) * wn
    values = np.linspace(1.0, 60.0, 400)

    def mc(client=None):
        return stability_probability(params, std, speeds, 2000, seed=0, client=client, chunk_size=250)

    def smap(client=None):
        return chunked_stability_map(params, speeds, "c", values, client=client, chunk_size=25)

    print("\nBall-balancer studies: Monte-Carlo P(stable) (2000 draws x 50 speeds, chunks of 250) and a "
          "stability map (400 damping values x 50 speeds, chunks of 25)\n")
    print("| run | Monte-Carlo (s) | stability map (s) | same numbers |")
    print("|---|---|---|---|")
    ref_mc, ref_map = mc(), smap()
    t_mc, t_map = timed(mc, runs), timed(smap, runs)
    print(f"| this process | {t_mc[0]:.2f} [{t_mc[1]:.2f}–{t_mc[2]:.2f}] | {t_map[0]:.2f} [{t_map[1]:.2f}–{t_map[2]:.2f}] "
          "| (reference) |")
    for workers in worker_counts:
        with LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None,
                          silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
            same = (np.array_equal(mc(client).stable_count, ref_mc.stable_count)
                    and np.array_equal(smap(client).stability_class, ref_map.stability_class))
            t_mc, t_map = timed(lambda: mc(client), runs), timed(lambda: smap(client), runs)
            print(f"| running scheduler + {workers} worker(s) | {t_mc[0]:.2f} [{t_mc[1]:.2f}–{t_mc[2]:.2f}] | "
                  f"{t_map[0]:.2f} [{t_map[1]:.2f}–{t_map[2]:.2f}] | {'yes' if same else 'NO'} |")


if __name__ == "__main__":
    sys.exit(main())
