"""FRFs in Universal File Format dataset 58 (ASCII) and 58b (binary), through pyuff.

Mapping of the dataset 58 records into :class:`~modal.frf.FRF`:

* record 6 ``func_type``: only 4 (frequency response function) is an FRF; a file
  with no FRF dataset (time response, spectra, coherence...) is refused with the
  type's name and number. FRF datasets are read and other datasets (for example
  coherence next to the FRFs, or datasets 151/164) are skipped.
* record 6 response/reference node and direction → point ids such as ``"101+Z"``
  (:func:`format_point`, :func:`parse_point`); node 0 on every channel → no ids.
* record 7 abscissa spacing/min/increment and record 8 abscissa units → Hz
  (``rad/s``, ``rpm``/``cpm``, ``kHz`` labels are converted; ``frequency_axis=`` overrides).
* records 9/10 specific data types, numerator/denominator: 8/13 receptance,
  11/13 mobility, 12/13 accelerance; anything else needs ``kind=`` (never guessed).
* several FRF datasets on one frequency axis → one multi-channel FRF, in file
  order; on different axes → an error unless ``dataset=`` (1-based) picks some.
* a file that ends inside a dataset is refused; one cut exactly between datasets is well formed,
  so it is only caught when the FRFs end inside a group of channels their own order implies
  (a warning, :func:`cut_group`); a cut single-reference file reads as a smaller complete one
  (``modal fit`` prints the channel count read).

Precision (the format's, not pyuff's choice): ASCII dataset 58 writes double
ordinates as E20.12 Fortran fields, 12 significant digits (relative rounding
≤ 5e-12), and the abscissa (minimum, increment, or each x of an uneven axis)
as E13.5, 6 significant digits. :func:`write_frf_uff` uses even spacing only
when the 6-digit minimum and increment rebuild the axis bit for bit, and warns
(:class:`~modal.errors.ModalWarning`) when an ASCII axis cannot be kept.
Binary 58b stores doubles, so there an axis that is not exactly even is
written point by point (uneven spacing) and both axis and response round-trip
bit-exactly.
"""
from __future__ import annotations

import os
import re
import tempfile
import warnings
from pathlib import Path
from datetime import datetime, timezone
from typing import Any

import numpy as np

from ..errors import FormatError, ModalWarning, warn, warn_caller
from ..frf import FRF
from ._atomic import atomic_path
from ._common import build_frf, check_file, frequency_factor, resolve_kind, source_name

__all__ = [
    "read_frf_uff", "write_frf_uff", "format_point", "parse_point", "FUNCTION_TYPES",
    "SPECIFIC_DATA_TYPES", "KIND_FROM_DATA_TYPES",
]

#: Record 6 field 1, function type (UFF dataset 58 specification).
FUNCTION_TYPES = {
    0: "general or unknown", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
    4: "frequency response function", 5: "transmissibility", 6: "coherence", 7: "auto correlation",
    8: "cross correlation", 9: "power spectral density", 10: "energy spectral density",
    11: "probability density function", 12: "spectrum", 13: "cumulative frequency distribution",
    14: "peaks valley", 15: "stress/cycles", 16: "strain/cycles", 17: "orbit",
    18: "mode indicator function", 19: "force pattern", 20: "partial power", 21: "partial coherence",
    22: "eigenvalue", 23: "eigenvector", 24: "shock response spectrum", 25: "finite impulse response filter",
    26: "multiple coherence", 27: "order function",
}
#: Records 8–11 field 1, specific data type.
SPECIFIC_DATA_TYPES = {
    0: "unknown", 1: "general", 2: "stress", 3: "strain", 5: "temperature", 6: "heat flux",
    8: "displacement", 9: "reaction force", 11: "velocity", 12: "acceleration", 13: "excitation force",
    15: "pressure", 16: "mass", 17: "time", 18: "frequency", 19: "rpm", 20: "order",
}
#: (numerator, denominator) specific data types → FRF kind.
KIND_FROM_DATA_TYPES = {(8, 13): "receptance", (11, 13): "mobility", (12, 13): "accelerance"}
_NUMERATOR = {kind: num for (num, _), kind in KIND_FROM_DATA_TYPES.items()}
_AXIS_LABEL = {"receptance": "Displacement", "mobility": "Velocity", "accelerance": "Acceleration"}
_ORD_DATA_TYPES = {2: "real single", 4: "real double", 5: "complex single", 6: "complex double"}

