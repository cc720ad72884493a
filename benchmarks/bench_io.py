"""Read (and write) time of a 1000-channel x 2001-line FRF in each file format.

Run ``python -m benchmarks.bench_io`` (``--runs N`` repetitions per format,
default 3; ``--channels``/``--lines`` to change the size; ``--formats`` to pick).
The FRF is synthetic (5 modes, 0..1000 Hz in 0.5 Hz steps, so UFF ASCII keeps the
axis exactly); files go to a temporary folder that is removed afterwards.

Columns: file size, write time (one run), read time as the median of the runs
(min–max in brackets), and whether the read-back FRF equals the original bit
for bit (UFF ASCII: 12 significant digits by the format).
"""
from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from modal import identify
from modal.io import read_frf, write_frf
from modal.synthetic import modal_frf

FORMATS = {  # name: (file suffix, write_frf format)
    "csv": (".csv", "csv"),
    "hdf5": (".h5", "hdf5"),
    "mat v5": (".mat", "mat"),
    "mat v7.3": (".mat", "mat73"),
    "uff 58b": (".uff", "uff58b"),
    "uff 58": (".uff", "uff58"),
}


def make_frf(n_channels: int, n_lines: int):
    """Synthetic accelerance: 5 modes, random complex modal constants per channel."""
    freq = 0.5 * np.arange(n_lines)
    rng = np.random.default_rng(0)
    const = rng.standard_normal((n_channels, 5)) + 0.1j * rng.standard_normal((n_channels, 5))
    return modal_frf(freq, [51.5, 142.2, 278.7, 460.4, 687.2], [0.01, 0.012, 0.008, 0.01, 0.015], const,
                     kind="accelerance", response_points=[f"{i + 1}+Z" for i in range(n_channels)],
                     reference_points=["1+Z"] * n_channels)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="read repetitions per format (median reported)")
    parser.add_argument("--channels", type=int, default=1000)
    parser.add_argument("--lines", type=int, default=2001)
    parser.add_argument("--formats", nargs="+", choices=sorted(FORMATS), default=list(FORMATS))
    args = parser.parse_args(argv)

    frf = make_frf(args.channels, args.lines)
    print(f"FRF: {frf.n_channels} channels x {frf.n_freq} lines, {args.runs} read runs per format")
    print(f"{'format':<10} {'size MB':>8} {'write s':>8} {'read s (median)':>16} {'[min-max]':>16}  exact")
    with tempfile.TemporaryDirectory() as folder:
        for name in args.formats:
            suffix, fmt = FORMATS[name]
            path = Path(folder) / f"bench_{fmt}{suffix}"
            t0 = time.perf_counter()
            write_frf(frf, path, format=fmt)
            t_write = time.perf_counter() - t0
            times = []
            for _ in range(args.runs):
                t0 = time.perf_counter()
                back = read_frf(path)
                times.append(time.perf_counter() - t0)
            exact = back == frf
            size = path.stat().st_size / 1e6
            spread = f"[{min(times):.2f}-{max(times):.2f}]"
            print(f"{name:<10} {size:8.1f} {t_write:8.2f} {statistics.median(times):16.2f} {spread:>16}  "
                  f"{'yes' if exact else 'no (12 digits)' if fmt == 'uff58' else 'NO'}")
            if fmt == "hdf5":  # read then fit, end to end, as `python -m modal fit` does
                fits = []
                for _ in range(args.runs):
                    t0 = time.perf_counter()
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        result = identify(read_frf(path))
                    fits.append(time.perf_counter() - t0)
                fit_line = (f"read + identify (nls), hdf5: {statistics.median(fits):.2f} s median "
                            f"[{min(fits):.2f}-{max(fits):.2f}], {len(result)} modes")
            path.unlink()
    if "hdf5" in args.formats:
        print(fit_line)


if __name__ == "__main__":
    main()
