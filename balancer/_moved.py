"""Old import paths kept after ``balancer`` was laid out one package per study.

``balancer.crank``, ``balancer.mounts``, ``balancer.crank_plots`` (now under
:mod:`balancer.compressor`), ``balancer.shaft`` and ``balancer.drive_report`` (now
under :mod:`balancer.drive`) keep working: each old path is a tiny module that
calls :func:`alias`, which makes the old name *the same module object* as the new
one (and likewise for a package's submodules, e.g. ``balancer.crank.model``).
So ``from balancer.crank import optimal_counterweight``, monkeypatching through
the old path and archives written before the move (whose ``@__class__`` names
``balancer.crank.model:SliderCrank``) all still work.
"""
from __future__ import annotations

import importlib
import sys

__all__ = ["alias"]


def alias(old_name: str, new_name: str, submodules: tuple[str, ...] = ()) -> None:
    """Register module ``new_name`` (and its ``submodules``) under ``old_name``.

    Parameters
    ----------
    old_name : str
        Dotted name users import (the shim module's ``__name__``).
    new_name : str
        Dotted name of the module's present home.
    submodules : tuple of str
        Submodule names of a package to alias as ``old_name.<sub>`` too.
    """
    module = importlib.import_module(new_name)
    sys.modules[old_name] = module
    for sub in submodules:
        sys.modules[f"{old_name}.{sub}"] = importlib.import_module(f"{new_name}.{sub}")
