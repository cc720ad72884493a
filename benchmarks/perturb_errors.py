"""Perturbation check of the test suite: scale one method's reported standard errors and see what fails.

Run ``python -m benchmarks.perturb_errors [--factor 2] [--tests PATH ...] [--methods M ...]``
(from the repository root; a few minutes).

For every method and every standard error it reports (natural frequency, damping
ratio, modal constant, k, c, m, and all of them together), the suite runs in a
subprocess with ``modal.identify`` wrapped so that this method's ``std`` fields are
multiplied by ``--factor``. A perturbation is *caught* when at least one test fails;
the table lists the first failing test of each. (Issue 21: on main, scaling
half-power's errors by 2, NLS's k, c, m by 2, its modal constant by 3 or the circle's
frequency or stiffness by 2 left all identification tests green.)

The wrapping is this module used as a pytest plugin (``-p benchmarks.perturb_errors``):
with ``MODALBAL_PERTURB=method:quantity:factor`` set, ``pytest_configure`` replaces
``modal.identify`` before any test module imports it.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
METHODS = ("halfpower", "circle", "nls", "global")
QUANTITIES = ("natural_frequency_hz", "damping_ratio", "modal_constant", "stiffness_n_per_m", "damping_n_s_per_m",
              "mass_kg")
ENV = "MODALBAL_PERTURB"
DEFAULT_TESTS = ("tests/calibration/test_calibration.py",)


def _scale(value, factor):
    import numpy as np

    out = np.asarray(value) * factor
    return out if out.ndim else out[()].item()


def scaled_result(result, method: str, quantities, factor: float):
    """``result`` with the ``std`` fields ``quantities`` of its modes times ``factor`` (if it is ``method``'s)."""
    if result.method != method:
        return result
    modes = []
    for mode in result.modes:
        std = dataclasses.replace(mode.std, **{q: _scale(getattr(mode.std, q), factor) for q in quantities})
        modes.append(dataclasses.replace(mode, std=std))
    return dataclasses.replace(result, modes=tuple(modes))


def pytest_configure(config) -> None:  # pragma: no cover - runs inside the perturbed subprocess
    """Wrap ``modal.identify`` when ``MODALBAL_PERTURB`` is set."""
    spec = os.environ.get(ENV)
    if not spec:
        return
    method, quantity, factor = spec.split(":")
    quantities = QUANTITIES if quantity == "all" else (quantity,)
    import modal

    original = modal.identify

    def perturbed(*args, **kwargs):
        return scaled_result(original(*args, **kwargs), method, quantities, float(factor))

    modal.identify = perturbed


def run(method: str, quantity: str, factor: float, tests) -> tuple[str | None, float]:
    """Run ``tests`` (only those naming ``method``) with the perturbation; (first failing test or None, s)."""
    env = {**os.environ, ENV: f"{method}:{quantity}:{factor}", "MPLBACKEND": "Agg"}
    command = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "-p", "benchmarks.perturb_errors",
               "-rf", "-k", method, *tests]
    start = time.perf_counter()
    proc = subprocess.run(command, cwd=ROOT, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    failed = re.findall(r"^FAILED (\S+)", proc.stdout, flags=re.M)
    if failed:
        return failed[0], seconds
    if proc.returncode not in (0, 5):  # 5: no test selected
        return f"(pytest exit {proc.returncode})", seconds
    return None, seconds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.perturb_errors", description=__doc__.splitlines()[0])
    parser.add_argument("--factor", type=float, default=2.0)
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    parser.add_argument("--tests", nargs="+", default=list(DEFAULT_TESTS))
    args = parser.parse_args(argv)
    print(f"Each reported standard error times {args.factor:g}, one method and quantity at a time; "
          f"tests run: {' '.join(args.tests)} (those naming the method, stopping at the first failure).\n")
    print("| method | std scaled | caught by (first failing test) | s |")
    print("|---|---|---|---|")
    missed = 0
    for method in args.methods:
        for quantity in (*QUANTITIES, "all"):
            failed, seconds = run(method, quantity, args.factor, args.tests)
            missed += failed is None
            print(f"| {method} | {quantity} | {failed or '**nothing failed**'} | {seconds:.0f} |", flush=True)
    print(f"\n{missed} perturbation(s) not caught.")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