_DIRECTIONS = {0: "", 1: "X", 2: "Y", 3: "Z", 4: "RX", 5: "RY", 6: "RZ"}
_DIRECTION_CODES = {v: k for k, v in _DIRECTIONS.items() if v}
_POINT = re.compile(r"^\s*(\d+)\s*(?:([+-])\s*(X|Y|Z|RX|RY|RZ))?\s*$", re.IGNORECASE)


# ------------------------------------------------------------ point ids
def format_point(node: int, direction: int) -> str:
    """Point id of a UFF node and direction: ``(101, 3)`` → ``"101+Z"``, ``(7, -5)`` → ``"7-RY"``.

    Parameters
    ----------
    node : int
        Node number (>= 0).
    direction : int
        0 scalar (no direction: the id is the node alone), ±1..±3 X/Y/Z translation,
        ±4..±6 rotation about X/Y/Z.
    """
    direction = int(direction)
    if abs(direction) not in _DIRECTIONS:
        raise ValueError(f"UFF direction must be in -6..6, got {direction}")
    if direction == 0:
        return str(int(node))
    return f"{int(node)}{'+' if direction > 0 else '-'}{_DIRECTIONS[abs(direction)]}"


def parse_point(point: str) -> tuple[int, int]:
    """Inverse of :func:`format_point`: ``"101+Z"`` → ``(101, 3)``, ``"5"`` → ``(5, 0)``.

    Raises
    ------
    ValueError
        The id is not ``<node>[+|-]<X|Y|Z|RX|RY|RZ>`` or a bare node number.
    """
    m = _POINT.match(str(point))
    if not m:
        raise ValueError(f"point id {point!r} is not '<node><+|-><X|Y|Z|RX|RY|RZ>' (e.g. '101+Z') or a node number")
    node, sign, axis = m.groups()
    if axis is None:
        return int(node), 0
    code = _DIRECTION_CODES[axis.upper()]
    return int(node), code if sign == "+" else -code


# ------------------------------------------------------------ reading
def _tag_offsets(data: bytes) -> list[int]:
    """Offsets of the '    -1' delimiter lines, found as pyuff finds them."""
    out, ind, n = [], -1, len(data)
    while True:
        ind = data.find(b"    -1", ind + 1)
        if ind == -1:
            return out
        end = ind + 6
        if end == n or (end < n and data[end] in (10, 13)) or (end + 74 < n and data[end:end + 74] == b" " * 74):
            out.append(ind)


def _type_name(func_type: int) -> str:
    return f"function type {func_type} ({FUNCTION_TYPES.get(func_type, 'unknown type')})"


def _data_type_name(code: int) -> str:
    return f"{code} ({SPECIFIC_DATA_TYPES.get(code, 'other')})"


class _Block:
    """One dataset of the file: its 1-based number, first line, and raw bytes."""

    def __init__(self, number: int, line: int, raw: bytes) -> None:
        self.number, self.line, self.raw = number, line, raw

    def where(self, record: int | None = None, field: str | None = None) -> str:
        text = f"dataset {self.number}"
        if record is not None:
            text += f" (line {self.line + record + 1}, record {record}" + (f", field {field})" if field else ")")
        return text


