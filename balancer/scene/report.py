"""A scene archive's balancing stages as sections of the HTML report (``python -m modal report``).

:func:`report_sections` is looked up by name by :mod:`modal.report.content` (modal never imports
balancer): one section per stage after identification, with the stage's headline numbers
(:func:`balancer.scene.summary.digest`, units from the field names) and its figures as PNG.
"""
from __future__ import annotations

import math

import numpy as np

from modal.archive import units_of
from modal.figures import png_bytes
from modal.report.content import Section

__all__ = ["report_sections"]

_SKIPPED = ("frf", "identify")  # the report draws these itself


def _value(key: str, value) -> str:
    unit = units_of(key) or ""
    unit = "" if unit == "1" else f" {unit}"
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, (int, float, np.integer, np.floating)):
        number = float(value)
        return ("n/a" if not math.isfinite(number) else f"{number:.5g}") + unit
    if isinstance(value, (list, tuple)) and all(isinstance(v, (int, float, np.integer, np.floating)) for v in value):
        shown = ", ".join(f"{float(v):.4g}" for v in value[:8]) + (f", … ({len(value)} values)" if len(value) > 8 else "")
        return f"[{shown}]{unit}"
    if isinstance(value, (list, tuple)):
        return "; ".join(str(v) for v in value)
    return str(value)


def _rows(prefix: str, digest: dict) -> list[tuple[str, str]]:
    rows = []
    for key, value in digest.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            rows += _rows(f"{name}.", value)
        elif isinstance(value, list) and value and all(isinstance(v, (dict, list)) for v in value):
            rows.append((name, f"{len(value)} entries (in the archive)"))
        else:
            rows.append((name, _value(key, value)))
    return rows


def report_sections(archive) -> list[Section]:
    """One :class:`modal.report.content.Section` per balancing stage in a scene archive, in stage order."""
    from .plots import stage_figures
    from .schema import STAGES
    from .summary import digest

    results = archive.items
    sections = []
    for stage in STAGES:
        if stage in _SKIPPED or stage not in results:
            continue
        images = tuple((f"{stage}: {name}", png_bytes(fig, dpi=90)) for name, fig in stage_figures(stage, results))
        sections.append(Section(title=stage, rows=tuple(_rows("", digest(stage, results[stage]))), images=images))
    return sections
