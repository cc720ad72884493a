"""Helpers shared by the FRF readers: file checks, hints, frequency units, kind.

Every reader builds its error messages as ``"<file>: <where>: <what>; expected <what>"``
and raises :class:`~modal.errors.FormatError` (or lets the FRF model raise
:class:`~modal.errors.FRFValidationError`).
"""
from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FormatError
from ..frf import FRF, FRF_KINDS
from ..frf_units import frf_in_si
from ..units import TWO_PI

__all__ = [
    "HINTS", "check_hints", "check_file", "refuse_copies", "source_name", "resolve_kind", "frequency_factor",
    "frequency_unit_from_text", "build_frf", "KIND_ALIASES", "refuse_cut_last_value",
]

#: Keyword hints accepted by :func:`modal.io.read_frf` (a reader uses those that apply).
HINTS = frozenset({
    "kind", "frequency_axis", "variables", "layout", "delimiter", "decimal", "dataset",
    "frequency_hz", "frequency_start", "frequency_step", "response_points", "reference_points",
    "units",
})

#: Frequency units a column or hint may name, as the factor that turns them into Hz.
_FREQUENCY_FACTORS = {
    "hz": 1.0, "hertz": 1.0, "cps": 1.0, "1/s": 1.0, "khz": 1e3, "mhz": 1e6,
    "rad/s": 1.0 / TWO_PI, "rad/sec": 1.0 / TWO_PI, "rads": 1.0 / TWO_PI, "rad_s": 1.0 / TWO_PI,
    "cpm": 1.0 / 60.0, "rpm": 1.0 / 60.0, "1/min": 1.0 / 60.0,
}

#: Other spellings of the three kinds a file or a user may use.
KIND_ALIASES = {
    "receptance": "receptance", "compliance": "receptance", "dynamic compliance": "receptance",
    "displacement/force": "receptance",
    "mobility": "mobility", "velocity/force": "mobility", "admittance": "mobility",
    "accelerance": "accelerance", "inertance": "accelerance", "acceleration/force": "accelerance",
}


def source_name(path: str | os.PathLike) -> str:
    """The file name as the user gave it, for messages and ``FRF.source``."""
    return os.fspath(path)


def check_hints(hints: dict[str, Any]) -> None:
    """Refuse a misspelt hint (a programming error, so ``TypeError`` as Python does)."""
    unknown = sorted(set(hints) - HINTS)
    if unknown:
        raise TypeError(f"read_frf() got unknown hint(s) {', '.join(unknown)}; known: {', '.join(sorted(HINTS))}")


def refuse_copies(paths, what: str, why: str) -> None:
    """Refuse a list of files in which one holds the same bytes as another (given twice, or copied): ``what`` the
    files are and ``why`` a copy is wrong (in the message)."""
    import hashlib

    seen: dict[tuple[int, bytes], str] = {}
    for path in paths:
        try:
            with open(path, "rb") as fh:
                digest = hashlib.file_digest(fh, "sha256").digest()
            key = (os.path.getsize(path), digest)
        except OSError:
            continue  # the reader says what is wrong with it
        if key in seen:
            raise FormatError(f"{source_name(path)}: holds the same bytes as {seen[key]}; expected each of the "
                              f"{what} once ({why})")
        seen[key] = source_name(path)


def check_file(path: str | os.PathLike) -> Path:
    """A readable, non-empty regular file, or a :class:`FormatError` saying why not."""
    src = source_name(path)
    p = Path(path)
    if not p.exists():
        raise FormatError(f"{src}: no such file; expected an FRF file (UFF 58, CSV, MAT or HDF5)")
    if p.is_dir():
        raise FormatError(f"{src}: is a directory; expected an FRF file (UFF 58, CSV, MAT or HDF5)")
    try:
        size = p.stat().st_size
        with open(p, "rb"):
            pass
    except OSError as exc:
        raise FormatError(f"{src}: cannot be opened ({exc.strerror}); expected a readable file") from None
    if size == 0:
        raise FormatError(f"{src}: empty file (0 bytes); expected an FRF file (UFF 58, CSV, MAT or HDF5)")
    return p


def normalise_kind(value: Any, src: str, where: str) -> str:
    """A kind name from a file or a hint, aliases allowed; FormatError if unknown."""
    text = str(value).strip().lower()
    if text in KIND_ALIASES:
        return KIND_ALIASES[text]
    raise FormatError(
        f"{src}: {where}: unknown FRF kind {str(value)!r}; expected one of {', '.join(FRF_KINDS)}"
    )


def resolve_kind(file_kind: str | None, hints: dict[str, Any], src: str, where: str,
                 why_unknown: str = "the file does not say") -> str:
    """The FRF kind from the file and the ``kind=`` hint; never guessed.

    Parameters
    ----------
    file_kind : str or None
        What the file states (already normalised), or None.
    hints : dict
        The reader's hints; ``hints["kind"]`` may be None.
    src, where : str
        File name and the field the file's kind came from (for messages).
    why_unknown : str
        Why the file cannot tell, used when neither gives a kind.
    """
    hint = hints.get("kind")
    hint_kind = None if hint is None else normalise_kind(hint, src, "hint kind=")
    if file_kind is not None and hint_kind is not None and file_kind != hint_kind:
        raise FormatError(
            f"{src}: {where}: the file says {file_kind} but kind={hint_kind!r} was given; "
            "expected them to agree (drop the hint to use the file's kind)"
        )
    kind = file_kind or hint_kind
    if kind is None:
        raise FormatError(
            f"{src}: {where}: the FRF kind cannot be determined ({why_unknown}); "
            f"expected kind= (--kind) one of {', '.join(FRF_KINDS)}"
        )
    return kind


