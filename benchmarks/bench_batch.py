"""Batches of FRF files (``modal batch``): files per second against one process looping, scaling with workers.

Run ``python -m benchmarks.bench_batch [--files N] [--lines N] [--runs N] [--workers 1 2 4]``.
The files are UFF 58 driving-point mobilities with two modes and 0.1 % noise, fitted with the
default options (method auto: band-wise NLS). Rows:

- one process looping: :func:`modal.batch.task.fit_one` over the files in this process (no Dask,
  no archive): the baseline; and the same loop writing the same archive at the end (one
  :func:`modal.archive.write_archive` of every result: what the batch's archive costs per file);
- ``fit_files(..., workers=N, out=...)`` on the embedded LocalCluster (start of the cluster,
  hashing, fitting, per-file parts, archive and table; a fresh archive every run);
- the rerun of the same batch (every file reused: no cluster is started);
- a scheduler with N workers already running (``client=`` an open client): the batch without the
  cluster's start, as on an existing cluster.

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
from modal.batch.task import fit_one
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
    print(f"\nload average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
