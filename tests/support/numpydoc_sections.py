"""A small numpydoc reader for the documentation tests: the names a docstring's
``Parameters`` (or ``Attributes``) section documents, parsed from its entries.

A substring test ("name in docstring") passes for any one-letter parameter (``k``, ``n``,
``e`` occur in every text); only an entry line ``name : type`` (or ``a, b : type``, or a
bare ``name``) at the section's indentation counts here.
"""
from __future__ import annotations

import inspect
import re

_ENTRY = re.compile(r"^(\*{0,2}[A-Za-z_]\w*(?:\s*,\s*\*{0,2}[A-Za-z_]\w*)*)\s*(?::.*)?$")


def sections(doc: str) -> dict[str, list[str]]:
    """Section title -> its lines (a title is a line underlined by dashes of its length or more)."""
    lines = inspect.cleandoc(doc).splitlines()
    out: dict[str, list[str]] = {}
    current = None
    i = 0
    while i < len(lines):
        title = lines[i].strip()
        if (i + 1 < len(lines) and title and set(lines[i + 1].strip()) == {"-"}
                and len(lines[i + 1].strip()) >= len(title)):
            current = title
            out[current] = []
            i += 2
            continue
        if current is not None:
            out[current].append(lines[i])
        i += 1
    return out


def documented(doc: str, titles=("Parameters", "Other Parameters")) -> set[str]:
    """Names with an entry in the given sections (``*args``/``**kwargs`` without stars)."""
    names: set[str] = set()
    for title, lines in sections(doc or "").items():
        if title not in titles:
            continue
        for line in lines:
            if not line.strip() or line[0].isspace():
                continue  # descriptions are indented under their entry
            match = _ENTRY.match(line.strip())
            if match:
                names.update(name.strip().lstrip("*") for name in match.group(1).split(","))
    return names