def frequency_factor(unit: str, src: str, where: str) -> float:
    """Factor turning a frequency in ``unit`` ("hz", "khz", "rad/s", "cpm", "rpm") into Hz."""
    key = str(unit).strip().lower().replace(" ", "")
    if key in _FREQUENCY_FACTORS:
        return _FREQUENCY_FACTORS[key]
    raise FormatError(
        f"{src}: {where}: unknown frequency unit {unit!r}; expected one of hz, khz, rad/s, cpm, rpm"
    )


_UNIT_IN_TEXT = re.compile(r"rad\s*/\s*s(?:ec)?|rad_s|khz|hz|cpm|rpm|1/min", re.IGNORECASE)


def frequency_unit_from_text(text: str) -> str | None:
    """The frequency unit a column name mentions (``"Frequency [rad/s]"`` → ``"rad/s"``), or None."""
    m = _UNIT_IN_TEXT.search(text)
    if not m:
        return None
    return re.sub(r"\s", "", m.group(0).lower()).replace("sec", "s").replace("rad_s", "rad/s")


def hint_points(hints: dict[str, Any], n_channels: int, src: str):
    """Response and reference point ids given as hints (None where not given)."""
    out = []
    for name in ("response_points", "reference_points"):
        value = hints.get(name)
        if value is not None:
            if isinstance(value, str):
                value = [value] * n_channels
            value = tuple(str(v) for v in value)
            if len(value) != n_channels:
                raise FormatError(
                    f"{src}: hint {name}= has {len(value)} ids; expected one per channel ({n_channels})"
                )
        out.append(value)
    return tuple(out)


def build_frf(frequency_hz: np.ndarray, response: np.ndarray, kind: str, src: str, *,
              response_points=None, reference_points=None, units: str | None = None,
              hints: dict[str, Any] | None = None, squeeze: bool = True) -> FRF:
    """Make the :class:`FRF`: one channel becomes a 1-D response (if ``squeeze``), hints override, a unit
    :func:`modal.frf_units.frf_in_si` knows is converted to the kind's SI unit.

    The FRF model validates (NaN, Inf, duplicates → FRFValidationError; unsorted
    lines are sorted with a ModalWarning).
    """
    hints = hints or {}
    resp = np.asarray(response)
    if squeeze and resp.ndim == 2 and resp.shape[0] == 1:
        resp = resp[0]
    n_ch = 1 if resp.ndim == 1 else resp.shape[0]
    rsp_hint, ref_hint = hint_points(hints, n_ch, src)
    units = hints.get("units") or units
    return frf_in_si(FRF(  # a unit the toolkit knows (g/N, mm/s/N, in/lbf) becomes the kind's SI unit
        frequency_hz, resp, kind=kind,
        response_points=rsp_hint if rsp_hint is not None else response_points,
        reference_points=ref_hint if ref_hint is not None else reference_points,
        units=units, source=src,
    ))


def hint_frequency_axis(hints: dict[str, Any], n_lines: int, src: str, why: str) -> np.ndarray:
    """Frequency lines for a file that stores none: ``frequency_hz=`` or ``frequency_step=``.

    ``frequency_start`` (default 0) and ``frequency_step`` are in the unit of
    ``frequency_axis`` (default Hz).
    """
    if hints.get("frequency_hz") is not None:
        freq = np.asarray(hints["frequency_hz"], dtype=float).ravel()
        if freq.size != n_lines:
            raise FormatError(
                f"{src}: hint frequency_hz= has {freq.size} lines; expected {n_lines} (one per line of the file)"
            )
        return freq
    if hints.get("frequency_step") is not None:
        factor = frequency_factor(hints.get("frequency_axis") or "hz", src, "hint frequency_axis=")
        start = float(hints.get("frequency_start") or 0.0)
        step = float(hints["frequency_step"])
        if not (np.isfinite(step) and step > 0 and np.isfinite(start)):
            raise FormatError(f"{src}: hint frequency_step={step!r}; expected a finite step > 0")
        return (start + step * np.arange(n_lines)) * factor
    raise FormatError(
        f"{src}: {why}; expected frequency_hz= (the lines) or frequency_step= "
        "(and frequency_start=, default 0) to say where the lines are"
    )


def refuse_cut_last_value(text: str, rows: list[tuple[int, list[str]]], column: str, src: str) -> None:
    """Refuse a text table whose last number was cut: the file ends inside it.

    A file cut while being written or copied ends without a line break, its last row short of
    fields (each reader says so) or its last field cut inside a number: ``1.234567e-03`` cut to
    ``1.2345`` still parses, to a wrong value. The cut is decidable when the file ends without a
    line break inside a last value shorter than every other of its column (fixed-width writers:
    ``%.6e``, spreadsheets); it is not with writers of varying widths (``%g``, ``repr``) whose cut
    value stays as long as their shortest, and then it reads as written.

    Parameters
    ----------
    text : str
        The whole file.
    rows : list of (int, list of str)
        The data rows: line number (1-based) and fields, the last field being the last column.
    column : str
        The last column's name, for the message.
    src : str
        The file's name.

    Raises
    ------
    FormatError
        Naming the line and column, when the last value is cut.
    """
    if len(rows) < 3 or text.endswith(("\n", "\r")) or rows[-1][0] != len(text.splitlines()):
        return
    line_no, last = rows[-1]
    shortest = min(len(fields[-1]) for _, fields in rows[:-1])
    if len(last[-1]) < shortest:
        raise FormatError(f"{src}: line {line_no}, column {column!r}: {last[-1]!r} is shorter than every other "
                          f"value of its column ({shortest} characters or more) and the file ends inside it, "
                          f"without a line break (cut short?); expected whole rows (delete line {line_no} to "
                          "read the rest)")
