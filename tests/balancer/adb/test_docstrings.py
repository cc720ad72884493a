"""Every public ADB function documents each of its parameters; every result dataclass
documents each of its fields (numpydoc, checked with inspect as python-control does)."""
from __future__ import annotations

import dataclasses
import importlib
import inspect

import numpy as np
import pytest
from support.numpydoc_sections import documented

MODULES = ["parameters", "equations", "linear", "equilibria", "stability", "speed", "integrate", "analysis", "simulate", "drag", "studies", "plots", "verdict", "montecarlo"]


def _public(module_name):
    module = importlib.import_module(f"balancer.adb.{module_name}")
    for name in getattr(module, "__all__", []):
        obj = getattr(module, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            yield f"{module_name}.{name}", obj


ITEMS = [item for module in MODULES for item in _public(module)]


@pytest.mark.parametrize("qualified, obj", ITEMS, ids=[q for q, _ in ITEMS])
def test_parameters_and_fields_are_documented(qualified, obj):
    doc = inspect.getdoc(obj) or ""
    assert doc, f"{qualified} has no docstring"
    if inspect.isfunction(obj):
        names = [p for p in inspect.signature(obj).parameters if p not in ("self", "cls")]
        entries = documented(doc)
    elif dataclasses.is_dataclass(obj):
        names = [f.name for f in dataclasses.fields(obj)]
        entries = documented(doc, ("Parameters", "Attributes"))
    else:
        return
    # an entry in the Parameters/Attributes section, not a substring of the text (a
    # one-letter name such as k, n or e occurs in any docstring)
    missing = [name for name in names if name not in entries]
    assert not missing, f"{qualified}: undocumented {missing}"


def test_the_section_reader_wants_an_entry():
    doc = """Spring with stiffness k and mass m.

    Parameters
    ----------
    m : float
        Mass, kg; the stiffness k follows from it.
    a, b : float
        Two lengths, m.
    **kwargs
        Passed on.

    Returns
    -------
    k : float
    """
    assert documented(doc) == {"m", "a", "b", "kwargs"}


def test_result_dataclasses_hold_only_archivable_values():
    # results go to a generic HDF5 layer: numbers, strings, bools, arrays, tuples, nested dataclasses
    from balancer.adb import ADBParameters, find_equilibria, simulate, stable_speed_intervals

    p = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
    results = [stable_speed_intervals(p, 5 * p.natural_frequency_rad_s), find_equilibria(p, 200.0)[0],
               simulate(p, 200.0, 0.2, n_samples=51)]

    def check(value):
        if dataclasses.is_dataclass(value):
            for field in dataclasses.fields(value):
                check(getattr(value, field.name))
        elif isinstance(value, tuple):
            for item in value:
                check(item)
        else:
            assert isinstance(value, (int, float, str, bool, np.ndarray, np.integer, np.floating)), type(value)

    for result in results:
        assert dataclasses.is_dataclass(result)
        check(result)
