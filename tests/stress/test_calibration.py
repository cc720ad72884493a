"""Stress run: the calibration tests catch any reported standard error scaled by 2 or by 0.5 (issue 21).

For each method and factor, every quantity's reported errors (and all of them together)
are scaled the way ``benchmarks/perturb_errors.py`` scales them (``scaled_result`` on what
``modal.identify`` returns), and the calibration tests naming that method
(``tests/calibration/test_calibration.py``, every parametrised cell, as ``pytest -k METHOD``
selects them) run on those results: at least one must fail.

The calibration tests run here in-process on a copy of their module, with ``modal.identify``
replaced by a wrapper that identifies each noisy FRF once per method (the same call, the same
result) and scales a copy of the result for the perturbation under test. Scaling errors does
not change an estimate, so sharing the identifications across perturbations tests the same
thing as the benchmark's one pytest subprocess per perturbation, which repeats every
identification 14 times per method (four minutes per factor on two cores; here about one
calibration run per method).
"""
from __future__ import annotations

import hashlib
import importlib.util
import inspect
import itertools

import pytest

import modal
from support.paths import ROOT


def _load(name: str, path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


perturb = _load("perturb_errors", ROOT / "benchmarks" / "perturb_errors.py")
#: the calibration tests, a copy of their own (its caches are not the default run's)
calibration = _load("stress_calibration_copy", ROOT / "tests" / "calibration" / "test_calibration.py")
#: (method, FRF digest, options) -> the unperturbed result
_IDENTIFIED: dict = {}


def _digest(frf) -> str:
    h = hashlib.sha256()
    for array in (frf.frequency_hz, frf.response):
        h.update(array.tobytes())
    h.update(repr((frf.kind, frf.response_points, frf.reference_points)).encode())
    return h.hexdigest()


def _identify_once(original):
    def identify(frf, method="nls", **options):
        key = (method, _digest(frf), repr(sorted(options.items())))
        if key not in _IDENTIFIED:
            _IDENTIFIED[key] = original(frf, method, **options)
        return _IDENTIFIED[key]

    return identify


_identify = _identify_once(modal.identify)


def _cells(module, method: str):
    """(test function, arguments) of every parametrised cell whose test id names ``method``."""
    for name, func in vars(module).items():
        if not (name.startswith("test_") and inspect.isfunction(func)):
            continue
        grids = []
        for mark in getattr(func, "pytestmark", []):
            if mark.name == "parametrize":
                names = [n.strip() for n in mark.args[0].split(",")] if isinstance(mark.args[0], str) else mark.args[0]
                rows = [row if len(names) > 1 else (row,) for row in mark.args[1]]
                grids.append([dict(zip(names, row)) for row in rows])
        for combination in itertools.product(*grids):
            kwargs = {k: v for part in combination for k, v in part.items()}
            assert set(inspect.signature(func).parameters) == set(kwargs), (name, "takes fixtures")
            if method in name or method in "-".join(map(str, kwargs.values())):
                yield func, kwargs


def first_failure(method: str, quantity: str, factor: float, monkeypatch) -> str | None:
    """The first calibration cell of ``method`` that fails with its ``quantity`` errors × ``factor``."""
    quantities = perturb.QUANTITIES if quantity == "all" else (quantity,)
    monkeypatch.setattr(modal, "identify",
                        lambda *a, **k: perturb.scaled_result(_identify(*a, **k), method, quantities, factor))
    calibration.z_scores.cache_clear()
    try:
        for func, kwargs in _cells(calibration, method):
            try:
                func(**kwargs)
            except AssertionError:
                return f"{func.__name__}{kwargs}"
        return None
    finally:
        calibration.z_scores.cache_clear()
        monkeypatch.undo()


@pytest.mark.stress
@pytest.mark.parametrize("factor", [2.0, 0.5])
@pytest.mark.parametrize("method", perturb.METHODS)
def test_scaled_errors_make_a_calibration_test_fail(method, factor, monkeypatch):
    # the unperturbed calibration must pass, or a failure below would say nothing
    assert first_failure(method, "all", 1.0, monkeypatch) is None, f"{method}: calibration fails unperturbed"
    for quantity in (*perturb.QUANTITIES, "all"):
        assert first_failure(method, quantity, factor, monkeypatch) is not None, f"{method} {quantity} x{factor}"
