"""The global method on the measured free-free beam (data/real, three transfer FRFs of a roving-hammer test).

Prints the synthesis error |model − data| / |data| over 20–990 Hz (median and 90th percentile, the figures
tests/modal/global_/test_global.py holds to 4 % and 9 %) and every mode with its flags, lines per half-power
bandwidth and relative damping error.

Run: ``OPENBLAS_NUM_THREADS=1 python -m benchmarks.bench_beam``
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

import modal

REAL = Path(__file__).resolve().parent.parent / "data" / "real"


def beam_frf() -> modal.FRF:
    """The three beam files as one FRF: response at point 1, hammer at points 1, 2, 3 (0–1000 Hz, 1 Hz lines)."""
    channels = [modal.read_frf(p, frequency_step=1.0, kind="accelerance")
                for p in sorted(REAL.glob("pyuff_meas_point_*.txt"))]
    return modal.FRF(channels[0].frequency_hz, np.array([c.response for c in channels]), kind="accelerance",
                     response_points=["1"] * 3, reference_points=["1", "2", "3"])


def main() -> None:
    frf = beam_frf()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the flags are printed below
        result = modal.identify(frf, method="global")
    f = frf.frequency_hz
    band = (f >= 20) & (f <= 990)
    error = np.abs(result.synthesize(f[band]).channels - frf.channels[:, band]) / np.abs(frf.channels[:, band])
    print(f"synthesis error 20-990 Hz: median {100 * np.median(error):.2f} %, "
          f"90th percentile {100 * np.percentile(error, 90):.2f} %")
    print("| f_n Hz | ζ | lines per bandwidth | std ζ / ζ | flags |\n|---|---|---|---|---|")
    for mode in result:
        print(f"| {mode.natural_frequency_hz:.2f} | {mode.damping_ratio:.4f} | {mode.lines_per_bandwidth:.3f} | "
              f"{mode.std.damping_ratio / mode.damping_ratio:.3f} | {', '.join(mode.flags) or '-'} |")


if __name__ == "__main__":
    main()
