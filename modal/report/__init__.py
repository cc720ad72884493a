"""Reports of identification results: plain-text tables (the command line) and the HTML report.

``format_table`` and ``jsonable`` (:mod:`modal.report.tables`) are what the command lines print;
:func:`write_report` (:mod:`modal.report.html`) writes the self-contained HTML report of an archive
(``python -m modal report``), loaded on first use so the command lines do not pay for it.
"""
from __future__ import annotations

import importlib

from .tables import format_table, jsonable

__all__ = ["format_table", "jsonable", "write_report", "build_report", "ReportContent", "Section"]

_HOME = {"write_report": "html", "build_report": "html", "ReportContent": "content", "Section": "content"}


def __getattr__(name: str):
    if name in _HOME:
        value = getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
