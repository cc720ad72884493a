"""Stress run: the calibration tests catch any reported standard error scaled by 2 or by 0.5 (issue 21).

Each case runs the calibration tests of one method in a subprocess with that method's
errors of one quantity (or all of them) scaled (``benchmarks/perturb_errors.py``); at
least one test must fail. About 4 minutes per factor on two cores.
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from support.paths import ROOT  # noqa: E402
_SPEC = importlib.util.spec_from_file_location("perturb_errors", ROOT / "benchmarks" / "perturb_errors.py")
perturb = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(perturb)


@pytest.mark.stress
@pytest.mark.parametrize("factor", [2.0, 0.5])
@pytest.mark.parametrize("method", perturb.METHODS)
def test_scaled_errors_make_a_calibration_test_fail(method, factor):
    for quantity in (*perturb.QUANTITIES, "all"):
        failed, _ = perturb.run(method, quantity, factor, perturb.DEFAULT_TESTS)
        assert failed is not None, f"{method} {quantity} x{factor}: no test failed"
