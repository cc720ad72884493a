"""The vocabulary of scene files: value rules and references to earlier stages.

A rule takes a TOML value and returns it cleaned, or raises ``ValueError`` whose text
says what was expected (the schema puts the file and the key before it).  Values that
come from an earlier stage are written as references:

* ``"identified:mode1.stiffness"`` (also ``.damping``, ``.mass``, ``.frequency``,
  ``.damping_ratio``): mode 1 of ``[identify]`` (an impact test, ``[frf]``), on the channel
  ``[identify] channel`` (default: the first driving point), or of an operational test
  scaled by mass change (``[oma]``), on the channel ``[oma] channel``;
* ``"drive:speed"`` (rad/s) and ``"drive:stiffness"`` (N/m): the drive's hand-over to the
  rotor.

This module imports only the standard library and balancer's argument checks: the stage
registry is built from it, and the plotting processes read that registry.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from .._checks import scene_number

__all__ = ["POS", "NONNEG", "NUM", "INT", "BOOL", "STR", "FILES", "choice", "list_of", "ref_or", "complex_value",
           "Reference", "parse_reference", "IDENTIFIED_FIELDS", "DRIVE_FIELDS", "REFERENCE_STAGES"]

IDENTIFIED_FIELDS = {
    "stiffness": "stiffness_n_per_m", "damping": "damping_n_s_per_m", "mass": "mass_kg",
    "frequency": "natural_frequency_hz", "damping_ratio": "damping_ratio",
}
DRIVE_FIELDS = {"speed": "speed_rad_s", "stiffness": "stiffness_n_per_m"}
#: the stages a reference's source may name: the one whose section (its ``needs``) the scene has
REFERENCE_STAGES = {"identified": ("identify", "oma"), "drive": ("drive",)}
_REF = re.compile(r"^(identified):mode(\d+)\.(\w+)$|^(drive):(\w+)$")


def POS(v):
    return scene_number(v, positive=True)


def NONNEG(v):
    return scene_number(v, nonneg=True)


def NUM(v):
    return scene_number(v)


def INT(v):
    if isinstance(v, bool) or not isinstance(v, int):
        raise ValueError("an integer")
    return v


def BOOL(v):
    if not isinstance(v, bool):
        raise ValueError("true or false")
    return v


def STR(v):
    if not isinstance(v, str) or not v:
        raise ValueError("a non-empty string")
    return v


def FILES(v):
    """One file name, or a list of them (takes of one test)."""
    if isinstance(v, list):
        return list_of(STR)(v)
    if not isinstance(v, str) or not v:
        raise ValueError("a file name or a list of file names")
    return v


def choice(*options):
    def check(v):
        if v not in options:
            raise ValueError("one of " + ", ".join(repr(o) for o in options))
        return v
    return check


def list_of(check, length=None, min_length=1):
    def run(v):
        if not isinstance(v, list):
            raise ValueError(f"a list{f' of {length}' if length else ''}")
        if length is not None and len(v) != length:
            raise ValueError(f"a list of {length} values, got {len(v)}")
        if len(v) < min_length:
            raise ValueError(f"a list of at least {min_length} values")
        return [check(x) for x in v]
    return run


def ref_or(check, sources=("identified", "drive"), fields=None):
    """A reference to one of ``sources`` (a :class:`Reference`), or a value ``check`` accepts.

    ``fields`` names the one quantity the key holds (``"mass"``, ``"stiffness"``, ...): a reference to
    another quantity (a rotor mass written ``identified:mode1.stiffness``) is refused, since its number
    would be read in the wrong unit.
    """
    def run(v):
        if isinstance(v, str):
            ref = parse_reference(v)
            if ref.source not in sources:
                raise ValueError(f"a number or a reference to {' or '.join(sources)}")
            if fields is not None and ref.field not in fields:
                wanted = " or ".join(f'"{source}:{"modeN." if source == "identified" else ""}{field}"'
                                     for source in sources for field in fields
                                     if field in (IDENTIFIED_FIELDS if source == "identified" else DRIVE_FIELDS))
                raise ValueError(f"a {'/'.join(fields)}: a number or {wanted}; got a reference to a {ref.field}")
            return ref
        return check(v)
    return run


def complex_value(v):
    if isinstance(v, list):
        re_, im = list_of(NUM, length=2)(v)
        return complex(re_, im)
    return complex(NUM(v))


@dataclass(frozen=True)
class Reference:
    """A value taken from an earlier stage."""

    source: str  # "identified" or "drive"
    field: str
    mode: int = 0  # 1-based for identified
    text: str = ""


def parse_reference(text: str) -> Reference:
    """Parse ``identified:modeN.field`` or ``drive:field``; ValueError says what was expected."""
    match = _REF.match(text.strip())
    if not match:
        raise ValueError("a number or a reference like \"identified:mode1.stiffness\" or \"drive:speed\"")
    if match.group(1):
        mode, field = int(match.group(2)), match.group(3)
        if field not in IDENTIFIED_FIELDS:
            raise ValueError(f"an identified field among {', '.join(IDENTIFIED_FIELDS)} (got {field!r})")
        if mode < 1:
            raise ValueError("a mode number >= 1")
        return Reference("identified", field, mode, text)
    field = match.group(5)
    if field not in DRIVE_FIELDS:
        raise ValueError(f"a drive field among {', '.join(DRIVE_FIELDS)} (got {field!r})")
    return Reference("drive", field, 0, text)
