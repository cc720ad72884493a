"""Every public function of the drive study documents each of its parameters (numpydoc)."""
from __future__ import annotations

import inspect

import pytest

from support.numpydoc_sections import documented

from balancer import drive
from balancer.drive import report as drive_report
from balancer.drive import shaft


@pytest.mark.parametrize("module", [drive, shaft, drive_report])
def test_every_public_parameter_is_documented(module):
    for name in module.__all__:
        obj = getattr(module, name)
        if not callable(obj) or isinstance(obj, type):
            continue
        doc = inspect.getdoc(obj) or ""
        assert doc, f"{module.__name__}.{name} has no docstring"
        # an entry of the numpydoc Parameters section, not a substring of the text
        entries = documented(doc)
        for parameter in inspect.signature(obj).parameters:
            assert parameter in entries, f"{module.__name__}.{name}: parameter {parameter!r} is not documented"