def scan_datasets(path: str | os.PathLike, src: str) -> tuple[Any, list[_Block]]:
    """Open a UFF file with pyuff and list its datasets, refusing a file that ends inside one.

    Returns
    -------
    (pyuff.UFF, list of _Block)
        Each block has its 1-based ``number``, first ``line``, ``raw`` bytes and dataset ``type``.

    Raises
    ------
    FormatError
        No complete dataset, a last dataset without its closing ``-1`` line (the file
        ends early), or datasets pyuff does not see as we do.
    """
    import pyuff

    p = check_file(path)
    data = p.read_bytes()
    tags = _tag_offsets(data)
    if len(tags) < 2:
        raise FormatError(f"{src}: line 1: no complete dataset (found {len(tags)} '    -1' delimiter line); "
                          "expected datasets between pairs of '    -1' lines (truncated file?)")
    if len(tags) % 2:
        last = data.count(b"\n", 0, tags[-1]) + 1
        raise FormatError(f"{src}: line {last}: dataset {len(tags) // 2 + 1} has no closing '    -1' line: the file "
                          "ends early (truncated?); expected every dataset to end with one")
    blocks, line, pos = [], 1, 0
    for k in range(len(tags) // 2):  # line numbers counted incrementally (large files)
        line += data.count(b"\n", pos, tags[2 * k])
        pos = tags[2 * k]
        blocks.append(_Block(k + 1, line, data[tags[2 * k]:tags[2 * k + 1]]))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            uff = pyuff.UFF(os.fspath(p))
            types = [int(t) for t in uff.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exception
        raise FormatError(f"{src}: cannot be scanned as UFF ({exc}); "
                          "expected datasets between '    -1' lines") from None
    if len(types) != len(blocks):
        raise FormatError(f"{src}: {len(blocks)} datasets found but pyuff sees {len(types)}; "
                          "expected a well-formed UFF file")
    for b, t in zip(blocks, types):
        b.type = t
    return uff, blocks


def read_frf_uff(path: str | os.PathLike, **hints: Any) -> FRF:
    """Read the FRF datasets (58/58b, function type 4) of a UFF file.

    Parameters
    ----------
    path : path-like
    **hints
        ``kind`` (only needed when the data types do not say; must agree
        otherwise), ``dataset`` (1-based dataset number, or a list of them, as
        counted in the file over all datasets), ``frequency_axis`` (abscissa
        unit when the file's label is missing or wrong), ``response_points``,
        ``reference_points``, ``units``.

    Raises
    ------
    FormatError
        No FRF dataset (e.g. time data: names its function type), damaged or
        truncated datasets, unknown kind, datasets on different axes.
    """
    src = source_name(path)
    uff, blocks = scan_datasets(path, src)
    uff58 = [b for b in blocks if b.type == 58]
    if not uff58:
        kinds = ", ".join(sorted({str(b.type) for b in blocks}))
        raise FormatError(f"{src}: no dataset 58 (the file holds dataset types {kinds}); "
                          "expected dataset 58 or 58b with FRFs")
    headers = {b.number: read_dataset(uff, b, src, header_only=True) for b in uff58}
    chosen = _choose(hints.get("dataset"), blocks, headers, src)
    frfs = []
    for b in chosen:
        problem = check_header(b, src)
        if problem:
            raise FormatError(problem)
        dset = read_dataset(uff, b, src, header_only=False)
        frfs.append(_to_arrays(b, dset, src, hints))
    return _assemble(chosen, frfs, src, hints)


def read_dataset(uff, block: _Block, src: str, header_only: bool) -> dict:
    """One dataset 58 as pyuff's dict; a dataset pyuff cannot parse gets a message naming its bad record."""
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            dset = uff.read_sets(block.number - 1, header_only=header_only)
    except Exception:  # pyuff's messages carry no line; find the bad record ourselves
        raise FormatError(_diagnose(block, src)) from None
    if not isinstance(dset, dict) or "func_type" not in dset:
        raise FormatError(f"{src}: {block.where(6)}: record 6 is missing; expected a complete dataset 58 header")
    return dset


def _choose(hint, blocks: list[_Block], headers: dict[int, dict], src: str) -> list[_Block]:
    by_number = {b.number: b for b in blocks}
    if hint is not None:
        numbers = [hint] if isinstance(hint, (int, np.integer, str)) else list(hint)
        chosen = []
        for n in numbers:
            try:
                b = by_number[int(n)]
            except (KeyError, ValueError):
                raise FormatError(f"{src}: hint dataset={n!r}; expected a dataset number 1..{len(blocks)}") from None
            if b.number not in headers:
                raise FormatError(f"{src}: {b.where()}: is dataset type {b.type}; expected dataset 58 (hint dataset=)")
            ft = headers[b.number]["func_type"]
            if ft != 4:
                raise FormatError(f"{src}: {b.where(6, 'func_type')}: {_type_name(ft)} is not an FRF; "
                                  "expected 4 (frequency response function)")
            chosen.append(b)
        return chosen
    chosen = [by_number[n] for n, h in headers.items() if h["func_type"] == 4]
    if not chosen:
        first = min(headers)
        ft = headers[first]["func_type"]
        others = sorted({h["func_type"] for h in headers.values()} - {ft})
        more = f" (other datasets: {', '.join(_type_name(t) for t in others)})" if others else ""
        raise FormatError(f"{src}: {by_number[first].where(6, 'func_type')}: {_type_name(ft)} is not an FRF{more}; "
                          "expected 4 (frequency response function)")
    return chosen


def _to_arrays(b: _Block, d: dict, src: str, hints: dict[str, Any]) -> dict:
    odt = int(d.get("ord_data_type", 0))
    if odt not in (5, 6):
        name = _ORD_DATA_TYPES.get(odt, "unknown")
        raise FormatError(f"{src}: {b.where(7, 'ord_data_type')}: ordinate data type {odt} ({name}); "
                          "expected 5 or 6 (complex single/double) for an FRF")
    x = np.asarray(d["x"], dtype=float)
    h = np.asarray(d["data"], dtype=complex)
    n_pts = int(d.get("num_pts", -1))
    if h.size != n_pts or x.size != n_pts:
        raise FormatError(f"{src}: {b.where(7, 'num_pts')}: says {n_pts} points but the data records hold "
                          f"{h.size}; expected equal (truncated or damaged dataset?)")
    bad = ~np.isfinite(h)
    if bad.any() or not np.isfinite(x).all():
        i = int(np.flatnonzero(bad | ~np.isfinite(x))[0])
        raise FormatError(f"{src}: {b.where()} (data records, point {i + 1}): value {h[i]} at x={x[i]} "
                          "is not finite; expected finite numbers")
    # abscissa unit
    unit = hints.get("frequency_axis")
    where = "hint frequency_axis="
    if unit is None:
        adt = int(d.get("abscissa_spec_data_type", 0))
        label = str(d.get("abscissa_axis_units_lab", "")).strip()
        if adt == 17:
            raise FormatError(f"{src}: {b.where(8, 'abscissa_spec_data_type')}: abscissa is {_data_type_name(adt)}; "
                              "expected frequency (18) for an FRF")
        where = f"{b.where(8, 'abscissa_axis_units_lab')}"
        unit = label if label and label.upper() != "NONE" else ("rpm" if adt == 19 else "hz")
    factor = frequency_factor(unit, src, where)
    freq = x if factor == 1.0 else x * factor
    # kind
    pair = (int(d.get("ordinate_spec_data_type", 0)), int(d.get("orddenom_spec_data_type", 0)))
    kind = KIND_FROM_DATA_TYPES.get(pair)
    why = (f"ordinate numerator/denominator data types {_data_type_name(pair[0])}/{_data_type_name(pair[1])} "
           "are not 8/13, 11/13 or 12/13")
    # units label: numerator/denominator
    num = str(d.get("ordinate_axis_units_lab", "")).strip()
    den = str(d.get("orddenom_axis_units_lab", "")).strip()
    units = None
    if num and num.upper() != "NONE":
        # a force denominator (data type 13) without a unit label is in N, UFF's default unit system (SI)
        units = f"{num}/{den}" if den and den.upper() != "NONE" else (f"{num}/N" if pair[1] == 13 else num)
    rsp = (int(d.get("rsp_node", 0)), int(d.get("rsp_dir", 0)))
    ref = (int(d.get("ref_node", 0)), int(d.get("ref_dir", 0)))
    for name, (node, direction) in (("rsp_dir", rsp), ("ref_dir", ref)):
        if abs(direction) > 6:
            raise FormatError(f"{src}: {b.where(6, name)}: direction {direction}; expected -6..6")
    return {"freq": freq, "h": h, "kind": kind, "why": why, "units": units, "rsp": rsp, "ref": ref}


def _assemble(chosen: list[_Block], parts: list[dict], src: str, hints: dict[str, Any]) -> FRF:
    first, b0 = parts[0], chosen[0]
    for b, part in zip(chosen[1:], parts[1:]):
        f0, f1 = first["freq"], part["freq"]
        if f1.size != f0.size or not np.array_equal(f1, f0):
            raise FormatError(
                f"{src}: {b.where(7)}: frequency axis ({f1.size} lines, {f1[0]:g}–{f1[-1]:g} Hz) differs from "
                f"dataset {b0.number} ({f0.size} lines, {f0[0]:g}–{f0[-1]:g} Hz); expected one shared axis, "
                "or dataset= to choose datasets"
            )
        if part["kind"] != first["kind"]:
            raise FormatError(f"{src}: {b.where(9, 'ordinate_spec_data_type')}: kind {part['kind']} differs from "
                              f"dataset {b0.number} ({first['kind']}); expected one kind in a file")
    file_kind = first["kind"]
    kind = resolve_kind(file_kind, hints, src, b0.where(9, "ordinate_spec_data_type"), why_unknown=first["why"])
    units = first["units"] if all(p["units"] == first["units"] for p in parts) else None
    if units is not None and file_kind is None and hints.get("units") is None:
        units = None  # labels of an unknown quantity are not an FRF unit we can vouch for
    resp = np.array([p["h"] for p in parts])
    short = cut_group(chosen, parts)
    if short:
        warn_caller(f"{src}: {short}; the file may be cut between datasets (a file cut there reads as a smaller "
                    "complete one): expected the same channels in every group")

    def points(key):
        if all(p[key][0] == 0 for p in parts):
            return None
        return tuple(format_point(*p[key]) for p in parts)

    return build_frf(first["freq"], resp, kind, src, response_points=points("rsp"),
                     reference_points=points("ref"), units=units, hints=hints)


def cut_group(chosen: list[_Block], parts: list[dict]) -> str | None:
    """What says the FRF datasets end inside a group their own order implies, or None.

    A measurement grid written group by group (every response for one reference, then the next
    reference; or every reference for one response) and cut between datasets ends on a group that
    holds the first few channels of the others: the test here. Each group must be one run of
    datasets, every group but the last must list the same channels in the same order, and the last
    must list a strict start of them.

    Not decidable, so not said: a cut file of a single group (one reference, or one roving hammer
    response), a cut that falls exactly between groups, or files without point ids (node 0).
    """
    pairs = [(part["rsp"], part["ref"]) for part in parts]
    if any(rsp[0] == 0 or ref[0] == 0 for rsp, ref in pairs):
        return None
    for key, other, names in ((1, 0, ("reference", "response")), (0, 1, ("response", "reference"))):
        runs: list[tuple[tuple[int, int], list]] = []
        for pair in pairs:
            if runs and runs[-1][0] == pair[key]:
                runs[-1][1].append(pair[other])
            else:
                runs.append((pair[key], [pair[other]]))
        if len(runs) < 2 or len({k for k, _ in runs}) != len(runs):
            continue
        full = runs[0][1]
        head, (last_key, last) = runs[:-1], runs[-1]
        if any(r != full for _, r in head) or len(last) >= len(full) or last != full[:len(last)]:
            continue
        missing = ", ".join(format_point(*q) for q in full[len(last):])
        return (f"{chosen[-1].where()}: the last {names[0]} {format_point(*last_key)} has {len(last)} "
                f"{names[1]}(s) where each of the other {len(head)} has {len(full)} (missing {missing})")
    return None


_INT_FIELDS = {
    6: [(0, 5, "func_type"), (5, 15, "func_id"), (15, 20, "ver_num"), (20, 30, "load_case_id"),
        (41, 51, "rsp_node"), (51, 55, "rsp_dir"), (66, 76, "ref_node"), (76, 80, "ref_dir")],
    7: [(0, 10, "ord_data_type"), (10, 20, "num_pts"), (20, 30, "abscissa_spacing")],
    8: [(0, 10, "abscissa_spec_data_type")], 9: [(0, 10, "ordinate_spec_data_type")],
    10: [(0, 10, "orddenom_spec_data_type")], 11: [(0, 10, "z_axis_spec_data_type")],
}
_REQUIRED = {"func_type", "rsp_node", "rsp_dir", "ref_node", "ref_dir", "ord_data_type", "num_pts",
             "abscissa_spacing"}


def check_header(block: _Block, src: str) -> str | None:
    """A message for the first bad field of records 6–11 (pyuff reads some as 0 silently), or None."""
    lines = block.raw.split(b"\n", 14)
    if len(lines) < 14:
        return (f"{src}: {block.where()}: only {max(len(lines) - 1, 0)} lines before the closing '    -1'; "
                "expected 12 header records and data (truncated dataset?)")
    text = [ln.decode("latin-1").rstrip("\r") for ln in lines[:14]]
    for record, fields in _INT_FIELDS.items():
        ln = text[record + 1]
        for a, e, name in fields:
            tok = ln[a:e].strip()
            if name in _REQUIRED or tok:
                try:
                    int(tok)
                except ValueError:
                    return (f"{src}: {block.where(record, name)}: {tok!r} is not an integer; "
                            f"expected an integer in columns {a + 1}-{e}")
    for a, e, name in ((30, 43, "abscissa_min"), (43, 56, "abscissa_inc")):
        tok = text[8][a:e].strip()
        try:
            float(tok)
        except ValueError:
            return f"{src}: {block.where(7, name)}: {tok!r} is not a number; expected E13.5 in columns {a + 1}-{e}"
    return None


def _diagnose(block: _Block, src: str) -> str:
    """A message naming the first bad record or value of a dataset pyuff could not parse."""
    problem = check_header(block, src)
    if problem:
        return problem
    lines = block.raw.split(b"\n")
    text = [ln.decode("latin-1").rstrip("\r") for ln in lines[:14]]
    binary = text[1][6:7].lower() == "b"
    if binary:
        return (f"{src}: {block.where()}: the binary data cannot be decoded (byte order, precision or length "
                "do not match record 7); expected the 58b layout (pyuff.fix_58b may repair some vendor files)")
    odt, spacing, n_pts = int(text[8][0:10]), int(text[8][20:30]), int(text[8][10:20])
    widths = [20] * 4 if (odt in (4, 6) and spacing == 1) else ([13] * 6 if odt in (2, 5) else
                                                              ([13, 20, 13, 20] if odt == 4 else [13, 20, 20]))
    count = 0
    for k, raw in enumerate(lines[13:]):
        ln = raw.decode("latin-1").rstrip("\r")
        pos = 0
        for w in widths:
            tok = ln[pos:pos + w]
            pos += w
            if not tok.strip():
                continue
            try:
                float(tok)
                count += 1
            except ValueError:
                return (f"{src}: {block.where()} (line {block.line + 13 + k}, data record): {tok.strip()!r} "
                        f"is not a number; expected fields of {w} characters")
    per_point = (2 if odt in (5, 6) else 1) + (0 if spacing == 1 else 1)
    return (f"{src}: {block.where(7, 'num_pts')}: {count} values in the data records do not make "
            f"{n_pts} points of {per_point} value(s) each; expected {n_pts * per_point} "
            "(truncated or damaged dataset?)")


# ------------------------------------------------------------ writing
def _e13(value: float) -> float:
    return float("%13.5e" % value)


def write_frf_uff(frf: FRF, path: str | os.PathLike, binary: bool = False) -> None:
    """Write one dataset 58 (or 58b if ``binary``) per channel, atomically.

    Point ids must be ``"<node><+|-><X|Y|Z|RX|RY|RZ>"`` or node numbers
    (:func:`parse_point`); an FRF without ids gets node 0 (read back as no ids).
    The response unit is written as ordinate numerator/denominator labels
    ("m/s^2" over "N" for "m/s^2/N"), cut to the format's 20 characters.

    Warns
    -----
    ModalWarning
        ASCII only: the frequency axis cannot be written exactly in the format's
        6-digit abscissa fields (the warning gives the largest error).
    """
    import pyuff

    from .._version import __version__

    src = source_name(path)
    freq = np.asarray(frf.frequency_hz, dtype=float)
    n = freq.size
    mn, inc = _e13(freq[0]), _e13(freq[1] - freq[0])
    even = bool(np.array_equal(mn + np.arange(n) * inc, freq)) and mn == freq[0]
    if not binary and not even:
        rounded = np.array([_e13(v) for v in freq])
        err = np.abs(rounded - freq).max()
        if err > 0:
            warn(f"{src}: UFF 58 ASCII keeps 6 significant digits of an uneven frequency axis "
                 f"(E13.5 fields); the largest change is {err:.3g} Hz. Write 58b (format='uff58b') "
                 "or use an evenly spaced axis to keep it exactly", ModalWarning, stacklevel=4)
    units = frf.units or ""
    num_unit, den_unit = (units[:-2], "N") if units.endswith("/N") else (units, "NONE")
    created = datetime.now(timezone.utc).strftime("%d-%b-%y %H:%M:%S")
    dsets = []
    for ch in range(frf.n_channels):
        rsp = _node_dir(frf.response_points, ch, "response_points", src)
        ref = _node_dir(frf.reference_points, ch, "reference_points", src)
        dsets.append({
            "type": 58, "binary": int(bool(binary)),
            "id1": f"FRF channel {ch + 1}"[:80], "id2": f"modalbal {__version__}"[:80], "id3": created,
            "id4": "NONE", "id5": "NONE",
            "func_type": 4, "func_id": ch + 1, "ver_num": 0, "load_case_id": 0,
            "rsp_ent_name": "NONE", "rsp_node": rsp[0], "rsp_dir": rsp[1],
            "ref_ent_name": "NONE", "ref_node": ref[0], "ref_dir": ref[1],
            "abscissa_spacing": int(even), "abscissa_min": freq[0], "abscissa_inc": freq[1] - freq[0],
            "z_axis_value": 0.0,
            "abscissa_spec_data_type": 18, "abscissa_axis_lab": "Frequency", "abscissa_axis_units_lab": "Hz",
            "ordinate_spec_data_type": _NUMERATOR[frf.kind], "ordinate_len_unit_exp": 1,
            "ordinate_axis_lab": _AXIS_LABEL[frf.kind], "ordinate_axis_units_lab": (num_unit or "NONE")[:20],
            "orddenom_spec_data_type": 13, "orddenom_force_unit_exp": 1,
            "orddenom_axis_lab": "Force", "orddenom_axis_units_lab": den_unit[:20],
            "z_axis_spec_data_type": 0,
            "x": freq.copy(), "data": np.asarray(frf.channels[ch], dtype=complex).copy(),
        })
    with atomic_path(path) as tmp, tempfile.TemporaryDirectory(prefix="modalbal-uff-") as scratch_dir:
        scratch = Path(scratch_dir) / "set.uff"
        # pyuff rescans the whole file after every dataset it writes (quadratic in the number of
        # channels), so each dataset is written alone to a scratch file and appended here.
        # Mode "add" on an empty file: pyuff's "overwrite" truncates the file again when it
        # switches to binary for 58b data, losing the header it has just written.
        try:
            with open(tmp, "wb") as out, warnings.catch_warnings():
                warnings.simplefilter("ignore")
                for dset in dsets:
                    scratch.write_bytes(b"")
                    pyuff.UFF(os.fspath(scratch)).write_sets(dset, mode="add", force_double=True)
                    out.write(scratch.read_bytes())
        except Exception as exc:  # pyuff raises bare Exception
            raise FormatError(f"{src}: pyuff could not write dataset 58 ({exc})") from None


def _node_dir(points, ch: int, name: str, src: str) -> tuple[int, int]:
    if points is None:
        return 0, 0
    try:
        return parse_point(points[ch])
    except ValueError as exc:
        raise FormatError(f"{src}: field '{name}' channel {ch}: {exc}; "
                          "UFF stores a node number and a direction") from None
