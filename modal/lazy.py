"""Names of a package whose modules load when a name is first used (PEP 562).

A package lists where each such name lives and binds what :func:`lazy_names` returns to its own
``__getattr__`` and ``__dir__``: ``import`` of the package then costs only the modules it imports itself.
"""
from __future__ import annotations

import importlib
from typing import Callable, Mapping

__all__ = ["lazy_names"]


def lazy_names(package: str, home: Mapping[str, str]) -> tuple[Callable[[str], object], Callable[[], list]]:
    """``(__getattr__, __dir__)`` for ``package`` whose name ``n`` lives in its submodule ``home[n]``.

    The first use of a name imports its submodule and binds the name in the package, so later uses are plain
    lookups.
    """

    def __getattr__(name: str):
        if name not in home:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{home[name]}", package), name)
        setattr(importlib.import_module(package), name, value)
        return value

    def __dir__() -> list:
        return sorted({*vars(importlib.import_module(package)), *home})

    return __getattr__, __dir__
