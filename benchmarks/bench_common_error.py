"""The excitation's shared error of a force-window hammer test: calibration of the modal constants and run time.

Run ``python -m benchmarks.bench_common_error [--records N] [--cases 8 16]``.

Two modes seen by two accelerometers (12 and 31 Hz), hits of 100 N at 1024 Hz, force noise 0.2 N per sample,
response noise 1e-4 of its peak, a force window (``modal.estimate_frf(..., impact=True, window="force")``) and
:func:`modal.identify`'s defaults. Case ``8``: 4 hits, 8 s records (a 138-sample force window: 552 rows of 4097
lines); case ``16``: 3 hits, 16384-sample records (266 samples: 798 rows of 8193 lines). Prints whether the
estimate carries the shared error (``NoiseModel.relative_error``), the root mean square of |error| / reported
error of the driving point's constants over the records and both modes (calibrated: 1), and the median CPU
seconds of the estimate and of the identification (the first record left out: imports).
"""
from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import modal
from modal.synthetic_time import DigitalModes, hammer_force

SAMPLE_RATE_HZ = 1024.0
SYSTEM = DigitalModes([12.0, 31.0], [0.02, 0.015], [[1.0, 0.6], [0.5, -0.8]], SAMPLE_RATE_HZ)
#: case: (hit times, s; record duration, s)
CASES = {"8": ([0.5, 8.5, 16.5, 24.5], 33.5), "16": ([0.5, 17.5, 34.5], 51.5)}


def constants_errors(hits, duration_s: float, records: int) -> tuple[list[float], list[float], list[float], bool]:
    """(|error| / reported error of the driving point's constants, both modes; CPU s of each estimate; of each
    identification; whether every estimate carried the shared error) over ``records`` draws of the noise, for
    hits at the times ``hits`` (s) in a record of ``duration_s``."""
    n = int(duration_s * SAMPLE_RATE_HZ)
    force = hammer_force(n, SAMPLE_RATE_HZ, hits, amplitude_n=100.0)
    response = SYSTEM.respond(force)
    ratios, estimating, identifying, carried = [], [], [], True
    for seed in range(records):
        rng = np.random.default_rng(seed)
        measured = response + 1e-4 * np.abs(response).max() * rng.standard_normal(response.shape)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start = time.process_time()
            estimate = modal.estimate_frf(force + 0.2 * rng.standard_normal(n), measured, SAMPLE_RATE_HZ,
                                          impact=True, window="force")
            middle = time.process_time()
            result = modal.identify(estimate)
            estimating.append(middle - start)
            identifying.append(time.process_time() - middle)
        carried &= estimate.noise_model.relative_error is not None
        for k, fn in enumerate(SYSTEM.natural_frequency_hz):
            mode = min(result, key=lambda m: abs(m.natural_frequency_hz - fn))
            error = np.atleast_1d(mode.modal_constant)[0] - SYSTEM.modal_constant[0, k]
            ratios.append(abs(error) / np.atleast_1d(mode.std.modal_constant)[0])
    return ratios, estimating, identifying, carried


def run(case: str, records: int) -> str:
    """One line of results for ``case`` over ``records`` draws of the noise."""
    ratios, estimating, identifying, carried = constants_errors(*CASES[case], records)
    return (f"case {case}: shared error {'carried' if carried else 'not carried'}, constants' |e|/s RMS "
            f"{np.sqrt(np.mean(np.square(ratios))):.2f}, estimate {np.median(estimating[1:]):.3f} CPU-s, "
            f"identify {np.median(identifying[1:]):.3f} CPU-s (medians over {records - 1} records)")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_common_error",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=20, help="draws of the noise per case (default 20)")
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    args = parser.parse_args(argv)
    for case in args.cases:
        print(run(case, args.records), flush=True)


if __name__ == "__main__":
    main()
